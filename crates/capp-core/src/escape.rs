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
//!    imagination ([`crate::tree`]) looks for a goal configuration and a
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

use crate::kinematics::{forward_kinematics, Frames};
use crate::math::{max, min, norm, Vec3};
use crate::obstacle::Obstacle;
use crate::robot::{JointKind, Robot};
use crate::tree::Search;

/// Dead ends remembered per waypoint (a ring: the oldest is forgotten).
pub const MEMORY: usize = 8;
/// Walk candidates drawn at each attempt.
pub const CANDIDATES: usize = 4;
/// Detour points around a blocking obstacle (two axes across the blocked
/// direction, both ways).
pub const DETOURS: usize = 4;
/// An obstacle is detoured around only when its inflated bounding box is
/// smaller than this fraction of the robot's reach (a floor or a wall is
/// not gone round).
pub const DETOUR_SIZE: f32 = 0.5;
/// Two dead ends are the same place when their end-effector positions are
/// within this fraction of the robot's reach.
pub const SAME_PLACE: f32 = 0.02;
/// Steps a walk may go without getting closer to its goal before it counts
/// as blocked.
pub const WALK_PATIENCE: u16 = 5;

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
    /// Searches per waypoint ([`crate::tree`]): the first attempts that
    /// would walk search for a path first (the arm holding still), and walk
    /// it when one is found; 0 turns searches off.
    pub searches: u8,
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

