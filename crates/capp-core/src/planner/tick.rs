//! The tracked step ([`Motion::Tracked`]): a fixed control period, each
//! joint within its rate, acceleration and jerk limits, and every tick's
//! stop cleared before the tick is taken ([`crate::tracker`]).
//!
//! 1. **Velocity target**: the law's rate, scaled to cover in one period
//!    the motion the law asked of its step (`rate h / dt`); slowed, all
//!    joints alike, so each joint can still stop within the law's remaining
//!    way (`|rate| arrival_s`, [`crate::control::Proposal::arrival_s`]):
//!    the braking approach that arrives at rest; and each joint slowed
//!    alone so it can stop before its limit. At the final target, within
//!    tolerance, the target is rest.
//! 2. **Candidates**: the tracker's next tick toward that target; a
//!    refused one is tried again, at most [`MAX_TRIES`] in all; the first
//!    starts from the last taken share, grown by the margin that tick left
//!    (`growth`). A joint whose stop would leave its range brakes instead.
//!    A candidate is taken when every joint's excursion (this tick's motion
//!    and the stop after it) keeps every link within its room
//!    ([`crate::tracker::clearance`]) and the configuration it reaches is
//!    clear and not creeping onto a surface. The next try after a refusal:
//!    * a link end whose stop would close on its obstacle's half-space, or
//!      a configuration creeping onto the closest obstacle: that point's
//!      approach is taken out of the target ([`slide`]), at three quarters
//!      of the speed reached;
//!    * otherwise a share of the speed the refused one reached
//!      ([`DriveState::reached_share`]): at most three quarters, and no
//!      more than the room it left allows ([`stop_margin`]).
//! 3. **Otherwise brake**: the next tick of the stop the last taken tick
//!    cleared (at rest: stay, and time runs). An arm at rest that could not
//!    move even at the least share ([`MIN_SHARE`]) is refused, and the
//!    planner treats it as a dead end, as a refused step; at a larger share
//!    it holds. The next tick starts from the last share tried, grown by a
//!    quarter, or from the share of the velocity target the drive still
//!    moves at after braking, whichever is larger.
//! 4. **Ending short of the target** (a dead end with nothing left to try,
//!    or the escape's return): the arm brakes to rest, tick by tick, before
//!    the run ends ([`Planner`]'s `ending_step`).

use super::Planner;
use crate::avoidance::surface_normal;
use crate::control::{Drive, Proposal};
use crate::evaluation::Evaluation;
use crate::math::{all_finite, min};
use crate::mission::Motion;
use crate::planner::waypoints;
use crate::projection::CONTACT_FLOOR;
use crate::scenario::Scenario;
use crate::target::Target;
use crate::tracker::clearance::{stop_margin, Approach};
use crate::tracker::profile::{braking_speed, stopping_span};
use crate::tracker::slide::slide;
use crate::tracker::{excursion_of, DriveState};

/// Most candidates a tick tries before braking.
const MAX_TRIES: usize = 3;

/// A refused candidate's margin ([`stop_margin`]) times this bounds the next
/// candidate's share of the last one's velocity target ...
const SHARE_BACKOFF: f32 = 0.9;

/// ... as does this: each try cuts it to three quarters at most (seeds
/// 1-5 of the suite: against halving, the same reach, 4-8 % less motion
/// time in the obstacle families).
const MAX_SHARE_STEP: f32 = 0.75;

/// After a tick that braked, the next tick's first candidate moves toward
/// this times the last share tried (at most all) of its velocity target:
/// near a surface the speed the room allows changes little from tick to
/// tick, and starting there spares the refused candidates (and the braking
/// between them) of starting at full. After a taken tick, the growth is
/// [`growth`] of its margin.
const SHARE_GROWTH: f32 = 1.25;

/// No candidate slower than this share of the velocity target is tried
/// (the tick brakes instead).
const MIN_SHARE: f32 = 1.0 / 1024.0;

/// A joint is at rest when its speed is below this fraction of its rate
/// limit (and its acceleration below this fraction of its limit).
pub const REST_FRACTION: f32 = 0.01;

