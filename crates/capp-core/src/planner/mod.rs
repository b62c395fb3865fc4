//! The planner: one [`Planner::step`] turns the current joint vector into the
//! next, following the paper's loop (Fig. 6a) with its open problems closed.
//! This module is the orchestrator; each policy lives in its own module:
//!
//! 1. **evaluate**: the current configuration's frames, pose error, obstacle
//!    gradient and clearances are kept from the last accepted step
//!    ([`crate::evaluation`]); waypoints within tolerance are passed
//!    (`planner/waypoints.rs`);
//! 2. **choose the drive goal**: the waypoint, or what the escape drives to
//!    (a detour's point, a walk's configuration; [`crate::escape`]). While
//!    the escape searches, the arm holds still and the step runs a slice of
//!    the search instead;
//! 3. **propose**: the law's rate, projected against the obstacles (eqs.
//!    13-18, 24), through one interface for every law
//!    ([`crate::control::law::propose`]);
//! 4. **bound**: within the joint limits, and no point travelling farther
//!    than its clearance allows (conservative advancement; `planner/motion.rs`);
//! 5. **accept or shorten**: Euler integration `q' = clamp(q + h qdot)`, a
//!    full evaluation of `q'`, accepted when every avoidance point is clear
//!    (and not creeping onto a surface) and `V` does not rise unless the
//!    proposal allows it; else `h` is halved, at most `max_halvings` times,
//!    and a step with no acceptable size is not taken;
//! 6. **account**: progress and stall detection (`planner/progress.rs`), the escape's
//!    bookkeeping, the outcome (`Reached`, `Stalled`, `Capped`).
//!
//! A step costs one forward pass, one potential sweep and O(n) algebra, plus
//! one more evaluation per halving (the search's slice: a fixed number of
//! evaluations). Nothing allocates; the planner is a fixed-size value.

mod motion;
mod progress;
mod report;
mod start;
mod tick;
mod waypoints;

pub use report::{Outcome, Phase, StartError, StepError, StepReport};

use crate::control::law::{propose, LawWorkspace};
use crate::control::{Drive, Proposal};
use crate::escape::search::Scratch;
use crate::escape::{worth_escaping, Escape, Leg, Stall};
use crate::evaluation::{target_error, Evaluations};
use crate::kinematics::Frames;
use crate::math::all_finite;
use crate::mission::Motion;
use crate::projection::CONTACT_FLOOR;
use crate::scenario::Scenario;
use crate::target::{pose_error, Target};
use crate::tracker::{turnaround_ticks, DriveState};
use progress::Progress;

/// The planner's mutable state: the joint vector and every buffer a step
/// needs, sized once for `N` joints. The model ([`Scenario`]) is passed to
/// each call, never stored.
#[derive(Clone, Debug)]
pub struct Planner<const N: usize> {
    n: usize,
    q: [f32; N],
    /// The evaluations of the current configuration and of the candidate.
    evals: Evaluations<N>,
    q_next: [f32; N],
    rate: [f32; N],
    /// The buffers of the law that runs.
    law: LawWorkspace<N>,
    /// The dead-end escape's state.
    escape: Escape<N>,
    step: u32,
    phase: Phase,
    /// Position error change over the last step (the listing's `error_step`).
    error_step: f32,
    /// The lowest `V` of the current waypoint and when: stall detection.
    progress: Progress,
    last: StepReport,
    /// Every joint's velocity and acceleration ([`Motion::Tracked`]).
    drive: DriveState<N>,
    /// The velocities the tracker moves toward this tick.
    velocity_target: [f32; N],
    /// The share of its velocity target the next tick's first candidate
    /// moves toward: the last taken share grown by its margin, or after a
    /// brake the last share tried, grown ([`Motion::Tracked`]).
    share: f32,
    /// How a tracked run that ended short of its target ends once the arm
    /// is at rest: until then every tick brakes ([`Motion::Tracked`]).
    ending: Option<Outcome>,
}

