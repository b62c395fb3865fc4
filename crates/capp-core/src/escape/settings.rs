//! The escape's budget and how its walks are drawn: a leaf, so the
//! mission's settings can hold it without importing the escape.

use crate::settings_field::{first_bad, positive, SettingsField};

/// The escape budget and how walks are drawn.
#[derive(Clone, Copy, Debug, PartialEq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub struct EscapeSettings {
    /// Escape attempts per waypoint; 0 turns escapes off (a stall then ends
    /// the run after `stall_window` steps, as before).
    pub attempts: u8,
    /// Steps without a new low of `V` (by `stall_progress`) that make a dead
    /// end under the damped law, at least 1 (the first-order laws, which
    /// creep, use `stall_window`).
    pub window: u16,
    /// Most steps of one walk, at least 1.
    pub walk_steps: u16,
    /// How far a first walk may move each joint, as a fraction of its range,
    /// in `(0, 1]`; later visits to the same dead end walk farther.
    pub reach: f32,
    /// Seed of the walks' generator (mixed with the start configuration).
    pub seed: u32,
    /// Searches per waypoint ([`crate::escape::search`]): the first attempts that
    /// would walk search for a path first (the arm holding still), and walk
    /// it when one is found; 0 turns searches off.
    pub searches: u8,
}

impl EscapeSettings {
    /// Checks each value's range.
    pub fn validate(&self) -> Result<(), SettingsField> {
        first_bad(&[(
            self.window >= 1 && self.walk_steps >= 1 && positive(self.reach) && self.reach <= 1.0,
            SettingsField::Escape,
        )])
    }
}

impl Default for EscapeSettings {
    fn default() -> Self {
        EscapeSettings {
            attempts: 64,
            window: 20,
            walk_steps: 200,
            reach: 0.5,
            seed: 0x2545_F491,
            searches: 4,
        }
    }
}
