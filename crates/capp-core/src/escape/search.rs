//! The escape's search at a dead end, in imagination (the arm holds still
//! while it runs; the planner gives it a bounded slice per step,
//! [`SEARCH_EVALUATIONS`] evaluations of the arm): a goal configuration, then a tree in joint space
//! from the dead end to it, then the arm walks the tree's path.
//!
//! 1. **Goal**: no inverse kinematics. The law descends from random
//!    configurations ([`DESCENTS`] of them, at most [`DESCENT_STEPS`] law
//!    steps each, every step cut by conservative advancement and accepted
//!    as a real step would be) until one ends within [`GOAL_NEAR`] position
//!    tolerances of the target: a collision-free configuration from which
//!    the law finishes.
//! 2. **Trunk**: a dead end is pressed on a surface, where few directions
//!    are clear. The tree's first nodes leave it down the obstacle
//!    potential (in the metric of the rate limits) for at most
//!    [`TRUNK_STEPS`] advancement-bounded steps, until out of the band where
//!    the projection engages.
//! 3. **Tree**: RRT-Connect's greedy connection toward the goal
//!    configuration (a [`GOAL_BIAS`] share of the extensions, each carrying
//!    on while it is taken) and RRT's exploration toward random
//!    configurations otherwise, from the nearest node in seconds at the rate
//!    limits; edges at most [`EDGE_STEPS`] time steps at the rate limits,
//!    checked at [`EDGE_CHECKS`] configurations along them (clear, and above
//!    the contact floor or no closer than where they come from); an edge
//!    blocked part of the way is kept as far as it was checked clear
//!    (RRT's extend), and a greedy connection stops there. At most
//!    [`EXTENSIONS`] extensions and [`TREE_NODES`] nodes; the search ends at
//!    the first node within one edge of the goal configuration.
//! 4. **Shortcut**: the path is shortened greedily, as sampling planners
//!    do: from each node, the farthest later node a straight segment
//!    reaches, checked at the edges' spacing, at most [`SHORTCUT_CHECKS`]
//!    configurations in all.
//!
//! The tree is a plan: the walk along its path checks every one of its
//! steps like any other step (conservative advancement, evaluation,
//! acceptance), so a plan that an edge check missed ends the walk blocked,
//! never in an obstacle. Memory: `TREE_NODES x (4 N + 5) + 8 N` bytes (18
//! joints: 19 KiB).

use crate::control::joint_space::gap;
use crate::control::law::{propose, DriveGoal, LawWorkspace};
use crate::control::{time_at_limits, LawInput, LawKind};
use crate::escape::rng::Rng;
use crate::escape::tree::{Tree, TREE_NODES};
use crate::evaluation::Evaluation;
use crate::math::{all_finite, max, min};
use crate::projection::CONTACT_FLOOR;
use crate::robot::{JointKind, Robot};
use crate::scenario::Scenario;
use crate::step_size::{advancement, StepRule};
use crate::target::Target;

/// Random configurations the law descends from, per search.
pub const DESCENTS: u16 = 16;
/// Law steps per descent.
pub const DESCENT_STEPS: u16 = 60;
/// A descent that ends within this many position tolerances of the target
/// gives the goal configuration.
pub const GOAL_NEAR: f32 = 10.0;
/// Most steps of the trunk.
pub const TRUNK_STEPS: u16 = 16;
/// Extensions of the tree per search.
pub const EXTENSIONS: u16 = 2 * TREE_NODES as u16;
/// How far beyond the span between the dead end and the goal configuration
/// a revolute joint's random samples reach, radians.
pub const SAMPLE_TURN: f32 = core::f32::consts::PI;
/// Share of the extensions that reach for the goal configuration.
pub const GOAL_BIAS: f32 = 0.3;
/// Longest edge, in planner time steps at the rate limits.
pub const EDGE_STEPS: f32 = 10.0;
/// Configurations checked along an edge.
pub const EDGE_CHECKS: usize = 5;
/// Most configurations checked while shortening a path; the rest of the
/// path is kept as found.
pub const SHORTCUT_CHECKS: u16 = 256;
/// Evaluations of the arm (kinematics, pose error, potential) a planner
/// step may spend on the search: the search's cost per step, about what a
/// step with its halvings costs.
pub const SEARCH_EVALUATIONS: u16 = 8;