/// Which side of the blocking obstacle an escape passes: the axis of the
/// obstacle's own frame along which the walk's end point is farthest out (in
/// units of its semi-axes), and the sign.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub struct Side {
    /// The obstacle (0-based).
    pub obstacle: u8,
    /// 0, 1, 2 for its x, y, z axis.
    pub axis: u8,
    /// Whether on the axis' positive side.
    pub positive: bool,
}

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
    /// ([`crate::tree`]); if none is found, the walk drawn for this attempt.
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
    rng: u32,
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
            rng: 1,
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
        // FNV-1a over the start's bits, then the seed; never zero (xorshift).
        let mut h: u32 = 0x811C_9DC5 ^ seed;
        for x in start {
            for b in x.to_bits().to_le_bytes() {
                h = (h ^ b as u32).wrapping_mul(0x0100_0193);
            }
        }
        *rng = if h == 0 { 0x9E37_79B9 } else { h };
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

    /// The current attempt's search ([`crate::tree`]).
    pub fn search_mut(&mut self) -> &mut Search<N> {
        &mut self.search
    }

    /// The search found its path ([`Search::path`]): walk it, node by node.
    pub fn follow(&mut self) {
        if let EscapeState::Searching { attempt, side } = self.state {
            self.start_walk(EscapeState::Following { attempt, side });
            self.path_at = 0;
            self.next_node();
        }
    }

    /// The search found nothing: the walk drawn for this attempt instead.
    pub fn search_failed(&mut self) {
        if let EscapeState::Searching { attempt, side } = self.state {
            self.start_walk(EscapeState::Walking { attempt, side });
        }
    }

    /// On to the next node of the path, if there is one.
    fn next_node(&mut self) -> bool {
        let next = self.path_at as usize + 1;
        match self.search.path().get(next) {
            Some(&i) => {
                self.path_at = next as u8;
                self.goal = *self.search.tree.node(i as usize);
                self.walked = 0;
                self.idle = 0;
                self.closest = f32::INFINITY;
                true
            }
            _ => false,
        }
    }

    /// Uniform in `[-1, 1)` (xorshift32).
    pub fn uniform(&mut self) -> f32 {
        let mut x = self.rng;
        x ^= x << 13;
        x ^= x >> 17;
        x ^= x << 5;
        self.rng = x;
        (x >> 8) as f32 * (2.0 / (1u32 << 24) as f32) - 1.0
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

    /// The law stalled at `q` (frames `frames`, value `v`, obstacle gradient
    /// `mu`, closest pair's obstacle `blocking`), aiming at `target`, the arm
    /// kept `margin` (length units) off the obstacles. Starts the next
    /// detour or walk and returns `true`, or, the attempts spent, starts the
    /// return to the best configuration and returns `false`. `scratch` is
    /// overwritten (forward kinematics of the candidates).
    #[allow(clippy::too_many_arguments)]
    pub fn on_stall(
        &mut self,
        settings: &EscapeSettings,
        robot: &Robot<N>,
        obstacles: &[Obstacle],
        q: &[f32],
        frames: &Frames<N>,
        v: f32,
        mu: &[f32],
        blocking: Option<u8>,
        target: Vec3,
        margin: f32,
        scratch: &mut Frames<N>,
    ) -> bool {
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
                    obstacle,
                    o,
                    hand,
                    target,
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
                let step = reach * self.uniform() * (joint.max - joint.min);
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

    /// After a step of a walk, a return or a detour that left it `gap` from
    /// its goal (seconds at the rate limits for walks, length units for a
    /// detour, whose goal counts as reached within `reached`): whether it is
    /// over (reached, blocked, or out of steps). A finished walk or detour
    /// hands back to the law (`Descending`); a finished return is the end of
    /// the run.
    pub fn walked(&mut self, settings: &EscapeSettings, gap: f32, reached: f32) -> bool {
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

/// Below this share of its average mobility the end effector counts as
/// unable to move along a direction (a planar arm out of its plane).
pub const IMMOBILE: f32 = 0.01;

/// Whether the end effector at `frames` can move along the unit direction
/// `u`: `|J_p^T u|^2` (what the joints can do along `u`) at least
/// [`IMMOBILE`] times its mean over directions, `trace(J_p J_p^T) / 3`. O(n).
fn mobile<const N: usize>(robot: &Robot<N>, frames: &Frames<N>, u: &Vec3) -> bool {
    let p = frames.end_position();
    let (mut along, mut total) = (0.0f32, 0.0f32);
    for (j, joint) in robot.joints().iter().enumerate().take(frames.len()) {
        let z = frames.axis(j);
        let column = match joint.kind {
            JointKind::Revolute => z.cross(&(p - frames.pivot(j))),
            JointKind::Prismatic => z,
        };
        let a = column.dot(u);
        along += a * a;
        total += column.dot(&column);
    }
    along >= IMMOBILE * total / 3.0
}

/// The `which`-th best (shortest) detour round `obstacle` (index `index`)
/// for a hand at `hand` aiming at `target`: a point `margin` plus 5 % of
/// `reach` outside the obstacle's inflated bounding box, beside it across
/// the blocked direction, on a side the hand can move toward (`mobile`); `None` for an obstacle too big to go round, or when fewer
/// than `which + 1` such points exist.
#[allow(clippy::too_many_arguments)]
fn detour(
    obstacle: &Obstacle,
    index: u8,
    hand: Vec3,
    target: Vec3,
    which: usize,
    reach: f32,
    margin: f32,
    mobile: impl Fn(&Vec3) -> bool,
) -> Option<(Vec3, Side)> {
    let axes = obstacle.source().semi_axes;
    let rotation = obstacle.rotation();
    let size = libm::sqrtf(axes.iter().map(|a| a * a).sum::<f32>()) + margin;
    if size > DETOUR_SIZE * reach {
        return None;
    }
    let centre = obstacle.centre();
    let mut blocked = target - hand;
    if blocked.norm_squared() <= f32::MIN_POSITIVE {
        blocked = centre - hand;
    }
    let d = blocked / norm(&blocked);
    // Two directions across d: away from the world z axis unless d is it.
    let helper = if d.z.abs() < 0.9 {
        Vec3::z()
    } else {
        Vec3::x()
    };
    let across = d.cross(&helper);
    let e1 = across / norm(&across);
    let e2 = d.cross(&e1);
    let mut points = [(f32::INFINITY, Vec3::zeros()); DETOURS];
    for (k, slot) in points.iter_mut().enumerate() {
        let u = match k {
            0 => e1,
            1 => -e1,
            2 => e2,
            _ => -e2,
        };
        // Support of the inflated box in direction u.
        let local = rotation.transpose() * u;
        let extent: f32 = local
            .iter()
            .zip(axes)
            .map(|(l, a)| l.abs() * (a + margin))
            .sum();
        if !mobile(&u) {
            continue;
        }
        let point = centre + u * (extent + margin + 0.05 * reach);
        *slot = (norm(&(point - hand)) + norm(&(target - point)), point);
    }
    // The which-th shortest (a tiny selection sort over four).
    for i in 0..DETOURS {
        for j in i + 1..DETOURS {
            if points[j].0 < points[i].0 {
                points.swap(i, j);
            }
        }
    }
    let (length, point) = *points.get(which)?;
    length
        .is_finite()
        .then(|| (point, side_of(obstacle, index, point)))
}

/// The side of `obstacle` (index `index`) that `point` is on.
fn side_of(obstacle: &Obstacle, index: u8, point: Vec3) -> Side {
    let x = obstacle.rotation().transpose() * (point - obstacle.centre());
    let axes = obstacle.source().semi_axes;
    let (mut axis, mut far, mut positive) = (0u8, f32::NEG_INFINITY, true);
    for (i, (&xi, a)) in x.iter().zip(axes).enumerate() {
        let u = xi.abs() / max(a, f32::MIN_POSITIVE);
        if u > far {
            (axis, far, positive) = (i as u8, u, xi >= 0.0);
        }
    }
    Side {
        obstacle: index,
        axis,
        positive,
    }
}