impl<const N: usize> Planner<N> {
    /// Starts a plan from `start` (one value per joint, within limits, every
    /// avoidance point outside every inflated obstacle).
    pub fn new<const M: usize, const W: usize>(
        scenario: &Scenario<N, M, W>,
        start: &[f32],
    ) -> Result<Self, StartError> {
        let mut planner = Self::empty();
        planner.restart(scenario, start)?;
        Ok(planner)
    }

    /// A planner with no joints and nothing to do (`Done`): a placeholder
    /// for a planner started in place by [`Planner::restart`] (a board keeps
    /// its workspace in a `static`). Stepping it changes nothing.
    pub fn empty() -> Self {
        let mut planner = Planner {
            n: 0,
            q: [0.0; N],
            evals: Evaluations::new(),
            q_next: [0.0; N],
            rate: [0.0; N],
            law: LawWorkspace::default(),
            escape: Escape::new(0, &[]),
            step: 0,
            phase: Phase::Done(Outcome::Stalled),
            error_step: 0.0,
            progress: Progress::new(),
            last: StepReport::at_start(Phase::Done(Outcome::Stalled)),
            drive: DriveState::at_rest(0),
            velocity_target: [0.0; N],
            share: 1.0,
            ending: None,
        };
        planner.reset(&[]);
        planner
    }

    /// The current joint vector (`n` values: radians or length units).
    pub fn joints(&self) -> &[f32] {
        &self.q[..self.n.min(N)]
    }

    /// The joint rate of the last step (per second), after projection and
    /// limits: with [`Motion::Tracked`], the joints' velocities.
    pub fn rates(&self) -> &[f32] {
        &self.rate[..self.n.min(N)]
    }

    /// The joints' velocities (per second) and accelerations (per second
    /// squared) after the last tick ([`Motion::Tracked`]; at rest
    /// throughout with [`Motion::Stepped`]).
    pub fn drive(&self) -> &DriveState<N> {
        &self.drive
    }

    /// Frames of the current configuration.
    pub fn frames(&self) -> &Frames<N> {
        &self.evals.now().frames
    }

    /// Current obstacle gradient `mu = dP/dq` (eq. 20).
    pub fn obstacle_gradient(&self) -> &[f32] {
        &self.evals.now().mu[..self.n.min(N)]
    }

    /// Current phase.
    pub fn phase(&self) -> Phase {
        self.phase
    }

    /// The report of the last step (or of the start).
    pub fn last_report(&self) -> &StepReport {
        &self.last
    }

    /// Whether the run has ended.
    pub fn is_done(&self) -> bool {
        matches!(self.phase, Phase::Done(_))
    }

    fn report(&self, h: f32, constrained: bool, halvings: u8) -> StepReport {
        StepReport {
            step: self.step,
            time_step_s: h,
            v: self.evals.now().error.v,
            position_error: self.evals.now().error.position,
            orientation_error: self.evals.now().error.orientation,
            clearance: self.evals.now().field.clearance,
            phase: self.phase,
            constrained,
            halvings,
            escape: self.escape.state(),
        }
    }

    /// Takes one planning step. Returns the report; a finished planner returns
    /// its final report again without moving.
    // Not inlined: the board's serving loop reaches it from two places, and
    // a copy of the step is 7 KiB of flash.
    #[inline(never)]
    pub fn step<const M: usize, const W: usize>(
        &mut self,
        scenario: &Scenario<N, M, W>,
    ) -> Result<StepReport, StepError> {
        if scenario.robot().len() != self.n {
            return Err(StepError::ScenarioMismatch);
        }
        // self.n <= N always; the `min` lets the optimiser drop the bounds checks.
        let n = self.n.min(N);
        // 1. Evaluate: the waypoints already within tolerance are passed.
        self.pass_waypoints(scenario);
        let Some(target) = self.active_target(scenario)? else {
            self.last = self.report(0.0, false, 0);
            return Ok(self.last);
        };
        if let Some(outcome) = self.ending {
            return Ok(self.ending_step(scenario, &target, outcome));
        }
        if self.escape.is_searching() {
            return Ok(self.search_step(scenario, &target));
        }
        // 2. The drive goal: the waypoint, a detour's point or a walk's goal.
        let escaping = self.escape.is_escaping();
        let (drive_target, goal) = self.escape.drive_goal(scenario, &target);
        // 3. Propose (eqs. 13-18, 24).
        let input = self
            .evals
            .now()
            .law_input(scenario, &self.q[..n], self.error_step);
        let proposal = propose(&input, goal, &mut self.law, &mut self.rate[..n]);
        let (accepted, h, halvings) = if scenario.settings().motion == Motion::Tracked {
            // 4-5. The tracker: a tick toward the rate whose stop is clear,
            // or a tick of the stop already cleared.
            let settle = self.settling(scenario, &target);
            self.tick(scenario, &drive_target, &proposal, settle)
        } else {
            // 4. Bound: the joint limits, conservative advancement.
            let h = motion::bound(
                scenario,
                self.evals.now(),
                &self.q[..n],
                &mut self.rate[..n],
                proposal.time_step_s,
            );
            // 5. Accept or shorten.
            self.take(scenario, &drive_target, &proposal, h)
        };
        // 6. Account: progress, the escape, the outcome.
        self.account(scenario, &target, escaping, accepted);
        self.last = self.report_step(scenario, &target, h, proposal.constrained, halvings);
        Ok(self.last)
    }

