//! ARM MPS2 + AN386 (Cortex-M4F, 25 MHz) as QEMU emulates it: CMSDK APB UART0
//! at 0x4000_4000 for the protocol, SysTick for the loop, defmt over semihosting.

use core::ptr::{read_volatile, write_volatile};

use embedded_hal_nb::{nb, serial};
use {defmt_semihosting as _, panic_semihosting as _};

use crate::tick::SysTicker;

/// Board name for the log.
pub const NAME: &str = "mps2-an386";
/// Core clock.
const CORE_HZ: u32 = 25_000_000;
/// Control-loop rate.
pub const TICK_HZ: u32 = 1_000;
const UART0: usize = 0x4000_4000;
const BAUD: u32 = 115_200;

const DATA: usize = 0x00;
const STATE: usize = 0x04;
const CTRL: usize = 0x08;
const BAUDDIV: usize = 0x10;
const STATE_TX_FULL: u32 = 1 << 0;
const STATE_RX_FULL: u32 = 1 << 1;
const STATE_OVERRUNS: u32 = 0b11 << 2;
const CTRL_TX_RX_EN: u32 = 0b11;

/// The CMSDK APB UART, polled.
pub struct CmsdkUart {
    base: usize,
}

impl CmsdkUart {
    fn reg(&self, offset: usize) -> *mut u32 {
        (self.base + offset) as *mut u32
    }

    /// Enables transmitter and receiver at `BAUD`.
    fn new(base: usize) -> Self {
        let u = CmsdkUart { base };
        // SAFETY: the UART's registers, owned by this driver alone.
        unsafe {
            write_volatile(u.reg(BAUDDIV), CORE_HZ / BAUD);
            write_volatile(u.reg(CTRL), CTRL_TX_RX_EN);
        }
        u
    }
}

impl serial::ErrorType for CmsdkUart {
    type Error = serial::ErrorKind;
}

impl serial::Read<u8> for CmsdkUart {
    fn read(&mut self) -> nb::Result<u8, Self::Error> {
        // SAFETY: see `new`.
        let state = unsafe { read_volatile(self.reg(STATE)) };
        if state & STATE_OVERRUNS != 0 {
            unsafe { write_volatile(self.reg(STATE), STATE_OVERRUNS) };
            return Err(nb::Error::Other(serial::ErrorKind::Overrun));
        }
        if state & STATE_RX_FULL == 0 {
            return Err(nb::Error::WouldBlock);
        }
        Ok(unsafe { read_volatile(self.reg(DATA)) } as u8)
    }
}

impl serial::Write<u8> for CmsdkUart {
    fn write(&mut self, word: u8) -> nb::Result<(), Self::Error> {
        // SAFETY: see `new`.
        if unsafe { read_volatile(self.reg(STATE)) } & STATE_TX_FULL != 0 {
            return Err(nb::Error::WouldBlock);
        }
        unsafe { write_volatile(self.reg(DATA), word as u32) };
        Ok(())
    }

    fn flush(&mut self) -> nb::Result<(), Self::Error> {
        // SAFETY: see `new`.
        if unsafe { read_volatile(self.reg(STATE)) } & STATE_TX_FULL != 0 {
            return Err(nb::Error::WouldBlock);
        }
        Ok(())
    }
}

/// Takes the peripherals: UART0 and the loop timer.
pub fn init() -> (CmsdkUart, SysTicker) {
    let cp = cortex_m::Peripherals::take().unwrap();
    (
        CmsdkUart::new(UART0),
        SysTicker::start(cp.SYST, CORE_HZ, TICK_HZ),
    )
}