/// Where a search is.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
enum Stage {
    /// Descending from random configurations, for a goal configuration.
    Goal,
    /// Leaving the dead end's surface.
    Trunk,
    /// Growing the tree toward the goal configuration.
    Grow,
    /// Shortening the path found: straight segments across its nodes.
    Shortcut,
}

/// A search's fixed-size state.
#[derive(Clone, Debug)]
pub struct Search<const N: usize> {
    /// The tree (root: the dead end).
    tree: Tree<N>,
    /// The goal configuration, once found.
    goal: [f32; N],
    /// The current descent's configuration.
    probe: [f32; N],
    /// What the search is doing.
    stage: Stage,
    /// Whether a descent is under way from `probe`, and its steps.
    probing: bool,
    /// Law steps of the current descent.
    probe_steps: u16,
    /// Descents started.
    descents: u16,
    /// Trunk steps taken, and the trunk's last node.
    trunk_steps: u16,
    /// The trunk's last node.
    base: u8,
    /// Extensions tried.
    extensions: u16,
    /// The node a greedy connection carries on from.
    connecting: Option<u8>,
    /// The path found (node indices, root first), shortened in place.
    path: [u8; TREE_NODES],
    /// Its length.
    path_len: u8,
    /// Shortcut: the path position the segment starts from, the one it
    /// tries to reach, the next position to write, the configuration of the
    /// segment to check next, and the checks spent.
    from: u8,
    /// See `from`.
    to: u8,
    /// See `from`.
    out: u8,
    /// See `from`.
    check: u16,
    /// See `from`.
    shortcut_checks: u16,
}

impl<const N: usize> Default for Search<N> {
    fn default() -> Self {
        Search {
            tree: Tree::default(),
            goal: [0.0; N],
            probe: [0.0; N],
            stage: Stage::Goal,
            probing: false,
            probe_steps: 0,
            descents: 0,
            trunk_steps: 0,
            base: 0,
            extensions: 0,
            connecting: None,
            path: [0; TREE_NODES],
            path_len: 0,
            from: 0,
            to: 0,
            out: 0,
            check: 0,
            shortcut_checks: 0,
        }
    }
}

impl<const N: usize> Search<N> {
    /// [`Search::default`] in place.
    pub fn clear(&mut self) {
        self.tree.clear();
        self.restart();
    }

    /// A new search from the dead end `root` (value `v`).
    pub fn begin(&mut self, root: &[f32], v: f32) {
        self.tree.plant(root, v);
        self.restart();
    }

    /// Everything but the tree back to its initial value.
    fn restart(&mut self) {
        self.goal.fill(0.0);
        self.probe.fill(0.0);
        self.stage = Stage::Goal;
        self.probing = false;
        self.probe_steps = 0;
        self.descents = 0;
        self.trunk_steps = 0;
        self.base = 0;
        self.extensions = 0;
        self.connecting = None;
        self.path.fill(0);
        self.path_len = 0;
        self.from = 0;
        self.to = 0;
        self.out = 0;
        self.check = 0;
        self.shortcut_checks = 0;
    }

    /// The path to node `end` is found: shorten it next.
    fn found(&mut self, end: usize) {
        self.path_len = self.tree.path(end, &mut self.path) as u8;
        self.stage = Stage::Shortcut;
        // The trunk's nodes on the path (node k at position k, up to its
        // last node) are kept as they are: each is a step the planner
        // would take off the surface, where a straight shortcut from the
        // dead end may graze it.
        let trunk = (1..=self.base as usize)
            .take_while(|&k| self.path.get(k).is_some_and(|&p| p as usize == k))
            .count()
            .min((self.path_len as usize).saturating_sub(1));
        self.from = trunk as u8;
        self.out = trunk as u8 + 1;
        self.to = self.path_len.saturating_sub(1);
        self.check = 1;
    }

    /// The path, shortened: node indices, the dead end first.
    fn path(&self) -> &[u8] {
        &self.path[..(self.path_len as usize).min(TREE_NODES)]
    }