    /// Runs until done, calling `visit` after every step. Returns the outcome.
    pub fn run<const M: usize, const W: usize>(
        &mut self,
        scenario: &Scenario<N, M, W>,
        mut visit: impl FnMut(&Self, &StepReport),
    ) -> Result<Outcome, StepError> {
        loop {
            let report = self.step(scenario)?;
            visit(self, &report);
            if let Phase::Done(outcome) = report.phase {
                return Ok(outcome);
            }
        }
    }

    /// The active waypoint's target, or `None` when the run is over (done
    /// before, or the step cap reached now).
    fn active_target<const M: usize, const W: usize>(
        &mut self,
        scenario: &Scenario<N, M, W>,
    ) -> Result<Option<Target>, StepError> {
        let waypoint = match self.phase {
            Phase::Done(_) => return Ok(None),
            Phase::Moving { waypoint } => waypoint as usize,
        };
        let Some(&target) = scenario.targets().get(waypoint) else {
            return Err(StepError::ScenarioMismatch);
        };
        if self.step >= scenario.settings().max_steps {
            self.phase = Phase::Done(Outcome::Capped);
            return Ok(None);
        }
        Ok(Some(target))
    }

    /// A step of the escape's search: the arm holds still while a slice of
    /// it runs in the candidate's buffers.
    // Not inlined: cold, and out of the step's hot loops.
    #[inline(never)]
    fn search_step<const M: usize, const W: usize>(
        &mut self,
        scenario: &Scenario<N, M, W>,
        target: &Target,
    ) -> StepReport {
        let held = if scenario.settings().motion == Motion::Tracked {
            // The arm holds by braking to rest, in real time.
            self.brake(scenario, target);
            scenario.settings().time_step_s
        } else {
            0.0
        };
        let scratch = Scratch {
            next: self.evals.next_mut(),
            q: &mut self.q_next,
            rate: &mut self.rate,
            law: &mut self.law,
        };
        self.escape.search_step(scenario, target, scratch);
        self.step += 1;
        let n = self.n.min(N);
        self.rate[..n].fill(0.0);
        if scenario.settings().motion == Motion::Tracked {
            for (r, &v) in self.rate[..n].iter_mut().zip(self.drive.velocity()) {
                *r = v;
            }
            // An arm braked to rest within the final target's tolerance
            // has reached it: this tick's row says so (the next step would
            // say it in a row of no time, off the control period).
            self.pass_waypoints(scenario);
        } else {
            self.drive.record_step(&[], 0.0);
        }
        if self.step >= scenario.settings().max_steps && !self.is_done() {
            self.phase = Phase::Done(Outcome::Capped);
        }
        self.last = self.report(held, false, 0);
        self.last
    }

