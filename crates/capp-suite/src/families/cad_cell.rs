//! A CAD-like work cell for the Franka Emika Panda (metres, from its URDF):
//! every obstacle a primitive on true signed distance (issue 24, "Worlds
//! from CAD"), none a super-ellipsoid.
//!
//! Robot, margins, start and goal rules as [`super::panda_shelves`]: the
//! vendored URDF, base to flange; 0.08 m at joints, 0.06 m inside links,
//! three points per link; the checked link pairs kept
//! [`super::panda_shelves::LINK_MARGIN`] radius sums apart at start and goal;
//! even cases start at the ready pose when it is clear. Target: position and
//! orientation of the goal configuration, tolerances 0.005 m and 0.05.
//!
//! Scene, all `shape = "box" | "cylinder" | "capsule" | "sphere" | "convex"`:
//! - the table top just under the base (a box);
//! - a shelf unit of true boxes (two side panels, a top, one to three
//!   boards, sometimes a back panel) at a random azimuth 0.4 to 0.6 m out;
//! - a vertical pipe (a cylinder from the table up 0.9 to 1.3 m) beside the
//!   cell, away from the shelf's azimuth;
//! - often a horizontal pipe (a cylinder along a tangent of the base, 0.25
//!   to 1 m above the table) on the side away from the shelf;
//! - on the table: sometimes a box turned about z, sometimes a part (a
//!   capsule lying on the table, a ball, or a part from CAD as its mesh's
//!   convex hull: [`part_hull`]);
//! - then obstacles in the way of the motion (arm points of the joint-space
//!   midpoint: a box turned about z, a pipe section vertical or horizontal,
//!   a capsule, a ball or a mesh hull; on the straight end-effector path: a
//!   box turned about z), each shrunk until start and goal stay clear.

use std::f64::consts::FRAC_PI_2;

use super::panda_shelves::{robot, LINK_MARGIN, READY};
use super::scene::{
    arm_points, end_path_points, midpoint, shelf_unit, table_top_spec, Draft, ShelfSizes,
};
use super::Family;
use crate::case::{round, Case, Form, Obstacle, RobotSpec};
use crate::rng::Rng;

/// The family.
pub const FAMILY: Family = Family {
    name: "cad_cell",
    description: "Franka Emika Panda (URDF) in a cell of CAD primitives: true boxes (shelf, table, parts), cylindrical pipes, capsules, balls, parts as convex mesh hulls; tolerances 0.005 m / 0.05",
    count: 80,
    generate,
};

/// A true box of half-extents `h` at `centre`, turned by `yaw` about its own z.
pub fn true_box(name: impl Into<String>, centre: [f64; 3], h: [f64; 3], yaw: f64) -> Obstacle {
    let mut o = Obstacle::solid(name, centre, Form::Cuboid { half_extents: h });
    o.euler[2] = yaw;
    o
}

/// A cylinder (flat ends) of `radius` and full `length` at `centre`:
/// vertical when `horizontal` is `None`, else lying along the horizontal
/// direction at angle `Some(yaw)` from x.
pub fn pipe(
    name: impl Into<String>,
    centre: [f64; 3],
    radius: f64,
    length: f64,
    horizontal: Option<f64>,
) -> Obstacle {
    lay(
        Obstacle::solid(name, centre, Form::Cylinder { radius, length }),
        horizontal,
    )
}

/// A capsule of `radius` and segment `length` at `centre`, vertical or
/// lying along `Some(yaw)` (as [`pipe`]).
pub fn capsule(
    name: impl Into<String>,
    centre: [f64; 3],
    radius: f64,
    length: f64,
    horizontal: Option<f64>,
) -> Obstacle {
    lay(
        Obstacle::solid(name, centre, Form::Capsule { radius, length }),
        horizontal,
    )
}

