//! Counts the instructions one planner step (and each of its phases, and the
//! paper's finite-difference listing) executes on the Cortex-M4F, under QEMU:
//!
//!     cd firmware && cargo build --release --example step_count
//!     qemu-system-arm -machine mps2-an386 -icount shift=0 -nographic -monitor none \
//!         -semihosting-config enable=on,target=native \
//!         -kernel target/thumbv7em-none-eabihf/release/examples/step_count
//!
//! With `-icount shift=0` QEMU's virtual clock advances exactly 1 ns per
//! executed instruction, and the mps2-an386 SysTick (core clock source) counts
//! at 25 MHz of that clock: one tick = 40 instructions. Every figure is a mean
//! over repetitions of the same work from the same state, minus the cost of
//! reading the clock; the count is checked first on a loop of known length.
//! Output: one `M4F <scene> <joints> <obstacles> <what> <value>` line per
//! figure on the semihosting console (stdout), then QEMU exits.
//! `cargo xtask bench` runs this and collects the lines.
#![no_std]
#![no_main]

use core::arch::asm;
use core::hint::black_box;
use core::sync::atomic::{compiler_fence, Ordering};

use capp_bench::scenes::{
    self, Scene, INFLUENCE_SWEEP_IN, PIPS_OBSTACLES, SCALING_JOINTS, SCALING_OBSTACLES,
};
use capp_bench::{Listing, PhaseBench};
use capp_core::control::LawKind;
use capp_core::{Planner, Scenario};
use cortex_m::peripheral::{syst::SystClkSource, SYST};
use cortex_m_rt::entry;

/// The board's interrupt vectors (cortex-m-rt's `device` feature is on).
#[path = "../src/board/mps2_an386_pac.rs"]
#[allow(dead_code, unused_imports)]
mod pac;
use cortex_m_semihosting::{debug, hprintln};
use {defmt_semihosting as _, panic_semihosting as _};

/// Instructions per SysTick tick: 1 ns per instruction, 25 MHz SysTick.
const INSTRUCTIONS_PER_TICK: u64 = 40;
/// SysTick is a 24-bit down-counter.
const SYSTICK_MASK: u32 = 0x00FF_FFFF;
/// Repetitions of a single step or phase (timed together: +-1.6 instructions).
const REPS: u32 = 50;
/// Consecutive steps timed along the trajectory after the warm-up.
const WINDOW: u32 = 200;

/// SysTick running free over its full 24 bits from the core clock.
fn start_clock(mut syst: SYST) -> SYST {
    syst.set_clock_source(SystClkSource::Core);
    syst.set_reload(SYSTICK_MASK);
    syst.clear_current();
    syst.enable_counter();
    syst
}

#[inline(always)]
fn ticks() -> u32 {
    compiler_fence(Ordering::SeqCst);
    let t = SYST::get_current();
    compiler_fence(Ordering::SeqCst);
    t
}

/// Ticks elapsed since `start` (intervals under 2^24 ticks = 671 M instructions).
#[inline(always)]
fn since(start: u32) -> u32 {
    start.wrapping_sub(ticks()) & SYSTICK_MASK
}

/// Mean instructions of `work` over `reps` runs, each after `setup`, in tenths,
/// with `overhead_tenths` (the clock reads) removed; and the largest single run.
fn count<S>(
    reps: u32,
    overhead_tenths: u64,
    state: &mut S,
    mut setup: impl FnMut(&mut S),
    mut work: impl FnMut(&mut S),
) -> (u64, u64) {
    let mut total = 0u64;
    let mut max = 0u64;
    for _ in 0..reps {
        setup(state);
        let t0 = ticks();
        work(state);
        let t = since(t0) as u64 * INSTRUCTIONS_PER_TICK;
        total += t;
        max = max.max(t);
    }
    let mean = (total * 10 / reps as u64).saturating_sub(overhead_tenths);
    (mean, max.saturating_sub(overhead_tenths / 10))
}

