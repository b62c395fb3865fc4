//! The planner: one [`Planner::step`] turns the current joint vector into the
//! next, following the paper's loop (Fig. 6a) with its open problems closed.
//!
//! One step:
//!
//! 1. pass every waypoint already within tolerance (the last one ends the run);
//! 2. `g_i = J_i^T e_i` from the current frames (eqs. 13-14, O(n));
//! 3. the weighted rate `M eps_hat` (eqs. 15, 18; see [`crate::control`]);
//! 4. the one-sided projection against the obstacle gradient (eq. 24, see
//!    [`crate::projection`]), then a uniform scale into the joints' rate limits;
//! 5. the step size `h` by the listing's rule: `h_max` far from the target,
//!    `|err / err_dot| h_max` when the last step's change would overshoot,
//!    `fine_step_fraction * h_max` within `fine_radius`; and at most
//!    `V / (G . qdot)`, the step that would remove all of `V` to first order;
//! 6. Euler integration `q' = clamp(q + h qdot)` (clamped into the limits) and a
//!    full evaluation of `q'` (frames, errors, potential gradient, clearance);
//! 7. acceptance: every avoidance point strictly outside every inflated
//!    obstacle, and, unless the projection constrained the motion, `V` not
//!    above its current value. Otherwise `h` is halved (at most `max_halvings`
//!    times); a step with no acceptable size is not taken (Euler overshoot is
//!    shortened, never taken);
//! 8. dead-end detection: `Stalled` when `V` has made no new low (by
//!    `stall_progress`) within `stall_window` steps; `Capped` at `max_steps`.
//!
//! The accepted evaluation is kept for the next step, so a step costs one
//! forward pass, one potential sweep and O(n) algebra, plus one more pass per
//! halving. Nothing allocates; the planner is a fixed-size value.

use crate::avoidance::{potential_gradient, Clearance, ObstacleField};
use crate::control::damped::damped_rate;
use crate::control::first_order::first_order_rate;
use crate::control::joint_space::{gap, joint_rate, joint_v};
use crate::control::{pose_error, Drive, LawKind, LawWorkspace, PoseError, Target};
use crate::escape::{Escape, EscapeState};
use crate::kinematics::{forward_kinematics, Frames};
use crate::math::{all_finite, norm};
use crate::mission::Settings;
use crate::projection::{strength, Guard};
use crate::robot::Robot;
use crate::scenario::Scenario;
use crate::step_size::advancement;

mod search;

/// Fraction of `engage_clearance` (in `C - 1`) below which a step may not
/// bring the closest pair closer: the arm stops short of resting on an
/// inflated surface (where `f32` rounding decides contact) instead of
/// creeping onto it in ever smaller steps.
pub const CONTACT_FLOOR: f32 = 0.01;

/// Pose error, as a fraction of the robot's reach, below which a stall is
/// `f32` rounding, not a dead end: no escape is tried.
pub const NUMERIC_FLOOR: f32 = 1.0e-5;

/// A detour's point counts as reached within this fraction of the reach.
pub const DETOUR_RADIUS: f32 = 0.01;

