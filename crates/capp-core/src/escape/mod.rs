//! What happens at a dead end: the planner escapes and carries on, in the
//! manner of the randomized potential planner (Barraquand and Latombe), with
//! fixed-size state and a seeded generator, so the board and the host escape
//! the same way to the bit.
//!
//! A dead end is where the law stops making progress (`V` makes no new low
//! by `stall_progress` in [`EscapeSettings::window`] steps) short of the
//! target: the arm pressed against an obstacle it cannot pass by descent, a
//! joint at its limit, a local minimum of `V`. Then, up to
//! [`EscapeSettings::attempts`] times per waypoint:
//!
//! 1. **Remember** the dead end (end-effector position and `V`) in a memory of
//!    [`MEMORY`] entries. Stalling again where one was remembered (the end
//!    effector within [`SAME_PLACE`] of the robot's reach, `V` no lower) is
//!    falling back into it: the walks from there grow longer.
//! 2. **Detour** (the first tries at each dead end): when an obstacle of a
//!    size comparable to the arm blocks (the closest pair's), the end
//!    effector is sent to a point beside it: [`DETOURS`] points just outside
//!    its inflated bounding box, across the direction from the hand to the
//!    target, taken in order of the detour they make (hand to point to
//!    target: the shortest first, since it costs the least motion time,
//!    which is what a user is judged on; clearance is the projection's job).
//!    The law drives there as to any target (position only), for at most
//!    [`EscapeSettings::walk_steps`] steps, then turns back to the target.
//! 3. **Search** (the first [`EscapeSettings::searches`] attempts of a
//!    waypoint that would walk): the arm holds still while a search in
//!    imagination ([`crate::escape::search`]) looks for a goal configuration and a
//!    tree to it; a path found is walked node by node
//!    ([`EscapeState::Following`]), else the walk below is.
//! 4. **Walk** (once the detours are spent, or with no such obstacle):
//!    [`CANDIDATES`] random joint configurations around the current one, each
//!    joint moved by up to `reach` (growing with the visits) of its range; a
//!    candidate that would approach the obstacles (`mu . dq > 0`) is mirrored
//!    to move away from them. The one whose end effector makes the shortest
//!    detour to the target is taken, and walked to straight in joint space
//!    ([`crate::control::joint_space`]), every step checked like any other,
//!    for at most [`EscapeSettings::walk_steps`] steps or until it is reached
//!    or blocked.
//! 5. **Descend** again with the law. Progress below the best `V` carries on
//!    as normal; the next stall starts the next attempt.
//!
//! Either way the report names the side of the blocking obstacle taken.
//!
//! When the attempts are spent the planner walks back, straight in joint
//! space, toward the best configuration it found (the lowest `V`) and ends
//! `Stalled` when it gets there, or where the return is blocked (an arm
//! pressed against an obstacle may not get all the way back: the report
//! and `capp run`'s summary say which). Every
//! escape step costs a bounded amount: a walk step is a joint-space step;
//! choosing a walk adds [`CANDIDATES`] forward kinematics passes.

pub mod detour;
pub mod rng;
pub mod search;
pub mod settings;
pub mod tree;

pub use detour::Side;
pub use settings::EscapeSettings;

use crate::control::joint_space::gap;
use crate::control::law::DriveGoal;
use crate::evaluation::Evaluation;
use crate::kinematics::{forward_kinematics, Frames};
use crate::math::{min, norm, Vec3};
use crate::scenario::Scenario;
use crate::target::Target;
use detour::{detour, mobile, side_of, DETOURS};
use rng::Rng;
use search::{Scratch, Search, Slice};

/// Dead ends remembered per waypoint (a ring: the oldest is forgotten).
pub const MEMORY: usize = 8;
/// Walk candidates drawn at each attempt.
pub const CANDIDATES: usize = 4;
/// Two dead ends are the same place when their end-effector positions are
/// within this fraction of the robot's reach.
pub const SAME_PLACE: f32 = 0.02;
/// Steps a walk may go without getting closer to its goal before it counts
/// as blocked.
pub const WALK_PATIENCE: u16 = 5;
/// Pose error, as a fraction of the robot's reach, below which a stall is
/// `f32` rounding, not a dead end: no escape is tried.
pub const NUMERIC_FLOOR: f32 = 1.0e-5;
/// A detour's point counts as reached within this fraction of the reach.
pub const DETOUR_RADIUS: f32 = 0.01;