/// How much faster than a taken tick (as a share of the velocity target)
/// the next tick's first candidate goes, from the taken tick's stop margin
/// `m` (at least 1): `sqrt(SHARE_BACKOFF m)`. A stop's travel grows between
/// linearly and quadratically with the speed, so this aims the next tick's
/// margin at about `1 / SHARE_BACKOFF` when the room stays: fast where there
/// is room, slowing a little as the room closes in, instead of speeding up
/// by a fixed factor until a refusal brakes the arm. From
/// [`crate::tracker::clearance::EXACT_MARGIN`] on, the true margin is only
/// known to be at least that (link pairs cleared by that much are left
/// out), so the growth may overshoot the room. It is not capped there (it was, at
/// 1.42x a tick): a share is only a velocity target, which the drive
/// approaches within its acceleration and jerk limits and the next
/// candidate's stop is checked, while a cap kept an arm that had slowed for
/// one close surface crawling for a second once the room came back (over
/// seeds 1-5 of the suite: 4-6 % less motion time near obstacles, see
/// README's figures).
fn growth(m: f32) -> f32 {
    crate::math::sqrt(SHARE_BACKOFF * m)
}

/// The arm's closest avoidance point and obstacle in `now` as an
/// [`Approach`]: the point, its link, and the direction in which its `C`
/// grows (eq. 25's gradient, normalised), to slide along when a candidate
/// would creep onto that obstacle (`None`: no obstacle within influence,
/// or the point on or inside its inflation).
fn closest_approach<const N: usize, const M: usize, const W: usize>(
    scenario: &Scenario<N, M, W>,
    now: &Evaluation<N>,
) -> Option<Approach> {
    let closest = now.field.clearance?;
    let (at, normal, _) = surface_normal(
        &now.frames,
        scenario.world(),
        &scenario.settings().avoidance,
        closest.point,
        closest.obstacle,
        None,
    )?;
    Some(Approach {
        link: at.link as usize,
        point: at.position,
        normal,
    })
}

impl<const N: usize> Planner<N> {
    /// Whether the arm is at rest ([`REST_FRACTION`]); always, with
    /// [`Motion::Stepped`].
    pub(super) fn at_rest<const M: usize, const W: usize>(
        &self,
        scenario: &Scenario<N, M, W>,
    ) -> bool {
        scenario.settings().motion != Motion::Tracked
            || self
                .drive
                .is_at_rest(scenario.drive_limits(), REST_FRACTION)
    }

    /// Whether the tick should come to rest: the final target is within
    /// tolerance.
    pub(super) fn settling<const M: usize, const W: usize>(
        &self,
        scenario: &Scenario<N, M, W>,
        target: &Target,
    ) -> bool {
        let n = self.n.min(N);
        let last = match self.phase {
            super::Phase::Moving { waypoint } => waypoint as usize + 1 >= scenario.targets().len(),
            super::Phase::Done(_) => true,
        };
        last && waypoints::within(
            scenario,
            &self.q[..n],
            self.evals.now(),
            target,
            self.escape.subgoal().is_some(),
        )
    }