/// Mean instructions of `work`, in tenths: `reps` runs of `setup` then `work`
/// timed as one interval, less `reps` runs of `setup` alone. Each interval is
/// read to 40 instructions, so the mean is good to `80 / reps`; the clock
/// reads cancel.
fn repeat<S>(
    reps: u32,
    state: &mut S,
    mut setup: impl FnMut(&mut S),
    mut work: impl FnMut(&mut S),
) -> u64 {
    let t0 = ticks();
    for _ in 0..reps {
        setup(black_box(&mut *state));
        work(black_box(&mut *state));
    }
    let with = since(t0) as u64;
    let t0 = ticks();
    for _ in 0..reps {
        setup(black_box(&mut *state));
        black_box(&mut *state);
    }
    let without = since(t0) as u64;
    with.saturating_sub(without) * INSTRUCTIONS_PER_TICK * 10 / reps as u64
}

/// A loop of exactly two instructions per iteration (`subs`, `bne`).
#[inline(never)]
fn spin(iterations: u32) {
    // SAFETY: register-only loop, no memory or stack use.
    unsafe {
        asm!("1:", "subs {0}, {0}, #1", "bne 1b", inout(reg) iterations => _, options(nomem, nostack));
    }
}

fn line(scene: &str, joints: usize, obstacles: usize, what: &str, tenths: u64) {
    hprintln!(
        "M4F {} {} {} {} {}.{}",
        scene,
        joints,
        obstacles,
        what,
        tenths / 10,
        tenths % 10
    );
}

fn stack_pointer() -> usize {
    cortex_m::register::msp::read() as usize
}

const PAINT: u32 = 0xCCCC_CCCC;
const PAINT_BYTES: usize = 32 * 1024;

/// Bytes of stack `work` uses below the caller's frame, by painting.
#[inline(never)]
fn stack_use(work: impl FnOnce()) -> usize {
    let top = stack_pointer() - 256;
    let bottom = top - PAINT_BYTES;
    let mut p = bottom;
    while p < top {
        // SAFETY: unused stack below the current frame (4 MiB of RAM, the
        // stack grows down from its top); nothing lives there yet.
        unsafe { core::ptr::write_volatile(p as *mut u32, PAINT) };
        p += 4;
    }
    work();
    let mut p = bottom;
    // SAFETY: the same words, read back.
    while p < top && unsafe { core::ptr::read_volatile(p as *const u32) } == PAINT {
        p += 4;
    }
    top + 256 - p
}

/// Step, phases, listing and a trajectory window for one scene.
fn measure<const N: usize>(
    name: &str,
    scene: &Scene<N>,
    overhead: u64,
    with_phases: bool,
    listing_reps: u32,
) {
    let (n, m) = (scene.joints, scene.scenario.obstacles().len());
    let sc = &scene.scenario;
    let Ok(snapshot) = scenes::warm_up(scene) else {
        hprintln!("M4F {} {} {} error warm-up", name, n, m);
        return;
    };
    let mut planner = snapshot.clone();
    let step = repeat(
        REPS,
        &mut planner,
        |p| p.clone_from(&snapshot),
        |p| {
            black_box(p.step(sc).ok());
        },
    );
    line(name, n, m, "step", step);
    let mut phases = PhaseBench::new(sc, &snapshot);
    line(
        name,
        n,
        m,
        "active_pairs",
        phases.active_pairs() as u64 * 10,
    );
    if with_phases {
        let k = repeat(
            REPS,
            &mut phases,
            |_| {},
            |b| {
                black_box(b.kinematics(sc));
            },
        );
        line(name, n, m, "kinematics", k);
        let c = repeat(
            REPS,
            &mut phases,
            |_| {},
            |b| {
                black_box(b.control_law(sc));
            },
        );
        line(name, n, m, "control_law", c);
        let o = repeat(
            REPS,
            &mut phases,
            |_| {},
            |b| {
                black_box(b.obstacles(sc));
            },
        );
        line(name, n, m, "obstacles", o);
        let l = repeat(
            REPS,
            &mut phases,
            |_| {},
            |b| {
                black_box(b.link_pairs(sc));
            },
        );
        line(name, n, m, "link_pairs", l);
        let p = repeat(
            REPS,
            &mut phases,
            |_| {},
            |b| {
                black_box(b.projection_integration(sc));
            },
        );
        line(name, n, m, "projection_integration", p);
        // A run of consecutive steps, to the end of the run or WINDOW steps:
        // the mean and the worst along the path.
        planner.clone_from(&snapshot);
        let (mut halvings, mut steps, mut total, mut max) = (0u64, 0u64, 0u64, 0u64);
        while steps < WINDOW as u64 && !planner.is_done() {
            let (one, _) = count(
                1,
                overhead,
                &mut planner,
                |_| {},
                |p| {
                    if let Ok(r) = p.step(sc) {
                        halvings += r.halvings as u64;
                    }
                },
            );
            steps += 1;
            total += one;
            max = max.max(one);
        }
        if let Some(mean) = total.checked_div(steps) {
            line(name, n, m, "window_mean", mean);
            line(name, n, m, "window_max", max);
            line(name, n, m, "window_steps", steps * 10);
            line(name, n, m, "window_halvings", halvings * 10);
        }
    }
    if with_phases && m > 0 {
        pair_costs(name, scene, &snapshot);
    }
    if listing_reps > 0 {
        let start = Listing::<N>::new(snapshot.joints());
        let mut listing = start.clone();
        let l = repeat(
            listing_reps,
            &mut listing,
            |l| l.clone_from(&start),
            |l| {
                black_box(l.step(sc));
            },
        );
        line(name, n, m, "listing_step", l);
    }
}