    /// The configuration at position `k` of the path found, if the path
    /// has one there.
    pub fn path_node(&self, k: usize) -> Option<&[f32; N]> {
        let &i = self.path().get(k)?;
        Some(self.tree.node(i as usize))
    }
}

/// What a slice of the search came to.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Slice {
    /// Not done yet.
    Working,
    /// A path ([`Search::path_node`]).
    Found,
    /// The budget is spent, no path.
    Failed,
}

/// The planner's buffers the search imagines in: the candidate's
/// evaluation, its configuration, a joint rate and the law's workspace.
/// Borrowed for one slice, never the arm's own state (the arm holds still).
pub struct Scratch<'a, const N: usize> {
    /// The evaluation of the imagined configuration.
    pub next: &'a mut Evaluation<N>,
    /// The imagined configuration.
    pub q: &'a mut [f32; N],
    /// A joint rate.
    pub rate: &'a mut [f32; N],
    /// The law's buffers.
    pub law: &'a mut LawWorkspace<N>,
}

/// One planner step's share of the search: units of work (a descent's law
/// step, a trunk step, a tree extension, a shortcut check) until
/// [`SEARCH_EVALUATIONS`] evaluations of the arm are spent.
pub fn slice<const N: usize, const M: usize, const W: usize>(
    search: &mut Search<N>,
    rng: &mut Rng,
    scenario: &Scenario<N, M, W>,
    target: &Target,
    s: &mut Scratch<'_, N>,
) -> Slice {
    let mut spent = 0u16;
    let im = &mut Imagination {
        scenario,
        target,
        s,
    };
    while spent < SEARCH_EVALUATIONS {
        let slice = match search.stage {
            Stage::Goal => goal_unit(search, rng, im, &mut spent),
            Stage::Trunk => trunk_unit(search, im, &mut spent),
            Stage::Grow => grow_unit(search, rng, im, &mut spent),
            Stage::Shortcut => shortcut_unit(search, im, &mut spent),
        };
        if slice != Slice::Working {
            return slice;
        }
    }
    Slice::Working
}

/// `q` drawn uniformly within the joint limits.
fn draw_configuration<const N: usize>(rng: &mut Rng, robot: &Robot<N>, q: &mut [f32; N]) {
    for (j, joint) in robot.joints().iter().enumerate().take(robot.len().min(N)) {
        q[j] = draw(rng, joint.min, joint.max);
    }
}

/// A value drawn uniformly in `[lo, hi]`.
fn draw(rng: &mut Rng, lo: f32, hi: f32) -> f32 {
    let u = 0.5 * (rng.uniform() + 1.0);
    lo + u * (hi - lo)
}

/// `q` drawn uniformly within the joint limits and, for a revolute joint,
/// within [`SAMPLE_TURN`] radians beyond the span between `a` and `b` (the
/// dead end and the goal configuration): a joint of a wide range (the UR5's
/// +-2 pi) is not explored a turn away from both ends.
fn draw_between<const N: usize>(
    rng: &mut Rng,
    robot: &Robot<N>,
    a: &[f32; N],
    b: &[f32; N],
    q: &mut [f32; N],
) {
    for (j, joint) in robot.joints().iter().enumerate().take(robot.len().min(N)) {
        q[j] = match joint.kind {
            JointKind::Revolute => draw(
                rng,
                max(joint.min, min(a[j], b[j]) - SAMPLE_TURN),
                min(joint.max, max(a[j], b[j]) + SAMPLE_TURN),
            ),
            JointKind::Prismatic => draw(rng, joint.min, joint.max),
        };
    }
}

/// The configuration `along` seconds (at `rate`) from `qa`, within the
/// joint limits, into `q`.
fn along_edge<const N: usize>(
    robot: &Robot<N>,
    qa: &[f32; N],
    rate: &[f32; N],
    along: f32,
    q: &mut [f32; N],
) {
    for (j, joint) in robot.joints().iter().enumerate().take(robot.len().min(N)) {
        q[j] = joint.clamp(qa[j] + along * rate[j]);
    }
}

