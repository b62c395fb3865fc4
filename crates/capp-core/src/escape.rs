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
//! 2. **Choose a walk**: [`CANDIDATES`] random joint configurations around the
//!    current one, each joint moved by up to `reach` (growing with the visits)
//!    of its range; a candidate that would approach the obstacles (`mu . dq >
//!    0`) is mirrored to move away from them. The one whose end effector makes
//!    the shortest detour to the target (current hand position to candidate
//!    to target: the path that costs the least motion time, which is what a
//!    user is judged on; the larger clearance is left to the projection) is
//!    taken, and the side of the blocking obstacle it passes is reported.
//! 3. **Walk** straight to it in joint space ([`crate::control::joint_space`]),
//!    every step checked like any other, for at most
//!    [`EscapeSettings::walk_steps`] steps or until it is reached or blocked.
//! 4. **Descend** again with the law. Progress below the best `V` carries on
//!    as normal; the next stall starts the next attempt.
//!
//! When the attempts are spent the planner walks back to the best
//! configuration it found (the lowest `V`) and ends `Stalled` there. Every
//! escape step costs a bounded amount: a walk step is a joint-space step;
//! choosing a walk adds [`CANDIDATES`] forward kinematics passes.

use crate::kinematics::{forward_kinematics, Frames};
use crate::math::{max, min, Vec3};
use crate::obstacle::Obstacle;
use crate::robot::Robot;

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

/// The escape budget and how walks are drawn.
#[derive(Clone, Copy, Debug, PartialEq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub struct EscapeSettings {
    /// Escape attempts per waypoint; 0 turns escapes off (a stall then ends
    /// the run after `stall_window` steps, as before).
    pub attempts: u8,
    /// Steps without a new low of `V` (by `stall_progress`) that make a dead
    /// end, at least 1.
    pub window: u16,
    /// Most steps of one walk, at least 1.
    pub walk_steps: u16,
    /// How far a first walk may move each joint, as a fraction of its range,
    /// in `(0, 1]`; later visits to the same dead end walk farther.
    pub reach: f32,
    /// Seed of the walks' generator (mixed with the start configuration).
    pub seed: u32,
}

