//! The forward pass of a chain of general joints ([`crate::robot::origin`]):
//! each joint's stored origin already turns its axis onto `z`, so a joint is
//! "fixed transform, then rotate about (slide along) z":
//!
//! ```text
//! pivot_j = o_{j-1} + R_{j-1} t_j        R'_j = R_{j-1} O_j
//! R_j     = R'_j Rot_z(q_j)               (revolute; prismatic: o_j = pivot_j + q_j z'_j)
//! ```
//!
//! About 80 flops a joint; the DH pass is about 40.

use super::frames::Frames;
use crate::math::{sin_cos, Mat3, Vec3};
use crate::robot::{JointKind, Robot};

/// Every pivot and axis of `robot`'s general joints at `q` into `frames`
/// (the last link's end is the last joint's moved origin, before the tool);
/// returns the last joint's moved origin and rotation.
///
/// Never inlined: the forward pass is called from a dozen places, and a
/// DH robot (the board's) must not carry a copy of this one in each.
#[inline(never)]
pub(super) fn forward<const N: usize>(
    robot: &Robot<N>,
    q: &[f32],
    frames: &mut Frames<N>,
) -> (Vec3, Mat3) {
    let mut rot = Mat3::identity();
    let mut o = Vec3::zeros();
    let mut n = 0usize;
    let segments = robot.has_link_segments();
    frames.segments = segments;
    frames.base = o;
    for (j, ((joint, link), &qj)) in robot.joints().iter().zip(robot.links()).zip(q).enumerate() {
        // The joint's frame at q = 0: the previous frame, then the origin.
        let pivot = o + rot * link.origin.translation;
        rot *= link.origin.rotation;
        match j.checked_sub(1) {
            None => frames.base = pivot,
            Some(previous) => {
                if let Some(end) = frames.link_end.get_mut(previous) {
                    *end = pivot;
                }
            }
        }
        let x = rot.column(0).into_owned();
        let y = rot.column(1).into_owned();
        let z = rot.column(2).into_owned();
        if let Some(axis) = frames.axis.get_mut(j) {
            *axis = z;
        }
        o = pivot;
        match joint.kind {
            JointKind::Revolute => {
                let (s, c) = sin_cos(qj);
                rot = Mat3::from_columns(&[x * c + y * s, y * c - x * s, z]);
            }
            JointKind::Prismatic => o += z * qj,
        }
        // The capsule's segment, fixed in the body this joint moves.
        if segments {
            if let Some(out) = frames.segment.get_mut(j) {
                *out = link.segment.map(|p| o + rot * p);
            }
        }
        n += 1;
    }
    // The last link ends at the last joint's moved origin (the tool, if
    // any, is applied by the caller).
    if let Some(end) = n.checked_sub(1).and_then(|k| frames.link_end.get_mut(k)) {
        *end = o;
    }
    frames.n = n;
    (o, rot)
}