/// A descent's next unit: start one from a random configuration, or take
/// its next law step. Keeps `s.next` the evaluation of the probe while a
/// descent is under way.
fn goal_unit<const N: usize, const M: usize, const W: usize>(
    search: &mut Search<N>,
    rng: &mut Rng,
    im: &mut Imagination<'_, '_, N, M, W>,
    spent: &mut u16,
) -> Slice {
    let scenario = im.scenario;
    let (settings, robot, n) = (scenario.settings(), scenario.robot(), im.n());
    let edge_s = EDGE_STEPS * settings.time_step_s;
    if !search.probing {
        if search.descents >= DESCENTS {
            return Slice::Failed;
        }
        search.descents += 1;
        draw_configuration(rng, robot, im.s.q);
        *spent += 1;
        if im.accept(f32::INFINITY) {
            search.probe = *im.s.q;
            search.probing = true;
            search.probe_steps = 0;
        }
        return Slice::Working;
    }
    let near = GOAL_NEAR * settings.position_tolerance;
    let v = im.s.next.error.v;
    if v <= 0.5 * near * near {
        search.goal = search.probe;
        search.stage = Stage::Trunk;
        return Slice::Working;
    }
    if search.probe_steps >= DESCENT_STEPS {
        search.probing = false;
        return Slice::Working;
    }
    search.probe_steps += 1;
    let probe = search.probe;
    let c = im.s.next.closest();
    *spent += 1;
    let taken = im.law_step(&probe[..n], edge_s) > 0.0 && im.accept(c) && im.s.next.error.v < v;
    if taken {
        search.probe = *im.s.q;
    } else {
        search.probing = false;
    }
    Slice::Working
}

/// The trunk's next step away from the surface the dead end is on.
fn trunk_unit<const N: usize, const M: usize, const W: usize>(
    search: &mut Search<N>,
    im: &mut Imagination<'_, '_, N, M, W>,
    spent: &mut u16,
) -> Slice {
    let scenario = im.scenario;
    let (settings, robot, n) = (scenario.settings(), scenario.robot(), im.n());
    let edge_s = EDGE_STEPS * settings.time_step_s;
    if search.trunk_steps >= TRUNK_STEPS {
        search.stage = Stage::Grow;
        return Slice::Working;
    }
    search.trunk_steps += 1;
    let base = search.base as usize;
    let qa = *search.tree.node(base);
    im.evaluate(&qa[..n]);
    *spent += 2;
    let c_a = im.s.next.closest();
    let mut leave = c_a >= settings.avoidance.engage_clearance;
    if !leave {
        // Down the potential in the metric of the rate limits.
        for (j, joint) in robot.joints().iter().enumerate().take(n) {
            im.s.rate[j] = -im.s.next.mu[j] * joint.max_rate * joint.max_rate;
        }
        let t = time_at_limits(robot, &im.s.rate[..n]);
        leave = !(t > 0.0 && t.is_finite());
        if !leave {
            im.s.rate[..n].iter_mut().for_each(|r| *r /= t);
            leave = im.advance(&qa[..n], edge_s) <= 0.0 || !im.accept(c_a);
        }
    }
    let v = im.s.next.error.v;
    if leave {
        search.stage = Stage::Grow;
        return Slice::Working;
    }
    match search.tree.push(&im.s.q[..n], base, v) {
        Some(i) => search.base = i as u8,
        None => search.stage = Stage::Grow,
    }
    Slice::Working
}