/// Instructions of one point / obstacle evaluation (`Obstacle::contact`):
/// the mean over the pairs within influence and over those outside it.
fn pair_costs<const N: usize>(name: &str, scene: &Scene<N>, planner: &Planner<N>) {
    let sc = &scene.scenario;
    let (n, m) = (scene.joints, sc.obstacles().len());
    let avoidance = &sc.settings().avoidance;
    let (mut active, mut active_n, mut idle, mut idle_n) = (0u64, 0u64, 0u64, 0u64);
    for point in capp_core::avoidance::points(planner.frames(), avoidance) {
        for obstacle in sc.obstacles() {
            let mut hit = false;
            let c = repeat(
                8,
                &mut hit,
                |_| {},
                |h| {
                    *h = black_box(obstacle.contact(black_box(&point.position), point.kind, &[]))
                        .is_some();
                },
            );
            if hit {
                active += c;
                active_n += 1;
            } else {
                idle += c;
                idle_n += 1;
            }
        }
    }
    if let Some(mean) = active.checked_div(active_n) {
        line(name, n, m, "contact_within_influence", mean);
    }
    if let Some(mean) = idle.checked_div(idle_n) {
        line(name, n, m, "contact_outside_influence", mean);
    }
}

/// `Obstacle::contact` for every point of `points` against `obstacle`, each
/// result kept (`black_box`).
#[inline(never)]
fn contacts(
    obstacle: &capp_core::obstacle::Obstacle,
    points: &[capp_core::math::Vec3],
    hulls: &[capp_core::obstacle::Hull],
) {
    for point in points {
        black_box(obstacle.contact(point, capp_core::obstacle::PointKind::Link, hulls));
    }
}

/// What building each hull costs (`Hull::set`: the checks, the support's
/// cells, the topology, the faces' cells), once each, in place
/// (`build_<label>`). Its own function: the shape costs' register
/// allocation stays as it was.
#[inline(never)]
fn hull_builds(hulls: &[(&str, &[[f32; 3]])]) {
    let mut built = capp_core::obstacle::Hull::empty();
    for (label, vertices) in hulls {
        let cost = repeat(
            1,
            &mut built,
            |_| {},
            |h| {
                let _ = h.set(black_box(vertices));
            },
        );
        hprintln!("M4F shape 0 1 build_{} {}.{}", label, cost / 10, cost % 10);
    }
}