/// What the escape is doing, for the step report and the board's status.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub enum EscapeState {
    /// Not escaping: the law drives (the count of attempts made so far).
    Descending {
        /// Attempts made for the current waypoint.
        attempts: u8,
    },
    /// Sending the end effector round the blocking obstacle.
    Detouring {
        /// Which attempt (1-based).
        attempt: u8,
        /// The side of the blocking obstacle taken.
        side: Side,
    },
    /// Walking away from a dead end.
    Walking {
        /// Which attempt (1-based).
        attempt: u8,
        /// The side of the blocking obstacle taken, if an obstacle blocked.
        side: Option<Side>,
    },
    /// Searching for a path in imagination, the arm holding still
    /// ([`crate::escape::search`]); if none is found, the walk drawn for this attempt.
    Searching {
        /// Which attempt (1-based).
        attempt: u8,
        /// The side of the blocking obstacle the fallback walk takes, if an
        /// obstacle blocked.
        side: Option<Side>,
    },
    /// Walking the path the search found, node by node.
    Following {
        /// Which attempt (1-based).
        attempt: u8,
        /// The side of the blocking obstacle the fallback walk would have
        /// taken, if an obstacle blocked.
        side: Option<Side>,
    },
    /// The attempts are spent: back to the best configuration, then `Stalled`.
    Returning,
}

/// Where the law stalled: the configuration, its frames, `V`, the obstacle
/// gradient `mu` (eq. 20), the closest pair's obstacle (the one blocking),
/// and the position of the target aimed at.
#[derive(Clone, Copy, Debug)]
pub struct Stall<'a, const N: usize> {
    /// The joint values.
    pub q: &'a [f32],
    /// Their frames.
    pub frames: &'a Frames<N>,
    /// `V` there.
    pub v: f32,
    /// The obstacle gradient there, one value per joint.
    pub mu: &'a [f32],
    /// The closest pair's obstacle, if any is within influence.
    pub blocking: Option<u8>,
    /// The target's position, length units.
    pub target: Vec3,
}

impl<'a, const N: usize> Stall<'a, N> {
    /// The stall at `q`, evaluated as `now`, short of `target`.
    pub fn at(q: &'a [f32], now: &'a Evaluation<N>, target: &Target) -> Self {
        let n = q.len().min(N);
        Stall {
            q,
            frames: &now.frames,
            v: now.error.v,
            mu: &now.mu[..n],
            blocking: now.field.clearance.map(|c| c.obstacle),
            target: target.position,
        }
    }
}

/// How a walk, a path, a return or a detour stands after a step.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Leg {
    /// Still under way.
    Going,
    /// Over (reached, blocked or out of steps): the law descends toward the
    /// waypoint again, with a fresh stall window.
    Over,
    /// The return to the best configuration is over: the run ends `Stalled`.
    Returned,
}

/// Whether a stall at `V = v` short of `target` is worth escaping: escapes
/// on, the target within the chain's reach (farther from the base than the
/// whole chain, no configuration reaches it), and `V` above `f32` noise
/// ([`NUMERIC_FLOOR`] of the reach; seconds for a joint goal's `V`).
pub fn worth_escaping<const N: usize, const M: usize, const W: usize>(
    scenario: &Scenario<N, M, W>,
    target: &Target,
    v: f32,
) -> bool {
    let settings = scenario.settings();
    let noise = if target.joints.is_some() {
        NUMERIC_FLOOR
    } else {
        NUMERIC_FLOOR * scenario.robot().reach()
    };
    let out_of_reach = target.joints.is_none()
        && norm(&target.position) > scenario.robot().reach() + settings.position_tolerance;
    !(settings.escape.attempts == 0 || out_of_reach || v <= 0.5 * noise * noise)
}

/// One remembered dead end.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
struct DeadEnd {
    position: Vec3,
    v: f32,
    visits: u8,
    /// Detours tried from here.
    detours: u8,
}

