//! Host time per planner step over the scaling sweep (chains of 6 to 32
//! joints, 0 to 64 obstacles), measured interleaved: every round times a
//! batch of steps on each scene in turn, so a burst of other work on a shared
//! machine hits all scenes alike instead of a few; the figure is the median
//! over rounds. Each step starts from a fresh copy of the warmed-up state
//! (copy not timed), as in the criterion benches.
//!
//!     cargo run --release -p capp-bench --example host_scaling [-- ROUNDS]
//!
//! Output: one `HOST <joints> <obstacles> <ns per step>` line per scene.

use std::hint::black_box;
use std::time::Instant;

use capp_bench::scenes::{self, SCALING_JOINTS, SCALING_OBSTACLES};
use capp_core::Planner;

/// Steps per batch (one timed interval).
const BATCH: usize = 16;

fn main() {
    let rounds: usize = std::env::args()
        .nth(1)
        .and_then(|a| a.parse().ok())
        .unwrap_or(101);
    let mut cases = Vec::new();
    for n in SCALING_JOINTS {
        for m in SCALING_OBSTACLES {
            let scene = match scenes::chain(n, m) {
                Ok(s) => s,
                Err(e) => {
                    eprintln!("chain {n} x {m}: {e:?}");
                    std::process::exit(1);
                }
            };
            let planner = match scenes::warm_up(&scene) {
                Ok(p) => p,
                Err(e) => {
                    eprintln!("chain {n} x {m}: {e:?}");
                    std::process::exit(1);
                }
            };
            cases.push((n, m, scene, planner, Vec::with_capacity(rounds)));
        }
    }
    let mut copies: Vec<Planner<{ scenes::MAX_CHAIN_JOINTS }>> = Vec::with_capacity(BATCH);
    for _ in 0..rounds {
        for (_, _, scene, planner, times) in cases.iter_mut() {
            copies.clear();
            copies.extend(std::iter::repeat_n(planner.clone(), BATCH));
            let start = Instant::now();
            for copy in copies.iter_mut() {
                black_box(copy.step(&scene.scenario).ok());
            }
            times.push(start.elapsed().as_nanos() as f64 / BATCH as f64);
        }
    }
    for (n, m, _, _, times) in cases.iter_mut() {
        times.sort_by(f64::total_cmp);
        println!("HOST {n} {m} {:.1}", times[times.len() / 2]);
    }
}
