//! ST Nucleo-F446RE: STM32F446RE at 180 MHz from the ST-LINK's 8 MHz clock,
//! USART2 (PA2 TX, PA3 RX: the ST-LINK virtual COM port) for the protocol
//! (receive by interrupt), SysTick for the loop, the DWT cycle counter,
//! defmt over RTT (read by `probe-rs run`).
//!
//! Clocks: `stm32f4xx-hal`'s `freeze` sets the PLL for 180 MHz from HSE
//! bypass, turns on the regulator's over-drive (needed above 168 MHz), sets
//! the flash to 5 wait states (`(180 MHz - 1) / 30 MHz` at 3.3 V) and turns on
//! the ART accelerator (instruction cache, data cache, prefetch: `FLASH_ACR`
//! `ICEN`, `DCEN`, `PRFTEN`). `log_clocks` reads `FLASH_ACR` back into the log.

/// The device module RTIC needs: the PAC.
pub use stm32f4xx_hal::pac;
use stm32f4xx_hal::{
    prelude::*,
    serial::{config::Config, Rx as HalRx, RxListen, Serial, Tx as HalTx},
};

use crate::tick::SysTicker;

/// Board name for the log.
pub const NAME: &str = "nucleo-f446re";
/// Core clock (the DWT cycle counter's rate).
pub const CORE_HZ: u32 = 180_000_000;
/// Control-loop rate.
pub const TICK_HZ: u32 = 100;
/// UART rate: a setpoint of 18 joints with their velocities and
/// accelerations (protocol 7: ~240 bytes) takes ~21 ms, more than the 10 ms
/// tick, so use `Run { every: 3 }` there (32 joints, ~410 bytes: `every: 4`),
/// or setpoints are dropped (and counted).
const BAUD: u32 = 115_200;

/// USART2, transmit half (polled by the main loop).
pub type Tx = HalTx<pac::USART2>;
/// USART2, receive half (read by its interrupt).
pub type Rx = HalRx<pac::USART2>;

/// The cycle counter: the DWT's `CYCCNT` (enabled in `init`).
pub fn cycles() -> u32 {
    cortex_m::peripheral::DWT::cycle_count()
}

/// What the board gives the application.
pub struct Board {
    /// USART2, transmit half.
    pub tx: Tx,
    /// USART2, receive half (its RXNE interrupt is enabled).
    pub rx: Rx,
    /// The loop timer.
    pub ticker: SysTicker,
}

/// Clocks, USART2 (receive interrupt on), the DWT cycle counter, SysTick.
pub fn init(
    syst: cortex_m::peripheral::SYST,
    dcb: &mut cortex_m::peripheral::DCB,
    dwt: &mut cortex_m::peripheral::DWT,
) -> Board {
    // SAFETY: RTIC's init runs once, before anything else uses the peripherals.
    let dp = unsafe { pac::Peripherals::steal() };
    let rcc = dp.RCC.constrain();
    let clocks = rcc
        .cfgr
        .use_hse(8.MHz())
        .bypass_hse_oscillator()
        .sysclk(CORE_HZ.Hz())
        .freeze();
    dcb.enable_trace();
    dwt.enable_cycle_counter();
    let gpioa = dp.GPIOA.split();
    let serial = Serial::new(
        dp.USART2,
        (gpioa.pa2, gpioa.pa3),
        Config::default().baudrate(BAUD.bps()),
        &clocks,
    )
    .unwrap();
    let (tx, mut rx) = serial.split();
    rx.listen();
    Board {
        tx,
        rx,
        ticker: SysTicker::start(syst, CORE_HZ, TICK_HZ),
    }
}

/// Logs the clock setup as the flash controller has it.
pub fn log_clocks() {
    // SAFETY: a read of FLASH_ACR.
    let acr = unsafe { (*pac::FLASH::ptr()).acr().read() };
    defmt::info!(
        "core clock {} Hz; flash {} wait states, ART: icache {} dcache {} prefetch {}",
        CORE_HZ,
        acr.latency().bits(),
        acr.icen().bit_is_set(),
        acr.dcen().bit_is_set(),
        acr.prften().bit_is_set()
    );
}

/// Stops on an unrecoverable fault: the message in the defmt log, then a
/// breakpoint, where `probe-rs run` stops and prints the backtrace.
pub fn fatal(message: &str) -> ! {
    defmt::error!("{}", message);
    loop {
        cortex_m::asm::bkpt();
    }
}