/// The escape's fixed-size state, for `N` joints.
#[derive(Clone, Debug)]
pub struct Escape<const N: usize> {
    rng: Rng,
    state: EscapeState,
    /// The walk's goal (or the best configuration, when returning).
    goal: [f32; N],
    /// The detour's point for the end effector.
    subgoal: Vec3,
    /// Steps of the current walk, and of those without progress.
    walked: u16,
    idle: u16,
    /// Closest the walk came to its goal (seconds at the rate limits).
    closest: f32,
    /// The lowest `V` of the current waypoint and where.
    best_q: [f32; N],
    best_v: f32,
    memory: [DeadEnd; MEMORY],
    remembered: u8,
    next_slot: u8,
    /// The search of the current attempt, and where the walk along its
    /// path is (a position in [`Search::path`]).
    search: Search<N>,
    searches: u8,
    path_at: u8,
}

impl<const N: usize> Escape<N> {
    /// Fresh state: nothing remembered, the generator seeded from `seed` and
    /// the bits of the start configuration `start`.
    pub fn new(seed: u32, start: &[f32]) -> Self {
        let mut escape = Escape {
            rng: Rng::seeded(0, &[]),
            state: EscapeState::Descending { attempts: 0 },
            goal: [0.0; N],
            subgoal: Vec3::zeros(),
            walked: 0,
            idle: 0,
            closest: f32::INFINITY,
            best_q: [0.0; N],
            best_v: f32::INFINITY,
            memory: [DeadEnd::default(); MEMORY],
            remembered: 0,
            next_slot: 0,
            search: Search::default(),
            searches: 0,
            path_at: 0,
        };
        escape.reset(seed, start);
        escape
    }

    /// [`Escape::new`] in place.
    pub fn reset(&mut self, seed: u32, start: &[f32]) {
        // Every field is named: a field added here fails to compile.
        let Escape {
            rng,
            state,
            goal,
            subgoal,
            walked,
            idle,
            closest,
            best_q,
            best_v,
            memory,
            remembered,
            next_slot,
            search,
            searches,
            path_at,
        } = self;
        *rng = Rng::seeded(seed, start);
        *state = EscapeState::Descending { attempts: 0 };
        goal.fill(0.0);
        *subgoal = Vec3::zeros();
        *walked = 0;
        *idle = 0;
        *closest = f32::INFINITY;
        let len = start.len().min(N);
        best_q.fill(0.0);
        best_q[..len].copy_from_slice(&start[..len]);
        *best_v = f32::INFINITY;
        memory.fill(DeadEnd::default());
        *remembered = 0;
        *next_slot = 0;
        search.clear();
        *searches = 0;
        *path_at = 0;
    }

    /// A new waypoint: its dead ends and attempts start from nothing (the
    /// generator runs on).
    pub fn next_waypoint(&mut self, q: &[f32], v: f32) {
        self.state = EscapeState::Descending { attempts: 0 };
        self.remembered = 0;
        self.next_slot = 0;
        self.searches = 0;
        self.best_v = v;
        let len = q.len().min(N);
        self.best_q[..len].copy_from_slice(&q[..len]);
    }

    /// What the escape is doing.
    pub fn state(&self) -> EscapeState {
        self.state
    }

    /// The goal of the current walk (or of the return), when there is one.
    pub fn goal(&self) -> Option<&[f32; N]> {
        match self.state {
            EscapeState::Walking { .. }
            | EscapeState::Following { .. }
            | EscapeState::Returning => Some(&self.goal),
            _ => None,
        }
    }

    /// The end effector's point of the current detour, when there is one.
    pub fn subgoal(&self) -> Option<Vec3> {
        match self.state {
            EscapeState::Detouring { .. } => Some(self.subgoal),
            _ => None,
        }
    }

    /// Notes a configuration the law reached with value `v` (keeps the best).
    pub fn record(&mut self, q: &[f32], v: f32) {
        if v < self.best_v {
            self.best_v = v;
            let len = q.len().min(N);
            self.best_q[..len].copy_from_slice(&q[..len]);
        }
    }

    /// Whether the arm is holding still while the search runs.
    pub fn is_searching(&self) -> bool {
        matches!(self.state, EscapeState::Searching { .. })
    }

    /// Whether a walk, a path, a return or a detour is under way (the law
    /// is not descending toward the waypoint).
    pub fn is_escaping(&self) -> bool {
        !matches!(
            self.state,
            EscapeState::Descending { .. } | EscapeState::Searching { .. }
        )
    }

