//! The device module RTIC needs for the mps2-an386 (`#[rtic::app(device =
//! ...)]`): the CMSDK CM4 interrupt numbers this firmware uses, the NVIC's
//! priority bits and the interrupt part of the vector table, as an svd2rust
//! PAC would give them (the handlers' weak aliases are in
//! `boards/mps2-an386/device.x`). Also linked by the examples, whose
//! cortex-m-rt wants the device's vector table.

/// Priority bits of the AN386's NVIC (CMSDK_CM4.h `__NVIC_PRIO_BITS`).
pub const NVIC_PRIO_BITS: u8 = 3;

/// External interrupts (CMSDK_CM4.h numbering, as QEMU's mps2 wires them).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
#[repr(u16)]
#[allow(clippy::upper_case_acronyms, dead_code)]
pub enum Interrupt {
    /// UART0 receive.
    UART0RX = 0,
    /// UART0 transmit.
    UART0TX = 1,
    /// UART 0-2 overrun, combined.
    UARTOVF = 12,
}
pub use self::Interrupt as interrupt;

// SAFETY: the numbers are the device's external interrupt numbers.
unsafe impl cortex_m::interrupt::InterruptNumber for Interrupt {
    fn number(self) -> u16 {
        self as u16
    }
}

/// A vector table entry.
pub union Vector {
    handler: unsafe extern "C" fn(),
    reserved: u32,
}

extern "C" {
    fn UART0RX();
    fn UART0TX();
    fn UARTOVF();
    fn DefaultHandler();
}

/// The 32 external interrupt vectors, placed after cortex-m-rt's exceptions.
#[link_section = ".vector_table.interrupts"]
#[no_mangle]
pub static __INTERRUPTS: [Vector; 32] = {
    let mut v = [const {
        Vector {
            handler: DefaultHandler,
        }
    }; 32];
    v[0] = Vector { handler: UART0RX };
    v[1] = Vector { handler: UART0TX };
    v[12] = Vector { handler: UARTOVF };
    v[31] = Vector { reserved: 0 };
    v
};
