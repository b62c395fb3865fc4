//! One URDF `<joint>` on the chain, checked and turned into a [`ChainJoint`].
//!
//! Accepted: revolute, continuous, prismatic (fixed joints are folded by
//! `fold.rs` and never reach here). Refused: planar, floating, spherical, a
//! `<mimic>`, a zero or non-finite axis, a revolute or prismatic joint
//! without `<limit>`, NaN limits, lower > upper, a negative velocity.

use nalgebra::{Isometry3, Unit};

use crate::chain::{ChainJoint, JointKind};
use crate::error::Problem;
use crate::pose;

/// How `joint` moves: `None` for a fixed joint, an error for the kinds a
/// chain cannot hold.
pub(crate) fn kind(joint: &urdf_rs::Joint) -> Result<Option<JointKind>, Problem> {
    use urdf_rs::JointType as T;
    let unsupported = |name: &str| Err(Problem::UnsupportedJointType(name.into()));
    match joint.joint_type {
        T::Revolute => Ok(Some(JointKind::Revolute)),
        T::Continuous => Ok(Some(JointKind::Continuous)),
        T::Prismatic => Ok(Some(JointKind::Prismatic)),
        T::Fixed => Ok(None),
        T::Floating => unsupported("floating"),
        T::Planar => unsupported("planar"),
        T::Spherical => unsupported("spherical"),
    }
}

/// `joint`, of moving `kind`, as a chain joint whose `origin` is
/// `before * <origin>`, where `before` holds the fixed joints folded in ahead
/// of it. `has_limit` tells whether the file wrote a `<limit>` (`scan.rs`).
pub(crate) fn chain_joint(
    joint: &urdf_rs::Joint,
    kind: JointKind,
    before: &Isometry3<f64>,
    has_limit: bool,
) -> Result<ChainJoint, Problem> {
    if let Some(mimic) = &joint.mimic {
        return Err(Problem::Mimic(mimic.joint.clone()));
    }
    let origin = before * pose::isometry(&joint.origin)?;
    let axis = pose::vector(*joint.axis.xyz, "axis xyz")?;
    let axis = Unit::try_new(axis, 0.0)
        .ok_or_else(|| Problem::ZeroAxis(format!("{} {} {}", axis.x, axis.y, axis.z)))?;
    let (lower, upper) = limits(joint, kind, has_limit)?;
    let velocity = joint.limit.velocity;
    if velocity.is_nan() {
        return Err(Problem::NonFinite("limit velocity"));
    }
    if velocity < 0.0 {
        return Err(Problem::NegativeVelocity(velocity));
    }
    Ok(ChainJoint {
        name: joint.name.clone(),
        kind,
        origin,
        axis,
        lower,
        upper,
        velocity: (velocity > 0.0 && velocity.is_finite()).then_some(velocity),
    })
}

/// The position limits: infinite for continuous joints, checked otherwise.
/// An infinite lower (upper) bound is URDF 1.2's "no limit"; any other
/// infinity or a NaN is refused.
fn limits(joint: &urdf_rs::Joint, kind: JointKind, has_limit: bool) -> Result<(f64, f64), Problem> {
    if kind == JointKind::Continuous {
        return Ok((f64::NEG_INFINITY, f64::INFINITY));
    }
    if !has_limit {
        return Err(Problem::MissingLimit(match kind {
            JointKind::Prismatic => "prismatic",
            _ => "revolute",
        }));
    }
    let (lower, upper) = (joint.limit.lower, joint.limit.upper);
    if lower.is_nan() || lower == f64::INFINITY {
        return Err(Problem::NonFinite("limit lower"));
    }
    if upper.is_nan() || upper == f64::NEG_INFINITY {
        return Err(Problem::NonFinite("limit upper"));
    }
    if lower > upper {
        return Err(Problem::LimitsReversed { lower, upper });
    }
    Ok((lower, upper))
}
