//! Where a tracked tick's instructions go, function by function: runs 40
//! tracked PIPS + 8 ticks (issue 22) from `step_count`'s warmed-up state,
//! between two calls of a marker, for QEMU's instruction trace:
//!
//!     bash scripts/profile_tick.sh
//!
//! The script builds this, runs it one instruction a translation block
//! (`-singlestep -d exec,nochain`), and counts the instructions executed
//! between the markers by the function they belong to (inlined code counts
//! as its caller's). Counts, not timings: `step_count` has the totals.
#![no_std]
#![no_main]

use core::hint::black_box;

use capp_bench::scenes;
use cortex_m_rt::entry;

/// The board's interrupt vectors (cortex-m-rt's `device` feature is on).
#[path = "../src/board/mps2_an386_pac.rs"]
#[allow(dead_code, unused_imports)]
mod pac;
use cortex_m_semihosting::{debug, hprintln};
use {defmt_semihosting as _, panic_semihosting as _};

/// Ticks profiled.
const TICKS: usize = 40;

/// Called before and after the profiled ticks: the script counts between
/// its first two calls.
#[inline(never)]
#[no_mangle]
pub extern "C" fn capp_profile_marker() {
    black_box(());
}

#[entry]
fn main() -> ! {
    match scenes::pips_tracked(8) {
        Ok(scene) => match scenes::warm_up(&scene) {
            Ok(mut planner) => {
                let scenario = &scene.scenario;
                capp_profile_marker();
                for _ in 0..TICKS {
                    black_box(planner.step(scenario).ok());
                }
                capp_profile_marker();
                hprintln!("profile_tick: {} ticks", TICKS);
            }
            Err(_) => hprintln!("profile_tick: warm-up failed"),
        },
        Err(_) => hprintln!("profile_tick: no scene"),
    }
    debug::exit(debug::EXIT_SUCCESS);
    loop {
        cortex_m::asm::nop();
    }
}