/// Instructions of one point / obstacle evaluation (`Obstacle::contact`)
/// for each shape, of PIPS size (inches, the listing's margins and 24 in of
/// influence), aligned and turned: the mean over the points of a spiral of
/// 96 around the shape that are within its influence, each timed alone over
/// 16 repetitions (`what` = `contact_<shape>_<aligned|turned>`) and all of
/// them in a loop ([`contacts`], 16 repetitions; `loop_<shape>_<...>`). Two
/// lines per shape and orientation, `obstacles` = 1.
fn shape_costs() {
    use capp_core::obstacle::{Hull, Obstacle, PointKind};
    use capp_core::{Shape, Solid};
    // A 16-vertex hull of the boxes' size: an octagonal prism, its
    // octagon's corners on the ellipse of semi-axes 20 and 15, z = +-10.
    let mut prism = [[0.0f32; 3]; 16];
    for (i, v) in prism.iter_mut().enumerate() {
        let (s, c) = capp_core::math::sin_cos(core::f32::consts::FRAC_PI_4 * (i % 8) as f32 + 0.3);
        *v = [20.0 * c, 15.0 * s, if i < 8 { 10.0 } else { -10.0 }];
    }
    let Ok(hull) = Hull::new(&prism) else {
        return;
    };
    // The box's 8 corners, and a 16-gon prism of 32 vertices (the most a
    // hull takes): how the cost grows with the vertex count.
    let corners: [[f32; 3]; 8] = core::array::from_fn(|i| {
        let side = |bit: usize, half: f32| if i & bit == 0 { half } else { -half };
        [side(1, 20.0), side(2, 15.0), side(4, 10.0)]
    });
    let Ok(hull8) = Hull::new(&corners) else {
        return;
    };
    let mut big = [[0.0f32; 3]; 32];
    for (i, v) in big.iter_mut().enumerate() {
        let (s, c) = capp_core::math::sin_cos(core::f32::consts::PI / 8.0 * (i % 16) as f32 + 0.3);
        *v = [20.0 * c, 15.0 * s, if i < 16 { 10.0 } else { -10.0 }];
    }
    let Ok(hull32) = Hull::new(&big) else {
        return;
    };
    hull_builds(&[
        ("hull16", &prism[..]),
        ("hull8", &corners[..]),
        ("hull32", &big[..]),
    ]);
    let hulls = [hull, hull8, hull32];
    let shapes = [
        (
            "superellipsoid8",
            Shape::SuperEllipsoid {
                semi_axes: [20.0, 15.0, 10.0],
                exponents: [8.0; 3],
            },
        ),
        (
            "superellipsoid2",
            Shape::SuperEllipsoid {
                semi_axes: [20.0, 15.0, 10.0],
                exponents: [2.0; 3],
            },
        ),
        ("sphere", Shape::Sphere { radius: 15.0 }),
        (
            "box",
            Shape::Cuboid {
                half_extents: [20.0, 15.0, 10.0],
            },
        ),
        (
            "capsule",
            Shape::Capsule {
                radius: 10.0,
                length: 30.0,
            },
        ),
        (
            "cylinder",
            Shape::Cylinder {
                radius: 12.0,
                length: 36.0,
            },
        ),
        ("hull16", Shape::Convex { hull: 0 }),
        ("hull8", Shape::Convex { hull: 1 }),
        ("hull32", Shape::Convex { hull: 2 }),
    ];
    for (label, shape) in shapes {
        for (turn, euler_123) in [("aligned", [0.0; 3]), ("turned", [0.3, -0.5, 0.9])] {
            let solid = Solid {
                centre: [100.0, -40.0, 30.0],
                euler_123,
                shape,
            };
            let Ok(obstacle) = Obstacle::new_in(0, &solid, &hulls, [6.0, 3.0], 24.0) else {
                continue;
            };
            // A spiral of directions, at 1.2 x the shape's size from its
            // centre: points outside the inflated shape, within influence.
            let mut points = [capp_core::math::Vec3::zeros(); 96];
            let mut within = 0usize;
            for i in 0..96u32 {
                let z = 1.0 - (2.0 * i as f32 + 1.0) / 96.0;
                let ring = capp_core::math::sqrt(1.0 - z * z);
                let (s, c) = capp_core::math::sin_cos(2.399_963 * i as f32);
                let r = 30.0;
                let point = capp_core::math::Vec3::new(
                    100.0 + r * ring * c,
                    -40.0 + r * ring * s,
                    30.0 + r * z,
                );
                if obstacle.contact(&point, PointKind::Link, &hulls).is_some() {
                    points[within] = point;
                    within += 1;
                }
            }
            // Each point alone (the obstacle a constant of this function:
            // its sizes may be folded into the code) ...
            let mut alone = 0u64;
            for point in &points[..within] {
                let mut hit = false;
                alone += repeat(
                    16,
                    &mut hit,
                    |_| {},
                    |h| {
                        *h = black_box(obstacle.contact(black_box(point), PointKind::Link, &hulls))
                            .is_some();
                    },
                );
            }
            // ... and the pairs in a loop of their own, as the planner's
            // pair loop runs them: the obstacle as data, `contact` inlined,
            // the loop's own few instructions a pair included.
            let in_loop = repeat(
                16,
                &mut (),
                |_| {},
                |_| contacts(black_box(&obstacle), black_box(&points[..within]), &hulls),
            );
            let within = within as u64;
            for (what, total) in [("contact", alone), ("loop", in_loop)] {
                if let Some(mean) = total.checked_div(within) {
                    hprintln!(
                        "M4F shape 0 1 {}_{}_{} {}.{}",
                        what,
                        label,
                        turn,
                        mean / 10,
                        mean % 10
                    );
                }
            }
        }
    }
}

