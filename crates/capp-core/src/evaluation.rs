//! Everything known about one configuration: its frames, its error from
//! the target, the obstacle gradient and clearances; and the planner's two
//! slots of them (the current configuration and the candidate). The escape's
//! search evaluates its imagined configurations into the candidate slot.

use crate::avoidance::{potential_gradient, HalfSpace, ObstacleField};
use crate::control::joint_space::joint_v;
use crate::control::LawInput;
use crate::kinematics::{forward_kinematics, Frames};
use crate::scenario::Scenario;
use crate::self_collision::field::{link_pairs, ClosePairs, SelfField};
use crate::self_collision::INFLUENCE;
use crate::target::{pose_error, PoseError, Target};

/// The error from `target` of the arm at `q` (frames `frames`): the pose
/// error (eqs. 11-12); for a joint goal, with `V` the joint-space distance
/// ([`joint_v`]).
pub fn target_error<const N: usize, const M: usize, const W: usize>(
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
pub struct Evaluation<const N: usize> {
    /// Every frame of the chain (eqs. 5-6).
    pub frames: Frames<N>,
    /// The pose error from the target evaluated against (eqs. 11-12).
    pub error: PoseError,
    /// The obstacle gradient `mu = dP/dq` (eq. 20).
    pub mu: [f32; N],
    /// Per link, the square of its room for one step (length units
    /// squared): a lower bound on its points' distance to any inflated
    /// obstacle, and at most its share of the gap to every checked link
    /// ([`crate::self_collision::field`]).
    pub distance_sq: [f32; N],
    /// What the obstacles say (eq. 26's potential, the closest pair, ...).
    pub field: ObstacleField,
    /// What the checked link pairs say (their potential, the closest pair).
    pub links: SelfField,
    /// With [`crate::Motion::Tracked`]: the link pairs measured, whose
    /// relative motion the tracker bounds (their gaps are not in
    /// `distance_sq`).
    pub close_pairs: ClosePairs,
    /// With [`crate::Motion::Tracked`]: each link's half-space against its
    /// nearest obstacle, along which it may slide
    /// ([`crate::tracker::clearance`]).
    pub planes: [Option<HalfSpace>; N],
}

impl<const N: usize> Default for Evaluation<N> {
    fn default() -> Self {
        Self::new()
    }
}

impl<const N: usize> Evaluation<N> {
    /// Nothing evaluated yet.
    pub fn new() -> Self {
        Evaluation {
            frames: Frames::default(),
            error: PoseError::default(),
            mu: [0.0; N],
            distance_sq: [0.0; N],
            field: ObstacleField::default(),
            links: SelfField::default(),
            close_pairs: ClosePairs::new(),
            planes: [None; N],
        }
    }

    /// Every field to its initial value, in place.
    pub fn reset(&mut self) {
        // Every field is named: a field added to `Evaluation` fails to compile here.
        let Evaluation {
            frames,
            error,
            mu,
            distance_sq,
            field,
            links,
            close_pairs,
            planes,
        } = self;
        close_pairs.clear();
        planes.fill(None);
        frames.clear();
        *error = PoseError::default();
        mu.fill(0.0);
        distance_sq.fill(0.0);
        *field = ObstacleField::default();
        *links = SelfField::default();
    }

    /// What a law reads of this evaluation, for the arm at `q` (the
    /// configuration evaluated) whose position error changed by
    /// `error_step` over the last step ([`crate::control::law::propose`]).
    #[inline]
    pub fn law_input<'a, const M: usize, const W: usize>(
        &'a self,
        scenario: &'a Scenario<N, M, W>,
        q: &'a [f32],
        error_step: f32,
    ) -> LawInput<'a, N> {
        let settings = scenario.settings();
        let n = scenario.robot().len().min(N);
        LawInput {
            robot: scenario.robot(),
            frames: &self.frames,
            q,
            error: &self.error,
            mu: &self.mu[..n],
            clearance: self.clearance(),
            law: &settings.law,
            engage_clearance: settings.avoidance.engage_clearance,
            step: settings.step_rule(),
            error_step,
        }
    }

    /// The closest pair's clearance within influence, an obstacle's `C - 1`
    /// or a link pair's `gap / (r_a + r_b)`, whichever is less (`None`: no
    /// pair within influence).
    pub fn clearance(&self) -> Option<f32> {
        match (self.field.clearance.map(|c| c.value), self.links.closest) {
            (Some(o), Some(l)) if l.clearance < INFLUENCE => Some(crate::math::min(o, l.clearance)),
            (o, Some(l)) if l.clearance < INFLUENCE => {
                Some(o.map_or(l.clearance, |o| crate::math::min(o, l.clearance)))
            }
            (o, _) => o,
        }
    }

    /// The closest pair's clearance ([`Evaluation::clearance`]; infinity: none).
    pub fn closest(&self) -> f32 {
        self.clearance().unwrap_or(f32::INFINITY)
    }

    /// Whether every avoidance point is outside every inflated obstacle and
    /// no two checked link capsules touch.
    pub fn clear(&self) -> bool {
        self.field.clear && self.links.clear
    }

    /// Whether a step may end here, coming from a configuration whose
    /// closest pair was at `c_from`: every point clear, and not creeping onto
    /// a surface (below `floor` the closest clearance may not shrink).
    pub fn safe_after(&self, c_from: f32, floor: f32) -> bool {
        let c = self.closest();
        self.clear() && (c >= floor || c >= c_from)
    }

    /// Evaluates the arm of `scenario` at `q` against `target`: forward
    /// kinematics, the error (eqs. 11-12), the potential and its gradient
    /// (eqs. 20, 25-26).
    pub fn evaluate<const M: usize, const W: usize>(
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
            scenario.world(),
            &scenario.settings().avoidance,
            &mut self.mu,
            &mut self.distance_sq,
            if scenario.settings().motion == crate::Motion::Tracked {
                Some(&mut self.planes[..])
            } else {
                None
            },
        );
        let capsules = scenario.capsules();
        self.close_pairs.clear();
        if capsules.is_on() {
            let n = robot.len().min(N);
            if scenario.settings().motion == crate::Motion::Tracked {
                // The links' rooms against their link pairs apart, so each
                // plane's other room holds them too.
                let mut rooms = [f32::INFINITY; N];
                self.links = link_pairs(
                    robot,
                    &self.frames,
                    capsules,
                    &mut self.mu[..n],
                    &mut rooms[..n],
                    None,
                    far_pairs(scenario.settings()),
                    Some(&mut self.close_pairs),
                );
                for ((d, plane), &room) in self
                    .distance_sq
                    .iter_mut()
                    .zip(self.planes.iter_mut())
                    .zip(&rooms)
                    .take(n)
                {
                    *d = crate::math::min(*d, room);
                    if let Some(h) = plane.as_mut() {
                        h.others_sq = crate::math::min(h.others_sq, room);
                    }
                }
            } else {
                self.links = link_pairs(
                    robot,
                    &self.frames,
                    capsules,
                    &mut self.mu[..n],
                    &mut self.distance_sq[..n],
                    self.field.nearest.map(|h| h.link),
                    far_pairs(scenario.settings()),
                    None,
                );
            }
            // The link of the nearest obstacle pair slides along its
            // half-space; its other room must hold its link pairs too.
            if let Some(h) = self.field.nearest.as_mut() {
                h.others_sq = crate::math::min(h.others_sq, self.links.pressed_room_sq);
            }
        } else {
            self.links = SelfField {
                clear: true,
                pressed_room_sq: f32::INFINITY,
                ..SelfField::default()
            };
        }
    }
}

