//! The figures collected into markdown tables, and spliced into BENCHMARKS.md
//! between its `xtask` markers.

use std::collections::BTreeMap;
use std::fmt::Write as _;
use std::path::Path;
use std::process::Command;

use anyhow::{bail, Result};

use capp_suite::report::grouped;

use crate::m4f::Counts;

/// Obstacle counts of the PIPS tables (as `capp_bench::scenes::PIPS_OBSTACLES`, plus 64).
pub const PIPS_OBSTACLES: [usize; 4] = [0, 8, 32, 64];
/// Influence distances of the sweep, inches (as `capp_bench::scenes::INFLUENCE_SWEEP_IN`).
pub const INFLUENCE_SWEEP_IN: [usize; 4] = [24, 12, 6, 3];
/// The scaling sweep (as `capp_bench::scenes`).
pub const SCALING_JOINTS: [usize; 5] = [6, 12, 18, 24, 32];
/// The scaling sweep (as `capp_bench::scenes`).
pub const SCALING_OBSTACLES: [usize; 5] = [0, 8, 16, 32, 64];

/// Markers in BENCHMARKS.md around the generated part.
pub const BEGIN: &str = "<!-- xtask bench: begin (generated, do not edit) -->";
/// End marker.
pub const END: &str = "<!-- xtask bench: end -->";

/// Host results, nanoseconds: criterion's medians by benchmark path
/// (`pips/step/8`), and the interleaved scaling sweep by (joints, obstacles).
#[derive(Debug, Default)]
pub struct Host {
    median_ns: BTreeMap<String, f64>,
    scaling_ns: BTreeMap<(usize, usize), f64>,
}

impl Host {
    /// Reads every `*/new/estimates.json` under `target/criterion`.
    pub fn load(dir: &Path) -> Result<Self> {
        let mut host = Host::default();
        if dir.is_dir() {
            visit(dir, dir, &mut host)?;
        }
        Ok(host)
    }

    /// Median time of one benchmark, nanoseconds.
    pub fn get(&self, path: &str) -> Option<f64> {
        self.median_ns.get(path).copied()
    }

    /// Reads the `HOST <joints> <obstacles> <ns>` lines of `examples/host_scaling.rs`.
    pub fn add_scaling(&mut self, text: &str) -> Result<()> {
        for line in text.lines() {
            if let ["HOST", n, m, ns] = line.split_whitespace().collect::<Vec<_>>()[..] {
                self.scaling_ns
                    .insert((n.parse()?, m.parse()?), ns.parse()?);
            }
        }
        Ok(())
    }

    /// Median host time per step of the chain of `joints` with `obstacles`, nanoseconds.
    pub fn scaling(&self, joints: usize, obstacles: usize) -> Option<f64> {
        self.scaling_ns.get(&(joints, obstacles)).copied()
    }
}

fn visit(base: &Path, dir: &Path, host: &mut Host) -> Result<()> {
    for entry in std::fs::read_dir(dir)? {
        let path = entry?.path();
        if !path.is_dir() {
            continue;
        }
        let estimates = path.join("new/estimates.json");
        if estimates.is_file() {
            let json: serde_json::Value =
                serde_json::from_str(&std::fs::read_to_string(&estimates)?)?;
            let id = path
                .strip_prefix(base)?
                .to_string_lossy()
                .replace('\\', "/");
            if let Some(ns) = json["median"]["point_estimate"].as_f64() {
                host.median_ns.insert(id, ns);
            }
        }
        visit(base, &path, host)?;
    }
    Ok(())
}

/// Both boards' firmware.
#[derive(Debug)]
pub struct Firmware {
    /// mps2-an386 (QEMU), with the peak stack from the end-to-end test.
    pub mps2: FirmwareSize,
    /// Nucleo-F446RE (build only).
    pub f446: FirmwareSize,
}

/// The firmware binary's memory.
#[derive(Debug)]
pub struct FirmwareSize {
    /// `.vector_table + .text + .rodata + .data`, bytes.
    pub flash: u64,
    /// `.data + .bss + .uninit`, bytes.
    pub static_ram: u64,
    /// Deepest stack use reported by the end-to-end test, bytes.
    pub peak_stack: Option<u64>,
}