#[entry]
fn main() -> ! {
    let cp = cortex_m::Peripherals::take().unwrap();
    let _clock = start_clock(cp.SYST);
    hprintln!("capp step_count: mps2-an386, 1 instruction = 1 ns (-icount shift=0), SysTick 25 MHz = 40 instructions per tick");

    // The clock's own cost, then a loop of known length.
    let (overhead, _) = count(200, 0, &mut (), |_| {}, |_| {});
    line("clock", 0, 0, "overhead", overhead);
    for iterations in [10_000u32, 100_000] {
        let c = repeat(16, &mut (), |_| {}, |_| spin(iterations));
        // Expected: 2 per iteration plus the call, set-up and return (a handful).
        line(
            "calibration",
            0,
            0,
            if iterations == 10_000 {
                "spin_10000"
            } else {
                "spin_100000"
            },
            c,
        );
    }

    // What each obstacle shape costs per point / obstacle pair (issue 24).
    shape_costs();

    // Memory of the planner: model (scenario) and workspace (planner).
    line(
        "memory",
        18,
        64,
        "scenario_bytes",
        core::mem::size_of::<Scenario<18, 64, 1>>() as u64 * 10,
    );
    line(
        "memory",
        18,
        64,
        "planner_bytes",
        core::mem::size_of::<Planner<18>>() as u64 * 10,
    );

    let all = [PIPS_OBSTACLES[0], PIPS_OBSTACLES[1], PIPS_OBSTACLES[2], 64];
    let pips_counts: &[usize] = if cfg!(feature = "step-count-quick") {
        &all[..2]
    } else {
        &all
    };
    for &k in pips_counts {
        match scenes::pips(k) {
            Ok(scene) => {
                let listing_reps = if k <= 32 { 2 } else { 0 };
                measure("pips", &scene, overhead, true, listing_reps);
                if k == 64 {
                    if let Ok(mut planner) = scenes::warm_up(&scene) {
                        let used = stack_use(|| {
                            black_box(planner.step(&scene.scenario).ok());
                        });
                        line("memory", 18, 64, "step_stack_bytes", used as u64 * 10);
                    }
                }
            }
            Err(e) => hprintln!("M4F pips 18 {} error {:?}", k, e),
        }
    }
    // What self-collision costs: the same PIPS + 8 step without capsules.
    if let Ok(scene) = scenes::pips_without_self_collision(8) {
        measure("pips_self_off", &scene, overhead, false, 0);
    }
    // What general (URDF) joints cost (issue 23): the same PIPS + 8 step,
    // the arm written as general joints.
    if let Ok(scene) = scenes::pips_general(8) {
        measure("pips_general", &scene, overhead, false, 0);
    }
    // What link segments cost: every capsule a segment of its own.
    if let Ok(scene) = scenes::pips_segments(8) {
        measure("pips_segments", &scene, overhead, false, 0);
    }
    // What the tracker costs (issue 22): the same PIPS + 8, a tracked tick.
    if let Ok(scene) = scenes::pips_tracked(8) {
        measure("pips_tracked", &scene, overhead, true, 0);
    }
    // What each law costs: one step of PIPS with 8 obstacles from the same
    // warmed-up state (the default law's), `joints` = 18.
    if let Ok(snapshot) = scenes::pips(8).and_then(|s| scenes::warm_up(&s)) {
        for (law, kind) in [
            ("law_damped_least_squares", LawKind::DampedLeastSquares),
            ("law_gradient", LawKind::Gradient),
            ("law_paper", LawKind::Paper),
        ] {
            let Ok(scene) = scenes::pips_with_law(8, kind) else {
                hprintln!("M4F {} 18 8 error scene", law);
                continue;
            };
            let mut planner = snapshot.clone();
            let step = repeat(
                REPS,
                &mut planner,
                |p| p.clone_from(&snapshot),
                |p| {
                    black_box(p.step(&scene.scenario).ok());
                },
            );
            line(law, 18, 8, "step", step);
        }
    }
    // What escaping costs: every step of the two shipped dead ends.
    for (name, scene) in [
        ("pips_escape", scenes::pips_escape()),
        ("pips_dead_end", scenes::pips_dead_end()),
    ] {
        match scene {
            Ok(scene) => {
                escape_costs(name, &scene, overhead);
                // The box of pips_escape, the wall of pips_dead_end.
                let blocking = scene.scenario.obstacles().len() as u8 - 1;
                stall_costs(name, &scene, blocking);
            }
            Err(e) => hprintln!("M4F {} 18 0 error {:?}", name, e),
        }
    }
    if !cfg!(feature = "step-count-quick") {
        sweeps(overhead);
    }
    hprintln!("capp step_count: done");
    debug::exit(debug::EXIT_SUCCESS);
    loop {
        cortex_m::asm::wfi();
    }
}

