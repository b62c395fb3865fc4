//! Progress and stall detection: the lowest `V` of the current waypoint and
//! the step it was reached; a dead end is no new low (by `stall_progress`)
//! within the window.

use crate::control::LawKind;
use crate::mission::Settings;

/// The lowest `V` so far and when.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Progress {
    best_v: f32,
    best_step: u32,
}

impl Progress {
    /// No `V` seen yet.
    pub const fn new() -> Self {
        Progress {
            best_v: f32::INFINITY,
            best_step: 0,
        }
    }

    /// A fresh window from `V = v` at `step` (a new waypoint, the end of an
    /// escape's leg, the start).
    pub fn restart(&mut self, v: f32, step: u32) {
        self.best_v = v;
        self.best_step = step;
    }

    /// Notes `V = v` after `step`: a new low when below the best by the
    /// relative `stall_progress`.
    pub fn observe(&mut self, v: f32, step: u32, stall_progress: f32) {
        if v < self.best_v * (1.0 - stall_progress) {
            self.best_v = v;
            self.best_step = step;
        }
    }

    /// Whether the law has made no progress for long enough to call it a
    /// dead end at `step`: the escape's window for the damped law, which
    /// converges in tens of steps; the stall window for the first-order
    /// laws, which creep (and for every law with escapes off). `lag()`
    /// steps are added to the window: a tracked arm's turnaround
    /// ([`crate::tracker::turnaround_ticks`]), in which `V` may rise while
    /// the drive catches up with a law that has turned; it is asked for
    /// only once the window itself has passed without progress.
    pub fn stalled(&self, settings: &Settings, step: u32, lag: impl FnOnce() -> u32) -> bool {
        let fast = settings.law.kind == LawKind::DampedLeastSquares;
        let window = if settings.escape.attempts > 0 && fast {
            settings.escape.window as u32
        } else {
            settings.stall_window
        };
        let waited = step - self.best_step;
        waited >= window && waited >= window.saturating_add(lag())
    }
}
