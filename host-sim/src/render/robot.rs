//! `capp robot SCENARIO --render DIR`: the robot as the planner sees it, at
//! its start configuration.
//!
//! | file | what |
//! |---|---|
//! | `robot.svg`, `robot.png` | the three orthographic views of `arm.png` ([`super::views`]): the arm (blue), each link's capsule (the segment and radius self-collision checks: the chord between pivots, or the link's segment when the scenario gives one; teal band), for a URDF robot the capsules fitted to each body's `<collision>` geometry (orange; the base's too, which nothing checks), the obstacles and the target, a legend |
//! | `viewer.html` | the 3-D viewer ([`super::viewer`]) for the one configuration, opening with the link capsules shown, and a URDF robot's fitted capsules |

use std::path::{Path, PathBuf};

use anyhow::Result;

use super::canvas::{Canvas, Rgb, Shape, P2};
use super::chart::{legend_marker, Marker};
use super::font;
use super::viewer::{viewer_with, ViewerOptions};
use super::views::{
    border, bounds, capsule_outline, obstacle_names, page, panel_frame, panels, silhouettes,
    surfaces, unit_name, Panel, LEFT, OBSTACLE, START, TARGET, TITLES, TOP,
};
use crate::geometry::{collision_capsules, pose, Pose};
use crate::problem::Problem;
use crate::trajectory::Trajectory;

/// Names of the files [`render_robot`] writes, in order.
pub const FILES: [&str; 3] = ["robot.svg", "robot.png", "viewer.html"];

/// The link capsules' colour.
pub const LINK_CAPSULE: Rgb = [0, 140, 150];
/// The fitted collision capsules' colour.
pub const COLLISION_CAPSULE: Rgb = [225, 115, 0];
const INK: Rgb = [30, 30, 30];
const MUTED: Rgb = [90, 90, 90];
/// Panel side, pixels (as `arm.png`'s).
const PANEL: f64 = 360.0;

/// The start configuration, widened.
pub fn start(problem: &Problem) -> Vec<f64> {
    problem.start.iter().map(|&x| x as f64).collect()
}

/// A capsule as a band: see-through fill and its outline, clipped to `p`.
fn band(canvas: &mut Canvas, p: &Panel, capsule: ([f64; 3], [f64; 3], f64), color: Rgb, fill: f64) {
    let (a, b, radius) = capsule;
    if radius <= 0.0 {
        return;
    }
    let mut outline = capsule_outline(p, &a, &b, radius);
    canvas.push(Shape::Polygon {
        points: outline.clone(),
        fill: color,
        opacity: fill,
        clip: Some(p.clip()),
    });
    if let Some(&first) = outline.first() {
        outline.push(first);
    }
    canvas.push(Shape::line(outline, color, 1.2).clipped(p.clip()));
}

/// The views of the robot at `q`: link capsules, fitted collision
/// capsules, the arm, the obstacles and the target.
pub fn robot_scene(problem: &Problem, q: &[f64]) -> Canvas {
    let Pose {
        origins, capsules, ..
    } = pose(problem, q);
    let fitted = collision_capsules(problem, q);
    let reach: Vec<[f64; 3]> = fitted
        .iter()
        .flat_map(|c| [[c[0], c[1], c[2]], [c[3], c[4], c[5]]])
        .chain(capsules.iter().flatten().copied())
        .chain(origins.iter().copied())
        .collect();
    let (centre, side) = bounds(problem, &[reach]);
    let mut canvas = page(PANEL, 0.0);
    let unit = &problem.length_unit;
    canvas.push(
        Shape::text(
            (LEFT, 26.0),
            16.0,
            format!("{}: the robot at its start configuration", problem.name),
        )
        .colored(INK),
    );
    canvas.push(
        Shape::text(
            (LEFT, 46.0),
            11.5,
            format!(
                "orthographic views, lengths in {}; grey: obstacles (true surfaces)",
                unit_name(unit)
            ),
        )
        .colored(MUTED),
    );
    let surfaces = surfaces(problem);
    let views = panels(centre, side, PANEL);
    for (p, title) in views.iter().zip(TITLES) {
        panel_frame(&mut canvas, p, title, side, unit);
        let hulls = silhouettes(&mut canvas, p, &surfaces);
        for (k, &[a, b]) in capsules.iter().enumerate() {
            let radius = problem.links.radius.get(k).copied().unwrap_or(0.0) as f64;
            band(&mut canvas, p, (a, b, radius), LINK_CAPSULE, 0.12);
        }
        for c in &fitted {
            let ends = ([c[0], c[1], c[2]], [c[3], c[4], c[5]], c[6]);
            band(&mut canvas, p, ends, COLLISION_CAPSULE, 0.3);
        }
        let arm: Vec<P2> = origins.iter().map(|o| p.map(o)).collect();
        canvas.push(Shape::line(arm.clone(), START, 2.0).clipped(p.clip()));
        for &centre in &arm {
            canvas.push(Shape::Disc {
                centre,
                radius: 2.5,
                color: INK,
            });
        }
        for w in &problem.waypoints {
            canvas.push(Shape::Disc {
                centre: p.map(&w.position.map(f64::from)),
                radius: 4.0,
                color: TARGET,
            });
        }
        obstacle_names(&mut canvas, problem, p, &hulls, &arm);
        border(&mut canvas, p);
    }
    legend(&mut canvas, (LEFT, TOP + PANEL + 60.0), !fitted.is_empty());
    canvas
}

/// The legend row under the panels.
fn legend(canvas: &mut Canvas, at: P2, fitted: bool) {
    let (mut x, y) = at;
    let size = 11.5;
    let mut items = vec![
        ("arm (joint pivots)", START, Marker::Line),
        (
            "link capsules (what self-collision checks)",
            LINK_CAPSULE,
            Marker::Bar,
        ),
    ];
    if fitted {
        items.push(("URDF collision capsules", COLLISION_CAPSULE, Marker::Bar));
    }
    items.extend([
        ("target", TARGET, Marker::Dot),
        ("obstacle", OBSTACLE, Marker::Bar),
    ]);
    for (name, color, marker) in items {
        legend_marker(canvas, (x, y), color, marker);
        canvas.push(Shape::text((x + 24.0, y + 4.0), size, name).colored(INK));
        x += 24.0 + font::width(name, size) + 24.0;
    }
}

/// Draws `problem`'s robot at its start configuration into `dir`; returns
/// the files written ([`FILES`]).
pub fn render_robot(problem: &Problem, dir: &Path) -> Result<Vec<PathBuf>> {
    let q = start(problem);
    let mut written = robot_scene(problem, &q).write(dir, "robot")?;
    let options = ViewerOptions {
        capsules_shown: true,
        collision_capsules: true,
    };
    let page = viewer_with(problem, &Trajectory::still(&q), options);
    let path = dir.join("viewer.html");
    std::fs::write(&path, page)?;
    written.push(path);
    Ok(written)
}
