//! The control-loop timer: SysTick at a fixed rate, its interrupt (an RTIC
//! task, `main.rs`) counting ticks.

use core::sync::atomic::{AtomicU32, Ordering};

use cortex_m::peripheral::{syst::SystClkSource, SYST};

static TICKS: AtomicU32 = AtomicU32::new(0);

/// The SysTick interrupt's work.
pub fn on_tick() {
    TICKS.fetch_add(1, Ordering::Relaxed);
}

/// SysTick as a [`capp_node::Ticker`].
pub struct SysTicker {
    _syst: SYST,
    seen: u32,
}

impl SysTicker {
    /// Starts SysTick at `rate_hz` from the core clock `core_hz`.
    pub fn start(mut syst: SYST, core_hz: u32, rate_hz: u32) -> Self {
        syst.set_clock_source(SystClkSource::Core);
        syst.set_reload(core_hz / rate_hz - 1);
        syst.clear_current();
        syst.enable_interrupt();
        syst.enable_counter();
        SysTicker {
            _syst: syst,
            seen: TICKS.load(Ordering::Relaxed),
        }
    }
}

impl capp_node::Ticker for SysTicker {
    fn take(&mut self) -> u32 {
        let now = TICKS.load(Ordering::Relaxed);
        let n = now.wrapping_sub(self.seen);
        self.seen = now;
        n
    }
}
