//! `step()` fed arbitrary robots, obstacles, waypoints, settings and starts,
//! built through the validating constructors (which must refuse, not panic,
//! on NaN, inf, inverted limits, non-rotations, zero axes, ...; DH rows and
//! general joints, mixed too, and a tool), then planned for a few steps with the
//! invariants of `capp_fuzz::plan_a_few_steps` checked after each.
//!
//! Every number is either any `f32` bit pattern (so the checks see NaN, inf,
//! subnormals and huge values) or a tame value in a plausible range (so most
//! inputs get past validation and reach the planner).
#![no_main]

use arbitrary::Arbitrary;
use capp_core::control::LawKind;
use capp_core::robot::{JointOrigin, Placement};
use capp_core::{Joint, JointKind, Scenario, Settings, Shape, Solid, Waypoint};
use capp_fuzz::plan_a_few_steps;
use libfuzzer_sys::fuzz_target;

#[derive(Debug, Clone, Copy)]
enum Num {
    Any(f32),
    /// `k / 32767 * scale`: in `[-scale, scale]`.
    Tame(i16),
}

/// Mostly tame (a problem has dozens of numbers, and one wild one usually
/// gets the whole problem refused), one in sixteen any bit pattern.
impl<'a> Arbitrary<'a> for Num {
    fn arbitrary(u: &mut arbitrary::Unstructured<'a>) -> arbitrary::Result<Self> {
        Ok(if u8::arbitrary(u)? < 240 {
            Num::Tame(i16::arbitrary(u)?)
        } else {
            Num::Any(f32::arbitrary(u)?)
        })
    }
}

impl Num {
    fn get(self, scale: f32) -> f32 {
        match self {
            Num::Any(x) => x,
            Num::Tame(k) => k as f32 / i16::MAX as f32 * scale,
        }
    }
    /// A tame value in `(0, scale]`, or any.
    fn positive(self, scale: f32) -> f32 {
        match self {
            Num::Any(x) => x,
            Num::Tame(k) => (k.unsigned_abs() as f32 + 1.0) / 32769.0 * scale,
        }
    }
}

#[derive(Arbitrary, Debug)]
struct FuzzJoint {
    prismatic: bool,
    alpha: Num,
    a: Num,
    fixed: Num,
    min: Num,
    span: Num,
    max_rate: Num,
    weight: Num,
    start: Num,
    /// A general joint (URDF-style): its origin and axis; `alpha`, `a` and
    /// `fixed` are then unused.
    general: Option<FuzzOrigin>,
}

#[derive(Arbitrary, Debug)]
struct FuzzOrigin {
    /// Euler angles of the rotation, or raw rows.
    rotation: Result<[Num; 3], [[Num; 3]; 3]>,
    translation: [Num; 3],
    axis: [Num; 3],
}

impl FuzzOrigin {
    fn placement(&self) -> Placement {
        Placement {
            rotation: match &self.rotation {
                Ok(e) => rotation(e.map(|x| x.get(3.2))),
                Err(rows) => rows.map(|r| r.map(|x| x.get(1.0))),
            },
            translation: self.translation.map(|x| x.get(10.0)),
        }
    }
}

#[derive(Arbitrary, Debug)]
struct FuzzObstacle {
    centre: [Num; 3],
    semi_axes: [Num; 3],
    exponents: [Num; 3],
    euler_123: [Num; 3],
    /// The shape, modulo 5: a super-ellipsoid, then the CAD primitives
    /// (their sizes from `semi_axes`).
    shape: u8,
}

#[derive(Arbitrary, Debug)]
struct FuzzWaypoint {
    position: [Num; 3],
    /// Euler angles of a rotation, or raw rows.
    orientation: Option<Result<[Num; 3], [[Num; 3]; 3]>>,
}

#[derive(Arbitrary, Debug)]
struct FuzzSettings {
    defaults: bool,
    time_step_s: Num,
    fine_radius: Num,
    fine_step_fraction: Num,
    position_tolerance: Num,
    orientation_tolerance: Num,
    law: u8,
    orientation_scale: Num,
    approach_radius: Num,
    joint_margin: Num,
    link_margin: Num,
    points_per_link: u8,
    influence_distance: Num,
    engage_clearance: Num,
    advance_fraction: Num,
    damping: Num,
    escape_attempts: u8,
    escape_window: u16,
    escape_walk_steps: u16,
    escape_reach: Num,
    escape_seed: u32,
    max_steps: u16,
    stall_window: u16,
    stall_progress: Num,
    max_halvings: u8,
}

#[derive(Arbitrary, Debug)]
struct Input {
    joints: Vec<FuzzJoint>,
    obstacles: Vec<FuzzObstacle>,
    waypoints: Vec<FuzzWaypoint>,
    settings: FuzzSettings,
    /// The end effector's frame in the last joint's.
    tool: Option<FuzzOrigin>,
    /// Hull vertex lists (convex obstacles name them; any count, any
    /// vertices: the core refuses what is not a hull).
    hulls: Vec<Vec<[Num; 3]>>,
}

/// `R = Rz Ry Rx` rows, from Euler angles.
fn rotation(e: [f32; 3]) -> [[f32; 3]; 3] {
    let (sx, cx) = e[0].sin_cos();
    let (sy, cy) = e[1].sin_cos();
    let (sz, cz) = e[2].sin_cos();
    [
        [cz * cy, cz * sy * sx - sz * cx, cz * sy * cx + sz * sx],
        [sz * cy, sz * sy * sx + cz * cx, sz * sy * cx - cz * sx],
        [-sy, cy * sx, cy * cx],
    ]
}