    /// One tracked tick toward the law's `proposal` (its rate in
    /// `self.rate`), evaluated against `drive_target`; `settle`: toward
    /// rest. Counts the step. Returns whether the arm moved or was taken
    /// moving, the period (seconds) and the candidates refused.
    // Not inlined: the tracked branch of the step, apart from the stepped one.
    #[inline(never)]
    pub(super) fn tick<const M: usize, const W: usize>(
        &mut self,
        scenario: &Scenario<N, M, W>,
        drive_target: &Target,
        proposal: &Proposal,
        settle: bool,
    ) -> (bool, f32, u8) {
        let (settings, robot, limits) = (
            scenario.settings(),
            scenario.robot(),
            scenario.drive_limits(),
        );
        let n = self.n.min(N).min(limits.len());
        let dt = settings.time_step_s;
        self.step += 1;
        self.velocity_target(scenario, proposal, settle);
        let floor = CONTACT_FLOOR * settings.avoidance.engage_clearance;
        let fraction = settings.avoidance.advance_fraction;
        let mut refused = 0u8;
        let mut share = min(self.share, 1.0).max(MIN_SHARE);
        let mut aim = self.velocity_target;
        for _ in 0..MAX_TRIES {
            let mut target = aim;
            target[..n].iter_mut().for_each(|t| *t *= share);
            let mut next = self.drive.toward(limits, dt, &target[..n]);
            let mut travel = [0.0f32; N];
            self.keep_in_range(scenario, &mut next, &mut travel[..n]);
            let now = self.evals.now();
            let stop = stop_margin(
                robot,
                &now.frames,
                &now.distance_sq[..n],
                &now.planes[..n],
                &now.close_pairs,
                &next,
                &travel[..n],
                limits,
                dt,
                fraction,
            );
            let margin = stop.margin;
            if margin >= 1.0 {
                next.advance(&self.q[..n], dt, &mut self.q_next[..n]);
                self.clamp_next(scenario);
                self.evals
                    .next_mut()
                    .evaluate(scenario, &self.q_next[..n], drive_target);
                let (now, candidate) = (self.evals.now(), self.evals.next());
                if candidate.safe_after(now.closest(), floor) && all_finite(&self.q_next[..n]) {
                    // At most all of it (an infinite margin: no room bound).
                    self.share = min(share * growth(margin), 1.0);
                    self.commit(next);
                    return (true, dt, refused);
                }
                // Creeping onto the closest obstacle: slide along it.
                if let Some(approach) = closest_approach(scenario, now) {
                    slide(robot, limits, &now.frames, &approach, &mut aim[..n]);
                }
                share = next.reached_share(&aim[..n], share) * MAX_SHARE_STEP;
            } else {
                // A link end that would close on its half-space slides
                // along it instead, at three quarters of the speed.
                // Otherwise a stop's travel grows at least linearly with
                // the share, so the margin's share of this one is the most
                // that could fit (less what the current motion cannot shed
                // in one tick: the backoff), and each try cuts it by a
                // quarter at least.
                let slid = stop
                    .approach
                    .is_some_and(|a| slide(robot, limits, &now.frames, &a, &mut aim[..n]));
                let cut = if slid {
                    MAX_SHARE_STEP
                } else {
                    min(margin * SHARE_BACKOFF, MAX_SHARE_STEP)
                };
                share = next.reached_share(&aim[..n], share) * cut;
            }
            refused = refused.saturating_add(1);
            if share < MIN_SHARE {
                break;
            }
        }
        self.share = share * SHARE_GROWTH;
        // Brake: the stop the last tick cleared. An arm at rest whose
        // candidates were all refused holds this tick; it may still move at
        // the smaller share the next tick starts from, so it is a dead end
        // only once no share above the least may be tried.
        let moving = !self.drive.is_at_rest(limits, 0.0);
        self.brake(scenario, drive_target);
        // The next tick starts no slower than the drive still goes: the
        // tries may have been refused for the stop of the speed the drive
        // already had, which braking sheds, and a share cut far below it
        // would brake the arm to a crawl the room does not ask for.
        let going = self.drive.reached_share(&aim[..n], 1.0);
        self.share = crate::math::max(self.share, going);
        (moving || share >= MIN_SHARE, dt, refused)
    }

    /// A tick of the stop at the limits (nothing, at rest), evaluated
    /// against `target`.
    // Not inlined: the search's hold and the tick's fallback share it.
    #[inline(never)]
    pub(super) fn brake<const M: usize, const W: usize>(
        &mut self,
        scenario: &Scenario<N, M, W>,
        target: &Target,
    ) {
        let limits = scenario.drive_limits();
        let n = self.n.min(N).min(limits.len());
        if self.drive.is_at_rest(limits, 0.0) {
            self.rate[..n].fill(0.0);
            return;
        }
        let dt = scenario.settings().time_step_s;
        let next = self.drive.braking(limits, dt);
        next.advance(&self.q[..n], dt, &mut self.q_next[..n]);
        self.clamp_next(scenario);
        self.evals
            .next_mut()
            .evaluate(scenario, &self.q_next[..n], target);
        self.commit(next);
    }