impl FirmwareSize {
    /// From `size -A` output and the end-to-end test's log.
    pub fn parse(size: &str, e2e_log: &str) -> Self {
        let section = |name: &str| -> u64 {
            size.lines()
                .filter_map(|l| {
                    let f: Vec<&str> = l.split_whitespace().collect();
                    (f.first() == Some(&name)).then(|| f.get(1)?.parse::<u64>().ok())?
                })
                .sum()
        };
        let peak_stack = e2e_log
            .lines()
            .filter_map(|l| l.strip_prefix("peak stack: "))
            .filter_map(|l| l.split_whitespace().next()?.parse().ok())
            .max();
        FirmwareSize {
            flash: section(".vector_table")
                + section(".text")
                + section(".rodata")
                + section(".data"),
            static_ram: section(".data") + section(".bss") + section(".uninit"),
            peak_stack,
        }
    }
}

/// What the figures were measured on.
#[derive(Debug)]
pub struct Machine {
    /// Host CPU model and core count.
    pub cpu: String,
    /// `rustc -V`.
    pub rustc: String,
    /// `qemu-system-arm --version`, first line.
    pub qemu: String,
}

impl Machine {
    /// Asks the system.
    pub fn probe(_cargo: &str) -> Self {
        let first_line = |program: &str, arg: &str| {
            Command::new(program)
                .arg(arg)
                .output()
                .ok()
                .and_then(|o| String::from_utf8(o.stdout).ok())
                .and_then(|s| s.lines().next().map(str::to_string))
                .unwrap_or_else(|| "unknown".into())
        };
        let model = capp_suite::cli::cpu_model();
        let cores = std::thread::available_parallelism().map_or(0, |n| n.get());
        Machine {
            cpu: format!("{model}, {cores} cores available"),
            rustc: first_line("rustc", "-V"),
            qemu: first_line("qemu-system-arm", "--version"),
        }
    }
}

fn opt(x: Option<f64>, f: impl Fn(f64) -> String) -> String {
    x.map_or_else(|| "-".into(), f)
}

fn ns(x: f64) -> String {
    if x >= 100_000.0 {
        format!("{:.0} us", x / 1000.0)
    } else if x >= 1000.0 {
        format!("{:.2} us", x / 1000.0)
    } else {
        format!("{x:.0} ns")
    }
}

/// Least-squares fit of `y = sum_i c_i f_i` over rows `(features, y)`;
/// returns the coefficients and the largest relative residual.
pub fn fit<const K: usize>(rows: &[([f64; K], f64)]) -> Option<([f64; K], f64)> {
    if rows.len() < K {
        return None;
    }
    let mut ata = [[0.0f64; K]; K];
    let mut aty = [0.0f64; K];
    for (f, y) in rows {
        for i in 0..K {
            for j in 0..K {
                ata[i][j] += f[i] * f[j];
            }
            aty[i] += f[i] * y;
        }
    }
    let coef = solve(ata, aty)?;
    let worst = rows
        .iter()
        .map(|(f, y)| ((0..K).map(|i| coef[i] * f[i]).sum::<f64>() - y).abs() / y)
        .fold(0.0, f64::max);
    Some((coef, worst))
}

/// Gauss-Jordan elimination with partial pivoting.
fn solve<const K: usize>(mut a: [[f64; K]; K], mut b: [f64; K]) -> Option<[f64; K]> {
    for col in 0..K {
        let pivot = (col..K).max_by(|&i, &j| a[i][col].abs().total_cmp(&a[j][col].abs()))?;
        if a[pivot][col].abs() < 1e-12 {
            return None;
        }
        a.swap(col, pivot);
        b.swap(col, pivot);
        for row in 0..K {
            if row != col {
                let k = a[row][col] / a[col][col];
                let pivot_row = a[col];
                for (x, p) in a[row].iter_mut().zip(pivot_row) {
                    *x -= k * p;
                }
                b[row] -= k * b[col];
            }
        }
    }
    let mut x = [0.0; K];
    for i in 0..K {
        x[i] = b[i] / a[i][i];
    }
    Some(x)
}