fn settings(f: &FuzzSettings) -> Settings {
    let mut s = Settings::default();
    if f.defaults {
        s.max_steps = 1 + f.max_steps as u32;
        return s;
    }
    s.time_step_s = f.time_step_s.positive(0.2);
    s.fine_radius = f.fine_radius.positive(5.0);
    s.fine_step_fraction = f.fine_step_fraction.positive(1.0);
    s.position_tolerance = f.position_tolerance.positive(1.0);
    s.orientation_tolerance = f.orientation_tolerance.positive(1.0);
    s.law.kind = match f.law % 3 {
        0 => LawKind::Paper,
        1 => LawKind::Gradient,
        _ => LawKind::DampedLeastSquares,
    };
    s.law.damping = f.damping.positive(1.5);
    // Mostly valid; 0 windows and walks, and reach above 1, check the refusal.
    s.escape.attempts = f.escape_attempts % 16;
    s.escape.window = f.escape_window % 100;
    s.escape.walk_steps = f.escape_walk_steps % 100;
    s.escape.reach = f.escape_reach.positive(1.2);
    s.escape.seed = f.escape_seed;
    s.avoidance.advance_fraction = f.advance_fraction.positive(1.5);
    s.law.orientation_scale = f.orientation_scale.positive(20.0);
    s.law.approach_radius = f.approach_radius.positive(5.0);
    s.avoidance.joint_margin = f.joint_margin.positive(5.0);
    s.avoidance.link_margin = f.link_margin.positive(5.0);
    // Mostly valid (1 to 8); 9 and 10 check the refusal.
    s.avoidance.points_per_link = 1 + f.points_per_link % 10;
    s.avoidance.influence_distance = f.influence_distance.positive(30.0);
    s.avoidance.engage_clearance = f.engage_clearance.positive(3.0);
    s.max_steps = 1 + f.max_steps as u32;
    s.stall_window = 1 + f.stall_window as u32;
    s.stall_progress = f.stall_progress.positive(0.5);
    s.max_halvings = f.max_halvings % 20;
    s
}

fuzz_target!(|input: Input| {
    let mut joints = Vec::new();
    let mut start = Vec::new();
    for j in input.joints.iter().take(34) {
        let (alpha, a, fixed) = (j.alpha.get(3.2), j.a.get(10.0), j.fixed.get(3.2));
        let min = j.min.get(3.0);
        let max = min + j.span.positive(6.0);
        let rate = j.max_rate.positive(2.0);
        let kind = if j.prismatic {
            JointKind::Prismatic
        } else {
            JointKind::Revolute
        };
        let joint = match (&j.general, kind) {
            (Some(g), _) => {
                let origin = JointOrigin {
                    placement: g.placement(),
                    axis: g.axis.map(|x| x.get(1.0)),
                };
                Joint::general(kind, origin, min, max, rate)
            }
            (None, JointKind::Prismatic) => Joint::prismatic(alpha, a, fixed, min, max, rate),
            (None, JointKind::Revolute) => Joint::revolute(alpha, a, fixed, min, max, rate),
        };
        joints.push(joint.with_weight(j.weight.positive(1.0)));
        // Tame starts land inside the limits.
        start.push(match j.start {
            Num::Any(x) => x,
            Num::Tame(k) => min + (k as f32 / i16::MAX as f32 * 0.5 + 0.5) * (max - min),
        });
    }
    let obstacles: Vec<Solid> = input
        .obstacles
        .iter()
        .take(66)
        .map(|o| {
            let sizes = o.semi_axes.map(|x| x.positive(5.0));
            let shape = match o.shape % 6 {
                0 => Shape::SuperEllipsoid {
                    semi_axes: sizes,
                    exponents: o.exponents.map(|x| 1.0 + x.positive(11.0)),
                },
                1 => Shape::Sphere { radius: sizes[0] },
                2 => Shape::Cuboid {
                    half_extents: sizes,
                },
                3 => Shape::Capsule {
                    radius: sizes[0],
                    length: sizes[1],
                },
                4 => Shape::Cylinder {
                    radius: sizes[0],
                    length: sizes[1],
                },
                _ => Shape::Convex { hull: o.shape / 6 },
            };
            Solid {
                centre: o.centre.map(|x| x.get(40.0)),
                euler_123: o.euler_123.map(|x| x.get(3.2)),
                shape,
            }
        })
        .collect();
    let waypoints: Vec<Waypoint> = input
        .waypoints
        .iter()
        .take(17)
        .map(|w| Waypoint {
            position: w.position.map(|x| x.get(40.0)),
            orientation: match &w.orientation {
                None => None,
                Some(Ok(e)) => Some(rotation(e.map(|x| x.get(3.2)))),
                Some(Err(rows)) => Some(rows.map(|r| r.map(|x| x.get(1.0)))),
            },
        })
        .collect();
    let settings = settings(&input.settings);

    let tool = input
        .tool
        .as_ref()
        .map_or(Placement::IDENTITY, FuzzOrigin::placement);
    let hulls: Vec<Vec<[f32; 3]>> = input
        .hulls
        .iter()
        .take(10)
        .map(|h| h.iter().take(40).map(|v| v.map(|x| x.get(8.0))).collect())
        .collect();
    let hull_slices: Vec<&[[f32; 3]]> = hulls.iter().map(|h| &h[..]).collect();
    // In place, as a board builds it (Scenario::init_with_hulls validates
    // the robot, the hulls, the obstacles and the mission).
    let mut scenario = Box::new(Scenario::<32, 64, 16>::empty());
    if scenario
        .init_with_hulls(
            &joints,
            &tool,
            &obstacles,
            &hull_slices,
            &waypoints,
            settings,
        )
        .is_err()
    {
        return;
    }
    plan_a_few_steps(&scenario, &start);
});