    /// What the law drives to this step, aiming at the waypoint `target`:
    /// the target to evaluate against (a detour's point, position only, or
    /// `target`) and the law's goal (a walk's configuration, the waypoint's
    /// joint configuration, or the pose).
    pub fn drive_goal<'a, const M: usize, const W: usize>(
        &'a self,
        scenario: &'a Scenario<N, M, W>,
        target: &Target,
    ) -> (Target, DriveGoal<'a>) {
        let n = scenario.robot().len().min(N);
        if let Some(point) = self.subgoal() {
            return (Target::pose(point, None), DriveGoal::Pose);
        }
        let goal = match (self.goal(), target.joints) {
            (Some(goal), _) if matches!(self.state, EscapeState::Following { .. }) => {
                DriveGoal::Path(&goal[..n])
            }
            (Some(goal), _) => DriveGoal::Walk(&goal[..n]),
            (None, Some(k)) => scenario
                .joint_goal(k)
                .map_or(DriveGoal::Pose, DriveGoal::Joints),
            (None, None) => DriveGoal::Pose,
        };
        (*target, goal)
    }

    /// One planner step's slice of the search ([`search`]), aiming at
    /// `target`, imagined in the planner's `scratch` buffers (the arm holds
    /// still). A path found is then followed; a failed search walks the
    /// walk drawn for this attempt.
    pub fn search_step<const M: usize, const W: usize>(
        &mut self,
        scenario: &Scenario<N, M, W>,
        target: &Target,
        mut scratch: Scratch<'_, N>,
    ) {
        match search::slice(
            &mut self.search,
            &mut self.rng,
            scenario,
            target,
            &mut scratch,
        ) {
            Slice::Working => {}
            Slice::Found => self.follow(),
            Slice::Failed => self.search_failed(),
        }
    }

    /// The search found its path: walk it, node by node.
    fn follow(&mut self) {
        if let EscapeState::Searching { attempt, side } = self.state {
            self.start_walk(EscapeState::Following { attempt, side });
            self.path_at = 0;
            self.next_node();
        }
    }

    /// The search found nothing: the walk drawn for this attempt instead.
    fn search_failed(&mut self) {
        if let EscapeState::Searching { attempt, side } = self.state {
            self.start_walk(EscapeState::Walking { attempt, side });
        }
    }

    /// On to the next node of the path, if there is one.
    fn next_node(&mut self) -> bool {
        let next = self.path_at as usize + 1;
        match self.search.path_node(next) {
            Some(&node) => {
                self.path_at = next as u8;
                self.goal = node;
                self.walked = 0;
                self.idle = 0;
                self.closest = f32::INFINITY;
                true
            }
            _ => false,
        }
    }

    /// Remembers a dead end at `position` with `v`; returns its slot (whose
    /// `visits` counts how often the arm has now been there).
    fn remember(&mut self, position: Vec3, v: f32, reach: f32) -> usize {
        let near = SAME_PLACE * reach;
        let count = (self.remembered as usize).min(MEMORY);
        for (i, d) in self.memory[..count].iter_mut().enumerate() {
            if (d.position - position).norm_squared() <= near * near && v >= d.v * 0.99 {
                d.visits = d.visits.saturating_add(1);
                return i;
            }
        }
        let slot = (self.next_slot as usize) % MEMORY;
        self.memory[slot] = DeadEnd {
            position,
            v,
            visits: 1,
            detours: 0,
        };
        self.next_slot = ((slot + 1) % MEMORY) as u8;
        self.remembered = (count + 1).min(MEMORY) as u8;
        slot
    }

    /// The law stalled (`at`): starts the next detour, search or walk and
    /// returns `true`, or, the attempts spent, starts the return to the best
    /// configuration and returns `false`. The arm is kept the avoidance's
    /// joint margin off the obstacles. `scratch` is overwritten (forward
    /// kinematics of the walk's candidates).
    pub fn on_stall<const M: usize, const W: usize>(
        &mut self,
        scenario: &Scenario<N, M, W>,
        at: &Stall<'_, N>,
        scratch: &mut Frames<N>,
    ) -> bool {
        let settings = &scenario.settings().escape;
        let (robot, obstacles) = (scenario.robot(), scenario.obstacles());
        let margin = scenario.settings().avoidance.joint_margin;
        let Stall {
            q,
            frames,
            v,
            mu,
            blocking,
            target,
        } = *at;
        let attempts = match self.state {
            EscapeState::Descending { attempts } => attempts,
            _ => return false,
        };
        let n = robot.len().min(q.len());
        let hand = frames.end_position();
        if attempts >= settings.attempts {
            self.goal[..n].copy_from_slice(&self.best_q[..n]);
            self.start_walk(EscapeState::Returning);
            return false;
        }
        let slot = self.remember(hand, v, robot.reach());
        let dead_end = self.memory.get(slot).copied().unwrap_or_default();
        // Round the blocking obstacle first, if it is one to go round.
        if let Some((o, obstacle)) = blocking.and_then(|o| Some((o, obstacles.get(o as usize)?))) {
            let tried = dead_end.detours as usize;
            if tried < DETOURS {
                let mobile = |u: &Vec3| mobile(robot, frames, u);
                if let Some((point, side)) = detour(
                    (obstacle, o),
                    (hand, target),
                    tried,
                    robot.reach(),
                    margin,
                    mobile,
                ) {
                    if let Some(d) = self.memory.get_mut(slot) {
                        d.detours += 1;
                    }
                    self.subgoal = point;
                    self.start_walk(EscapeState::Detouring {
                        attempt: attempts + 1,
                        side,
                    });
                    return true;
                }
            }
        }
        let visits = dead_end.visits.saturating_sub(dead_end.detours).max(1);
        let reach = min(settings.reach * (1.0 + 0.5 * (visits as f32 - 1.0)), 1.0);
        let mut best = f32::INFINITY;
        let mut candidate = [0.0f32; N];
        for _ in 0..CANDIDATES {
            let mut toward = 0.0f32;
            for (j, joint) in robot.joints().iter().enumerate() {
                let step = reach * self.rng.uniform() * (joint.max - joint.min);
                if let Some(c) = candidate.get_mut(j) {
                    *c = step;
                }
                toward += mu.get(j).copied().unwrap_or(0.0) * step;
            }
            // Away from the obstacles, not into them.
            let sign = if toward > 0.0 { -1.0 } else { 1.0 };
            for (j, (joint, &qj)) in robot.joints().iter().zip(q).enumerate() {
                if let Some(c) = candidate.get_mut(j) {
                    *c = joint.clamp(qj + sign * *c);
                }
            }
            forward_kinematics(robot, &candidate[..n], scratch);
            let end = scratch.end_position();
            let detour = norm(&(end - hand)) + norm(&(target - end));
            if detour < best {
                best = detour;
                self.goal[..n].copy_from_slice(&candidate[..n]);
            }
        }
        let side = blocking.and_then(|o| {
            let obstacle = obstacles.get(o as usize)?;
            forward_kinematics(robot, &self.goal[..n], scratch);
            Some(side_of(obstacle, o, scratch.end_position()))
        });
        if self.searches < settings.searches {
            // Search first (the arm holds still); this walk if nothing is found.
            self.searches += 1;
            self.search.begin(q, v);
            self.start_walk(EscapeState::Searching {
                attempt: attempts + 1,
                side,
            });
        } else {
            self.start_walk(EscapeState::Walking {
                attempt: attempts + 1,
                side,
            });
        }
        true
    }

    fn start_walk(&mut self, state: EscapeState) {
        self.state = state;
        self.walked = 0;
        self.idle = 0;
        self.closest = f32::INFINITY;
    }

    /// After a step of a walk, a path, a return or a detour that left the arm
    /// at `q` (frames `frames`): whether it is over, and how. A detour's
    /// point counts as reached within [`DETOUR_RADIUS`] of the reach; a
    /// walk's configuration within a tenth of a time step at the rate
    /// limits.
    pub fn after_step<const M: usize, const W: usize>(
        &mut self,
        scenario: &Scenario<N, M, W>,
        q: &[f32],
        frames: &Frames<N>,
    ) -> Leg {
        let (settings, robot) = (scenario.settings(), scenario.robot());
        let n = robot.len().min(N).min(q.len());
        let (gap, reached) = if let Some(point) = self.subgoal() {
            let radius = DETOUR_RADIUS * robot.reach();
            (norm(&(point - frames.end_position())), radius)
        } else if let Some(goal) = self.goal() {
            (gap(robot, &q[..n], &goal[..n]), 0.1 * settings.time_step_s)
        } else {
            return Leg::Going;
        };
        let returning = self.state == EscapeState::Returning;
        match (self.walked(&settings.escape, gap, reached), returning) {
            (false, _) => Leg::Going,
            (true, false) => Leg::Over,
            (true, true) => Leg::Returned,
        }
    }

    /// After a step of a walk, a return or a detour that left it `gap` from
    /// its goal (seconds at the rate limits for walks, length units for a
    /// detour, whose goal counts as reached within `reached`): whether it is
    /// over (reached, blocked, or out of steps). A finished walk or detour
    /// hands back to the law (`Descending`); a finished return is the end of
    /// the run.
    fn walked(&mut self, settings: &EscapeSettings, gap: f32, reached: f32) -> bool {
        self.walked = self.walked.saturating_add(1);
        // Progress: a tenth of the goal tolerance closer than ever before.
        if gap < self.closest - 0.1 * reached {
            self.closest = gap;
            self.idle = 0;
        } else {
            self.idle = self.idle.saturating_add(1);
        }
        let (limit, patience) = match self.state {
            // Back to the best configuration: as patient as a detour.
            EscapeState::Returning => (settings.walk_steps.saturating_mul(2), settings.window),
            // The law slows near the point; give it the stall window.
            EscapeState::Detouring { .. } => (settings.walk_steps, settings.window),
            _ => (settings.walk_steps, WALK_PATIENCE),
        };
        if gap <= reached && matches!(self.state, EscapeState::Following { .. }) && self.next_node()
        {
            return false;
        }
        let over = gap <= reached || self.idle >= patience || self.walked >= limit;
        if over {
            match self.state {
                EscapeState::Walking { attempt, .. }
                | EscapeState::Following { attempt, .. }
                | EscapeState::Detouring { attempt, .. } => {
                    self.state = EscapeState::Descending { attempts: attempt };
                }
                _ => {}
            }
        }
        over
    }
}

