//! `[robot] urdf = "..."`: a robot from a URDF file, through `capp-urdf`,
//! as the core's general joints ([`capp_core::robot::origin`]).
//!
//! - Each moving joint between `base_link` and `tip_link` becomes a general
//!   joint: its `<origin>` (fixed joints before it folded in) and `<axis>`;
//!   the fixed joints after the last one become the robot's tool.
//! - Lengths: URDF is in metres; they are converted to the scenario's length
//!   unit. Angles are radians whatever `[units] angle` says (the unit applies
//!   to what the scenario file itself writes: overrides, starts, Euler angles).
//! - Limits: `<limit lower upper>`; a continuous joint (or a revolute one
//!   URDF 1.2 leaves unlimited) gets [`CONTINUOUS_RANGE_RAD`] each way: the
//!   planner does not wrap angles. A prismatic joint without finite limits,
//!   or any joint without a `<limit velocity>`, must be completed by a
//!   `[[robot.overrides]]` entry ([`missing_fields`] names what is missing).
//! - Pivots: each revolute joint's frame is slid along its own axis
//!   ([`super::pivots`]) so that each link's chord, from its joint's pivot
//!   to the next, runs through the link's body; no body, axis or the tip
//!   moves, in any configuration. The joints, the tool and the bodies'
//!   capsules are given in the slid frames.
//! - Self-collision: each link's `<collision>` geometry (primitives, or STL,
//!   OBJ, Collada meshes fitted with capsules by `capp-urdf`) is enclosed in
//!   one capsule, round the link's chord or, where that is much smaller,
//!   round a segment of its own fixed in the body ([`super::link_capsule`]);
//!   the core checks that capsule. The base's own geometry is not checked:
//!   the core has no link before the first joint.

use std::path::Path;

use super::link_capsule::link_capsule;
use capp_core::robot::{JointOrigin, Placement};
use capp_core::{Joint, JointKind};
use capp_urdf::{Chain, LoadOptions, UrdfError};
use nalgebra::Isometry3;

/// A continuous joint's range each way from zero, radians: one turn.
pub const CONTINUOUS_RANGE_RAD: f64 = 2.0 * std::f64::consts::PI;

/// A robot read from a URDF file, in the scenario's length unit.
pub struct UrdfRobot {
    /// The chain as `capp-urdf` read it (metres), its pivots slid
    /// ([`UrdfRobot::pivot_slide`]): its joints, tool and bodies are in the
    /// frames the planner uses.
    pub chain: Chain,
    /// How far each joint's pivot was slid along its unit axis from the
    /// URDF's joint origin, metres ([`super::pivots`]).
    pub pivot_slide: Vec<f64>,
    /// One general joint per moving joint. A value the URDF does not give
    /// (see [`missing_fields`]) is NaN until an override sets it.
    pub joints: Vec<Joint>,
    /// The URDF joint names.
    pub names: Vec<String>,
    /// The tip link's frame in the last moving joint's.
    pub tool: Placement,
    /// The capsule radius enclosing each link's collision geometry, length
    /// units; `None` for a link with none.
    pub radii: Vec<Option<f32>>,
    /// Each link's capsule segment in its joint's (slid) frame after its
    /// motion, length units ([`super::link_capsule`]): empty when every
    /// link's capsule is round its chord, else one per link (a link without
    /// geometry, or whose chord does as well, gives its chord).
    pub segments: Vec<[[f32; 3]; 2]>,
    /// The home configuration: every joint at zero, or mid-range where zero
    /// is outside its limits.
    pub home: Vec<f32>,
}

