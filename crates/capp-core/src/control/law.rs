//! One interface for every law: [`propose`] reads a [`LawInput`] and the
//! [`DriveGoal`] the escape and the waypoint choose, writes the joint rate
//! and returns a [`Proposal`] (how the rate was formed, whether the
//! obstacle projection constrained it, the step to try, whether `V` may
//! rise). The planner calls it once per step; the escape's search calls it
//! for its imagined steps. Adding a law: a module beside [`damped`] with a
//! function of the same shape, a [`LawKind`], a branch here
//! (`docs/extending.md`).

use crate::control::damped::{self, damped_rate};
use crate::control::first_order::{self, first_order_rate};
use crate::control::joint_space::joint_rate;
use crate::control::{LawInput, LawKind, Proposal};

/// What the law drives to this step.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum DriveGoal<'a> {
    /// The pose of `LawInput::error`'s target, by the law of
    /// [`crate::control::LawSettings::kind`].
    Pose,
    /// Straight in joint space to a joint-space waypoint's configuration
    /// ([`crate::control::joint_space`]); `V` may not rise unless the
    /// projection constrained the step.
    Joints(&'a [f32]),
    /// Straight in joint space along an escape's walk or its return
    /// ([`crate::escape`]): `V` may rise (it is leaving a dead end).
    Walk(&'a [f32]),
    /// Straight in joint space to the next node of a path the escape's
    /// search found ([`crate::escape::search`]): as [`DriveGoal::Walk`],
    /// but not projected against the obstacles' gradient. The search
    /// checked the edge clear; the projection would remove the part of it
    /// that runs toward a close obstacle or link, which stalls the walk
    /// where the path passes near one. Conservative advancement and the
    /// step's checks still bound every step.
    Path(&'a [f32]),
}

/// The buffers of both law families, side by side. One enum holding either
/// would take the larger one's room instead of the sum (928 B less for 32
/// joints), but switching its variant builds the new workspace on the stack
/// and moves it: 3.9 KB of stack in every function that inlines the switch,
/// the firmware's `Run` handler among them (its peak stack went from 5.0 to
/// 8.3 KB when the damped workspace grew by [`crate::control::saturation`]'s buffers). Side by
/// side, nothing is built but in place.
#[derive(Clone, Debug, Default)]
pub struct LawWorkspace<const N: usize> {
    /// [`LawKind::Gradient`] and [`LawKind::Paper`].
    pub first_order: first_order::FirstOrderWorkspace<N>,
    /// [`LawKind::DampedLeastSquares`].
    pub damped: damped::DampedWorkspace<N>,
}

impl<const N: usize> LawWorkspace<N> {
    /// Every buffer to zero, in place.
    pub fn clear(&mut self) {
        self.first_order.clear();
        self.damped.clear();
    }
}

/// The step of the law `goal` names for the arm of `input`: writes the
/// joint rate (per second, `robot.len()` values) into `rate`. Bounded work:
/// one O(n) pass per law, plus the damped law's 6 x 6 solve and at most
/// [`crate::control::saturation::MOST_HELD`] saturation rounds.
#[inline]
pub fn propose<const N: usize>(
    input: &LawInput<'_, N>,
    goal: DriveGoal<'_>,
    ws: &mut LawWorkspace<N>,
    rate: &mut [f32],
) -> Proposal {
    match goal {
        DriveGoal::Joints(goal) => joint_rate(input, goal, false, true, rate),
        DriveGoal::Walk(goal) => joint_rate(input, goal, true, true, rate),
        DriveGoal::Path(goal) => joint_rate(input, goal, true, false, rate),
        DriveGoal::Pose => match input.law.kind {
            LawKind::Gradient | LawKind::Paper => {
                first_order_rate(input, &mut ws.first_order, rate)
            }
            LawKind::DampedLeastSquares => damped_rate(input, &mut ws.damped, rate),
        },
    }
}