/// One extension of the tree: toward the goal configuration (carrying on a
/// greedy connection) or toward a random configuration.
fn grow_unit<const N: usize, const M: usize, const W: usize>(
    search: &mut Search<N>,
    rng: &mut Rng,
    im: &mut Imagination<'_, '_, N, M, W>,
    spent: &mut u16,
) -> Slice {
    let scenario = im.scenario;
    let (settings, robot, n) = (scenario.settings(), scenario.robot(), im.n());
    let edge_s = EDGE_STEPS * settings.time_step_s;
    if search.extensions >= EXTENSIONS || search.tree.is_full() {
        return Slice::Failed;
    }
    search.extensions += 1;
    let goal = search.goal;
    let a = match search.connecting {
        Some(a) => {
            *im.s.q = goal;
            a as usize
        }
        None => {
            if rng.uniform() < 2.0 * GOAL_BIAS - 1.0 {
                *im.s.q = goal;
                search.connecting = Some(0);
            } else {
                draw_between(rng, robot, search.tree.node(0), &goal, im.s.q);
            }
            search.tree.nearest(robot, &im.s.q[..n])
        }
    };
    let qa = *search.tree.node(a);
    let sample = *im.s.q;
    for j in 0..n {
        im.s.rate[j] = (sample[j] - qa[j]) / edge_s;
    }
    let t = time_at_limits(robot, &im.s.rate[..n]);
    if t > 1.0 {
        im.s.rate[..n].iter_mut().for_each(|r| *r /= t);
    }
    // The edge, checked at configurations along it: a plan, not a motion
    // (the walk along it checks each of its steps).
    im.evaluate(&qa[..n]);
    *spent += 1;
    let mut c_from = im.s.next.closest();
    let mut clear = all_finite(&im.s.rate[..n]);
    // The last configuration checked clear along the edge, and its `V`.
    let mut last_clear = 0usize;
    let mut last_v = 0.0f32;
    let along = |k: usize| edge_s * k as f32 / EDGE_CHECKS as f32;
    for k in 1..=EDGE_CHECKS {
        if !clear {
            break;
        }
        along_edge(robot, &qa, im.s.rate, along(k), im.s.q);
        *spent += 1;
        clear = im.accept(c_from);
        c_from = im.s.next.closest();
        if clear {
            (last_clear, last_v) = (k, im.s.next.error.v);
        }
    }
    if !clear {
        // RRT's extend: the edge as far as it was checked clear, if any
        // of it was; a greedy connection stops there.
        search.connecting = None;
        if last_clear == 0 {
            return Slice::Working;
        }
        along_edge(robot, &qa, im.s.rate, along(last_clear), im.s.q);
    }
    let Some(i) = search.tree.push(&im.s.q[..n], a, last_v) else {
        return Slice::Failed;
    };
    if clear && search.connecting.is_some() {
        search.connecting = Some(i as u8);
    }
    if gap(robot, &im.s.q[..n], &goal[..n]) <= edge_s {
        search.found(i);
    }
    Slice::Working
}

/// One configuration of the shortcut being checked: the segment from path
/// position `from` to `to`, at the spacing of an edge's checks.
fn shortcut_unit<const N: usize, const M: usize, const W: usize>(
    search: &mut Search<N>,
    im: &mut Imagination<'_, '_, N, M, W>,
    spent: &mut u16,
) -> Slice {
    let scenario = im.scenario;
    let (settings, robot, n) = (scenario.settings(), scenario.robot(), im.n());
    let spacing = EDGE_STEPS * settings.time_step_s / EDGE_CHECKS as f32;
    let len = search.path_len as usize;
    let (from, to) = (search.from as usize, search.to as usize);
    if from + 1 >= len {
        search.path_len = search.out;
        return Slice::Found;
    }
    let node = |search: &Search<N>, k: usize| {
        *search
            .tree
            .node(search.path.get(k).copied().unwrap_or(0) as usize)
    };
    let (a, b) = (node(search, from), node(search, to));
    let checks = libm::ceilf(gap(robot, &a[..n], &b[..n]) / spacing) as u16;
    // A tree edge is already checked; a spent budget keeps the rest.
    let keep = to == from + 1 || search.shortcut_checks >= SHORTCUT_CHECKS;
    let mut accept = keep;
    if !keep {
        let k = search.check;
        search.shortcut_checks += 1;
        let t = k as f32 / checks.max(1) as f32;
        for j in 0..n {
            im.s.q[j] = a[j] + t * (b[j] - a[j]);
        }
        *spent += 1;
        let clear = im.accept(f32::INFINITY);
        if !clear {
            search.to -= 1;
            search.check = 1;
            return Slice::Working;
        }
        if k < checks {
            search.check = k + 1;
            return Slice::Working;
        }
        accept = true;
    }
    if accept {
        let (out, next) = (search.out as usize, if keep { from + 1 } else { to });
        if let (Some(&v), true) = (search.path.get(next), out < TREE_NODES) {
            search.path[out] = v;
        }
        search.out += 1;
        search.from = next as u8;
        search.to = (len - 1) as u8;
        search.check = 1;
    }
    Slice::Working
}