/// A joint goal is passed when the joints are within this fraction of a
/// time step of it at their rate limits.
pub const JOINT_GOAL_TOLERANCE: f32 = 0.05;

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
    /// `step` was given a scenario with another joint count than `new`.
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
            StartError::ScenarioMismatch => {
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

/// The error from `target` of the arm at `q` (frames `frames`): the pose
/// error (eqs. 11-12); for a joint goal, with `V` the joint-space distance
/// ([`joint_v`]).
fn target_error<const N: usize, const M: usize, const W: usize>(
    scenario: &Scenario<N, M, W>,
    frames: &Frames<N>,
    q: &[f32],
    target: &Target,
) -> PoseError {
    let mut e = pose_error(frames, target, scenario.settings().law.orientation_scale);
    if let Some(goal) = target.joints.and_then(|k| scenario.joint_goal(k)) {
        e.v = joint_v(scenario.robot(), q, goal);
    }
    e
}

/// Everything known about one configuration.
#[derive(Clone, Debug)]
struct Evaluation<const N: usize> {
    frames: Frames<N>,
    error: PoseError,
    mu: [f32; N],
    /// Per link, the square of a lower bound on its points' distance to any
    /// inflated obstacle.
    distance_sq: [f32; N],
    field: ObstacleField,
}

impl<const N: usize> Evaluation<N> {
    fn new() -> Self {
        Evaluation {
            frames: Frames::default(),
            error: PoseError::default(),
            mu: [0.0; N],
            distance_sq: [0.0; N],
            field: ObstacleField::default(),
        }
    }

    /// Every field to its initial value, in place.
    fn reset(&mut self) {
        // Every field is named: a field added to `Evaluation` fails to compile here.
        let Evaluation {
            frames,
            error,
            mu,
            distance_sq,
            field,
        } = self;
        *frames = Frames::default();
        *error = PoseError::default();
        mu.fill(0.0);
        distance_sq.fill(0.0);
        *field = ObstacleField::default();
    }

    /// `C - 1` of the closest pair within influence (infinity: none).
    fn closest(&self) -> f32 {
        self.field.clearance.map_or(f32::INFINITY, |c| c.value)
    }

    /// Whether a step may end here, coming from a configuration whose
    /// closest pair was at `c_from`: every point clear, and not creeping onto
    /// a surface (below `floor` the closest clearance may not shrink).
    fn safe_after(&self, c_from: f32, floor: f32) -> bool {
        let c = self.closest();
        self.field.clear && (c >= floor || c >= c_from)
    }

    fn evaluate<const M: usize, const W: usize>(
        &mut self,
        scenario: &Scenario<N, M, W>,
        q: &[f32],
        target: &Target,
    ) {
        let robot = scenario.robot();
        forward_kinematics(robot, q, &mut self.frames);
        self.error = target_error(scenario, &self.frames, q, target);
        self.field = potential_gradient(
            robot,
            &self.frames,
            scenario.obstacles(),
            &scenario.settings().avoidance,
            &mut self.mu,
            &mut self.distance_sq,
        );
    }
}

/// The evaluation of the current configuration (`now`) and of the candidate
/// (`next`), in two slots: accepting the candidate swaps their roles, not
/// their contents (an evaluation is some 700 bytes for PIPS).
#[derive(Clone, Debug)]
struct Evaluations<const N: usize> {
    slots: [Evaluation<N>; 2],
    /// The slot of `now` (0 or 1); `next` is the other.
    now: usize,
}

impl<const N: usize> Evaluations<N> {
    fn new() -> Self {
        Evaluations {
            slots: [Evaluation::new(), Evaluation::new()],
            now: 0,
        }
    }

    /// Both evaluations to their initial values, in place.
    fn reset(&mut self) {
        self.slots.iter_mut().for_each(Evaluation::reset);
        self.now = 0;
    }

    // `& 1`: the index is provably in bounds (no panic path).
    #[inline(always)]
    fn now(&self) -> &Evaluation<N> {
        &self.slots[self.now & 1]
    }

    #[inline(always)]
    fn now_mut(&mut self) -> &mut Evaluation<N> {
        &mut self.slots[self.now & 1]
    }

    #[inline(always)]
    fn next(&self) -> &Evaluation<N> {
        &self.slots[(self.now & 1) ^ 1]
    }

    #[inline(always)]
    fn next_mut(&mut self) -> &mut Evaluation<N> {
        &mut self.slots[(self.now & 1) ^ 1]
    }

    /// `(now, next)`, both writable.
    #[inline(always)]
    fn both_mut(&mut self) -> (&mut Evaluation<N>, &mut Evaluation<N>) {
        let [a, b] = &mut self.slots;
        if self.now & 1 == 0 {
            (a, b)
        } else {
            (b, a)
        }
    }

    /// The candidate becomes the current evaluation (and the old current
    /// one the slot the next candidate is evaluated into).
    #[inline(always)]
    fn accept(&mut self) {
        self.now ^= 1;
    }
}

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
    best_v: f32,
    best_step: u32,
    last: StepReport,
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
            best_v: f32::INFINITY,
            best_step: 0,
            last: StepReport {
                step: 0,
                time_step_s: 0.0,
                v: 0.0,
                position_error: 0.0,
                orientation_error: 0.0,
                clearance: None,
                phase: Phase::Done(Outcome::Stalled),
                constrained: false,
                halvings: 0,
                escape: EscapeState::Descending { attempts: 0 },
            },
        };
        planner.reset(&[]);
        planner
    }

    /// [`Planner::new`] in place: the same checks and the same plan (to the
    /// bit), without a planner-sized value on the stack. On error `self` is
    /// left as [`Planner::empty`].
    pub fn restart<const M: usize, const W: usize>(
        &mut self,
        scenario: &Scenario<N, M, W>,
        start: &[f32],
    ) -> Result<(), StartError> {
        let result = self.begin(scenario, start);
        if result.is_err() {
            self.clear();
        }
        result
    }

    /// Makes this planner [`Planner::empty`], in place.
    pub fn clear(&mut self) {
        self.reset(&[]);
    }

    fn begin<const M: usize, const W: usize>(
        &mut self,
        scenario: &Scenario<N, M, W>,
        start: &[f32],
    ) -> Result<(), StartError> {
        let robot = scenario.robot();
        let n = robot.len();
        if start.len() != n {
            return Err(StartError::WrongLength {
                given: start.len(),
                joints: n,
            });
        }
        if let Some(joint) = start.iter().position(|x| !x.is_finite()) {
            return Err(StartError::NotFinite { joint: joint as u8 });
        }
        if let Some(joint) = robot.first_outside_limits(start) {
            return Err(StartError::OutsideLimits { joint: joint as u8 });
        }
        self.reset(start);
        self.escape.reset(scenario.settings().escape.seed, start);
        // Scenario::new refuses a mission without waypoints, so this never fails.
        let Some(&target) = scenario.targets().first() else {
            return Err(StartError::ScenarioMismatch);
        };
        let n = self.n.min(N);
        self.evals
            .now_mut()
            .evaluate(scenario, &self.q[..n], &target);
        if !self.evals.now().field.clear {
            let c = self.evals.now().field.clearance.unwrap_or(Clearance {
                value: 0.0,
                point: 0,
                obstacle: 0,
            });
            return Err(StartError::InObstacle {
                point: c.point,
                obstacle: c.obstacle,
            });
        }
        self.best_v = self.evals.now().error.v;
        self.last = self.report(0.0, false, 0);
        Ok(())
    }

    /// Every field to its value at the start of a plan from `start` (at most
    /// `N` values; none: the empty planner), in place.
    fn reset(&mut self, start: &[f32]) {
        // Every field is named: a field added to `Planner` fails to compile here.
        let Planner {
            n,
            q,
            evals,
            q_next,
            rate,
            law,
            escape,
            step,
            phase,
            error_step,
            best_v,
            best_step,
            last,
        } = self;
        let len = start.len().min(N);
        *n = len;
        q.fill(0.0);
        q[..len].copy_from_slice(&start[..len]);
        evals.reset();
        *q_next = *q;
        rate.fill(0.0);
        law.clear();
        escape.reset(0, start);
        *step = 0;
        *phase = if len == 0 {
            Phase::Done(Outcome::Stalled)
        } else {
            Phase::Moving { waypoint: 0 }
        };
        *error_step = 0.0;
        *best_v = f32::INFINITY;
        *best_step = 0;
        *last = StepReport {
            step: 0,
            time_step_s: 0.0,
            v: 0.0,
            position_error: 0.0,
            orientation_error: 0.0,
            clearance: None,
            phase: *phase,
            constrained: false,
            halvings: 0,
            escape: EscapeState::Descending { attempts: 0 },
        };
    }

    /// The current joint vector (`n` values: radians or length units).
    pub fn joints(&self) -> &[f32] {
        &self.q[..self.n.min(N)]
    }

    /// The joint rate of the last step (per second), after projection and limits.
    pub fn rates(&self) -> &[f32] {
        &self.rate[..self.n.min(N)]
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

    /// Moves on past every waypoint within tolerance of the current pose.
    fn pass_waypoints<const M: usize, const W: usize>(&mut self, scenario: &Scenario<N, M, W>) {
        let settings = scenario.settings();
        let targets = scenario.targets();
        let n = self.n.min(N);
        while let Phase::Moving { waypoint } = self.phase {
            let Some(target) = targets.get(waypoint as usize) else {
                return;
            };
            let within = match target.joints.and_then(|k| scenario.joint_goal(k)) {
                // A joint goal: within a twentieth of a step of it.
                Some(goal) => {
                    gap(scenario.robot(), &self.q[..n], goal)
                        <= JOINT_GOAL_TOLERANCE * settings.time_step_s
                }
                None => {
                    // While detouring, `now.error` is the detour point's; the
                    // waypoint is judged by its own.
                    let e = match self.escape.subgoal() {
                        Some(_) => pose_error(
                            &self.evals.now().frames,
                            target,
                            settings.law.orientation_scale,
                        ),
                        None => self.evals.now().error,
                    };
                    e.position <= settings.position_tolerance
                        && (!e.has_orientation || e.orientation <= settings.orientation_tolerance)
                }
            };
            if !within {
                return;
            }
            let next = waypoint as usize + 1;
            if next >= targets.len() {
                self.phase = Phase::Done(Outcome::Reached);
                return;
            }
            self.phase = Phase::Moving {
                waypoint: next as u8,
            };
            if let Some(target) = targets.get(next) {
                self.evals.now_mut().error =
                    target_error(scenario, &self.evals.now().frames, &self.q[..n], target);
            }
            self.best_v = self.evals.now().error.v;
            self.best_step = self.step;
            self.error_step = 0.0;
            self.escape
                .next_waypoint(&self.q[..n], self.evals.now().error.v);
        }
    }

    /// Whether the law has made no progress for long enough to call it a
    /// dead end: the escape's window for the damped law, which converges in
    /// tens of steps; the stall window for the first-order laws, which creep
    /// (and for every law with escapes off).
    fn stalled(&self, settings: &Settings) -> bool {
        let fast = settings.law.kind == LawKind::DampedLeastSquares;
        let window = if settings.escape.attempts > 0 && fast {
            settings.escape.window as u32
        } else {
            settings.stall_window
        };
        self.step - self.best_step >= window
    }

    /// A dead end: escape, or (escapes off, or spent and back at the best
    /// configuration) end `Stalled`.
    fn on_stall<const M: usize, const W: usize>(
        &mut self,
        scenario: &Scenario<N, M, W>,
        target: &Target,
    ) {
        let settings = scenario.settings();
        // Within f32 noise of the target there is nothing to escape from.
        let noise = if target.joints.is_some() {
            NUMERIC_FLOOR // seconds, for a joint goal's V
        } else {
            NUMERIC_FLOOR * scenario.robot().reach()
        };
        // Farther from the base than the whole chain: no configuration
        // reaches it, so there is nothing to escape to.
        let out_of_reach = target.joints.is_none()
            && norm(&target.position) > scenario.robot().reach() + settings.position_tolerance;
        if settings.escape.attempts == 0
            || out_of_reach
            || self.evals.now().error.v <= 0.5 * noise * noise
        {
            self.phase = Phase::Done(Outcome::Stalled);
            return;
        }
        let n = self.n.min(N);
        let (now, next) = self.evals.both_mut();
        self.escape.on_stall(
            &settings.escape,
            scenario.robot(),
            scenario.obstacles(),
            &self.q[..n],
            &now.frames,
            now.error.v,
            &now.mu[..n],
            now.field.clearance.map(|c| c.obstacle),
            target.position,
            settings.avoidance.joint_margin,
            &mut next.frames,
        );
        // A detour begins: from now on `now.error` is its point's (the
        // configuration does not change until the next step; later steps
        // evaluate against the point).
        if let Some(point) = self.escape.subgoal() {
            self.evals.now_mut().error = pose_error(
                &self.evals.now().frames,
                &Target::pose(point, None),
                settings.law.orientation_scale,
            );
        }
    }

    /// After a step of a walk or a detour: is it over? A finished walk or
    /// detour hands back to the law (toward `target`) with a fresh stall
    /// window; a finished return ends `Stalled`.
    fn after_escape_step<const M: usize, const W: usize>(
        &mut self,
        scenario: &Scenario<N, M, W>,
        target: &Target,
    ) {
        let (settings, robot) = (scenario.settings(), scenario.robot());
        let n = self.n.min(N);
        let (gap, reached) = if let Some(point) = self.escape.subgoal() {
            let radius = DETOUR_RADIUS * robot.reach();
            (
                norm(&(point - self.evals.now().frames.end_position())),
                radius,
            )
        } else if let Some(goal) = self.escape.goal() {
            (
                gap(robot, &self.q[..n], &goal[..n]),
                0.1 * settings.time_step_s,
            )
        } else {
            return;
        };
        let returning = self.escape.state() == EscapeState::Returning;
        if self.escape.walked(&settings.escape, gap, reached) {
            if returning {
                self.phase = Phase::Done(Outcome::Stalled);
            }
            // Back to the target: its error, and a fresh stall window.
            self.evals.now_mut().error =
                target_error(scenario, &self.evals.now().frames, &self.q[..n], target);
            self.best_v = self.evals.now().error.v;
            self.best_step = self.step;
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
    ) -> Result<StepReport, StartError> {
        let robot: &Robot<N> = scenario.robot();
        if robot.len() != self.n {
            return Err(StartError::ScenarioMismatch);
        }
        // self.n <= N always; the `min` lets the optimiser drop the bounds checks.
        let n = self.n.min(N);
        let settings = *scenario.settings();
        self.pass_waypoints(scenario);
        let waypoint = match self.phase {
            Phase::Done(_) => {
                self.last = self.report(0.0, false, 0);
                return Ok(self.last);
            }
            Phase::Moving { waypoint } => waypoint as usize,
        };
        let Some(target) = scenario.targets().get(waypoint).copied() else {
            return Err(StartError::ScenarioMismatch);
        };
        if self.step >= settings.max_steps {
            self.phase = Phase::Done(Outcome::Capped);
            self.last = self.report(0.0, false, 0);
            return Ok(self.last);
        }
        // Searching for a path: the arm holds still while a slice of the
        // search runs; a path found is walked, else this attempt's walk.
        if matches!(self.escape.state(), EscapeState::Searching { .. }) {
            match self.search_slice(scenario, &target) {
                search::Slice::Working => {}
                search::Slice::Found => self.escape.follow(),
                search::Slice::Failed => self.escape.search_failed(),
            }
            self.step += 1;
            self.rate[..n].fill(0.0);
            if self.step >= settings.max_steps {
                self.phase = Phase::Done(Outcome::Capped);
            }
            self.last = self.report(0.0, false, 0);
            return Ok(self.last);
        }
        // What the law drives to: the target, or a detour's point beside the
        // obstacle that blocked it (position only).
        let detour = self.escape.subgoal();
        let drive_target = match detour {
            Some(point) => Target::pose(point, None),
            None => target,
        };

        // The law proposes a rate and a step (eqs. 13-18, 24).
        let engage = strength(
            self.evals.now().field.clearance.map(|c| c.value),
            settings.avoidance.engage_clearance,
        );
        let guard = Guard::at(
            &self.evals.now().mu[..n],
            self.evals.now().field.clearance.map(|c| c.value),
            settings.avoidance.engage_clearance,
            CONTACT_FLOOR,
        );
        let walking = self.escape.goal().is_some();
        let escaping = walking || detour.is_some();
        // Straight in joint space: an escape walk, or a joint goal.
        let joint_goal = match (self.escape.goal(), drive_target.joints) {
            (Some(goal), _) => Some(&goal[..n]),
            (None, Some(k)) => scenario.joint_goal(k),
            (None, None) => None,
        };
        let (drive, constrained, mut h) = match (joint_goal, settings.law.kind) {
            (Some(goal), _) => {
                let step = joint_rate(
                    robot,
                    &self.q[..n],
                    goal,
                    &guard,
                    settings.time_step_s,
                    &mut self.rate[..n],
                );
                (step.drive, step.constrained, settings.time_step_s)
            }
            (None, LawKind::Gradient | LawKind::Paper) => first_order_rate(
                robot,
                &self.evals.now().frames,
                &self.q[..n],
                &self.evals.now().error,
                &self.evals.now().mu[..n],
                engage,
                &settings,
                self.error_step,
                &mut self.law.first_order,
                &mut self.rate[..n],
            ),
            (None, LawKind::DampedLeastSquares) => {
                let step = damped_rate(
                    robot,
                    &self.evals.now().frames,
                    &self.q[..n],
                    &self.evals.now().error,
                    &guard,
                    &settings.law,
                    settings.time_step_s,
                    &mut self.law.damped,
                    &mut self.rate[..n],
                );
                (step.drive, step.constrained, settings.time_step_s)
            }
        };
        if !all_finite(&self.rate[..n]) {
            self.rate[..n].fill(0.0);
        }
        // A joint that would pass a limit within h stops at it: the step is
        // the straight segment to the clamped point, so every shorter step is
        // a part of it and stays within the limits.
        if h > 0.0 {
            for ((r, &qj), joint) in self.rate[..n]
                .iter_mut()
                .zip(&self.q[..n])
                .zip(robot.joints())
            {
                let end = joint.clamp(qj + h * *r);
                if end != qj + h * *r {
                    *r = (end - qj) / h;
                }
            }
        }
        let err = self.evals.now().error.position;
        // No point may travel farther than a fraction of its clearance.
        h = advancement(
            robot,
            &self.evals.now().frames,
            &self.evals.now().distance_sq[..n],
            self.evals.now().field.nearest.as_ref(),
            &self.rate[..n],
            h,
            settings.avoidance.advance_fraction,
        );

        // Integrate, evaluate, accept or halve.
        let mut halvings = 0;
        let mut accepted = false;
        if drive != Drive::Idle || constrained {
            loop {
                for j in 0..n {
                    let joint = &robot.joints()[j];
                    self.q_next[j] = joint.clamp(self.q[j] + h * self.rate[j]);
                }
                self.evals
                    .next_mut()
                    .evaluate(scenario, &self.q_next[..n], &drive_target);
                let floor = CONTACT_FLOOR * settings.avoidance.engage_clearance;
                let safe = self
                    .evals
                    .next()
                    .safe_after(self.evals.now().closest(), floor);
                // A walk may climb V: it is leaving a dead end.
                let descends =
                    constrained || walking || self.evals.next().error.v <= self.evals.now().error.v;
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

        // Progress and outcome.
        if escaping {
            self.after_escape_step(scenario, &target);
        } else {
            if self.evals.now().error.v < self.best_v * (1.0 - settings.stall_progress) {
                self.best_v = self.evals.now().error.v;
                self.best_step = self.step;
            }
            self.escape.record(&self.q[..n], self.evals.now().error.v);
        }
        self.pass_waypoints(scenario);
        if let Phase::Moving { .. } = self.phase {
            // A refused step left the state as it was, so the next one would
            // be refused the same way: a dead end now, not after the window.
            if !escaping && (!accepted || self.stalled(&settings)) {
                self.on_stall(scenario, &target);
            }
            if self.step >= settings.max_steps && !self.is_done() {
                self.phase = Phase::Done(Outcome::Capped);
            }
        }
        self.last = self.report(h, constrained, halvings);
        if self.escape.subgoal().is_some() {
            // Report the target's errors, not the detour point's.
            let e = pose_error(
                &self.evals.now().frames,
                &target,
                settings.law.orientation_scale,
            );
            self.last.v = e.v;
            self.last.position_error = e.position;
            self.last.orientation_error = e.orientation;
        }
        Ok(self.last)
    }

    /// Runs until done, calling `visit` after every step. Returns the outcome.
    pub fn run<const M: usize, const W: usize>(
        &mut self,
        scenario: &Scenario<N, M, W>,
        mut visit: impl FnMut(&Self, &StepReport),
    ) -> Result<Outcome, StartError> {
        loop {
            let report = self.step(scenario)?;
            visit(self, &report);
            if let Phase::Done(outcome) = report.phase {
                return Ok(outcome);
            }
        }
    }
}