/// A part from CAD as a mesh's convex hull: 8 to 16 points on the unit
/// sphere squashed to semi-axes `size` times 0.6 to 1 (each axis), turned
/// by random 1-2-3 Euler angles, its corners (`f32`, as the loader reads
/// them, in the loader's order: [`capp_sim::polytope::hull_vertices`]).
pub fn part_hull(rng: &mut Rng, name: impl Into<String>, centre: [f64; 3], size: f64) -> Obstacle {
    let axes = [0, 1, 2].map(|_| size * rng.range(0.6, 1.0));
    let count = 8 + rng.below(9);
    let points: Vec<[f64; 3]> = (0..count)
        .map(|_| {
            let d = [0, 1, 2].map(|_| rng.range(-1.0, 1.0));
            let length = libm::sqrt(d[0] * d[0] + d[1] * d[1] + d[2] * d[2]).max(1e-3);
            [0, 1, 2].map(|a| round(axes[a] * d[a] / length))
        })
        .collect();
    let euler = [0, 1, 2].map(|_| rng.range(-3.1, 3.1));
    // Points on a sphere squashed by at most 0.6 span a volume: the hull
    // exists; should rounding drop a corner, the loader drops it too.
    let vertices = capp_sim::polytope::hull_vertices(&points).unwrap_or(points);
    let mut o = Obstacle::solid(name, centre, Form::Convex { vertices });
    o.euler = euler;
    o
}

/// Turns a shape's z axis to the horizontal direction at `yaw` from x
/// (`R = Rz(yaw) Ry(90 deg)`), or leaves it vertical.
fn lay(mut o: Obstacle, horizontal: Option<f64>) -> Obstacle {
    if let Some(yaw) = horizontal {
        o.euler = [0.0, FRAC_PI_2, yaw];
    }
    o
}

/// The shelf unit's panels as true boxes (the same sizes and placement as
/// [`shelf_unit`]'s exponent-8 boxes).
fn as_true_box(mut o: Obstacle) -> Obstacle {
    if let Form::SuperEllipsoid { semi_axes, .. } = o.shape {
        o.shape = Form::Cuboid {
            half_extents: semi_axes,
        };
    }
    o
}

fn generate(rng: &mut Rng, index: usize) -> Option<Case> {
    let from_ready = index.is_multiple_of(2);
    let ready: Vec<f64> = READY.iter().map(|&x| round(x)).collect();
    let name = format!("cad_cell-{index:03}");
    let mut draft = Draft::new(table_top_spec(
        &name,
        "Franka Emika Panda (URDF) in a cell of CAD primitives",
        RobotSpec::Urdf(robot()),
        ready.clone(),
    ))?;
    draft.keep_links_apart(LINK_MARGIN)?;

    let top = -0.01 - rng.range(0.0, 0.04);
    draft.push(true_box(
        "table",
        [0.15, 0.0, top - 0.05],
        [0.8, 0.8, 0.05],
        0.0,
    ));
    let (shelf, boards) = shelf_unit(
        rng,
        top,
        &ShelfSizes {
            azimuth: (-1.3, 1.3),
            near: (0.4, 0.6),
            half_depth: (0.12, 0.18),
            half_width: (0.25, 0.4),
            height: (0.8, 1.1),
            boards: 3,
            board_jitter: 0.04,
        },
    );
    let shelf_azimuth = shelf[0].euler[2];
    for o in shelf {
        draft.push(as_true_box(o));
    }
    // The side away from the shelf: the pipes and the parts go there.
    let away = |rng: &mut Rng| {
        let side = if rng.chance(0.5) { 1.0 } else { -1.0 };
        shelf_azimuth + side * rng.range(1.3, 2.3)
    };

    // A vertical pipe standing on the table.
    let height = rng.range(0.9, 1.3);
    let (r, a) = (rng.range(0.45, 0.7), away(rng));
    draft.push(pipe(
        "pipe (vertical)",
        [r * libm::cos(a), r * libm::sin(a), top + 0.5 * height],
        rng.range(0.025, 0.06),
        height,
        None,
    ));
    // A horizontal pipe along a tangent of the base.
    let horizontal = rng.chance(0.6);
    if horizontal {
        let (r, a) = (rng.range(0.4, 0.65), away(rng));
        let z = top + rng.range(0.25, 1.0);
        draft.push(pipe(
            "pipe (horizontal)",
            [r * libm::cos(a), r * libm::sin(a), z],
            rng.range(0.02, 0.05),
            rng.range(0.5, 1.0),
            Some(a + FRAC_PI_2),
        ));
    }
    // On the table: a box, and a part (a capsule lying down, or a ball).
    if rng.chance(0.5) {
        let h = [
            rng.range(0.04, 0.1),
            rng.range(0.04, 0.1),
            rng.range(0.04, 0.12),
        ];
        let (r, a) = (rng.range(0.3, 0.5), rng.range(-3.1, 3.1));
        draft.push(true_box(
            "box on the table",
            [r * libm::cos(a), r * libm::sin(a), top + h[2]],
            h,
            rng.range(-1.5, 1.5) + a,
        ));
    }
    let part = rng.below(4);
    if part > 0 {
        let (r, a) = (rng.range(0.3, 0.55), away(rng));
        let (x, y) = (r * libm::cos(a), r * libm::sin(a));
        let radius = rng.range(0.03, 0.07);
        draft.push(match part {
            1 => capsule(
                "part on the table (capsule)",
                [x, y, top + radius],
                radius,
                rng.range(0.1, 0.25),
                Some(rng.range(-3.1, 3.1)),
            ),
            2 => Obstacle::solid(
                "part on the table (ball)",
                [x, y, top + radius],
                Form::Sphere { radius },
            ),
            _ => part_hull(
                rng,
                "part on the table (mesh hull)",
                [x, y, top + 1.5 * radius],
                1.5 * radius,
            ),
        });
    }

    let (start, at_ready) = draft.ready_or_random(rng, ready, from_ready)?;
    let goal = draft.random_goal(rng, &start, 0.8, 0.2, 1500)?;

    let placed = in_the_way(&mut draft, rng, &start, &goal);
    let tags = format!(
        "start {}; {boards} boards; {} pipe(s); {} obstacles ({placed} in the way)",
        if at_ready { "ready" } else { "random" },
        1 + horizontal as usize,
        draft.spec.obstacles.len()
    );
    draft.finish(FAMILY.name, index, tags, &start, &goal, true)
}

