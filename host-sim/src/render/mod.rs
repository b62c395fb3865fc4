//! Pictures of a run, all text in the shipped font (DejaVu Sans, [`font`]).
//!
//! | file | what |
//! |---|---|
//! | `arm.svg`, `arm.png` | three orthographic views (top XY, front XZ, side YZ) with ticks in the length unit: obstacle silhouettes and names, the end-effector path, the arm at six instants (blue = start, red = end), the waypoints and target (green), a legend; the path's escape stretches (detours teal, walks orange, the return dashed brown) with a diamond where each escape started |
//! | `plots.svg`, `plots.png` | `V`, position and orientation errors, clearance `C - 1` against step (log scales, units, legends, the engage clearance); each joint's velocity / rate limit and acceleration / acceleration limit (linear, the limits `±1` dashed, the largest marked); the steps spent escaping shaded, a band per escape |
//! | `viewer.html` | the run in 3-D (three.js, inlined: works offline): links with thickness, obstacle meshes, path (escape stretches coloured), target frame; orbit, zoom, pan, play, scrub; the step's `V`, errors, clearance and escape; a bar chart of each joint's velocity and acceleration as fractions of their limits |
//! | `motion.gif` | the three views with the arm moving (for READMEs and reports) |
//! | `animation.html` | the three views playing the motion as SVG (no WebGL needed) |
//!
//! `capp robot --render` draws the robot at its start configuration instead
//! ([`robot`]: `robot.svg`, `robot.png`, `viewer.html`).
//!
//! [`canvas`] is the scene list behind the SVG / PNG pairs; [`chart`] draws
//! labelled axes and ready-made bar and scatter figures for reports.

pub mod animation;
pub mod canvas;
pub mod chart;
pub mod font;
pub mod motion_gif;
pub mod plots;
pub mod robot;
pub mod viewer;
pub mod views;

use std::path::{Path, PathBuf};

use anyhow::Result;

pub use canvas::{Anchor, Canvas, Pixmap, Shape};

use crate::problem::Problem;
use crate::trajectory::{Trajectory, TrajectoryRow};

/// Names of the files [`render`] writes, in order.
pub const FILES: [&str; 7] = [
    "arm.svg",
    "arm.png",
    "plots.svg",
    "plots.png",
    "viewer.html",
    "motion.gif",
    "animation.html",
];

/// A value for a caption: fixed point in a readable range, else scientific.
pub fn format_value(v: f64) -> String {
    let m = v.abs();
    if m != 0.0 && !(1e-3..1e5).contains(&m) {
        format!("{v:.2e}")
    } else {
        format!("{v:.3}")
    }
}

/// `V ..., position error ..., orientation error ..., C - 1 ...` of one row.
pub fn status_line(problem: &Problem, row: &TrajectoryRow, f: fn(f64) -> String) -> String {
    let show = |v: Option<f64>| v.map_or("—".to_string(), f);
    let unit = &problem.length_unit;
    format!(
        "V {} {unit}²   position error {} {unit}   orientation error {}   C − 1 {}",
        show(row.v),
        show(row.position_error),
        show(row.orientation_error),
        show(row.clearance),
    )
}

/// Draws `trajectory` of `problem` into `dir`; returns the files written ([`FILES`]).
pub fn render(problem: &Problem, trajectory: &Trajectory, dir: &Path) -> Result<Vec<PathBuf>> {
    let scene = views::arm_scene(problem, trajectory, 360.0, 6);
    let plots = plots::plots(problem, trajectory);
    let mut written = scene.canvas.write(dir, "arm")?;
    written.extend(plots.write(dir, "plots")?);
    let pages: [(&str, Vec<u8>); 3] = [
        (
            "viewer.html",
            viewer::viewer(problem, trajectory).into_bytes(),
        ),
        ("motion.gif", motion_gif::motion_gif(problem, trajectory)?),
        (
            "animation.html",
            animation::animation(problem, &scene).into_bytes(),
        ),
    ];
    for (name, bytes) in pages {
        let path = dir.join(name);
        std::fs::write(&path, bytes)?;
        written.push(path);
    }
    Ok(written)
}