/// One slice's world: the model, the target aimed at and the planner's
/// scratch buffers the search imagines in.
struct Imagination<'a, 'b, const N: usize, const M: usize, const W: usize> {
    scenario: &'a Scenario<N, M, W>,
    target: &'a Target,
    s: &'a mut Scratch<'b, N>,
}

impl<const N: usize, const M: usize, const W: usize> Imagination<'_, '_, N, M, W> {
    /// The robot's joints (at most `N`).
    fn n(&self) -> usize {
        self.scenario.robot().len().min(N)
    }

    /// One law step in imagination from `qa` (evaluated into `s.next`): the
    /// damped law's step of at most `edge_s` at the rate limits, through the
    /// one law interface, cut by conservative advancement, into `s.q`.
    /// Returns the step (seconds), 0 when none can be taken.
    fn law_step(&mut self, qa: &[f32], edge_s: f32) -> f32 {
        let settings = self.scenario.settings();
        let n = self.n().min(qa.len());
        // The search's descents are the damped law's only: under a
        // first-order law no imagined step is taken (and no goal found).
        if settings.law.kind != LawKind::DampedLeastSquares {
            return 0.0;
        }
        let s = &mut *self.s;
        let input = LawInput {
            step: StepRule {
                time_step_s: edge_s,
                ..settings.step_rule()
            },
            ..s.next.law_input(self.scenario, &qa[..n], 0.0)
        };
        propose(&input, DriveGoal::Pose, s.law, &mut s.rate[..n]);
        self.advance(qa, edge_s)
    }

    /// `s.q = qa + h rate`, `h <= edge_s` cut by conservative advancement
    /// from `qa` (evaluated into `s.next`); returns `h`.
    fn advance(&mut self, qa: &[f32], edge_s: f32) -> f32 {
        let (settings, robot) = (self.scenario.settings(), self.scenario.robot());
        let n = self.n().min(qa.len());
        let s = &mut *self.s;
        if !all_finite(&s.rate[..n]) {
            return 0.0;
        }
        let h = advancement(
            robot,
            &s.next.frames,
            &s.next.distance_sq[..n],
            s.next.field.nearest.as_ref(),
            &s.rate[..n],
            edge_s,
            settings.avoidance.advance_fraction,
        );
        if h.is_nan() || h <= 0.0 {
            return 0.0;
        }
        let moves = qa.iter().zip(s.rate.iter()).zip(robot.joints()).take(n);
        for (next, ((&a, &r), joint)) in s.q.iter_mut().zip(moves) {
            *next = joint.clamp(a + h * r);
        }
        h
    }

    /// Evaluates `q` into `s.next`, against the target.
    fn evaluate(&mut self, q: &[f32]) {
        self.s.next.evaluate(self.scenario, q, self.target);
    }