#[cfg(test)]
mod tests {
    //! The escape's state machine, step by step: which state each event
    //! leads to, and what the law is then driven to.
    use super::*;
    use crate::evaluation::Evaluation;
    use crate::mission::{Settings, Waypoint};
    use crate::obstacle::SuperEllipsoid;
    use crate::robot::{Joint, Robot};

    const N: usize = 4;
    type Planar = Scenario<N, 2, 2>;

    /// A planar 4-link arm (links of 1, reach 4) aiming at (3, 0, 0), with
    /// a small box (semi-axes 0.2) in the way at (2, 1, 0).
    fn scenario(escape: EscapeSettings) -> Planar {
        let joint = Joint::revolute(0.0, 1.0, 0.0, -3.0, 3.0, 1.0);
        let robot = Robot::new(&[joint; N]).unwrap();
        let settings = Settings {
            escape,
            ..Settings::for_robot(&robot)
        };
        let mission = crate::Mission::new(&[Waypoint::at([3.0, 0.0, 0.0])], settings).unwrap();
        let obstacle = SuperEllipsoid::aligned([2.0, 1.5, 0.0], [0.2; 3], 2.0);
        Scenario::new(robot, &[obstacle], &mission).unwrap()
    }

    /// The evaluation at `q` against the scenario's target.
    fn evaluated(sc: &Planar, q: &[f32]) -> Evaluation<N> {
        let mut e = Evaluation::new();
        e.evaluate(sc, q, &sc.targets()[0]);
        e
    }

