//! Which joint vectors become setpoints: the listing's `joints.dat` policy
//! (a line whenever the position error moved by more than 1.0 or the
//! orientation error by more than 0.1 since the last line, plus the start and
//! the end), or every `k`-th step.

use crate::planner::{Phase, StepReport};

/// A decimation policy.
#[derive(Clone, Copy, Debug, PartialEq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub enum SetpointFilter {
    /// Every `k`-th step (`k >= 1`; 0 is read as 1), plus the start and the end.
    Every(u32),
    /// The listing's: when the errors changed by more than these amounts.
    ErrorChange {
        /// Position error change, length units (listing: 1.0).
        position: f32,
        /// Orientation error change (listing: 0.1).
        orientation: f32,
    },
}

impl SetpointFilter {
    /// The listing's `joints.dat` thresholds.
    pub const LISTING: SetpointFilter = SetpointFilter::ErrorChange {
        position: 1.0,
        orientation: 0.1,
    };
}

/// Applies a [`SetpointFilter`] to a stream of step reports.
#[derive(Clone, Copy, Debug)]
pub struct Decimator {
    filter: SetpointFilter,
    last_position: f32,
    last_orientation: f32,
    started: bool,
}

impl Decimator {
    /// A decimator with `filter`.
    pub fn new(filter: SetpointFilter) -> Self {
        Decimator {
            filter,
            last_position: 0.0,
            last_orientation: 0.0,
            started: false,
        }
    }

    /// Whether the joint vector after `report` is a setpoint. The first report
    /// offered (the start) and any final one always are.
    pub fn offer(&mut self, report: &StepReport) -> bool {
        let emit = !self.started
            || matches!(report.phase, Phase::Done(_))
            || match self.filter {
                SetpointFilter::Every(k) => report.step.is_multiple_of(k.max(1)),
                SetpointFilter::ErrorChange {
                    position,
                    orientation,
                } => {
                    (self.last_position - report.position_error).abs() > position
                        || (self.last_orientation - report.orientation_error).abs() > orientation
                }
            };
        if emit {
            self.started = true;
            self.last_position = report.position_error;
            self.last_orientation = report.orientation_error;
        }
        emit
    }
}