    /// Integrates the proposed rate over `h`, evaluates the candidate against
    /// `drive_target` and accepts it, or halves `h` and tries again (at most
    /// `max_halvings` times). Counts the step. Returns whether a step was
    /// taken, its size (0 if none) and the halvings.
    fn take<const M: usize, const W: usize>(
        &mut self,
        scenario: &Scenario<N, M, W>,
        drive_target: &Target,
        proposal: &Proposal,
        mut h: f32,
    ) -> (bool, f32, u8) {
        let (settings, robot) = (scenario.settings(), scenario.robot());
        let n = self.n.min(N);
        let err = self.evals.now().error.position;
        let floor = CONTACT_FLOOR * settings.avoidance.engage_clearance;
        let mut halvings = 0;
        let mut accepted = false;
        if proposal.drive != Drive::Idle || proposal.constrained {
            loop {
                motion::integrate(
                    robot,
                    &self.q[..n],
                    &self.rate[..n],
                    h,
                    &mut self.q_next[..n],
                );
                self.evals
                    .next_mut()
                    .evaluate(scenario, &self.q_next[..n], drive_target);
                let (now, next) = (self.evals.now(), self.evals.next());
                let safe = next.safe_after(now.closest(), floor);
                let descends = proposal.may_rise || next.error.v <= now.error.v;
                if safe && descends && all_finite(&self.q_next[..n]) {
                    accepted = true;
                    break;
                }
                if halvings >= settings.max_halvings {
                    break;
                }
                halvings += 1;
                h *= 0.5;
            }
        }
        self.step += 1;
        if accepted {
            self.evals.accept();
            self.q[..n].copy_from_slice(&self.q_next[..n]);
            self.error_step = self.evals.now().error.position - err;
        } else {
            h = 0.0;
            self.rate[..n].fill(0.0);
        }
        self.drive.record_step(&self.rate[..n], h);
        (accepted, h, halvings)
    }

    /// After a step: progress toward `target` (or the escape's leg), the
    /// waypoints passed, a dead end met, the step cap.
    fn account<const M: usize, const W: usize>(
        &mut self,
        scenario: &Scenario<N, M, W>,
        target: &Target,
        escaping: bool,
        accepted: bool,
    ) {
        let settings = scenario.settings();
        let n = self.n.min(N);
        if escaping {
            let leg = self
                .escape
                .after_step(scenario, &self.q[..n], &self.evals.now().frames);
            if leg == Leg::Returned {
                self.end(scenario, Outcome::Stalled);
            }
            if leg != Leg::Going {
                // Back to the target: its error, and a fresh stall window.
                self.retarget(scenario, target);
            }
        } else {
            let v = self.evals.now().error.v;
            self.progress.observe(v, self.step, settings.stall_progress);
            self.escape.record(&self.q[..n], v);
        }
        self.pass_waypoints(scenario);
        if let Phase::Moving { .. } = self.phase {
            // A refused step left the state as it was, so the next one would
            // be refused the same way: a dead end now, not after the window.
            // A tracked arm's `V` may rise while its velocity turns to
            // follow the law: the window waits that long too.
            let lag = || match settings.motion {
                Motion::Tracked => turnaround_ticks(scenario.drive_limits(), settings.time_step_s),
                Motion::Stepped => 0,
            };
            if !escaping && (!accepted || self.progress.stalled(settings, self.step, lag)) {
                self.on_stall(scenario, target);
            }
            if self.step >= settings.max_steps && !self.is_done() {
                self.phase = Phase::Done(Outcome::Capped);
            }
        }
    }

    /// Ends the run with `outcome`; a tracked arm still moving brakes to
    /// rest first, in real time ([`Planner::ending_step`]).
    fn end<const M: usize, const W: usize>(
        &mut self,
        scenario: &Scenario<N, M, W>,
        outcome: Outcome,
    ) {
        let tracked = scenario.settings().motion == Motion::Tracked;
        if !tracked || self.drive.is_at_rest(scenario.drive_limits(), 0.0) {
            self.phase = Phase::Done(outcome);
        } else {
            self.ending = Some(outcome);
        }
    }