/// One scaling point: joints, obstacles, pairs within influence, cost.
#[derive(Clone, Copy, Debug)]
pub struct Point {
    /// Joints `n`.
    pub joints: f64,
    /// Obstacles `m`.
    pub obstacles: f64,
    /// Point / obstacle pairs within influence at the measured state.
    pub active: f64,
    /// Instructions or nanoseconds per step.
    pub cost: f64,
}

/// Rows for the fit `a + b n + c n m`.
fn rows3(points: &[Point]) -> Vec<([f64; 3], f64)> {
    points
        .iter()
        .map(|p| ([1.0, p.joints, p.joints * p.obstacles], p.cost))
        .collect()
}

/// Rows for the fit `a + b n + c n m + d active`.
fn rows4(points: &[Point]) -> Vec<([f64; 4], f64)> {
    points
        .iter()
        .map(|p| ([1.0, p.joints, p.joints * p.obstacles, p.active], p.cost))
        .collect()
}

/// Scaling points, with `cost(n, m)` the M4F count or the host time.
fn scaling(counts: &Counts, cost: impl Fn(usize, usize) -> Option<f64>) -> Vec<Point> {
    let mut out = Vec::new();
    for n in SCALING_JOINTS {
        for m in SCALING_OBSTACLES {
            if let (Some(c), Some(active)) = (cost(n, m), counts.get("chain", n, m, "active_pairs"))
            {
                out.push(Point {
                    joints: n as f64,
                    obstacles: m as f64,
                    active,
                    cost: c,
                });
            }
        }
    }
    out
}

