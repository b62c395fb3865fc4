//! A joint's drive limits: rate, acceleration and jerk.

use crate::settings_field::positive;

/// Default time from rest to full rate at the acceleration limit, seconds:
/// `max_accel = max_rate / RAMP_TIME_S`.
pub const RAMP_TIME_S: f32 = 0.5;

/// Default time from zero to full acceleration at the jerk limit, seconds:
/// `max_jerk = max_accel / JERK_TIME_S`.
pub const JERK_TIME_S: f32 = 0.1;

/// Default control period, seconds.
pub const CONTROL_PERIOD_S: f32 = 0.05;

/// Longest control period accepted, seconds.
pub const MAX_CONTROL_PERIOD_S: f32 = 1.0;

/// One joint's limits. Units are the joint's: radians (revolute) or length
/// units (prismatic), per second, per second squared, per second cubed.
#[derive(Clone, Copy, Debug, PartialEq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub struct DriveLimits {
    /// Largest `|velocity|`, per second (the joint's `max_rate`).
    pub max_rate: f32,
    /// Largest `|acceleration|`, per second squared.
    pub max_accel: f32,
    /// Largest `|jerk|`, per second cubed.
    pub max_jerk: f32,
}

/// Which limit is bad.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub enum DriveLimitError {
    /// `max_rate` not finite or not positive.
    Rate,
    /// `max_accel` not finite or not positive.
    Accel,
    /// `max_jerk` not finite or not positive.
    Jerk,
    /// A control period outside `(0, MAX_CONTROL_PERIOD_S]`.
    Period,
}

impl DriveLimits {
    /// The defaults from a rate: full rate from rest in [`RAMP_TIME_S`],
    /// full acceleration from zero in [`JERK_TIME_S`].
    pub fn from_rate(max_rate: f32) -> Self {
        let max_accel = max_rate / RAMP_TIME_S;
        DriveLimits {
            max_rate,
            max_accel,
            max_jerk: max_accel / JERK_TIME_S,
        }
    }

    /// The time (seconds) to turn the joint from full rate one way to full
    /// rate the other at the limits: `2 max_rate / max_accel` at full
    /// acceleration, plus `max_accel / max_jerk` for the acceleration's own
    /// ramps (a trapezoidal acceleration).
    pub fn turnaround_s(&self) -> f32 {
        2.0 * self.max_rate / self.max_accel + self.max_accel / self.max_jerk
    }

    /// Every limit finite and positive.
    pub fn validate(&self) -> Result<(), DriveLimitError> {
        if !positive(self.max_rate) {
            Err(DriveLimitError::Rate)
        } else if !positive(self.max_accel) {
            Err(DriveLimitError::Accel)
        } else if !positive(self.max_jerk) {
            Err(DriveLimitError::Jerk)
        } else {
            Ok(())
        }
    }
}

/// A control period in `(0, MAX_CONTROL_PERIOD_S]` seconds.
pub fn validate_period(dt: f32) -> Result<(), DriveLimitError> {
    if positive(dt) && dt <= MAX_CONTROL_PERIOD_S {
        Ok(())
    } else {
        Err(DriveLimitError::Period)
    }
}
