//! Forward kinematics (eqs. 5-6) and exact Jacobian-transpose products (eq. 14).
//!
//! Frames: `T_0 = I` (the base), `T_k = T_{k-1} A_k`, the end effector is `T_n`.
//! Joint `k` (1-based) moves about / along the axis `z_{k-1}` of frame `k-1`
//! through its origin `o_{k-1}`. Here joints are 0-based: joint `j` moves about
//! [`Frames::axis`]`(j)` through [`Frames::pivot`]`(j)`, and its link ends at
//! [`Frames::link_end`]`(j)`: the next joint's pivot, or the end effector.
//!
//! [`Frames`] stores each joint's axis and pivot as they are, not as a DH
//! frame: everything downstream (the Jacobian columns, the avoidance points,
//! conservative advancement) reads only those, so a joint described another
//! way (a URDF joint: a fixed transform, then a motion about its own axis)
//! needs only its own forward pass here. [`Frames::column`] is the one
//! Jacobian column.
//!
//! Exact columns of the Jacobian of anything carried by a frame at or after
//! joint `j` (no finite differences):
//!
//! ```text
//! point p:      dp/dq_j = z x (p - o)   (revolute)      z   (prismatic)
//! direction u:  du/dq_j = z x u         (revolute)      0   (prismatic)
//! ```
//!
//! so for a force `f` applied at `p`, `(J^T f)_j = z . ((p - o) x f)` or `z . f`,
//! and for a direction error `e` on `u`, `(J_u^T e)_j = z . (u x e)` or `0`.
//! Each product costs O(n) after one forward pass; no 6 x n matrix is formed.

mod frames;
mod general;

pub use frames::Frames;

use crate::math::{sin_cos, Mat3, Vec3};
use crate::robot::{JointKind, Robot};

/// Computes every frame of `robot` at `q` into `frames` (eqs. 5-6; for
/// general joints, [`crate::robot::origin`]), then the tool's.
///
/// `q` must hold `robot.len()` values (the caller validated it); extra values
/// are ignored and missing ones are treated as the end of the chain.
/// Cost: one [`sin_cos`] per revolute joint and about 40 flops per DH joint
/// (about 80 per general joint).
pub fn forward_kinematics<const N: usize>(robot: &Robot<N>, q: &[f32], frames: &mut Frames<N>) {
    let (o, rot) = if robot.is_general() {
        general::forward(robot, q, frames)
    } else {
        forward_dh(robot, q, frames)
    };
    frames.end_rotation = rot;
    if let Some(tool) = robot.tool_transform() {
        let end = o + rot * tool.translation;
        if let Some(last) = frames
            .n
            .checked_sub(1)
            .and_then(|k| frames.link_end.get_mut(k))
        {
            *last = end;
        }
        frames.end_rotation = rot * tool.rotation;
    }
}

/// The DH chain (eq. 5): every frame into `frames` but the end rotation;
/// returns the last frame's origin and rotation.
fn forward_dh<const N: usize>(robot: &Robot<N>, q: &[f32], frames: &mut Frames<N>) -> (Vec3, Mat3) {
    let mut rot = Mat3::identity();
    let mut o = Vec3::zeros();
    let mut n = 0;
    frames.base = o;
    frames.segments = false;
    for (((joint, link), &qj), (end, axis)) in robot
        .joints()
        .iter()
        .zip(robot.links())
        .zip(q)
        .zip(frames.link_end.iter_mut().zip(frames.axis.iter_mut()))
    {
        let x = rot.column(0).into_owned();
        let y = rot.column(1).into_owned();
        let z = rot.column(2).into_owned();
        *axis = z;
        let (ct, st, d) = match joint.kind {
            JointKind::Revolute => {
                let (s, c) = sin_cos(qj);
                (c, s, joint.d)
            }
            JointKind::Prismatic => (link.cos_theta, link.sin_theta, qj),
        };
        // Columns of R_{k-1} Rot_z(theta) Rot_x(alpha).
        let xk = x * ct + y * st;
        let yt = y * ct - x * st;
        let yk = yt * link.cos_alpha + z * link.sin_alpha;
        let zk = z * link.cos_alpha - yt * link.sin_alpha;
        o += z * d + xk * joint.a;
        *end = o;
        rot = Mat3::from_columns(&[xk, yk, zk]);
        n += 1;
    }
    frames.n = n;
    (o, rot)
}

/// `J_p^T f` for a force `f` at the end effector: `out[j] = z_j . ((p - o_j) x f)`
/// (revolute) or `z_j . f` (prismatic). `out` must hold `frames.len()` values.
/// (The triple product in this order, not [`Frames::column`] dotted with
/// `f`: the same value, rounded as the plans have always been.)
pub fn end_point_force<const N: usize>(
    robot: &Robot<N>,
    frames: &Frames<N>,
    force: &Vec3,
    out: &mut [f32],
) {
    let p = frames.end_position();
    for (j, (joint, out)) in robot.joints().iter().zip(out.iter_mut()).enumerate() {
        let z = frames.axis(j);
        *out = match joint.kind {
            JointKind::Revolute => z.dot(&(p - frames.pivot(j)).cross(force)),
            JointKind::Prismatic => z.dot(force),
        };
    }
}

/// `J_u^T e` for an error `e` on the end-effector direction `u` (a column of
/// its rotation): `out[j] = z_j . (u x e)` (revolute) or `0` (prismatic).
pub fn end_direction_error<const N: usize>(
    robot: &Robot<N>,
    frames: &Frames<N>,
    u: &Vec3,
    e: &Vec3,
    out: &mut [f32],
) {
    let w = u.cross(e);
    for (j, (joint, out)) in robot.joints().iter().zip(out.iter_mut()).enumerate() {
        *out = match joint.kind {
            JointKind::Revolute => frames.axis(j).dot(&w),
            JointKind::Prismatic => 0.0,
        };
    }
}

/// End-effector twist for a joint rate: linear velocity `v = sum_j qdot_j dp/dq_j`
/// (length units per second) and angular velocity `w = sum_revolute qdot_j z_j`
/// (radians per second). O(n); `J qdot` without forming `J`.
pub fn end_twist<const N: usize>(
    robot: &Robot<N>,
    frames: &Frames<N>,
    rate: &[f32],
) -> (Vec3, Vec3) {
    let p = frames.end_position();
    let mut v = Vec3::zeros();
    let mut w = Vec3::zeros();
    for (j, (joint, &r)) in robot.joints().iter().zip(rate).enumerate() {
        let (linear, angular) = frames.column(j, joint.kind, &p);
        if joint.kind == JointKind::Revolute {
            w += angular * r;
        }
        v += linear * r;
    }
    (v, w)
}

/// Squared weighted size of each Jacobian column, into `out`: for joint `j`,
/// `|dp/dq_j|^2 + lambda^2 sum_i |du_i/dq_j|^2` = `|z x (p - o)|^2 + 2 lambda^2`
/// (revolute) or `1` (prismatic). Their gain-weighted sum bounds the largest
/// eigenvalue of `J M J^T` (it is its trace). O(n).
pub fn column_sizes<const N: usize>(
    robot: &Robot<N>,
    frames: &Frames<N>,
    orientation_scale: f32,
    out: &mut [f32],
) {
    let p = frames.end_position();
    let rot = 2.0 * orientation_scale * orientation_scale;
    for (j, (joint, out)) in robot.joints().iter().zip(out.iter_mut()).enumerate() {
        *out = match frames.column(j, joint.kind, &p) {
            (c, _) if joint.kind == JointKind::Revolute => c.dot(&c) + rot,
            _ => 1.0,
        };
    }
}