/// Every generated table, as markdown.
pub fn tables(
    host: &Host,
    counts: &Counts,
    firmware: Option<&Firmware>,
    machine: &Machine,
    quick: bool,
) -> String {
    let mut s = String::new();
    let w = &mut s;
    let _ = writeln!(
        w,
        "Measured by `cargo xtask bench{}`.",
        if quick { " --quick" } else { "" }
    );
    let _ = writeln!(w);
    let _ = writeln!(
        w,
        "- host: {}; {}; criterion medians",
        machine.cpu, machine.rustc
    );
    let _ = writeln!(
        w,
        "- target: {} (`-machine mps2-an386 -icount shift=0`), instructions executed",
        machine.qemu
    );
    let _ = writeln!(w);

    let _ = writeln!(
        w,
        "### One planner step of PIPS, against the paper's listing"
    );
    let _ = writeln!(w);
    let _ = writeln!(w, "| obstacles | pairs within influence | host: step | host: listing step | host ratio | M4F: step (instructions) | M4F: 200-step window, mean / max | M4F: listing step | M4F ratio |");
    let _ = writeln!(w, "|---|---|---|---|---|---|---|---|---|");
    for k in PIPS_OBSTACLES {
        let step = host.get(&format!("pips/step/{k}"));
        let listing = host.get(&format!("pips/listing_step/{k}"));
        let m_step = counts.get("pips", 18, k, "step");
        let m_listing = counts.get("pips", 18, k, "listing_step");
        let ratio = |a: Option<f64>, b: Option<f64>| match (a, b) {
            (Some(a), Some(b)) => format!("{:.0}x", b / a),
            _ => "-".into(),
        };
        let _ = writeln!(
            w,
            "| {k} | {} | {} | {} | {} | {} | {} / {} | {} | {} |",
            opt(counts.get("pips", 18, k, "active_pairs"), grouped),
            opt(step, ns),
            opt(listing, ns),
            ratio(step, listing),
            opt(m_step, grouped),
            opt(counts.get("pips", 18, k, "window_mean"), grouped),
            opt(counts.get("pips", 18, k, "window_max"), grouped),
            opt(m_listing, grouped),
            ratio(m_step, m_listing),
        );
    }
    let _ = writeln!(w);

    let _ = writeln!(
        w,
        "### The laws, and what escaping a dead end costs (M4F, PIPS)"
    );
    let _ = writeln!(w);
    let _ = writeln!(
        w,
        "One step of PIPS with 8 obstacles from the same state, by law: damped least squares (the default) {}, the gradient law {}, eq. 15 as printed {}.",
        opt(counts.get("law_damped_least_squares", 18, 8, "step"), grouped),
        opt(counts.get("law_gradient", 18, 8, "step"), grouped),
        opt(counts.get("law_paper", 18, 8, "step"), grouped),
    );
    let _ = writeln!(w);
    let _ = writeln!(
        w,
        "A tracked tick (issue 22, `motion = \"tracked\"`: the law's step, the tracker's candidates and their stop test) of PIPS with 8 obstacles from its warmed-up state: {}; the next {} ticks along the path: mean {}, worst {}, {} candidates refused. The stepped step without self-collision: {}.",
        opt(counts.get("pips_tracked", 18, 8, "step"), grouped),
        opt(counts.get("pips_tracked", 18, 8, "window_steps"), grouped),
        opt(counts.get("pips_tracked", 18, 8, "window_mean"), grouped),
        opt(counts.get("pips_tracked", 18, 8, "window_max"), grouped),
        opt(counts.get("pips_tracked", 18, 8, "window_halvings"), grouped),
        opt(counts.get("pips_self_off", 18, 8, "step"), grouped),
    );
    let _ = writeln!(w);
    let general = counts.get("pips_general", 18, 8, "step");
    let dh = counts.get("pips", 18, 8, "step");
    let _ = writeln!(
        w,
        "General (URDF) joints (issue 23): the same PIPS + 8 step with the arm written as general joints (`capp_core::robot::general_from_dh`: a fixed transform, then a turn about z): {} against {} for its DH rows, {} (target: at most 3 % above).",
        opt(general, grouped),
        opt(dh, grouped),
        above(general, dh),
    );
    let _ = writeln!(w);
    let segments = counts.get("pips_segments", 18, 8, "step");
    let _ = writeln!(
        w,
        "Link capsules round segments of their own (a URDF link whose body lies off its chord, `Robot::set_link_segments`; here every link's chord written in its body's frame): the same general PIPS + 8 step {} against {} round the chords, {}.",
        opt(segments, grouped),
        opt(general, grouped),
        above(segments, general),
    );
    let _ = writeln!(w);
    let _ = writeln!(w, "Every step of the two shipped dead ends, timed one at a time and grouped by what the escape was doing after it (`pips_escape.toml`: a detour round the box, then reached; `pips_dead_end.toml`: no path, so detours and walks until the 64 attempts are spent, the return to the best configuration, `Stalled`). A step's cost is set by its halvings (each one evaluates the arm again; at most `max_halvings` = 8), not by the escape; the steps that start an escape add `Escape::on_stall`, timed alone in the last column from the scene's warmed-up state.");
    let _ = writeln!(w);
    let _ = writeln!(w, "| scenario | obstacles | steps | law alone: mean / max | detour: mean / max | walk: mean / max | search slice: mean / max | searched path: mean / max | return: mean / max | steps that start an escape: count, mean / max | `on_stall` alone: detour / walk |");
    let _ = writeln!(w, "|---|---|---|---|---|---|---|---|---|---|---|");
    for (scene, m) in [("pips_escape", 7), ("pips_dead_end", 1)] {
        let get = |what: &str| counts.get(scene, 18, m, what);
        let pair = |what: &str| match get(&format!("{what}_steps")) {
            Some(_) => format!(
                "{} / {}",
                opt(get(&format!("{what}_mean")), grouped),
                opt(get(&format!("{what}_max")), grouped)
            ),
            None => "-".into(),
        };
        let steps: Option<f64> = ["descend", "detour", "walk", "search", "path", "return"]
            .iter()
            .map(|w| get(&format!("{w}_steps")).unwrap_or(0.0))
            .sum::<f64>()
            .into();
        let _ = writeln!(
            w,
            "| `{scene}` | {m} | {} | {} | {} | {} | {} | {} | {} | {}, {} | {} / {} |",
            opt(steps, grouped),
            pair("descend"),
            pair("detour"),
            pair("walk"),
            pair("search"),
            pair("path"),
            pair("return"),
            opt(get("escape_start_steps"), grouped),
            pair("escape_start"),
            opt(get("stall_detour"), grouped),
            opt(get("stall_walk"), grouped),
        );
    }
    let _ = writeln!(w);

    let _ = writeln!(w, "### Where the instructions go (M4F, PIPS)");
    let _ = writeln!(w);
    let _ = writeln!(w, "| obstacles | kinematics | control law | obstacles | link pairs | projection + integration | sum of phases | step | rest (state machine, copies) | one pair within influence | one pair outside |");
    let _ = writeln!(w, "|---|---|---|---|---|---|---|---|---|---|---|");
    for k in PIPS_OBSTACLES {
        let phase = |p: &str| counts.get("pips", 18, k, p);
        let parts = [
            "kinematics",
            "control_law",
            "obstacles",
            "link_pairs",
            "projection_integration",
        ]
        .map(phase);
        let sum: Option<f64> = parts.iter().copied().sum();
        let step = phase("step");
        let rest = match (step, sum) {
            (Some(a), Some(b)) => Some(a - b),
            _ => None,
        };
        let _ = writeln!(
            w,
            "| {k} | {} | {} | {} | {} | {} | {} | {} | {} | {} | {} |",
            opt(parts[0], grouped),
            opt(parts[1], grouped),
            opt(parts[2], grouped),
            opt(parts[3], grouped),
            opt(parts[4], grouped),
            opt(sum, grouped),
            opt(step, grouped),
            opt(rest, grouped),
            opt(phase("contact_within_influence"), grouped),
            opt(phase("contact_outside_influence"), grouped),
        );
    }
    let _ = writeln!(w);
    let _ = writeln!(w, "Host, the same phases (PIPS, 8 obstacles unless marked): kinematics {}, control law {}, projection + integration {}, obstacles {} (0) / {} (8) / {} (32).",
        opt(host.get("pips/kinematics"), ns),
        opt(host.get("pips/control_law"), ns),
        opt(host.get("pips/projection_integration"), ns),
        opt(host.get("pips/obstacles/0"), ns),
        opt(host.get("pips/obstacles/8"), ns),
        opt(host.get("pips/obstacles/32"), ns),
    );
    let _ = writeln!(w);

    let _ = writeln!(
        w,
        "### What the influence distance costs (M4F, PIPS, 8 obstacles)"
    );
    let _ = writeln!(w);
    let _ = writeln!(w, "The same scene with `avoidance.influence_distance` set smaller (24 in is the default); each run warmed up the same way, so the measured state differs a little. The 24 in row is the first table's 8-obstacle scene, timed from another call site in the counter: a few instructions apart.");
    let _ = writeln!(w);
    let _ = writeln!(
        w,
        "| influence distance | pairs within influence | M4F: step (instructions) |"
    );
    let _ = writeln!(w, "|---|---|---|");
    for inches in INFLUENCE_SWEEP_IN {
        let _ = writeln!(
            w,
            "| {inches} in | {} | {} |",
            opt(counts.get("influence", inches, 8, "active_pairs"), grouped),
            opt(counts.get("influence", inches, 8, "step"), grouped),
        );
    }
    let _ = writeln!(w);

    let _ = writeln!(
        w,
        "### What each obstacle shape costs (M4F, per point / obstacle pair)"
    );
    let _ = writeln!(w);
    let _ = writeln!(w, "`Obstacle::contact` for one avoidance point and one obstacle of PIPS size (inches; margin 3 in, 24 in of influence), the mean over those of 96 points round it that are within its influence (`step_count`'s `shape_costs`), measured two ways: each point alone, the obstacle a constant of the measuring function (as every stop before 44 measured it: the compiler may fold the obstacle's sizes into the code), and all the points in a loop of their own, as the planner's pair loop runs them (`contacts`: the obstacle as data, `contact` inlined, the loop's few instructions a pair included). The two differ by up to 25 instructions a pair as the compiler allocates registers differently; each ratio is against the exponent-8 super-ellipsoid measured the same way. Aligned: no Euler angles; turned: `[0.3, -0.5, 0.9]` rad (a sphere skips its rotation). The CAD primitives (issue 24) are measured on their true distance; the hull is an octagonal prism of 16 vertices (semi-axes 20 x 15 in, 20 in tall), measured by its faces and edges (`Hull::by_faces`, `obstacle/hull.rs`: the highest face's plane (with 8 faces or more, the highest of the few that sampling found highest in the point's direction cell: 3 of the prism's 10), its neighbours' planes, then the edge to the neighbour whose plane the point's projection is farthest beyond, certified inside the edge by that plane or at its end by the vertex's edges; GJK where that certifies nothing or the hull has more than 32 faces or 48 edges); the box's corners and a 32-vertex prism of the same size show how the cost grows with the vertices. Targets: a box and a sphere no more than a super-ellipsoid's, a capsule and a cylinder at most 1.5 x, a 16-vertex hull at most 4 x.");
    let _ = writeln!(w);
    let _ = writeln!(
        w,
        "| shape | alone: aligned | turned | aligned / super-ellipsoid 8 | turned / super-ellipsoid 8 | in a loop: aligned | turned | aligned / super-ellipsoid 8 | turned / super-ellipsoid 8 |"
    );
    let _ = writeln!(w, "|---|---|---|---|---|---|---|---|---|");
    let shape = |how: &str, label: &str, turn: &str| {
        counts.get("shape", 0, 1, &format!("{how}_{label}_{turn}"))
    };
    for (label, name) in [
        ("superellipsoid8", "super-ellipsoid, exponent 8"),
        ("superellipsoid2", "super-ellipsoid, exponent 2"),
        ("sphere", "sphere"),
        ("box", "box"),
        ("capsule", "capsule"),
        ("cylinder", "cylinder"),
        ("hull16", "convex hull, 16 vertices"),
        ("hull8", "convex hull, the box's 8 corners"),
        ("hull32", "convex hull, 32 vertices (a 16-gon prism)"),
    ] {
        let ratio = |a: Option<f64>, b: Option<f64>| match (a, b) {
            (Some(a), Some(b)) if b > 0.0 => format!("{:.2}", a / b),
            _ => "-".into(),
        };
        let _ = write!(w, "| {name} |");
        for how in ["contact", "loop"] {
            let (aligned, turned) = (shape(how, label, "aligned"), shape(how, label, "turned"));
            let _ = write!(
                w,
                " {} | {} | {} | {} |",
                opt(aligned, |x| format!("{x:.1}")),
                opt(turned, |x| format!("{x:.1}")),
                ratio(aligned, shape(how, "superellipsoid8", "aligned")),
                ratio(turned, shape(how, "superellipsoid8", "turned")),
            );
        }
        let _ = writeln!(w);
    }
    let _ = writeln!(w);
    let build = |label: &str| {
        opt(
            counts.get("shape", 0, 1, &format!("build_{label}")),
            grouped,
        )
    };
    let _ = writeln!(
        w,
        "Building a hull once (`Hull::set`, when a scenario is loaded or a `Hull` command arrives: the checks, the support's direction cells, the faces and edges by brute force, the faces' direction cells by sampling): the 16-vertex prism {}, the box's 8 corners {}, the 32-vertex prism {} M4F instructions.",
        build("hull16"),
        build("hull8"),
        build("hull32")
    );
    let _ = writeln!(w);

    let _ = writeln!(w, "### Scaling: chains of n joints, m obstacles");
    let _ = writeln!(w);
    let _ = writeln!(w, "M4F instructions per step (host in brackets: median over interleaved rounds, `crates/capp-bench/examples/host_scaling.rs`):");
    let _ = writeln!(w);
    let _ = write!(w, "| joints \\ obstacles |");
    for m in SCALING_OBSTACLES {
        let _ = write!(w, " {m} |");
    }
    let _ = writeln!(w);
    let _ = writeln!(w, "|---|{}", "---|".repeat(SCALING_OBSTACLES.len()));
    for n in SCALING_JOINTS {
        let _ = write!(w, "| {n} |");
        for m in SCALING_OBSTACLES {
            let host_ns = host.scaling(n, m);
            let _ = write!(
                w,
                " {}{} |",
                opt(counts.get("chain", n, m, "step"), grouped),
                host_ns.map_or(String::new(), |t| format!(" ({})", ns(t)))
            );
        }
        let _ = writeln!(w);
    }
    let _ = writeln!(w);
    let _ = writeln!(
        w,
        "Pairs within influence at the measured state (they vary with where the obstacles fell):"
    );
    let _ = writeln!(w);
    let _ = write!(w, "| joints \\ obstacles |");
    for m in SCALING_OBSTACLES {
        let _ = write!(w, " {m} |");
    }
    let _ = writeln!(w);
    let _ = writeln!(w, "|---|{}", "---|".repeat(SCALING_OBSTACLES.len()));
    for n in SCALING_JOINTS {
        let _ = write!(w, "| {n} |");
        for m in SCALING_OBSTACLES {
            let _ = write!(
                w,
                " {} |",
                opt(counts.get("chain", n, m, "active_pairs"), grouped)
            );
        }
        let _ = writeln!(w);
    }
    let _ = writeln!(w);
    let m4f = scaling(counts, |n, m| counts.get("chain", n, m, "step"));
    let host_points = scaling(counts, |n, m| host.scaling(n, m));
    let deviation = |worst: f64| {
        format!(
            "largest deviation of a measured point from the fit: {:.0} %",
            worst * 100.0
        )
    };
    let _ = writeln!(w, "Least-squares fits over the whole table (n joints, m obstacles, p pairs within influence):");
    let _ = writeln!(w);
    for (name, unit, points) in [("M4F", "instructions", &m4f), ("host", "ns", &host_points)] {
        match (fit(&rows3(points)), fit(&rows4(points))) {
            (Some(([a, b, c], w3)), Some(([a4, b4, c4, d4], w4))) => {
                let _ = writeln!(w, "- {name}: `{a:.0} + {b:.1} n + {c:.2} n m` {unit} ({}); with the pairs: `{a4:.0} + {b4:.1} n + {c4:.2} n m + {d4:.1} p` {unit} ({})", deviation(w3), deviation(w4));
            }
            _ => {
                let _ = writeln!(w, "- {name}: not measured in this run");
            }
        }
    }
    let _ = writeln!(w);
    let _ = writeln!(w, "![Cost per step against joints, one line per obstacle count: left M4F thousand instructions, right host microseconds](docs/img/scaling.svg)");
    let _ = writeln!(w, "Left: M4F, thousand instructions per step; right: host, microseconds per step; x: joints; one line per obstacle count (0, 8, 16, 32, 64). Also as `docs/img/scaling.png`.");
    let _ = writeln!(w);

    let _ = writeln!(w, "### Memory");
    let _ = writeln!(w);
    let _ = writeln!(w, "| what | bytes |");
    let _ = writeln!(w, "|---|---|");
    let scenario = counts.get("memory", 18, 64, "scenario_bytes");
    let planner = counts.get("memory", 18, 64, "planner_bytes");
    let _ = writeln!(
        w,
        "| model: `Scenario<18, 64, 1>` (PIPS, room for 64 obstacles, 1 waypoint) | {} |",
        opt(scenario, grouped)
    );
    let _ = writeln!(
        w,
        "| workspace: `Planner<18>` | {} |",
        opt(planner, grouped)
    );
    let total = match (scenario, planner) {
        (Some(a), Some(b)) => Some(a + b),
        _ => None,
    };
    let _ = writeln!(
        w,
        "| planner RAM, model + workspace | {} |",
        opt(total, grouped)
    );
    let _ = writeln!(
        w,
        "| stack of one `step()` (PIPS, 64 obstacles, painted) | {} |",
        opt(counts.get("memory", 18, 64, "step_stack_bytes"), grouped)
    );
    let _ = writeln!(w);
    let _ = writeln!(
        w,
        "The firmware (release ELF, `size -A`), with room for PIPS and 64 obstacles:"
    );
    let _ = writeln!(w);
    match firmware {
        Some(f) => {
            let _ = writeln!(w, "| firmware | mps2-an386 | Nucleo-F446RE | target |");
            let _ = writeln!(w, "|---|---|---|---|");
            let _ = writeln!(
                w,
                "| flash: `.vector_table + .text + .rodata + .data` | {} | {} | <= 122 880 (120 KiB; 112 KiB before the hulls' faces, 108 before the link segments, 104 KiB before the convex hulls, 96 KiB before issue 24's obstacle shapes) |",
                grouped(f.mps2.flash as f64),
                grouped(f.f446.flash as f64)
            );
            let _ = writeln!(
                w,
                "| static RAM: `.data + .bss + .uninit` | {} | {} | <= 106 496 (104 KiB; 96 KiB before the hulls' faces, 32 KiB before the search tree) |",
                grouped(f.mps2.static_ram as f64),
                grouped(f.f446.static_ram as f64)
            );
            let _ = writeln!(
                w,
                "| peak stack (painted; QEMU end-to-end test) | {} | same code; not measured on hardware | <= 8 192 (8 KiB) |",
                f.mps2.peak_stack.map_or("-".into(), |p| grouped(p as f64))
            );
        }
        None => {
            let _ = writeln!(w, "| firmware | not measured (`--quick`) |");
            let _ = writeln!(w, "|---|---|");
        }
    }
    let _ = writeln!(w);

    let _ = writeln!(w, "### The clock, checked");
    let _ = writeln!(w);
    let _ = writeln!(w, "| what | expected | measured |");
    let _ = writeln!(w, "|---|---|---|");
    let _ = writeln!(
        w,
        "| reading SysTick twice (subtracted from the window figures; cancels in the others) | a few | {} |",
        opt(counts.get("clock", 0, 0, "overhead"), |x| format!("{x:.1}"))
    );
    let _ = writeln!(
        w,
        "| `subs`/`bne` loop, 10 000 iterations | 20 000 + call | {} |",
        opt(counts.get("calibration", 0, 0, "spin_10000"), |x| format!(
            "{x:.1}"
        ))
    );
    let _ = writeln!(
        w,
        "| `subs`/`bne` loop, 100 000 iterations | 200 000 + call | {} |",
        opt(counts.get("calibration", 0, 0, "spin_100000"), |x| format!(
            "{x:.1}"
        ))
    );
    s
}

