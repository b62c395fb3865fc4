//! What the planner is asked to do: waypoints (the last one the target),
//! tolerances, step size, caps and the settings of every stage.
//!
//! A waypoint is a position and, optionally, an orientation (a rotation
//! matrix, rows as the listing reads them). The planner drives to each in turn;
//! a waypoint is passed when the position error is within
//! `position_tolerance` and (if it has an orientation) the orientation error
//! `sqrt(|e_1|^2 + |e_2|^2 + |e_3|^2)` within `orientation_tolerance` (the
//! listing's 0.4).

use crate::avoidance::AvoidanceSettings;
use crate::control::LawSettings;
use crate::escape::settings::EscapeSettings;
use crate::robot::Robot;
pub use crate::settings_field::SettingsField;
use crate::settings_field::{first_bad, positive};
use crate::step_size::StepRule;

/// A point to pass through, or the final target.
#[derive(Clone, Copy, Debug, PartialEq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub struct Waypoint {
    /// Position of the end effector, length units.
    pub position: [f32; 3],
    /// Orientation as a rotation matrix, row by row (`r11 r12 r13 / r21 ...`),
    /// or `None` when any orientation will do.
    pub orientation: Option<[[f32; 3]; 3]>,
}

impl Waypoint {
    /// A position-only waypoint.
    pub const fn at(position: [f32; 3]) -> Self {
        Waypoint {
            position,
            orientation: None,
        }
    }

    /// A waypoint with an orientation (rows of the rotation matrix).
    pub const fn pose(position: [f32; 3], rows: [[f32; 3]; 3]) -> Self {
        Waypoint {
            position,
            orientation: Some(rows),
        }
    }
}

/// Every setting of the planner. `Default` gives values sized for PIPS in inches.
#[derive(Clone, Copy, Debug, PartialEq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub struct Settings {
    /// Largest integration step `h`, seconds (the listing's `step`).
    pub time_step_s: f32,
    /// Position error (length units) under which the step is cut to
    /// `fine_step_fraction * time_step_s` (the listing: `10 * step`, then `step / 4`).
    pub fine_radius: f32,
    /// Fraction of the step used inside `fine_radius`, in `(0, 1]` (listing: 0.25).
    pub fine_step_fraction: f32,
    /// Position tolerance, length units.
    pub position_tolerance: f32,
    /// Orientation tolerance (root sum square of the column errors; listing: 0.4).
    pub orientation_tolerance: f32,
    /// The control law's weights and approach radii.
    pub law: LawSettings,
    /// Avoidance points, margins and influence distance.
    pub avoidance: AvoidanceSettings,
    /// Iteration cap: the run ends `Capped` after this many steps.
    pub max_steps: u32,
    /// Dead-end detection: `Stalled` when `V` has not reached a new low by
    /// `stall_progress` (relative) within this many steps.
    pub stall_window: u32,
    /// Relative decrease of `V` that counts as progress, in `[0, 1)`.
    pub stall_progress: f32,
    /// Most halvings of a step that would enter an obstacle or raise `V`, 0 to 16.
    pub max_halvings: u8,
    /// What happens at a dead end (see [`crate::escape`]).
    pub escape: EscapeSettings,
    /// How the joints move from step to step ([`Motion`]).
    pub motion: Motion,
}

/// How the planner turns the law's rate into motion.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub enum Motion {
    /// The paper's: an Euler step of the law's rate, of variable length (at
    /// most `time_step_s`), halved until it is clear; the rate may jump from
    /// step to step.
    Stepped,
    /// A fixed control period (`time_step_s`, at most
    /// [`crate::tracker::limits::MAX_CONTROL_PERIOD_S`]): the law's rate is
    /// the velocity the tracker moves toward within each joint's rate,
    /// acceleration and jerk limits, and every tick keeps the stop from its
    /// end clear ([`crate::tracker`]).
    Tracked,
}

impl Default for Settings {
    fn default() -> Self {
        Settings {
            time_step_s: 0.05,
            fine_radius: 1.0,
            fine_step_fraction: 0.25,
            position_tolerance: 0.1,
            orientation_tolerance: 0.05,
            law: LawSettings::default(),
            avoidance: AvoidanceSettings::default(),
            max_steps: 20_000,
            stall_window: 400,
            stall_progress: 0.01,
            max_halvings: 8,
            escape: EscapeSettings::default(),
            motion: Motion::Stepped,
        }
    }
}

impl Settings {
    /// The defaults for a robot whose characteristic length is
    /// `characteristic_length` (length units): [`Settings::default`]'s
    /// lengths (sized for PIPS in inches, whose reach is
    /// [`reference_length`]) scaled by `characteristic_length /
    /// reference_length()`. Every other default is a time, a count or a ratio,
    /// so a robot and its copy in other units get the same settings in their
    /// own units, and plan the same motion.
    pub fn relative_to(characteristic_length: f32) -> Self {
        Settings::default().scaled(characteristic_length / reference_length())
    }

    /// The defaults relative to `robot`'s reach ([`Robot::reach`]).
    pub fn for_robot<const N: usize>(robot: &Robot<N>) -> Self {
        Settings::relative_to(robot.reach())
    }

    /// These settings with every length multiplied by `k` (`k = 1` changes
    /// nothing, to the bit): tolerance, radii, the orientation scale, margins
    /// and the influence distance.
    pub fn scaled(mut self, k: f32) -> Self {
        if k != 1.0 {
            self.fine_radius *= k;
            self.position_tolerance *= k;
            self.law.orientation_scale *= k;
            self.law.approach_radius *= k;
            self.avoidance.joint_margin *= k;
            self.avoidance.link_margin *= k;
            self.avoidance.influence_distance *= k;
        }
        self
    }
}