impl Default for EscapeSettings {
    fn default() -> Self {
        EscapeSettings {
            attempts: 12,
            window: 40,
            walk_steps: 40,
            reach: 0.25,
            seed: 0x2545_F491,
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
    /// Walking away from a dead end.
    Walking {
        /// Which attempt (1-based).
        attempt: u8,
        /// The side of the blocking obstacle taken, if an obstacle blocked.
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
}

/// The escape's fixed-size state, for `N` joints.
#[derive(Clone, Debug)]
pub struct Escape<const N: usize> {
    rng: u32,
    state: EscapeState,
    /// The walk's goal (or the best configuration, when returning).
    goal: [f32; N],
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
}

impl<const N: usize> Escape<N> {
    /// Fresh state: nothing remembered, the generator seeded from `seed` and
    /// the bits of the start configuration `start`.
    pub fn new(seed: u32, start: &[f32]) -> Self {
        let mut escape = Escape {
            rng: 1,
            state: EscapeState::Descending { attempts: 0 },
            goal: [0.0; N],
            walked: 0,
            idle: 0,
            closest: f32::INFINITY,
            best_q: [0.0; N],
            best_v: f32::INFINITY,
            memory: [DeadEnd::default(); MEMORY],
            remembered: 0,
            next_slot: 0,
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
            walked,
            idle,
            closest,
            best_q,
            best_v,
            memory,
            remembered,
            next_slot,
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
    }

    /// A new waypoint: its dead ends and attempts start from nothing (the
    /// generator runs on).
    pub fn next_waypoint(&mut self, q: &[f32], v: f32) {
        self.state = EscapeState::Descending { attempts: 0 };
        self.remembered = 0;
        self.next_slot = 0;
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
            EscapeState::Descending { .. } => None,
            _ => Some(&self.goal),
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

    /// Uniform in `[-1, 1)` (xorshift32).
    fn uniform(&mut self) -> f32 {
        let mut x = self.rng;
        x ^= x << 13;
        x ^= x >> 17;
        x ^= x << 5;
        self.rng = x;
        (x >> 8) as f32 * (2.0 / (1u32 << 24) as f32) - 1.0
    }

    /// Remembers a dead end at `position` with `v`; returns how often the
    /// arm has now been there.
    fn remember(&mut self, position: Vec3, v: f32, reach: f32) -> u8 {
        let near = SAME_PLACE * reach;
        let count = (self.remembered as usize).min(MEMORY);
        for d in self.memory[..count].iter_mut() {
            if (d.position - position).norm_squared() <= near * near && v >= d.v * 0.99 {
                d.visits = d.visits.saturating_add(1);
                return d.visits;
            }
        }
        let slot = (self.next_slot as usize) % MEMORY;
        self.memory[slot] = DeadEnd {
            position,
            v,
            visits: 1,
        };
        self.next_slot = ((slot + 1) % MEMORY) as u8;
        self.remembered = (count + 1).min(MEMORY) as u8;
        1
    }

    /// The law stalled at `q` (frames `frames`, value `v`, obstacle gradient
    /// `mu`, closest pair's obstacle `blocking`), aiming at `target`. Starts
    /// the next walk and returns `true`, or, the attempts spent, starts the
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
        let visits = self.remember(hand, v, robot.reach());
        let reach = min(settings.reach * (1.0 + 0.5 * (visits as f32 - 1.0)), 1.0);
        let mut best = f32::INFINITY;
        let mut candidate = [0.0f32; N];
        for _ in 0..CANDIDATES {
            let mut toward = 0.0f32;
            for ((c, joint), m) in candidate
                .iter_mut()
                .zip(robot.joints())
                .zip(mu.iter().chain(core::iter::repeat(&0.0)))
            {
                let step = reach * self.uniform() * (joint.max - joint.min);
                *c = step;
                toward += m * step;
            }
            // Away from the obstacles, not into them.
            let sign = if toward > 0.0 { -1.0 } else { 1.0 };
            for ((c, joint), &qj) in candidate.iter_mut().zip(robot.joints()).zip(q) {
                *c = joint.clamp(qj + sign * *c);
            }
            forward_kinematics(robot, &candidate[..n], scratch);
            let end = scratch.end_position();
            let detour = (end - hand).norm() + (target - end).norm();
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
        self.start_walk(EscapeState::Walking {
            attempt: attempts + 1,
            side,
        });
        true
    }

    fn start_walk(&mut self, state: EscapeState) {
        self.state = state;
        self.walked = 0;
        self.idle = 0;
        self.closest = f32::INFINITY;
    }

    /// After a step of a walk (or of the return) that left the joints `gap`
    /// seconds (at the rate limits) from the goal: whether the walk is over
    /// (reached, blocked, or out of steps). A finished walk hands back to the
    /// law (`Descending`); a finished return is the end of the run.
    pub fn walked(&mut self, settings: &EscapeSettings, gap: f32, time_step_s: f32) -> bool {
        self.walked = self.walked.saturating_add(1);
        if gap < self.closest * 0.99 {
            self.closest = gap;
            self.idle = 0;
        } else {
            self.idle = self.idle.saturating_add(1);
        }
        let returning = self.state == EscapeState::Returning;
        let limit = if returning {
            settings.walk_steps.saturating_mul(2)
        } else {
            settings.walk_steps
        };
        let over = gap <= 0.01 * time_step_s || self.idle >= WALK_PATIENCE || self.walked >= limit;
        if over {
            if let EscapeState::Walking { attempt, .. } = self.state {
                self.state = EscapeState::Descending { attempts: attempt };
            }
        }
        over
    }
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