    /// Takes the tick: its state, its configuration (evaluated in `next`).
    fn commit(&mut self, next: DriveState<N>) {
        let n = self.n.min(N);
        let err = self.evals.now().error.position;
        self.drive = next;
        self.evals.accept();
        self.q[..n].copy_from_slice(&self.q_next[..n]);
        for (r, &v) in self.rate[..n].iter_mut().zip(self.drive.velocity()) {
            *r = v;
        }
        self.error_step = self.evals.now().error.position - err;
    }

    /// `q_next` within the joint limits (a guard for rounding: the stop of
    /// every taken tick stays within them).
    fn clamp_next<const M: usize, const W: usize>(&mut self, scenario: &Scenario<N, M, W>) {
        let n = self.n.min(N);
        for (q, joint) in self.q_next[..n].iter_mut().zip(scenario.robot().joints()) {
            *q = joint.clamp(*q);
        }
    }

    /// The velocities the tick moves toward (module docs, 1), into
    /// `self.velocity_target`.
    fn velocity_target<const M: usize, const W: usize>(
        &mut self,
        scenario: &Scenario<N, M, W>,
        proposal: &Proposal,
        settle: bool,
    ) {
        let (settings, robot, limits) = (
            scenario.settings(),
            scenario.robot(),
            scenario.drive_limits(),
        );
        let n = self.n.min(N).min(limits.len());
        let dt = settings.time_step_s;
        let idle = settle || (proposal.drive == Drive::Idle && !proposal.constrained);
        let pace = if idle || dt.is_nan() || dt <= 0.0 {
            0.0
        } else {
            min(proposal.time_step_s / dt, 1.0)
        };
        let target = &mut self.velocity_target[..n];
        for (t, &r) in target.iter_mut().zip(&self.rate[..n]) {
            *t = r * pace;
        }
        // The braking approach: every joint alike, so the direction holds.
        if proposal.arrival_s.is_finite() && pace > 0.0 {
            let mut share = 1.0f32;
            for ((&t, &r), l) in target.iter().zip(&self.rate[..n]).zip(limits) {
                let speed = t.abs();
                let cap = braking_speed(r.abs() * proposal.arrival_s, l, dt);
                if cap < speed {
                    share = min(share, cap / speed);
                }
            }
            target.iter_mut().for_each(|t| *t *= share);
        }
        // Each joint stops before its limit.
        for ((t, (&q, joint)), l) in target
            .iter_mut()
            .zip(self.q[..n].iter().zip(robot.joints()))
            .zip(limits)
        {
            let room = if *t > 0.0 {
                joint.max - q
            } else {
                q - joint.min
            };
            let cap = braking_speed(room, l, dt);
            *t = t.min(cap).max(-cap);
        }
    }

    /// A joint whose stop from `next` would leave its range brakes instead
    /// (its stop from the current state was kept within it); each joint's
    /// excursion from the `next` that results into `travel`
    /// ([`DriveState::excursion`], from the same stopping spans).
    fn keep_in_range<const M: usize, const W: usize>(
        &self,
        scenario: &Scenario<N, M, W>,
        next: &mut DriveState<N>,
        travel: &mut [f32],
    ) {
        let limits = scenario.drive_limits();
        let n = self.n.min(N).min(limits.len());
        let dt = scenario.settings().time_step_s;
        for (j, (((joint, l), &q), out)) in scenario
            .robot()
            .joints()
            .iter()
            .zip(limits)
            .zip(&self.q[..n])
            .zip(travel.iter_mut())
            .enumerate()
        {
            let (Some(&v), Some(&a)) = (next.velocity().get(j), next.acceleration().get(j)) else {
                continue;
            };
            let end = q + v * dt;
            let mut span = stopping_span(v, a, l, dt);
            let mut speed = v;
            if end - span.0 < joint.min || end + span.1 > joint.max {
                next.brake_joint(j, &self.drive, l, dt);
                if let (Some(&v), Some(&a)) = (next.velocity().get(j), next.acceleration().get(j)) {
                    (span, speed) = (stopping_span(v, a, l, dt), v);
                }
            }
            *out = excursion_of(speed, span, dt);
        }
    }
}