    /// A stall at `q` (evaluated), `blocking` the obstacle said to block.
    fn stall(escape: &mut Escape<N>, sc: &Planar, q: &[f32], blocking: Option<u8>) -> bool {
        let now = evaluated(sc, q);
        let mut at = Stall::at(q, &now, &sc.targets()[0]);
        at.blocking = blocking;
        let mut scratch = Frames::default();
        escape.on_stall(sc, &at, &mut scratch)
    }

    const Q: [f32; N] = [0.6, 0.4, -0.3, 0.2];

    #[test]
    fn a_fresh_escape_descends_toward_the_waypoint() {
        let sc = scenario(EscapeSettings::default());
        let escape = Escape::<N>::new(1, &Q);
        assert_eq!(escape.state(), EscapeState::Descending { attempts: 0 });
        assert!(!escape.is_escaping() && !escape.is_searching());
        let target = sc.targets()[0];
        assert_eq!(escape.drive_goal(&sc, &target), (target, DriveGoal::Pose));
    }

    #[test]
    fn a_small_blocking_obstacle_is_detoured_and_the_detour_ends_at_its_point() {
        let sc = scenario(EscapeSettings::default());
        let mut escape = Escape::<N>::new(1, &Q);
        assert!(stall(&mut escape, &sc, &Q, Some(0)));
        let EscapeState::Detouring { attempt: 1, side } = escape.state() else {
            panic!("not detouring: {:?}", escape.state());
        };
        assert_eq!(side.obstacle, 0);
        let point = escape.subgoal().unwrap();
        // Outside the box inflated by the joint margin, in the arm's plane
        // (the arm cannot leave it, so no detour point may).
        let margin = sc.settings().avoidance.joint_margin;
        let off = point - Vec3::new(2.0, 1.5, 0.0);
        assert!(off.amax() > 0.2 + margin, "{point:?}");
        assert!(point.z.abs() < 1e-5, "{point:?}");
        let (aim, goal) = escape.drive_goal(&sc, &sc.targets()[0]);
        assert_eq!(
            (aim.position, aim.orientation, goal),
            (point, None, DriveGoal::Pose)
        );
        assert!(escape.is_escaping());
        // A step that does not reach the point: still going.
        let frames = evaluated(&sc, &Q).frames;
        assert_eq!(escape.after_step(&sc, &Q, &frames), Leg::Going);
        // The hand at the point: the detour is over, the law descends again.
        let mut at_point = frames.clone();
        let reached = escape_frames_at(&mut at_point, point);
        assert_eq!(escape.after_step(&sc, &Q, reached), Leg::Over);
        assert_eq!(escape.state(), EscapeState::Descending { attempts: 1 });
    }

