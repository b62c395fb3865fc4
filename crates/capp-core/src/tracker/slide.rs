//! Sliding along a surface instead of slowing down. A tick whose stop
//! would bring a link end too close to its obstacle's half-space (the
//! [`Approach`] [`super::clearance::stop_margin`] names), or whose
//! configuration would creep onto the closest obstacle, tries again with
//! that point's motion toward the surface taken out of its velocity target.
//! Scaling the whole target down instead (the tick's answer to the other
//! refusals) slows every joint for one point's sake: pressed against a
//! surface, each tick uses up a share of the room left, until even the
//! least share is refused and the planner calls a dead end. Such refusals
//! began 41 of the 44 escapes of tracked snake runs (suite, seed 1); with
//! the slide, tracked runs escape about as often as stepped ones (seeds
//! 1-5: 646 runs against 661, 1 066 before).

use super::clearance::Approach;
use super::limits::DriveLimits;
use crate::kinematics::Frames;
use crate::robot::{JointKind, Robot};

/// Takes out of the velocity target `aim` its motion of `approach`'s point
/// toward the half-space's surface (when it has one): the joint-space row
/// `g_j = n . dp/dq_j` of the point `p` and normal `n`, and `aim` less its
/// share along `g` when `g . aim < 0`, so the point slides along the surface
/// (the paper's rate orthogonal to the potential's gradient, eq. 24, for
/// the one pair that bound the stop); then scaled, the direction kept, so
/// every joint is within its rate. Returns whether `aim` approached (and was
/// changed). Joints past the point's link do not move it.
pub fn slide<const N: usize>(
    robot: &Robot<N>,
    limits: &[DriveLimits],
    frames: &Frames<N>,
    approach: &Approach,
    aim: &mut [f32],
) -> bool {
    let mut g = [0.0f32; N];
    let (mut g_aim, mut g_g) = (0.0f32, 0.0f32);
    for (j, ((gj, joint), &a)) in g
        .iter_mut()
        .zip(robot.joints())
        .zip(aim.iter())
        .enumerate()
        .take(approach.link + 1)
    {
        let z = frames.axis(j);
        let column = match joint.kind {
            JointKind::Revolute => z.cross(&(approach.point - frames.pivot(j))),
            JointKind::Prismatic => z,
        };
        *gj = approach.normal.dot(&column);
        g_aim += *gj * a;
        g_g += *gj * *gj;
    }
    // Not approaching, or no row (NaN anywhere: as it was).
    if !(g_aim < 0.0 && g_g > 0.0) {
        return false;
    }
    let c = g_aim / g_g;
    let mut over = 0.0f32;
    for ((a, &gj), l) in aim.iter_mut().zip(&g).zip(limits) {
        *a -= c * gj;
        over = crate::math::max(over, a.abs() / l.max_rate);
    }
    if over > 1.0 {
        aim.iter_mut().for_each(|a| *a /= over);
    }
    true
}
