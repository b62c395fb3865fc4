//! Host benchmarks (criterion): one planner step of PIPS with 0, 8 and 32
//! obstacles against one step of the paper's listing (finite differences) on
//! the same scenarios and configuration, and each phase alone. (The scaling
//! sweep is `examples/host_scaling.rs`: interleaved, so a shared machine's
//! bursts do not land on a few of its 25 scenes.)
//!
//!     cargo bench -p capp-bench --bench step
//!
//! Every measurement starts from the warmed-up planner of `capp_bench::scenes`
//! (a fresh copy per iteration, outside the timed part). `cargo xtask bench`
//! runs this and collects the figures into BENCHMARKS.md.

use std::hint::black_box;
use std::time::Duration;

use capp_bench::scenes::{self, PIPS_OBSTACLES};
use capp_bench::{Listing, PhaseBench, Scene};
use capp_core::Planner;
use criterion::{criterion_group, criterion_main, BatchSize, BenchmarkId, Criterion};

fn scene_or_exit<const N: usize>(
    scene: Result<Scene<N>, capp_bench::SceneError>,
    what: &str,
) -> Scene<N> {
    match scene {
        Ok(s) => s,
        Err(e) => {
            eprintln!("benchmark scene {what}: {e:?}");
            std::process::exit(1);
        }
    }
}

fn warmed<const N: usize>(scene: &Scene<N>, what: &str) -> Planner<N> {
    match scenes::warm_up(scene) {
        Ok(p) => p,
        Err(e) => {
            eprintln!("benchmark scene {what}: {e:?}");
            std::process::exit(1);
        }
    }
}

fn pips(c: &mut Criterion) {
    let mut group = c.benchmark_group("pips");
    for k in PIPS_OBSTACLES {
        let scene = scene_or_exit(scenes::pips(k), "pips");
        let sc = &scene.scenario;
        let planner = warmed(&scene, "pips");
        group.bench_with_input(BenchmarkId::new("step", k), &k, |b, _| {
            b.iter_batched_ref(
                || planner.clone(),
                |p| black_box(p.step(sc)),
                BatchSize::SmallInput,
            )
        });
        let listing = Listing::<18>::new(planner.joints());
        group.bench_with_input(BenchmarkId::new("listing_step", k), &k, |b, _| {
            b.iter_batched_ref(
                || listing.clone(),
                |l| black_box(l.step(sc)),
                BatchSize::SmallInput,
            )
        });
        let mut phases = PhaseBench::new(sc, &planner);
        if k == 8 {
            group.bench_function("kinematics", |b| {
                b.iter(|| black_box(phases.kinematics(sc)))
            });
            group.bench_function("control_law", |b| {
                b.iter(|| black_box(phases.control_law(sc)))
            });
            group.bench_function("projection_integration", |b| {
                b.iter(|| black_box(phases.projection_integration(sc)))
            });
        }
        group.bench_with_input(BenchmarkId::new("obstacles", k), &k, |b, _| {
            b.iter(|| black_box(phases.obstacles(sc)))
        });
    }
    group.finish();
}

criterion_group! {
    name = benches;
    config = Criterion::default()
        .warm_up_time(Duration::from_millis(500))
        .measurement_time(Duration::from_secs(2))
        .sample_size(30);
    targets = pips
}
criterion_main!(benches);
