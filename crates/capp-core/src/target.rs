//! What the end effector is driven to, and how far it is from it (eqs.
//! 11-12): the [`Target`] of a waypoint (or of a detour's point) and the
//! [`PoseError`] of a configuration from it. A leaf: every law, the step-size
//! rules, the escape and the planner read these, and it reads only the
//! frames.
//!
//! Target `T_target` has columns `r_T1..r_T3` (orientation) and `r_T4`
//! (position); the end effector's are `r_n1..r_n4`:
//!
//! ```text
//! e_i = r_Ti - r_ni,  i = 1..4                              (eq. 11)
//! V   = sum_i 1/2 e_i . e_i                                 (eq. 12)
//! ```

use crate::kinematics::Frames;
use crate::math::{Mat3, Vec3};

/// Where the end effector should go: a position and, optionally, an orientation.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Target {
    /// `r_T4`, length units.
    pub position: Vec3,
    /// `R_target` (columns `r_T1..r_T3`), or `None` to ignore orientation.
    pub orientation: Option<Mat3>,
    /// A joint configuration to reach instead (index into the scenario's
    /// joint goals, [`crate::Scenario::joint_goal`]); `position` and
    /// `orientation` are then its pose, for the reports.
    pub joints: Option<u8>,
}

impl Target {
    /// A pose target (no joint configuration).
    pub const fn pose(position: Vec3, orientation: Option<Mat3>) -> Self {
        Target {
            position,
            orientation,
            joints: None,
        }
    }
}

/// The end effector's error from a target (eqs. 11-12).
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct PoseError {
    /// `e_1..e_3` (orientation columns, zero when the target has none) and `e_4` (position).
    pub e: [Vec3; 4],
    /// `V` of eq. 12 over the active terms, orientation columns weighted by `lambda^2`.
    pub v: f32,
    /// `|e_4|`, length units.
    pub position: f32,
    /// `sqrt(|e_1|^2 + |e_2|^2 + |e_3|^2)` (the listing's measure), dimensionless.
    pub orientation: f32,
    /// Whether the orientation terms are active.
    pub has_orientation: bool,
}

/// Errors of the end effector in `frames` from `target`; `V` weighs the
/// orientation columns by `lambda^2` (`orientation_scale`; 1 gives eq. 12).
pub fn pose_error<const N: usize>(
    frames: &Frames<N>,
    target: &Target,
    orientation_scale: f32,
) -> PoseError {
    let mut e = [Vec3::zeros(); 4];
    e[3] = target.position - frames.end_position();
    let position_sq = e[3].dot(&e[3]);
    let mut orientation_sq = 0.0;
    if let Some(r_target) = &target.orientation {
        for (i, ei) in e.iter_mut().take(3).enumerate() {
            *ei = r_target.column(i) - frames.end_rotation().column(i);
            orientation_sq += ei.dot(ei);
        }
    }
    PoseError {
        e,
        v: 0.5 * (position_sq + orientation_scale * orientation_scale * orientation_sq),
        position: crate::math::sqrt(position_sq),
        orientation: crate::math::sqrt(orientation_sq),
        has_orientation: target.orientation.is_some(),
    }
}