/// `doc` with the text between the markers replaced by `tables`.
pub fn splice(doc: &str, tables: &str) -> Result<String> {
    let (Some(begin), Some(end)) = (doc.find(BEGIN), doc.find(END)) else {
        bail!("BENCHMARKS.md lacks the markers {BEGIN} ... {END}");
    };
    if end < begin {
        bail!("BENCHMARKS.md: end marker before begin marker");
    }
    Ok(format!(
        "{}{BEGIN}\n\n{tables}\n{}",
        &doc[..begin],
        &doc[end..]
    ))
}

/// How far `count` is above `base`, as "+1.3 %" ("-" when either is missing).
fn above(count: Option<f64>, base: Option<f64>) -> String {
    match (count, base) {
        (Some(c), Some(b)) if b > 0.0 => format!("{:+.1} %", 100.0 * (c / b - 1.0)),
        _ => "-".into(),
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn fit_recovers_an_exact_linear_model() {
        let mut rows = Vec::new();
        for n in [6.0, 12.0, 18.0] {
            for m in [0.0, 8.0, 32.0] {
                rows.push(([1.0, n, n * m], 1000.0 + 50.0 * n + 3.0 * n * m));
            }
        }
        let ([a, b, c], worst) = fit(&rows).unwrap();
        assert!((a - 1000.0).abs() < 1e-6 && (b - 50.0).abs() < 1e-6 && (c - 3.0).abs() < 1e-6);
        assert!(worst < 1e-9);
    }

    #[test]
    fn splice_replaces_only_the_generated_part() {
        let doc = format!("head\n{BEGIN}\nold\n{END}\ntail\n");
        let out = splice(&doc, "new\n").unwrap();
        assert_eq!(out, format!("head\n{BEGIN}\n\nnew\n\n{END}\ntail\n"));
        assert!(splice("no markers", "x").is_err());
    }

    #[test]
    fn numbers_are_grouped_by_thousands() {
        assert_eq!(grouped(1234567.4), "1 234 567");
        assert_eq!(grouped(999.0), "999");
        assert_eq!(grouped(-1000.0), "-1 000");
    }
}