/// The evaluation of the current configuration (`now`) and of the candidate
/// (`next`), in two slots: accepting the candidate swaps their roles, not
/// their contents (an evaluation is some 700 bytes for PIPS).
#[derive(Clone, Debug)]
pub struct Evaluations<const N: usize> {
    slots: [Evaluation<N>; 2],
    /// The slot of `now` (0 or 1); `next` is the other.
    now: usize,
}

impl<const N: usize> Default for Evaluations<N> {
    fn default() -> Self {
        Self::new()
    }
}

impl<const N: usize> Evaluations<N> {
    /// Two empty slots.
    pub fn new() -> Self {
        Evaluations {
            slots: [Evaluation::new(), Evaluation::new()],
            now: 0,
        }
    }

    /// Both evaluations to their initial values, in place.
    pub fn reset(&mut self) {
        self.slots.iter_mut().for_each(Evaluation::reset);
        self.now = 0;
    }

    // `& 1`: the index is provably in bounds (no panic path).
    /// The current configuration's evaluation.
    #[inline(always)]
    pub fn now(&self) -> &Evaluation<N> {
        &self.slots[self.now & 1]
    }

    /// The current configuration's evaluation, writable.
    #[inline(always)]
    pub fn now_mut(&mut self) -> &mut Evaluation<N> {
        &mut self.slots[self.now & 1]
    }

    /// The candidate's evaluation.
    #[inline(always)]
    pub fn next(&self) -> &Evaluation<N> {
        &self.slots[(self.now & 1) ^ 1]
    }

    /// The candidate's evaluation, writable.
    #[inline(always)]
    pub fn next_mut(&mut self) -> &mut Evaluation<N> {
        &mut self.slots[(self.now & 1) ^ 1]
    }

    /// `(now, next)`, both writable.
    #[inline(always)]
    pub fn both_mut(&mut self) -> (&mut Evaluation<N>, &mut Evaluation<N>) {
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
    pub fn accept(&mut self) {
        self.now ^= 1;
    }
}

/// How far beyond the self-collision broad phase link pairs are still
/// measured for their rooms (`far` of [`link_pairs`]): with
/// [`crate::Motion::Tracked`] the influence distance (a tick's room must
/// hold the stop after it, and a far pair's room of a capsule radius would
/// hold the arm to a crawl); none with [`crate::Motion::Stepped`] (its
/// rooms, and plans, as before).
fn far_pairs(settings: &crate::Settings) -> f32 {
    match settings.motion {
        crate::Motion::Tracked => settings.avoidance.influence_distance,
        crate::Motion::Stepped => 0.0,
    }
}