/// Reads `path` with `options` and converts it, lengths times `per_metre`
/// (the scenario's length units per metre); with `slide_pivots`, each
/// revolute joint's pivot slid along its axis ([`super::pivots`]), else
/// the URDF's joint origins as they are.
pub fn import(
    path: &Path,
    options: &LoadOptions,
    per_metre: f64,
    slide_pivots: bool,
) -> Result<UrdfRobot, UrdfError> {
    let read = capp_urdf::load(path, options)?;
    let pivot_slide = match slide_pivots {
        true => super::pivots::slides(&read),
        false => vec![0.0; read.joints.len()],
    };
    let chain = super::pivots::slid(&read, &pivot_slide);
    let n = chain.joints.len();
    let mut joints = Vec::with_capacity(n);
    let mut home = Vec::with_capacity(n);
    for j in &chain.joints {
        let (kind, unit) = match j.kind {
            capp_urdf::JointKind::Revolute | capp_urdf::JointKind::Continuous => {
                (JointKind::Revolute, 1.0)
            }
            capp_urdf::JointKind::Prismatic => (JointKind::Prismatic, per_metre),
        };
        let limit = |v: f64, side: f64| match (v.is_finite(), kind) {
            (true, _) => v * unit,
            (false, JointKind::Revolute) => side * CONTINUOUS_RANGE_RAD,
            (false, JointKind::Prismatic) => f64::NAN,
        };
        let (min, max) = match j.kind {
            capp_urdf::JointKind::Continuous => (-CONTINUOUS_RANGE_RAD, CONTINUOUS_RANGE_RAD),
            _ => (limit(j.lower, -1.0), limit(j.upper, 1.0)),
        };
        let rate = j.velocity.map_or(f64::NAN, |v| v * unit);
        let a = j.axis.into_inner();
        let origin = JointOrigin {
            placement: placement(&j.origin, per_metre),
            axis: [a.x as f32, a.y as f32, a.z as f32],
        };
        joints.push(Joint::general(
            kind,
            origin,
            min as f32,
            max as f32,
            rate as f32,
        ));
        home.push(if min <= 0.0 && 0.0 <= max {
            0.0
        } else {
            (0.5 * (min + max)) as f32
        });
    }
    // Link k's capsule, in joint k's (slid) frame: round its chord, or
    // round a segment of its own where that is much smaller.
    let mut radii = Vec::with_capacity(n);
    let mut segments = Vec::with_capacity(n);
    let mut own_segments = false;
    let scaled = |p: &nalgebra::Point3<f64>| [p.x, p.y, p.z].map(|x| (x * per_metre) as f32);
    for k in 0..n {
        let (pivot, end) = super::pivots::chord(&chain, &[], k);
        let capsule = chain
            .bodies
            .get(k + 1)
            .and_then(|body| link_capsule(body, &pivot, &end));
        radii.push(capsule.map(|(c, _)| (c.radius * per_metre) as f32));
        let (a, b) = match capsule {
            Some((c, own)) => {
                own_segments |= own;
                (c.a, c.b)
            }
            None => (pivot, end),
        };
        segments.push([scaled(&a), scaled(&b)]);
    }
    if !own_segments {
        // Every capsule round its chord: the core's chords, to the bit.
        segments.clear();
    }
    Ok(UrdfRobot {
        names: chain.joints.iter().map(|j| j.name.clone()).collect(),
        tool: placement(&chain.tool, per_metre),
        joints,
        radii,
        segments,
        home,
        chain,
        pivot_slide,
    })
}

/// A rigid transform in `f32`, its translation times `per_metre`.
fn placement(iso: &Isometry3<f64>, per_metre: f64) -> Placement {
    let r = iso.rotation.to_rotation_matrix();
    let t = iso.translation.vector * per_metre;
    Placement {
        rotation: [0, 1, 2].map(|i| [0, 1, 2].map(|k| r[(i, k)] as f32)),
        translation: [t.x as f32, t.y as f32, t.z as f32],
    }
}

/// What a URDF joint still lacks after the overrides: `"min"`, `"max"`,
/// `"max_rate"` (NaN placeholders from [`import`]).
pub fn missing_fields(joint: &Joint) -> Vec<&'static str> {
    [
        (joint.min, "min"),
        (joint.max, "max"),
        (joint.max_rate, "max_rate"),
    ]
    .into_iter()
    .filter(|(v, _)| v.is_nan())
    .map(|(_, name)| name)
    .collect()
}