    /// `frames` with the end effector moved to `p` (what `after_step` reads
    /// of a detour).
    fn escape_frames_at(frames: &mut Frames<N>, p: Vec3) -> &Frames<N> {
        let joint = Joint::revolute(0.0, 1.0, 0.0, -3.0, 3.0, 1.0);
        let robot = Robot::<N>::new(&[joint; N]).unwrap();
        // Solve the planar arm for p: the last link along the x axis from
        // (p.x - 1, p.y), the first three folded to reach it.
        let (x, y) = (p.x - 1.0, p.y);
        let r = crate::math::sqrt(x * x + y * y);
        // Three unit links reaching distance r along the direction to (x, y):
        // the middle one along it, the outer two at +-a with 2 cos a + 1 = r.
        let a = libm::acosf(((r - 1.0) / 2.0).clamp(-1.0, 1.0));
        let phi = libm::atan2f(y, x);
        let q = [phi + a, -a, -a, a - phi];
        forward_kinematics(&robot, &q, frames);
        assert!(
            (frames.end_position() - p).norm() < 1e-3,
            "{:?}",
            frames.end_position()
        );
        frames
    }

    #[test]
    fn with_nothing_to_go_round_the_first_attempts_search_and_a_failed_search_walks() {
        let sc = scenario(EscapeSettings::default());
        let mut escape = Escape::<N>::new(1, &Q);
        assert!(stall(&mut escape, &sc, &Q, None));
        assert!(matches!(
            escape.state(),
            EscapeState::Searching {
                attempt: 1,
                side: None
            }
        ));
        assert!(escape.is_searching() && !escape.is_escaping());
        // The walk drawn for this attempt, taken when the search fails.
        escape.search_failed();
        assert!(matches!(
            escape.state(),
            EscapeState::Walking {
                attempt: 1,
                side: None
            }
        ));
        let goal = *escape.goal().unwrap();
        assert_ne!(goal, Q);
        for (j, (&g, joint)) in goal.iter().zip(sc.robot().joints()).enumerate() {
            assert!(joint.min <= g && g <= joint.max, "joint {j}: {g}");
        }
        let (aim, drive) = escape.drive_goal(&sc, &sc.targets()[0]);
        assert_eq!((aim, drive), (sc.targets()[0], DriveGoal::Walk(&goal[..])));
        // At the walk's goal: over, and the law descends again.
        let frames = evaluated(&sc, &goal).frames;
        assert_eq!(escape.after_step(&sc, &goal, &frames), Leg::Over);
        assert_eq!(escape.state(), EscapeState::Descending { attempts: 1 });
    }

