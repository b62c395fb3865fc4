//! ARM MPS2 + AN386 (Cortex-M4F, 25 MHz) as QEMU emulates it: CMSDK APB UART0
//! at 0x4000_4000 for the protocol (receive by interrupt), SysTick for the
//! loop, CMSDK TIMER0 as the cycle counter, defmt over semihosting.

use core::ptr::{read_volatile, write_volatile};

use embedded_hal_nb::{nb, serial};

use crate::tick::SysTicker;

/// Board name for the log.
pub const NAME: &str = "mps2-an386";
/// Core clock (TIMER0, the cycle counter, counts at it).
pub const CORE_HZ: u32 = 25_000_000;
/// Control-loop rate.
pub const TICK_HZ: u32 = 1_000;
const UART0: usize = 0x4000_4000;
const TIMER0: usize = 0x4000_0000;
const BAUD: u32 = 115_200;

const DATA: usize = 0x00;
const STATE: usize = 0x04;
const CTRL: usize = 0x08;
const INTCLEAR: usize = 0x0C;
const BAUDDIV: usize = 0x10;
const STATE_TX_FULL: u32 = 1 << 0;
const STATE_RX_FULL: u32 = 1 << 1;
const STATE_RX_OVERRUN: u32 = 1 << 3;
const CTRL_TX_EN: u32 = 1 << 0;
const CTRL_RX_EN: u32 = 1 << 1;
const CTRL_RX_INTEN: u32 = 1 << 3;
const INT_RX: u32 = 1 << 1;
const INT_RX_OVERRUN: u32 = 1 << 3;

/// The device module RTIC needs (`#[rtic::app(device = ...)]`).
#[path = "mps2_an386_pac.rs"]
pub mod pac;

fn reg(base: usize, offset: usize) -> *mut u32 {
    (base + offset) as *mut u32
}

/// The transmit side of UART0, polled by the main loop.
pub struct Tx {
    base: usize,
}

/// The receive side of UART0, read by its interrupt.
pub struct Rx {
    base: usize,
}

impl serial::ErrorType for Tx {
    type Error = serial::ErrorKind;
}

impl serial::ErrorType for Rx {
    type Error = serial::ErrorKind;
}

impl serial::Read<u8> for Rx {
    fn read(&mut self) -> nb::Result<u8, Self::Error> {
        // SAFETY: UART0's registers; only this half reads DATA and STATE's RX
        // bits, only the Tx half writes DATA.
        unsafe {
            // The interrupt status first: a byte arriving after the last read
            // sets it again, so no byte is left without an interrupt.
            write_volatile(reg(self.base, INTCLEAR), INT_RX | INT_RX_OVERRUN);
            let state = read_volatile(reg(self.base, STATE));
            if state & STATE_RX_OVERRUN != 0 {
                write_volatile(reg(self.base, STATE), STATE_RX_OVERRUN);
                return Err(nb::Error::Other(serial::ErrorKind::Overrun));
            }
            if state & STATE_RX_FULL == 0 {
                return Err(nb::Error::WouldBlock);
            }
            Ok(read_volatile(reg(self.base, DATA)) as u8)
        }
    }
}

impl serial::Write<u8> for Tx {
    fn write(&mut self, word: u8) -> nb::Result<(), Self::Error> {
        // SAFETY: see `Rx::read`.
        unsafe {
            if read_volatile(reg(self.base, STATE)) & STATE_TX_FULL != 0 {
                return Err(nb::Error::WouldBlock);
            }
            write_volatile(reg(self.base, DATA), word as u32);
        }
        Ok(())
    }

    fn flush(&mut self) -> nb::Result<(), Self::Error> {
        // SAFETY: see `Rx::read`.
        if unsafe { read_volatile(reg(self.base, STATE)) } & STATE_TX_FULL != 0 {
            return Err(nb::Error::WouldBlock);
        }
        Ok(())
    }
}