/// The characteristic length [`Settings::default`] is sized for: the reach of
/// PIPS in inches (about 248 in; [`crate::pips`]).
pub fn reference_length() -> f32 {
    crate::pips::robot::<{ crate::pips::JOINTS }>().map_or(1.0, |r| r.reach())
}

/// Why a mission was rejected. `waypoint` is 0-based.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub enum MissionError {
    /// No waypoints: there is no target.
    NoWaypoints,
    /// More waypoints than the capacity `W`.
    TooManyWaypoints {
        /// Capacity.
        capacity: usize,
    },
    /// A waypoint has a NaN or infinite coordinate, or one beyond 1e4.
    BadPosition {
        /// The waypoint.
        waypoint: u8,
    },
    /// A waypoint's orientation is not a rotation matrix (orthonormal, det +1).
    NotARotation {
        /// The waypoint.
        waypoint: u8,
    },
    /// A setting is out of its range.
    BadSetting(SettingsField),
    /// A joint-space waypoint was refused.
    BadJointGoal {
        /// The waypoint (0-based).
        waypoint: u8,
        /// Why.
        problem: JointGoalProblem,
    },
}

/// What is wrong with a joint-space waypoint.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub enum JointGoalProblem {
    /// There is no waypoint with that index.
    NoSuchWaypoint,
    /// Not one value per joint.
    WrongLength,
    /// A value is not finite or outside its joint's limits.
    OutsideLimits,
    /// More than [`crate::scenario::MAX_JOINT_GOALS`].
    TooMany,
}

impl core::fmt::Display for JointGoalProblem {
    fn fmt(&self, f: &mut core::fmt::Formatter<'_>) -> core::fmt::Result {
        f.write_str(match self {
            JointGoalProblem::NoSuchWaypoint => "there is no such waypoint",
            JointGoalProblem::WrongLength => "not one value per joint",
            JointGoalProblem::OutsideLimits => "a value is not finite or outside its limits",
            JointGoalProblem::TooMany => "more joint-space waypoints than the capacity",
        })
    }
}

impl core::fmt::Display for MissionError {
    fn fmt(&self, f: &mut core::fmt::Formatter<'_>) -> core::fmt::Result {
        match *self {
            MissionError::NoWaypoints => write!(f, "no waypoints: there is no target"),
            MissionError::TooManyWaypoints { capacity } => {
                write!(f, "more waypoints than the capacity of {capacity}")
            }
            MissionError::BadPosition { waypoint } => write!(
                f,
                "waypoint {}: position is not finite or farther than 1e4",
                waypoint as u32 + 1
            ),
            MissionError::NotARotation { waypoint } => write!(
                f,
                "waypoint {}: orientation is not a rotation matrix",
                waypoint as u32 + 1
            ),
            MissionError::BadSetting(field) => write!(f, "bad setting: {field}"),
            MissionError::BadJointGoal { waypoint, problem } => {
                write!(
                    f,
                    "waypoint {}: joint configuration: {problem}",
                    waypoint as u32 + 1
                )
            }
        }
    }
}

impl Settings {
    /// Checks every setting's range: its own, then each stage's
    /// ([`LawSettings::validate`], [`AvoidanceSettings::validate`],
    /// [`EscapeSettings::validate`]).
    // Not inlined: validation is cold, and one copy of it is enough (the
    // board's serving loop would otherwise carry its own, 1.5 KiB).
    #[inline(never)]
    pub fn validate(&self) -> Result<(), MissionError> {
        use SettingsField as F;
        let own = || {
            first_bad(&[
                (positive(self.position_tolerance), F::PositionTolerance),
                (
                    positive(self.orientation_tolerance),
                    F::OrientationTolerance,
                ),
            ])
        };
        let tail = || {
            first_bad(&[
                (self.max_steps >= 1, F::MaxSteps),
                (self.stall_window >= 1, F::StallWindow),
                (
                    self.stall_progress.is_finite()
                        && self.stall_progress >= 0.0
                        && self.stall_progress < 1.0,
                    F::StallProgress,
                ),
                (self.max_halvings <= 16, F::MaxHalvings),
                (
                    self.motion == Motion::Stepped
                        || self.time_step_s <= crate::tracker::limits::MAX_CONTROL_PERIOD_S,
                    F::TimeStep,
                ),
            ])
        };
        self.step_rule()
            .validate()
            .and_then(|()| own())
            .and_then(|()| self.law.validate())
            .and_then(|()| self.avoidance.validate())
            .and_then(|()| tail())
            .and_then(|()| self.escape.validate())
            .map_err(MissionError::BadSetting)
    }

    /// The first-order laws' step rule ([`StepRule`]), from this step size
    /// and fine radius.
    pub fn step_rule(&self) -> StepRule {
        StepRule {
            time_step_s: self.time_step_s,
            fine_radius: self.fine_radius,
            fine_step_fraction: self.fine_step_fraction,
        }
    }
}

/// Waypoints and settings, as a user gives them (validated by [`crate::Scenario::new`]).
#[derive(Clone, Debug, PartialEq)]
pub struct Mission<const W: usize> {
    /// Waypoints in order; the last is the target.
    pub waypoints: heapless::Vec<Waypoint, W>,
    /// Settings.
    pub settings: Settings,
}

impl<const W: usize> Mission<W> {
    /// A mission through `waypoints` with `settings`; fails if there are more than `W`.
    pub fn new(waypoints: &[Waypoint], settings: Settings) -> Result<Self, MissionError> {
        let waypoints = heapless::Vec::from_slice(waypoints)
            .map_err(|_| MissionError::TooManyWaypoints { capacity: W })?;
        Ok(Mission {
            waypoints,
            settings,
        })
    }
}