/// Every step of `scene` from its start to the end of the run, one at a
/// time: the most instructions of a step in each escape state (plain
/// descent, detour, walk, return to the best configuration, a slice of a
/// search, a step along a searched path), and of the
/// steps that start an escape (the law's step plus choosing the detour or
/// drawing and scoring the walk's candidates), with the step counts.
fn escape_costs(name: &str, scene: &Scene<{ scenes::PIPS_JOINTS }>, overhead: u64) {
    use capp_core::escape::EscapeState;
    let sc = &scene.scenario;
    let (n, m) = (scene.joints, sc.obstacles().len());
    let Ok(mut planner) = Planner::new(sc, &scene.start[..n]) else {
        hprintln!("M4F {} {} {} error start", name, n, m);
        return;
    };
    const WHAT: [[&str; 3]; 7] = [
        ["descend_max", "descend_mean", "descend_steps"],
        ["detour_max", "detour_mean", "detour_steps"],
        ["walk_max", "walk_mean", "walk_steps"],
        ["return_max", "return_mean", "return_steps"],
        [
            "escape_start_max",
            "escape_start_mean",
            "escape_start_steps",
        ],
        ["search_max", "search_mean", "search_steps"],
        ["path_max", "path_mean", "path_steps"],
    ];
    let (mut max, mut total, mut steps) = ([0u64; 7], [0u64; 7], [0u64; 7]);
    let mut previous = planner.last_report().escape;
    while !planner.is_done() {
        let mut state = previous;
        let (_, one) = count(
            1,
            overhead,
            &mut planner,
            |_| {},
            |p| {
                if let Ok(report) = p.step(sc) {
                    state = report.escape;
                }
            },
        );
        let descending = |s| matches!(s, EscapeState::Descending { .. });
        // A step that ran a slice of a search began in that state.
        let bucket = match (previous, state) {
            (EscapeState::Searching { .. }, _) => 5,
            (_, EscapeState::Descending { .. }) => 0,
            (_, EscapeState::Detouring { .. }) => 1,
            (_, EscapeState::Walking { .. }) => 2,
            (_, EscapeState::Returning) => 3,
            (_, EscapeState::Searching { .. }) => 5,
            (_, EscapeState::Following { .. }) => 6,
        };
        let starts = descending(previous) && !descending(state);
        for b in [Some(bucket), starts.then_some(4)].into_iter().flatten() {
            max[b] = max[b].max(one);
            total[b] += one;
            steps[b] += 1;
        }
        previous = state;
    }
    for b in 0..WHAT.len() {
        if let Some(mean) = (total[b] * 10).checked_div(steps[b]) {
            let [max_name, mean_name, steps_name] = WHAT[b];
            line(name, n, m, max_name, max[b] * 10);
            line(name, n, m, mean_name, mean);
            line(name, n, m, steps_name, steps[b] * 10);
        }
    }
}

