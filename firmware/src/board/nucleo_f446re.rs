//! ST Nucleo-F446RE: STM32F446RE at 180 MHz from the ST-LINK's 8 MHz clock,
//! USART2 (PA2 TX, PA3 RX: the ST-LINK virtual COM port) for the protocol,
//! SysTick for the loop, defmt over RTT (read by `probe-rs run`).

use stm32f4xx_hal::{
    pac,
    prelude::*,
    serial::{config::Config, Serial},
};
use {defmt_rtt as _, panic_probe as _};

use crate::tick::SysTicker;

/// Board name for the log.
pub const NAME: &str = "nucleo-f446re";
const CORE_HZ: u32 = 180_000_000;
/// Control-loop rate.
pub const TICK_HZ: u32 = 100;
/// UART rate: a setpoint of 18 joints (~90 bytes) takes ~8 ms, within the
/// 10 ms tick; a 32-joint setpoint (~140 bytes, ~12 ms) does not, so use
/// `Run { every: 2 }` there, or setpoints are dropped (and counted).
const BAUD: u32 = 115_200;

/// Clocks, USART2 and the loop timer.
pub fn init() -> (Serial<pac::USART2>, SysTicker) {
    let dp = pac::Peripherals::take().unwrap();
    let cp = cortex_m::Peripherals::take().unwrap();
    let rcc = dp.RCC.constrain();
    let clocks = rcc
        .cfgr
        .use_hse(8.MHz())
        .bypass_hse_oscillator()
        .sysclk(CORE_HZ.Hz())
        .freeze();
    let gpioa = dp.GPIOA.split();
    let serial = dp
        .USART2
        .serial(
            (gpioa.pa2, gpioa.pa3),
            Config::default().baudrate(BAUD.bps()),
            &clocks,
        )
        .unwrap();
    (serial, SysTicker::start(cp.SYST, CORE_HZ, TICK_HZ))
}
