//! What the planner reports: how a run ended ([`Outcome`]), where it is
//! ([`Phase`]), what one step did ([`StepReport`]), and why a plan could
//! not start ([`StartError`]) or a step not be taken ([`StepError`]).

use crate::avoidance::Clearance;
use crate::escape::EscapeState;

/// How a run ended.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub enum Outcome {
    /// The last waypoint was reached within tolerance.
    Reached,
    /// No progress in `V` over the stall window: a dead end, an unreachable
    /// target, or a target inside an obstacle.
    Stalled,
    /// The iteration cap was hit while still progressing.
    Capped,
}

/// Where the planner is.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub enum Phase {
    /// Driving toward the waypoint with this index.
    Moving {
        /// Active waypoint (0-based).
        waypoint: u8,
    },
    /// Finished.
    Done(Outcome),
}

/// Why a planner could not start, or could not take a step.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub enum StartError {
    /// The start vector's length is not the robot's joint count.
    WrongLength {
        /// Values given.
        given: usize,
        /// Joints of the robot.
        joints: usize,
    },
    /// A start value is NaN or infinite.
    NotFinite {
        /// The joint (0-based).
        joint: u8,
    },
    /// A start value is outside the joint's limits.
    OutsideLimits {
        /// The joint (0-based).
        joint: u8,
    },
    /// An avoidance point starts inside (or on) an inflated obstacle.
    InObstacle {
        /// Avoidance point id.
        point: u16,
        /// Obstacle index.
        obstacle: u8,
    },
    /// Two checked link capsules start in contact (self-collision).
    SelfCollision {
        /// The two links (0-based, the lower first).
        links: [u8; 2],
    },
    /// The scenario has no waypoint ([`crate::Scenario::new`] refuses
    /// such a mission, so a validated scenario never gives this).
    ScenarioMismatch,
}

impl core::fmt::Display for StartError {
    fn fmt(&self, f: &mut core::fmt::Formatter<'_>) -> core::fmt::Result {
        match *self {
            StartError::WrongLength { given, joints } => {
                write!(
                    f,
                    "start configuration has {given} values for {joints} joints"
                )
            }
            StartError::NotFinite { joint } => {
                write!(f, "start value of joint {} is not finite", joint as u32 + 1)
            }
            StartError::OutsideLimits { joint } => {
                write!(
                    f,
                    "start value of joint {} is outside its limits",
                    joint as u32 + 1
                )
            }
            StartError::InObstacle { point, obstacle } => write!(
                f,
                "start configuration puts avoidance point {point} inside obstacle {}",
                obstacle as u32 + 1
            ),
            StartError::SelfCollision { links: [a, b] } => write!(
                f,
                "start configuration puts link {} into link {} (self-collision)",
                a as u32 + 1,
                b as u32 + 1
            ),
            StartError::ScenarioMismatch => {
                write!(f, "the scenario has no waypoint")
            }
        }
    }
}

/// Why [`crate::Planner::step`] could not take a step.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub enum StepError {
    /// The scenario is not the one the planner was started with (another
    /// joint count, or fewer waypoints than the active one).
    ScenarioMismatch,
}

impl core::fmt::Display for StepError {
    fn fmt(&self, f: &mut core::fmt::Formatter<'_>) -> core::fmt::Result {
        match self {
            StepError::ScenarioMismatch => {
                write!(f, "the scenario does not match the planner's robot")
            }
        }
    }
}

/// What one step did, and where the arm now is.
#[derive(Clone, Copy, Debug, PartialEq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub struct StepReport {
    /// Steps taken so far (this one included).
    pub step: u32,
    /// Integration step used, seconds (0 when no step could be taken).
    pub time_step_s: f32,
    /// `V` of eq. 12 at the new configuration, for the active waypoint.
    pub v: f32,
    /// Position error, length units.
    pub position_error: f32,
    /// Orientation error (root sum square of the column errors).
    pub orientation_error: f32,
    /// Closest avoidance point / obstacle pair within influence.
    pub clearance: Option<Clearance>,
    /// Phase after this step (the active waypoint while moving).
    pub phase: Phase,
    /// Whether the obstacle projection changed the rate.
    pub constrained: bool,
    /// How many times the step was halved.
    pub halvings: u8,
    /// Whether the planner is escaping a dead end, and which attempt.
    pub escape: EscapeState,
}

impl StepReport {
    /// The report of a plan that has taken no step, in `phase`.
    pub const fn at_start(phase: Phase) -> Self {
        StepReport {
            step: 0,
            time_step_s: 0.0,
            v: 0.0,
            position_error: 0.0,
            orientation_error: 0.0,
            clearance: None,
            phase,
            constrained: false,
            halvings: 0,
            escape: EscapeState::Descending { attempts: 0 },
        }
    }
}