    /// Evaluates `s.q` into `s.next`: whether a step could be accepted
    /// there, coming from a configuration of clearance `c_from` (clear, and
    /// above the contact floor or no closer).
    fn accept(&mut self, c_from: f32) -> bool {
        let n = self.n();
        let s = &mut *self.s;
        s.next.evaluate(self.scenario, &s.q[..n], self.target);
        let floor = CONTACT_FLOOR * self.scenario.settings().avoidance.engage_clearance;
        s.next.safe_after(c_from, floor) && all_finite(&s.q[..n])
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::control::law::LawWorkspace;
    use crate::mission::{Settings, Waypoint};
    use crate::obstacle::SuperEllipsoid;
    use crate::robot::Joint;

    /// Random samples stay within the joint limits and, for a revolute
    /// joint, within `SAMPLE_TURN` beyond the span of the two ends; a
    /// prismatic joint's fill its range. Both bounds are approached.
    #[test]
    fn samples_stay_within_a_turn_of_the_dead_end_and_the_goal() {
        let wide = Joint::revolute(0.0, 1.0, 0.0, -6.2, 6.2, 1.0);
        let narrow = Joint::revolute(0.0, 1.0, 0.0, -1.0, 1.0, 1.0);
        let slide = Joint::prismatic(0.0, 0.0, 0.0, 0.5, 2.0, 1.0);
        let robot = Robot::<3>::new(&[wide, narrow, slide]).unwrap();
        let (a, b) = ([0.5f32, -0.2, 0.7], [1.5f32, 0.3, 0.9]);
        let mut rng = Rng::seeded(7, &[]);
        let mut q = [0.0f32; 3];
        let (mut lo, mut hi) = ([f32::INFINITY; 3], [f32::NEG_INFINITY; 3]);
        for _ in 0..4000 {
            draw_between(&mut rng, &robot, &a, &b, &mut q);
            for j in 0..3 {
                lo[j] = lo[j].min(q[j]);
                hi[j] = hi[j].max(q[j]);
            }
        }
        let expect = [
            (0.5 - SAMPLE_TURN, 1.5 + SAMPLE_TURN),
            (-1.0, 1.0),
            (0.5, 2.0),
        ];
        for j in 0..3 {
            let (l, h) = expect[j];
            assert!(
                lo[j] >= l && hi[j] <= h,
                "joint {j}: [{}, {}]",
                lo[j],
                hi[j]
            );
            assert!(lo[j] < l + 0.01 * (h - l) && hi[j] > h - 0.01 * (h - l));
        }
    }

    /// An edge toward the goal blocked partway by an obstacle is kept as
    /// far as it was checked clear (RRT's extend): the tree grows by one
    /// node, partway along the edge, clear, and the greedy connection stops.
    #[test]
    fn a_blocked_edge_is_kept_as_far_as_it_is_clear() {
        const N: usize = 2;
        // A planar 2-link arm (links of 1); a ball the elbow meets when
        // joint 1 turns from 0 toward 1.2 rad.
        let joint = Joint::revolute(0.0, 1.0, 0.0, -3.0, 3.0, 1.0);
        let robot = Robot::<N>::new(&[joint; N]).unwrap();
        let settings = Settings::for_robot(&robot);
        let mission = crate::Mission::new(&[Waypoint::at([0.0, 2.0, 0.0])], settings).unwrap();
        let ball = SuperEllipsoid::aligned([0.82, 0.57, 0.0], [0.1; 3], 2.0);
        let sc = Scenario::<N, 1, 1>::new(robot, &[ball], &mission).unwrap();
        let target = sc.targets()[0];
        let mut search = Search::<N>::default();
        search.begin(&[0.0, 0.0], 1.0);
        search.goal = [1.2, 0.0];
        search.stage = Stage::Grow;
        search.connecting = Some(0);
        let (mut next, mut q, mut rate) = (Evaluation::new(), [0.0f32; N], [0.0f32; N]);
        let mut law = LawWorkspace::default();
        let mut s = Scratch {
            next: &mut next,
            q: &mut q,
            rate: &mut rate,
            law: &mut law,
        };
        let im = &mut Imagination {
            scenario: &sc,
            target: &target,
            s: &mut s,
        };
        let mut rng = Rng::seeded(1, &[]);
        let mut spent = 0;
        assert_eq!(
            grow_unit(&mut search, &mut rng, im, &mut spent),
            Slice::Working
        );
        assert_eq!(search.tree.len(), 2, "one node added");
        let node = *search.tree.node(1);
        // Partway: joint 1 moved toward the goal but not all the way to
        // the edge's end (0.5 s at 1 rad/s), joint 2 still.
        assert!(node[0] > 0.0 && node[0] < 0.5, "{node:?}");
        assert_eq!(node[1], 0.0);
        im.evaluate(&node);
        assert!(im.s.next.clear(), "the kept node is clear");
        assert_eq!(search.connecting, None);
        // The whole edge was not clear: its end is in the ball.
        im.evaluate(&[0.5, 0.0]);
        assert!(!im.s.next.clear());
    }

    #[test]
    fn a_found_path_starts_at_the_dead_end_and_clears_in_place() {
        let mut s = Search::<3>::default();
        s.begin(&[1.0, 2.0, 3.0], 2.0);
        s.found(0);
        assert_eq!(s.path(), &[0]);
        assert_eq!(s.path_node(0), Some(&[1.0, 2.0, 3.0]));
        assert_eq!(s.stage, Stage::Shortcut);
        s.clear();
        assert!(s.tree.is_empty() && s.path().is_empty());
        assert_eq!(s.path_node(0), None);
        assert_eq!(s.stage, Stage::Goal);
    }
}