/// The cycle counter: CMSDK TIMER0 counting down from `u32::MAX` at the core
/// clock (under QEMU: emulated time, which follows the host's speed).
pub fn cycles() -> u32 {
    // SAFETY: a read of TIMER0's VALUE register, configured in `init`.
    u32::MAX - unsafe { read_volatile(reg(TIMER0, 0x04)) }
}

/// What the board gives the application.
pub struct Board {
    /// UART0, transmit half.
    pub tx: Tx,
    /// UART0, receive half (its interrupt is enabled).
    pub rx: Rx,
    /// The loop timer.
    pub ticker: SysTicker,
}

/// UART0 at `BAUD` with its receive interrupt, TIMER0 free
/// running, SysTick at `TICK_HZ`. (QEMU has no DWT cycle counter: TIMER0
/// counts instead.)
pub fn init(
    syst: cortex_m::peripheral::SYST,
    _dcb: &mut cortex_m::peripheral::DCB,
    _dwt: &mut cortex_m::peripheral::DWT,
) -> Board {
    // SAFETY: UART0's and TIMER0's registers, configured once, here.
    unsafe {
        write_volatile(reg(UART0, BAUDDIV), CORE_HZ / BAUD);
        write_volatile(
            reg(UART0, CTRL),
            // No overrun interrupt (it is shared by UARTs 0-2): the next
            // receive interrupt reports an overrun from STATE.
            CTRL_TX_EN | CTRL_RX_EN | CTRL_RX_INTEN,
        );
        write_volatile(reg(TIMER0, 0x08), u32::MAX); // RELOAD
        write_volatile(reg(TIMER0, 0x04), u32::MAX); // VALUE
        write_volatile(reg(TIMER0, 0x00), 1); // CTRL: enable
    }
    Board {
        tx: Tx { base: UART0 },
        rx: Rx { base: UART0 },
        ticker: SysTicker::start(syst, CORE_HZ, TICK_HZ),
    }
}

/// Logs the board's clock setup.
pub fn log_clocks() {
    defmt::info!("core clock {} Hz (QEMU: no wait states to set)", CORE_HZ);
}

/// Ends the program on an unrecoverable fault: the message on the host's
/// stderr (semihosting), QEMU exits with status 1.
pub fn fatal(message: &str) -> ! {
    to_stderr(&["capp-firmware: ", message, "\n"]);
    exit_failure()
}

/// The panic handler (`main.rs`): where and what on the host's stderr, QEMU
/// exits with status 1. Written here, not `panic-semihosting`, because that
/// crate formats the `PanicInfo` with `core::fmt`, 1.2 KB of the image's
/// flash; a message with arguments is named, not formatted.
pub fn panicked(info: &core::panic::PanicInfo) -> ! {
    let message = info
        .message()
        .as_str()
        .unwrap_or("(a message with arguments)");
    let (file, line) = info
        .location()
        .map_or(("?", 0), |at| (at.file(), at.line()));
    let mut digits = [0u8; 10];
    to_stderr(&[
        "capp-firmware: panicked at ",
        file,
        ":",
        decimal(line, &mut digits),
        ": ",
        message,
        "\n",
    ]);
    exit_failure()
}

/// `value` in decimal, in `digits`.
fn decimal(mut value: u32, digits: &mut [u8; 10]) -> &str {
    let mut start = digits.len();
    loop {
        start -= 1;
        digits[start] = b'0' + (value % 10) as u8;
        value /= 10;
        if value == 0 || start == 0 {
            break;
        }
    }
    core::str::from_utf8(&digits[start..]).unwrap_or("?")
}

fn to_stderr(parts: &[&str]) {
    if let Ok(mut stderr) = cortex_m_semihosting::hio::hstderr() {
        for part in parts {
            let _ = stderr.write_all(part.as_bytes());
        }
    }
}

fn exit_failure() -> ! {
    loop {
        cortex_m_semihosting::debug::exit(cortex_m_semihosting::debug::EXIT_FAILURE);
    }
}