/// What choosing an escape costs by itself (`Escape::on_stall`, the work a
/// stall adds to its step), from the scene's state after the warm-up: a
/// detour round obstacle `blocking` (placing the detour points), and a walk
/// with no obstacle to go round (drawing and scoring the candidates, one
/// forward kinematics pass each).
fn stall_costs(name: &str, scene: &Scene<{ scenes::PIPS_JOINTS }>, blocking: u8) {
    use capp_core::escape::{Escape, Stall};
    use capp_core::kinematics::Frames;
    let sc = &scene.scenario;
    let (n, m) = (scene.joints, sc.obstacles().len());
    let Ok(planner) = scenes::warm_up(scene) else {
        hprintln!("M4F {} {} {} error warm-up", name, n, m);
        return;
    };
    let Some(target) = sc.targets().first() else {
        return;
    };
    let settings = sc.settings();
    let fresh = Escape::<{ scenes::PIPS_JOINTS }>::new(settings.escape.seed, &scene.start[..n]);
    let mu = [1.0f32; scenes::PIPS_JOINTS];
    let mut scratch = Frames::default();
    for (what, obstacle) in [("stall_detour", Some(blocking)), ("stall_walk", None)] {
        let mut escape = fresh.clone();
        let c = repeat(
            REPS,
            &mut escape,
            |e| e.clone_from(&fresh),
            |e| {
                let stall = Stall {
                    q: planner.joints(),
                    frames: planner.frames(),
                    v: 1.0,
                    mu: &mu[..n],
                    blocking: obstacle,
                    target: target.position,
                };
                black_box(e.on_stall(sc, &stall, &mut scratch));
            },
        );
        line(name, n, m, what, c);
    }
}

/// The influence-distance sweep and the chain scaling table.
fn sweeps(overhead: u64) {
    // What the influence distance costs: PIPS with 8 obstacles, one line per
    // distance, `joints` = the distance in inches.
    for influence in INFLUENCE_SWEEP_IN {
        let inches = influence as usize;
        let measured = scenes::pips_with_influence(8, influence)
            .map_err(|_| "scene")
            .and_then(|scene| {
                let snapshot = scenes::warm_up(&scene).map_err(|_| "warm-up")?;
                let mut planner = snapshot.clone();
                let step = repeat(
                    REPS,
                    &mut planner,
                    |p| p.clone_from(&snapshot),
                    |p| {
                        black_box(p.step(&scene.scenario).ok());
                    },
                );
                let pairs = PhaseBench::new(&scene.scenario, &snapshot).active_pairs();
                Ok((step, pairs))
            });
        match measured {
            Ok((step, pairs)) => {
                line("influence", inches, 8, "step", step);
                line("influence", inches, 8, "active_pairs", pairs as u64 * 10);
            }
            Err(e) => hprintln!("M4F influence {} 8 error {}", inches, e),
        }
    }
    for n in SCALING_JOINTS {
        for m in SCALING_OBSTACLES {
            match scenes::chain(n, m) {
                Ok(scene) => measure("chain", &scene, overhead, false, 0),
                Err(e) => hprintln!("M4F chain {} {} error {:?}", n, m, e),
            }
        }
    }
}
