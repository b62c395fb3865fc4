//! # capp-core: the CAPP planner, `no_std`, allocation-free, `f32`
//!
//! A collision-avoiding path planner for highly redundant ("serpentine")
//! manipulators, after R. M. Byers, *Automated Path Planning of the Payload
//! Inspection and Processing System* (NASA/UCF). Equation numbers in the docs
//! refer to that paper.
//!
//! The crate is split the way rigid-body libraries split it: an immutable
//! description of the problem, checked once, and a mutable workspace that the
//! per-step algorithms write into.
//!
//! | module | owns |
//! |---|---|
//! | [`robot`] | the Denavit-Hartenberg chain, joint kinds, limits, rates, weights (eq. 5) |
//! | [`pips`] | the 18-joint PIPS of Table 1 as a preset |
//! | [`kinematics`] | forward kinematics into [`kinematics::Frames`] (each joint's axis and pivot), the Jacobian column, exact Jacobian-transpose products (eqs. 6, 14) |
//! | [`target`] | the target and the pose error (eqs. 11-12) |
//! | [`evaluation`] | everything known about one configuration, and the planner's two slots of it |
//! | [`obstacle`] | super-ellipsoid obstacles, their inside-outside function and its gradient (eq. 25) |
//! | [`avoidance`] | avoidance points on the arm, the potential of eq. 26 and its joint-space gradient (eq. 20) |
//! | [`control`] | the laws that drive the end effector, all called through [`control::law::propose`]: the Lyapunov law (eqs. 11-15), the gradient law, the joint weighting (eq. 18); [`control::damped`], damped least squares on `V` (the default); [`control::saturation`], how it spends the rate limits of a redundant arm |
//! | [`linalg`] | the 6 x 6 symmetric positive definite solve the damped law needs |
//! | [`projection`] | keeping the joint rate orthogonal to the obstacle gradient (eqs. 22-24) |
//! | [`step_size`] | how long a step is: the listing's rule, its bounds, conservative advancement |
//! | [`escape`] | what happens at a dead end: remembered, detoured, searched ([`escape::search`]), walked away from, descended again |
//! | [`mission`] | waypoints, tolerances and planner settings (each stage's settings validate themselves; [`settings_field`] names a bad one) |
//! | [`scenario`] | robot + obstacles + mission, validated together |
//! | [`planner`] | the per-step loop: evaluate, choose the drive goal, propose, bound, accept or shorten, account |
//! | [`tracker`] | how fast: the joint drives' rate, acceleration and jerk limits, the jerk-limited, time-synchronised move toward the law's rates at a fixed control period, the stop at the limits and its travel |
//! | [`setpoint`] | decimation of the joint stream, as the listing's `joints.dat` |
//!
//! Units: angles in radians, lengths in whatever unit the robot is described in
//! (PIPS: inches), time in seconds. Rates are per second. The planner's
//! length-valued defaults are fractions of the robot's reach
//! ([`Settings::for_robot`]), and the default law measures joint motion in
//! seconds at the rate limits, so a robot written in another unit plans the
//! same motion (`tests/units.rs`).
//!
//! ## Rules
//!
//! * Nothing here allocates; capacities are const generics (`N` joints, `M`
//!   obstacles, `W` waypoints) and a full container is an error value.
//! * Nothing here panics on any input: values from outside are checked by the
//!   constructors ([`robot::Robot::new`], [`scenario::Scenario::new`],
//!   [`planner::Planner::new`]) and the algorithms then work on valid values.
//!   Indexing inside the algorithms is by counts that validation bounded.
//! * Work per [`planner::Planner::step`] is bounded by the joint, point and
//!   obstacle counts (and a fixed number of step halvings); no loop depends on
//!   the data's values.
//! * Every transcendental goes through `libm` or [`math::sin_cos`] (plain `f32`
//!   operations, which round alike everywhere), and every square root through
//!   [`math::sqrt`] (correctly rounded: the FPU's instruction on the board),
//!   so the same inputs give the same bits on the host and on a Cortex-M4F.
//! * No `unsafe` but the inline assembly behind [`math::sqrt`] and the C
//!   library's `sqrtf` behind [`math::sqrt_inline`] on the board
//!   (the FPU's square root instruction).
#![cfg_attr(not(feature = "trace"), no_std)]
#![deny(unsafe_code)]
#![warn(missing_docs)]

#[cfg(test)]
extern crate std;

pub mod avoidance;
pub mod control;
pub mod escape;
pub mod evaluation;
pub mod kinematics;
pub mod linalg;
pub mod math;
pub mod mission;
pub mod obstacle;
pub mod pips;
pub mod planner;
pub mod projection;
pub mod robot;
pub mod scenario;
pub mod self_collision;
pub mod setpoint;
pub mod settings_field;
pub mod step_size;
pub mod target;
pub mod tracker;

pub use mission::{Mission, MissionError, Motion, Settings, Waypoint};
pub use obstacle::{Hull, HullError, ObstacleError, Shape, Solid, SuperEllipsoid, World};
pub use planner::{Outcome, Phase, Planner, StartError, StepError, StepReport};
pub use robot::{Joint, JointKind, Robot, RobotError};
pub use scenario::{Scenario, ScenarioError};
pub use setpoint::SetpointFilter;

/// Largest chain the crate is tested with; capacities above it work but are untested.
pub const TESTED_MAX_JOINTS: usize = 32;
