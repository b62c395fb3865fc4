//! Which setting is out of range: the error every settings struct's
//! `validate` returns ([`crate::Settings`] aggregates them into
//! [`crate::MissionError::BadSetting`]). A leaf, so that each stage's
//! settings can check themselves without importing the mission.

/// `x` finite and above zero.
pub fn positive(x: f32) -> bool {
    x.is_finite() && x > 0.0
}

/// `x` finite and not below zero.
pub fn non_negative(x: f32) -> bool {
    x.is_finite() && x >= 0.0
}

/// The field of the first failed check, in order.
pub fn first_bad(checks: &[(bool, SettingsField)]) -> Result<(), SettingsField> {
    match checks.iter().find(|(ok, _)| !ok) {
        Some((_, field)) => Err(*field),
        None => Ok(()),
    }
}

/// Which setting an error is about.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub enum SettingsField {
    /// `time_step_s`
    TimeStep,
    /// `fine_radius`
    FineRadius,
    /// `fine_step_fraction`
    FineStepFraction,
    /// `position_tolerance`
    PositionTolerance,
    /// `orientation_tolerance`
    OrientationTolerance,
    /// `law.orientation_scale`
    OrientationScale,
    /// `law.approach_radius`
    ApproachRadius,
    /// `avoidance.joint_margin` or `avoidance.link_margin`
    Margin,
    /// `avoidance.points_per_link`
    PointsPerLink,
    /// `avoidance.influence_distance`
    InfluenceDistance,
    /// `avoidance.engage_clearance`
    EngageClearance,
    /// `avoidance.advance_fraction`
    AdvanceFraction,
    /// `law.damping`
    Damping,
    /// `escape.window`, `escape.walk_steps` or `escape.reach`
    Escape,
    /// `max_steps`
    MaxSteps,
    /// `stall_window`
    StallWindow,
    /// `stall_progress`
    StallProgress,
    /// `max_halvings`
    MaxHalvings,
}

impl core::fmt::Display for SettingsField {
    fn fmt(&self, f: &mut core::fmt::Formatter<'_>) -> core::fmt::Result {
        f.write_str(match self {
            SettingsField::TimeStep => "time_step_s must be positive and finite",
            SettingsField::FineRadius => "fine_radius must be non-negative and finite",
            SettingsField::FineStepFraction => "fine_step_fraction must be in (0, 1]",
            SettingsField::PositionTolerance => "position_tolerance must be positive and finite",
            SettingsField::OrientationTolerance => {
                "orientation_tolerance must be positive and finite"
            }
            SettingsField::OrientationScale => {
                "orientation_scale must be non-negative and at most 1e4"
            }
            SettingsField::ApproachRadius => "approach_radius must be non-negative and finite",
            SettingsField::Margin => "margins must be non-negative and at most 1e4",
            SettingsField::PointsPerLink => "points_per_link must be 1 to 8",
            SettingsField::InfluenceDistance => {
                "influence_distance must be positive and at most 1e4"
            }
            SettingsField::AdvanceFraction => "advance_fraction must be in (0, 1]",
            SettingsField::Damping => "damping must be positive and at most 1",
            SettingsField::Escape => {
                "escape: window and walk_steps must be at least 1, reach in (0, 1]"
            }
            SettingsField::EngageClearance => {
                "engage_clearance must be non-negative and at most 1e6"
            }
            SettingsField::MaxSteps => "max_steps must be at least 1",
            SettingsField::StallWindow => "stall_window must be at least 1",
            SettingsField::StallProgress => "stall_progress must be in [0, 1)",
            SettingsField::MaxHalvings => "max_halvings must be at most 16",
        })
    }
}