    /// A tick of a tracked run that has ended short of `target`: the stop
    /// the last taken tick cleared; at rest the run is over with `outcome`
    /// (or reached, should the arm have stopped within tolerance).
    // Not inlined: cold, and out of the step's hot loops.
    #[inline(never)]
    fn ending_step<const M: usize, const W: usize>(
        &mut self,
        scenario: &Scenario<N, M, W>,
        target: &Target,
        outcome: Outcome,
    ) -> StepReport {
        // `brake` leaves the rates at the drive's velocities.
        self.brake(scenario, target);
        self.step += 1;
        self.pass_waypoints(scenario);
        if !self.is_done() && self.drive.is_at_rest(scenario.drive_limits(), 0.0) {
            self.phase = Phase::Done(outcome);
        }
        if self.is_done() {
            self.ending = None;
        } else if self.step >= scenario.settings().max_steps {
            self.phase = Phase::Done(Outcome::Capped);
            self.ending = None;
        }
        self.last = self.report_step(scenario, target, scenario.settings().time_step_s, false, 0);
        self.last
    }

    /// The current configuration's error from `target`, and a fresh stall
    /// window from it.
    fn retarget<const M: usize, const W: usize>(
        &mut self,
        scenario: &Scenario<N, M, W>,
        target: &Target,
    ) {
        let n = self.n.min(N);
        let now = self.evals.now_mut();
        now.error = target_error(scenario, &now.frames, &self.q[..n], target);
        self.progress.restart(now.error.v, self.step);
    }

    /// A dead end short of `target`: escape, or (nothing to escape from, or
    /// escapes off) end `Stalled`.
    // Not inlined: cold, and out of the step's hot loops.
    #[inline(never)]
    fn on_stall<const M: usize, const W: usize>(
        &mut self,
        scenario: &Scenario<N, M, W>,
        target: &Target,
    ) {
        let n = self.n.min(N);
        if !worth_escaping(scenario, target, self.evals.now().error.v) {
            self.end(scenario, Outcome::Stalled);
            return;
        }
        let (now, next) = self.evals.both_mut();
        let stall = Stall::at(&self.q[..n], now, target);
        self.escape.on_stall(scenario, &stall, &mut next.frames);
        // A detour begins: from now on `now.error` is its point's (the
        // configuration does not change until the next step; later steps
        // evaluate against the point).
        if let Some(point) = self.escape.subgoal() {
            let now = self.evals.now_mut();
            now.error = pose_error(
                &now.frames,
                &Target::pose(point, None),
                scenario.settings().law.orientation_scale,
            );
        }
    }

    /// Moves on past every waypoint within tolerance of the current pose.
    fn pass_waypoints<const M: usize, const W: usize>(&mut self, scenario: &Scenario<N, M, W>) {
        let targets = scenario.targets();
        let n = self.n.min(N);
        while let Phase::Moving { waypoint } = self.phase {
            let Some(target) = targets.get(waypoint as usize) else {
                return;
            };
            let now = self.evals.now();
            let detouring = self.escape.subgoal().is_some();
            if !waypoints::within(scenario, &self.q[..n], now, target, detouring) {
                return;
            }
            let next = waypoint as usize + 1;
            if next >= targets.len() && !self.at_rest(scenario) {
                // Tracked: the target is reached at rest; the tick settles.
                return;
            }
            if next >= targets.len() {
                self.phase = Phase::Done(Outcome::Reached);
                return;
            }
            self.phase = Phase::Moving {
                waypoint: next as u8,
            };
            if let Some(target) = targets.get(next) {
                let now = self.evals.now_mut();
                now.error = target_error(scenario, &now.frames, &self.q[..n], target);
            }
            let v = self.evals.now().error.v;
            self.progress.restart(v, self.step);
            self.error_step = 0.0;
            self.escape.next_waypoint(&self.q[..n], v);
        }
    }

    /// The report of a step that aimed at `target`: during a detour, the
    /// target's errors, not the detour point's.
    fn report_step<const M: usize, const W: usize>(
        &self,
        scenario: &Scenario<N, M, W>,
        target: &Target,
        h: f32,
        constrained: bool,
        halvings: u8,
    ) -> StepReport {
        let mut report = self.report(h, constrained, halvings);
        if self.escape.subgoal().is_some() {
            let e = pose_error(
                &self.evals.now().frames,
                target,
                scenario.settings().law.orientation_scale,
            );
            report.v = e.v;
            report.position_error = e.position;
            report.orientation_error = e.orientation;
        }
        report
    }
}