/// Obstacles in the way of the motion from `start` to `goal`, as
/// [`Draft::boxes_in_the_way`] places them but of every primitive: one or
/// two at arm points of the joint-space midpoint (a box turned about z, a
/// pipe section, a capsule or a ball), then a box turned about z on the
/// straight end-effector path. Returns how many were placed.
fn in_the_way(draft: &mut Draft, rng: &mut Rng, start: &[f64], goal: &[f64]) -> usize {
    let (lo, hi) = (0.04, 0.08);
    let boxed = |label: &'static str| {
        move |rng: &mut Rng, centre: [f64; 3], scale: f64| {
            let h = [0, 1, 2].map(|_| scale * rng.range(lo, hi));
            true_box(label, centre, h, rng.range(-1.5, 1.5))
        }
    };
    let any = |rng: &mut Rng, centre: [f64; 3], scale: f64| {
        let label = "in the way (joint-space path)";
        let lying = rng.chance(0.5).then(|| rng.range(-3.1, 3.1));
        match rng.below(5) {
            0 => boxed(label)(rng, centre, scale),
            4 => {
                let size = scale * rng.range(lo, hi);
                part_hull(rng, "in the way (mesh hull)", centre, size)
            }
            1 => pipe(
                label,
                centre,
                scale * rng.range(0.02, 0.05),
                scale * rng.range(0.2, 0.5),
                lying,
            ),
            2 => capsule(
                label,
                centre,
                scale * rng.range(lo, hi),
                scale * rng.range(0.05, 0.2),
                lying,
            ),
            _ => Obstacle::solid(
                label,
                centre,
                Form::Sphere {
                    radius: scale * rng.range(lo, hi),
                },
            ),
        }
    };
    let joint_path = arm_points(draft.problem(), &midpoint(start, goal), 1);
    let mut placed = 0;
    for _ in 0..1 + rng.below(2) {
        placed += draft.place(rng, &joint_path, &[start, goal], 8, any) as usize;
    }
    let end_path = end_path_points(draft.problem(), start, goal);
    placed += draft.place(
        rng,
        &end_path,
        &[start, goal],
        8,
        boxed("in the way (end-effector path)"),
    ) as usize;
    placed
}