    /// A path the search found is driven to node by node as
    /// [`DriveGoal::Path`] (not projected: the search checked its edges),
    /// where a walk is [`DriveGoal::Walk`].
    #[test]
    fn a_found_path_is_driven_as_a_path_not_as_a_walk() {
        let sc = scenario(EscapeSettings::default());
        let mut escape = Escape::<N>::new(1, &Q);
        assert!(stall(&mut escape, &sc, &Q, None));
        assert!(escape.is_searching());
        escape.follow();
        assert!(matches!(
            escape.state(),
            EscapeState::Following { attempt: 1, .. }
        ));
        let goal = *escape.goal().unwrap();
        let (_, drive) = escape.drive_goal(&sc, &sc.targets()[0]);
        assert_eq!(drive, DriveGoal::Path(&goal[..]));
    }

    #[test]
    fn a_walk_with_no_progress_gives_up_after_its_patience() {
        let escape_settings = EscapeSettings {
            searches: 0,
            ..EscapeSettings::default()
        };
        let sc = scenario(escape_settings);
        let mut escape = Escape::<N>::new(1, &Q);
        assert!(stall(&mut escape, &sc, &Q, None));
        assert!(matches!(
            escape.state(),
            EscapeState::Walking { attempt: 1, .. }
        ));
        let frames = evaluated(&sc, &Q).frames;
        // The first step sets the closest gap; then WALK_PATIENCE steps
        // without getting closer end the walk.
        for _ in 0..WALK_PATIENCE {
            assert_eq!(escape.after_step(&sc, &Q, &frames), Leg::Going);
        }
        assert_eq!(escape.after_step(&sc, &Q, &frames), Leg::Over);
        assert_eq!(escape.state(), EscapeState::Descending { attempts: 1 });
    }

    #[test]
    fn spent_attempts_return_to_the_best_configuration_and_end_there() {
        let escape_settings = EscapeSettings {
            attempts: 1,
            searches: 0,
            ..EscapeSettings::default()
        };
        let sc = scenario(escape_settings);
        let mut escape = Escape::<N>::new(1, &Q);
        let best = [0.1, 0.2, 0.3, 0.4];
        escape.record(&best, 0.5);
        escape.record(&Q, 0.9); // higher: not the best
        assert!(stall(&mut escape, &sc, &Q, None));
        let frames = evaluated(&sc, &Q).frames;
        while escape.after_step(&sc, &Q, &frames) == Leg::Going {}
        assert_eq!(escape.state(), EscapeState::Descending { attempts: 1 });
        // The one attempt is spent: back to the best configuration.
        assert!(!stall(&mut escape, &sc, &Q, None));
        assert_eq!(escape.state(), EscapeState::Returning);
        assert_eq!(escape.goal(), Some(&best));
        let frames = evaluated(&sc, &best).frames;
        assert_eq!(escape.after_step(&sc, &best, &frames), Leg::Returned);
        // A new waypoint starts from nothing.
        escape.next_waypoint(&best, 0.5);
        assert_eq!(escape.state(), EscapeState::Descending { attempts: 0 });
    }

    #[test]
    fn escapes_are_worth_trying_only_when_on_within_reach_and_above_noise() {
        let on = scenario(EscapeSettings::default());
        let target = on.targets()[0];
        assert!(worth_escaping(&on, &target, 1.0));
        let off = scenario(EscapeSettings {
            attempts: 0,
            ..EscapeSettings::default()
        });
        assert!(!worth_escaping(&off, &target, 1.0));
        // Farther from the base than the whole chain (reach 4).
        let far = Target::pose(Vec3::new(5.0, 0.0, 0.0), None);
        assert!(!worth_escaping(&on, &far, 1.0));
        // Within f32 noise of the target.
        let noise = NUMERIC_FLOOR * on.robot().reach();
        assert!(!worth_escaping(&on, &target, 0.25 * noise * noise));
        assert!(worth_escaping(&on, &target, 2.0 * noise * noise));
    }
}
