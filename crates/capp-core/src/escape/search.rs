//! The escape's search at a dead end, in imagination (the arm holds still
//! while it runs; the planner gives it a bounded slice per step,
//! [`SEARCH_EVALUATIONS`] evaluations of the arm): a goal configuration,
//! then RRT-Connect in joint space between the dead end and it, then the
//! path found certified and shortened, then the arm walks it.
//!
//! 1. **Goal**: no inverse kinematics. The law descends from random
//!    configurations ([`DESCENTS`] of them, at most [`DESCENT_STEPS`] law
//!    steps each, every step cut by conservative advancement and accepted
//!    as a real step would be) until one ends within [`GOAL_NEAR`] position
//!    tolerances of the target: a collision-free configuration from which
//!    the law finishes. A draw the arm cannot stand in is drawn again (at
//!    most [`DESCENT_DRAWS`] draws): most of a UR5's joint box is in its
//!    table or in itself. The goal's revolute joints are then turned by
//!    whole turns to the angles nearest the dead end's (`nearest_turns`):
//!    the same arm in the same pose, not a turn of the shoulder away. A
//!    waypoint given as a joint configuration is its own goal configuration.
//! 2. **Trunk**: a dead end is pressed on a surface, where few directions
//!    are clear. The dead end's tree's first nodes leave it down the
//!    obstacle potential (in the metric of the rate limits) for at most
//!    [`TRUNK_STEPS`] advancement-bounded steps, until out of the band
//!    where the projection engages.
//! 3. **Trees**: RRT-Connect (Kuffner and LaValle, 2000): two trees, one
//!    from the dead end and one from the goal configuration, take turns to
//!    extend toward a random configuration (from the nearest node in seconds
//!    at the rate limits); after each extension the other tree connects
//!    greedily toward the node added, edge by edge while its edges are
//!    clear; the trees are joined when a connection reaches it. Edges are at
//!    most [`EDGE_STEPS`] time steps at the rate limits, checked at
//!    [`EDGE_CHECKS`] configurations along them (clear, and above the
//!    contact floor or no closer than where they come from); an edge blocked
//!    part of the way is kept as far as it was checked clear (RRT's
//!    extend), and a connection stops there. A node is kept only with
//!    [`NODE_FLOOR`] of clearance. At most [`EXTENSIONS`] edges and
//!    [`TREE_NODES`] nodes.
//! 4. **Certify and shorten**: sampled checks can miss an obstacle between
//!    them (a shelf's board, at a fast arm's speed); the path is certified
//!    before the arm walks it, lazily, as lazy PRM (Bohlin and Kavraki,
//!    2000) checks only the edges of the path it finds. From each node, the
//!    farthest later node a straight segment reaches is tried first (the
//!    shortcut of sampling planners; at most [`SHORTCUT_CHECKS`] sweep steps
//!    on those), else the next node; a segment is certified when
//!    conservative advancement sweeps it to its end (at most
//!    [`SEGMENT_SWEEPS`] steps), each step's end accepted as a step's. A
//!    tree edge that fails is pruned with the subtree it leads to, and the
//!    trees grow again (at most [`CERTIFY_SWEEPS`] sweep steps a search).
//!
//! The arm walks a certified path: every segment is a motion conservative
//! advancement allowed from where it starts, which the walk's own steps
//! (checked like any other) take. Memory: `TREE_NODES x (4 N + 6) + 12 N +
//! 64` bytes (18 joints: 19.5 KiB).

use crate::control::law::{propose, DriveGoal, LawWorkspace};
use crate::control::{time_at_limits, LawInput, LawKind};
use crate::escape::rng::Rng;
use crate::escape::tree::{Root, Tree, TREE_NODES};
use crate::evaluation::Evaluation;
use crate::math::{all_finite, max, min};
use crate::projection::CONTACT_FLOOR;
use crate::robot::{JointKind, Robot};
use crate::scenario::Scenario;
use crate::step_size::{advancement, StepRule};
use crate::target::Target;

/// Random configurations the law descends from, per search.
pub const DESCENTS: u16 = 16;
/// Random configurations drawn per search for the descents to start from:
/// a draw the arm cannot stand in (an obstacle, its own links) is drawn
/// again, at most this many times in all.
pub const DESCENT_DRAWS: u16 = 8 * DESCENTS;
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
/// Longest edge, in planner time steps at the rate limits.
pub const EDGE_STEPS: f32 = 10.0;
/// A node is kept only where the closest pair's clearance is at least this
/// share of the engage clearance: the walk along the path must be able to
/// leave it (conservative advancement creeps next to a surface).
pub const NODE_FLOOR: f32 = 0.1;
/// A segment swept to within this share of its time is swept whole.
pub const EDGE_END: f32 = 1.0e-4;
/// Configurations checked along an edge.
pub const EDGE_CHECKS: usize = 5;
/// Most sweep steps spent on shortcuts (segments that skip nodes); the
/// rest of the path is certified edge by edge as found.
pub const SHORTCUT_CHECKS: u16 = 256;
/// Most conservative-advancement steps sweeping one segment of the path.
pub const SEGMENT_SWEEPS: u16 = 64;
/// Most sweep steps certifying the paths one search finds.
pub const CERTIFY_SWEEPS: u16 = 1024;
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
    /// Growing the two trees toward each other.
    Grow,
    /// Certifying and shortening the path found: swept segments across its
    /// nodes.
    Shortcut,
}

/// A greedy connection under way: one tree's edges from its node `from`
/// toward the other tree's node `toward`.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
struct Connection {
    from: u8,
    toward: u8,
}

/// A search's fixed-size state.
#[derive(Clone, Debug)]
pub struct Search<const N: usize> {
    /// The two trees (node 0: the dead end; the goal tree planted when they start to grow).
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
    /// Configurations drawn for the descents to start from.
    draws: u16,
    /// Trunk steps taken, and the trunk's last node.
    trunk_steps: u16,
    /// The trunk's last node.
    base: u8,
    /// Extensions tried.
    extensions: u16,
    /// The goal configuration's `V`.
    goal_v: f32,
    /// Whether the goal tree is planted.
    goal_planted: bool,
    /// The tree the next random extension grows.
    side: Root,
    /// A greedy connection under way.
    connecting: Option<Connection>,
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
    /// The segment's sweep: its steps (0: not begun), the configuration it
    /// reached and its time along the segment (seconds at the rate limits).
    sweep_steps: u16,
    /// See `sweep_steps`.
    sweep_q: [f32; N],
    /// See `sweep_steps`.
    sweep_at: f32,
    /// Sweep steps spent on segments that skip nodes.
    shortcut_checks: u16,
    /// Sweep steps spent in all.
    certify_steps: u16,
    /// The dead end side's node where the trees met.
    meeting: u8,
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
            draws: 0,
            trunk_steps: 0,
            base: 0,
            extensions: 0,
            goal_v: 0.0,
            goal_planted: false,
            side: Root::DeadEnd,
            connecting: None,
            path: [0; TREE_NODES],
            path_len: 0,
            from: 0,
            to: 0,
            out: 0,
            sweep_q: [0.0; N],
            sweep_at: 0.0,
            sweep_steps: 0,
            shortcut_checks: 0,
            certify_steps: 0,
            meeting: 0,
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
        self.draws = 0;
        self.trunk_steps = 0;
        self.base = 0;
        self.extensions = 0;
        self.goal_v = 0.0;
        self.goal_planted = false;
        self.side = Root::DeadEnd;
        self.connecting = None;
        self.path.fill(0);
        self.path_len = 0;
        self.from = 0;
        self.to = 0;
        self.out = 0;
        self.sweep_q.fill(0.0);
        self.sweep_at = 0.0;
        self.sweep_steps = 0;
        self.shortcut_checks = 0;
        self.certify_steps = 0;
        self.meeting = 0;
    }

    /// The trees are joined where `dead_end_side` and `goal_side` (nodes of
    /// the two trees at one configuration) meet: the path runs from the dead
    /// end to the first and from the second to the goal configuration.
    /// Shorten it next.
    fn found(&mut self, dead_end_side: usize, goal_side: usize) {
        let to_meeting = self.tree.path(dead_end_side, &mut self.path);
        // The meeting configuration once: the goal side's node replaces
        // the dead end side's.
        let len = self
            .tree
            .to_root(goal_side, &mut self.path, to_meeting.saturating_sub(1));
        self.path_len = len as u8;
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
        self.sweep_steps = 0;
        self.meeting = dead_end_side as u8;
    }

    /// The goal configuration is `goal` (its `V`, `v`): the trunk next.
    fn goal_found(&mut self, goal: [f32; N], v: f32) {
        (self.goal, self.goal_v) = (goal, v);
        self.stage = Stage::Trunk;
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

/// `goal`'s revolute joints turned by whole turns to the angle nearest
/// `from`'s that their limits allow: the same arm in the same pose (a
/// revolute joint's transform repeats every turn), nearer in joint space.
/// A descent from a random configuration of a UR5 (every joint +-2 pi) ends
/// at any of up to 2^6 such copies of its pose, most of them turns away from
/// the dead end, with the table in between.
fn nearest_turns<const N: usize>(robot: &Robot<N>, from: &[f32; N], goal: &mut [f32; N]) {
    const TURN: f32 = 2.0 * core::f32::consts::PI;
    for (j, joint) in robot.joints().iter().enumerate().take(robot.len().min(N)) {
        if joint.kind != JointKind::Revolute {
            continue;
        }
        let mut turns = libm::roundf((goal[j] - from[j]) / TURN);
        let g = goal[j] - turns * TURN;
        if g > joint.max {
            turns += 1.0;
        } else if g < joint.min {
            turns -= 1.0;
        }
        let g = goal[j] - turns * TURN;
        // Not taken when no turn (the angle stays as it is, to the bit),
        // not finite, or outside the limits.
        if turns != 0.0 && g >= joint.min && g <= joint.max {
            goal[j] = g;
        }
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
/// its next law step, or, ended near the target, give the goal (at the
/// turns nearest the dead end). A joint goal is taken as it is, with no
/// descent. Keeps `s.next` the evaluation of the probe while a descent is
/// under way.
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
        // A joint goal is the goal configuration itself (as it is: its
        // joints are not turned), where the arm must stand: no descents.
        if let Some(joints) = im.target.joints.and_then(|k| scenario.joint_goal(k)) {
            let m = n.min(joints.len());
            im.s.q[..m].copy_from_slice(&joints[..m]);
            *spent += 1;
            if !im.accept(f32::INFINITY) {
                return Slice::Failed;
            }
            search.goal_found(*im.s.q, im.s.next.error.v);
            return Slice::Working;
        }
        if search.descents >= DESCENTS || search.draws >= DESCENT_DRAWS {
            return Slice::Failed;
        }
        search.draws += 1;
        draw_configuration(rng, robot, im.s.q);
        *spent += 1;
        if im.accept(f32::INFINITY) {
            search.descents += 1;
            search.probe = *im.s.q;
            search.probing = true;
            search.probe_steps = 0;
        }
        return Slice::Working;
    }
    let near = GOAL_NEAR * settings.position_tolerance;
    let v = im.s.next.error.v;
    if v <= 0.5 * near * near {
        // The same arm, its joints whole turns nearer the dead end's
        // (checked again: the turned angles are rounded).
        let (mut goal, mut goal_v) = (search.probe, v);
        let dead_end = *search.tree.node(0);
        *im.s.q = search.probe;
        nearest_turns(robot, &dead_end, im.s.q);
        if *im.s.q != search.probe {
            *spent += 1;
            if im.accept(f32::INFINITY) {
                (goal, goal_v) = (*im.s.q, im.s.next.error.v);
            }
        }
        search.goal_found(goal, goal_v);
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
    match search.tree.grow(&im.s.q[..n], base, v) {
        Some(i) => search.base = i as u8,
        None => search.stage = Stage::Grow,
    }
    Slice::Working
}

/// One unit of RRT-Connect: an extension of one tree toward a random
/// configuration (the trees take turns), then, unit by unit, the other
/// tree's greedy connection toward the node it added, carrying on while
/// its edges are clear. The trees are joined when a connection's edge
/// reaches that node.
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
    if !search.goal_planted {
        let (goal, v) = (search.goal, search.goal_v);
        if search.tree.plant_goal(&goal[..n], v).is_none() {
            return Slice::Failed;
        }
        search.goal_planted = true;
    }
    search.extensions += 1;
    let (a, toward) = match search.connecting {
        Some(c) => {
            *im.s.q = *search.tree.node(c.toward as usize);
            (c.from as usize, Some(c.toward as usize))
        }
        None => {
            let side = search.side;
            search.side = side.other();
            let goal = search.goal;
            draw_between(rng, robot, search.tree.node(0), &goal, im.s.q);
            (search.tree.nearest(robot, &im.s.q[..n], side), None)
        }
    };
    let qa = *search.tree.node(a);
    let sample = *im.s.q;
    let checked = im.check_edge(&qa, &sample, edge_s, spent);
    let v = match checked {
        EdgeCheck::Refused => {
            search.connecting = None;
            return Slice::Working;
        }
        EdgeCheck::Partial(v) | EdgeCheck::Whole { v, .. } => v,
    };
    let Some(i) = search.tree.grow(&im.s.q[..n], a, v) else {
        return Slice::Failed;
    };
    search.connecting = match (toward, checked) {
        // Joined: node `i` is at `x`, in the other tree.
        (
            Some(x),
            EdgeCheck::Whole {
                at_sample: true, ..
            },
        ) => {
            let (dead_end_side, goal_side) = match search.tree.root_of(x) {
                Root::DeadEnd => (x, i),
                Root::Goal => (i, x),
            };
            search.found(dead_end_side, goal_side);
            None
        }
        // A clear edge short of `x`: the connection carries on.
        (Some(x), EdgeCheck::Whole { .. }) => Some(Connection {
            from: i as u8,
            toward: x as u8,
        }),
        // RRT's extend: the edge as far as it was clear; a connection
        // stops there.
        (Some(_), _) => None,
        // The other tree reaches for the new node.
        (None, _) => {
            let other = search.tree.root_of(i).other();
            Some(Connection {
                from: search.tree.nearest(robot, &im.s.q[..n], other) as u8,
                toward: i as u8,
            })
        }
    };
    Slice::Working
}

/// One unit of the path's certification and shortening: conservative
/// advancement along the segment from path position `from` to `to` (the
/// farthest first), as many of its steps as the slice's evaluations allow.
/// A segment swept to its end is certified: the walk along it can take it.
/// A shortcut that fails is tried one node nearer; a tree edge that fails
/// (the edge checks missed an obstacle between them) prunes the node it
/// leads to and its subtree, and the trees grow again.
fn shortcut_unit<const N: usize, const M: usize, const W: usize>(
    search: &mut Search<N>,
    im: &mut Imagination<'_, '_, N, M, W>,
    spent: &mut u16,
) -> Slice {
    let n = im.n();
    let robot = im.scenario.robot();
    let len = search.path_len as usize;
    let (from, to) = (search.from as usize, search.to as usize);
    if from + 1 >= len {
        search.path_len = search.out;
        return Slice::Found;
    }
    if search.certify_steps >= CERTIFY_SWEEPS {
        return Slice::Failed;
    }
    let adjacent = to == from + 1;
    if !adjacent && search.shortcut_checks >= SHORTCUT_CHECKS {
        search.to = from as u8 + 1;
        search.sweep_steps = 0;
        return Slice::Working;
    }
    let node = |search: &Search<N>, k: usize| search.path.get(k).copied().unwrap_or(0) as usize;
    let (u, w) = (node(search, from), node(search, to));
    let (a, b) = (*search.tree.node(u), *search.tree.node(w));
    if search.sweep_steps == 0 {
        (search.sweep_q, search.sweep_at) = (a, 0.0);
    }
    // The segment at the rate limits: `duration` seconds at `rate`.
    for j in 0..n {
        im.s.rate[j] = b[j] - a[j];
    }
    let duration = time_at_limits(robot, &im.s.rate[..n]);
    let certified = if duration > 0.0 && duration.is_finite() {
        im.s.rate[..n].iter_mut().for_each(|r| *r /= duration);
        let mut q = search.sweep_q;
        im.evaluate(&q[..n]);
        *spent += 1;
        let mut c_from = im.s.next.closest();
        let verdict = loop {
            if search.sweep_steps >= SEGMENT_SWEEPS {
                break Some(false);
            }
            search.sweep_steps += 1;
            search.certify_steps += 1;
            if !adjacent {
                search.shortcut_checks += 1;
            }
            let h = im.advance(&q[..n], duration - search.sweep_at);
            *spent += 1;
            if h <= 0.0 || !im.accept(c_from) {
                break Some(false);
            }
            q = *im.s.q;
            search.sweep_at += h;
            c_from = im.s.next.closest();
            if search.sweep_at >= duration * (1.0 - EDGE_END) {
                break Some(true);
            }
            if *spent >= SEARCH_EVALUATIONS {
                break None;
            }
        };
        search.sweep_q = q;
        verdict
    } else {
        // One configuration twice: nothing to sweep.
        Some(duration == 0.0)
    };
    match certified {
        None => {}
        Some(true) => {
            if let Some(slot) = search.path.get_mut(search.out as usize) {
                *slot = w as u8;
            }
            search.out += 1;
            search.from = to as u8;
            search.to = (len - 1) as u8;
            search.sweep_steps = 0;
        }
        Some(false) if adjacent => {
            // The node this tree edge leads to (from its parent), or, where
            // the trees met, the dead end side's meeting node.
            let child = if search.tree.parent(w) == u {
                w
            } else if search.tree.parent(u) == w {
                u
            } else {
                search.meeting as usize
            };
            search.tree.prune(child);
            search.stage = Stage::Grow;
            search.connecting = None;
            search.sweep_steps = 0;
        }
        Some(false) => {
            search.to -= 1;
            search.sweep_steps = 0;
        }
    }
    Slice::Working
}

/// How far an edge was checked clear ([`Imagination::check_edge`]).
#[derive(Clone, Copy, Debug, PartialEq)]
enum EdgeCheck {
    /// Not far enough to keep (`s.q` undefined).
    Refused,
    /// Part of the way, to `s.q` (its `V`).
    Partial(f32),
    /// All of it, to `s.q` (its `V`); `at_sample`: the edge ends at the
    /// configuration it was drawn toward.
    Whole {
        /// `V` at the end.
        v: f32,
        /// Whether the end is the configuration aimed at.
        at_sample: bool,
    },
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

    /// The edge from `qa` toward `sample`, at most `edge_s` at the rate
    /// limits, checked at [`EDGE_CHECKS`] configurations along it (clear, not
    /// creeping onto a surface): cheap, and a plan only (a thin obstacle may
    /// lie between two checks); the path found is certified before it is
    /// walked ([`shortcut_unit`]). Leaves in `s.q` the farthest configuration
    /// checked before the first that is not clear, if it has at least
    /// [`NODE_FLOOR`] of clearance (a node the walk can leave).
    fn check_edge(
        &mut self,
        qa: &[f32; N],
        sample: &[f32; N],
        edge_s: f32,
        spent: &mut u16,
    ) -> EdgeCheck {
        let (settings, robot, n) = (self.scenario.settings(), self.scenario.robot(), self.n());
        for j in 0..n {
            self.s.rate[j] = (sample[j] - qa[j]) / edge_s;
        }
        let t = time_at_limits(robot, &self.s.rate[..n]);
        let at_sample = t <= 1.0;
        if !at_sample {
            self.s.rate[..n].iter_mut().for_each(|r| *r /= t);
        }
        self.evaluate(&qa[..n]);
        *spent += 1;
        let node_floor = NODE_FLOOR * settings.avoidance.engage_clearance;
        let mut c_from = self.s.next.closest();
        let mut clear = all_finite(&self.s.rate[..n]);
        // The farthest check a node may be put at, and its `V`.
        let (mut kept, mut kept_v) = (0usize, 0.0f32);
        let along = |k: usize| edge_s * k as f32 / EDGE_CHECKS as f32;
        for k in 1..=EDGE_CHECKS {
            if !clear {
                break;
            }
            along_edge(robot, qa, self.s.rate, along(k), self.s.q);
            *spent += 1;
            clear = self.accept(c_from);
            c_from = self.s.next.closest();
            if clear && c_from >= node_floor {
                (kept, kept_v) = (k, self.s.next.error.v);
            }
        }
        if kept == EDGE_CHECKS {
            return EdgeCheck::Whole {
                v: kept_v,
                at_sample,
            };
        }
        if kept == 0 {
            return EdgeCheck::Refused;
        }
        along_edge(robot, qa, self.s.rate, along(kept), self.s.q);
        EdgeCheck::Partial(kept_v)
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

    /// A goal turned by whole turns is the same arm nearer the dead end:
    /// every joint within its limits, no alternative turn within them
    /// nearer the dead end's angle, the same end-effector pose (forward
    /// kinematics) to f32 rounding, and a joint no turn fits in (range
    /// under a turn, or prismatic) keeps its value to the bit.
    #[test]
    fn a_goal_turned_by_whole_turns_is_the_same_arm_nearer_the_dead_end() {
        use crate::kinematics::{forward_kinematics, Frames};
        use core::f32::consts::PI;
        let wide = Joint::revolute(0.4, 0.7, 0.2, -6.2, 6.2, 1.0);
        let narrow = Joint::revolute(-0.3, 0.5, 0.0, -2.5, 2.5, 1.0);
        let slide = Joint::prismatic(0.2, 0.1, 0.0, 0.5, 2.0, 1.0);
        let robot = Robot::<4>::new(&[wide, narrow, wide, slide]).unwrap();
        let mut rng = Rng::seeded(11, &[]);
        let (mut before, mut after) = (Frames::default(), Frames::default());
        let mut turned = 0;
        for _ in 0..500 {
            let (mut from, mut goal) = ([0.0f32; 4], [0.0f32; 4]);
            draw_configuration(&mut rng, &robot, &mut from);
            draw_configuration(&mut rng, &robot, &mut goal);
            let mut q = goal;
            nearest_turns(&robot, &from, &mut q);
            for (j, joint) in robot.joints().iter().enumerate() {
                assert!(
                    q[j] >= joint.min && q[j] <= joint.max,
                    "joint {j}: {}",
                    q[j]
                );
                if joint.kind == JointKind::Prismatic || joint.max - joint.min < 2.0 * PI {
                    assert_eq!(q[j].to_bits(), goal[j].to_bits(), "joint {j}");
                    continue;
                }
                turned += usize::from(q[j] != goal[j]);
                let away = (q[j] - from[j]).abs();
                for other in [q[j] - 2.0 * PI, q[j] + 2.0 * PI] {
                    if other >= joint.min && other <= joint.max {
                        assert!((other - from[j]).abs() >= away - 1e-4, "joint {j}");
                    }
                }
            }
            forward_kinematics(&robot, &goal, &mut before);
            forward_kinematics(&robot, &q, &mut after);
            assert!((before.end_position() - after.end_position()).norm() < 1e-4);
            assert!((before.end_rotation() - after.end_rotation()).norm() < 1e-4);
        }
        assert!(turned > 100, "{turned} joints turned");
    }

    const N: usize = 2;

    /// A planar 2-link arm (links of 1) and a ball the elbow meets when
    /// joint 1 turns from 0 toward 1.2 rad.
    fn elbow_and_ball() -> Scenario<N, 1, 1> {
        let joint = Joint::revolute(0.0, 1.0, 0.0, -3.0, 3.0, 1.0);
        let robot = Robot::<N>::new(&[joint; N]).unwrap();
        let settings = Settings::for_robot(&robot);
        let mission = crate::Mission::new(&[Waypoint::at([0.0, 2.0, 0.0])], settings).unwrap();
        let ball = SuperEllipsoid::aligned([0.82, 0.57, 0.0], [0.1; 3], 2.0);
        Scenario::<N, 1, 1>::new(robot, &[ball], &mission).unwrap()
    }

    /// The planner's buffers a search imagines in.
    struct Buffers {
        next: Evaluation<N>,
        q: [f32; N],
        rate: [f32; N],
        law: LawWorkspace<N>,
    }

    impl Buffers {
        fn new() -> Self {
            Buffers {
                next: Evaluation::new(),
                q: [0.0; N],
                rate: [0.0; N],
                law: LawWorkspace::default(),
            }
        }

        fn scratch(&mut self) -> Scratch<'_, N> {
            Scratch {
                next: &mut self.next,
                q: &mut self.q,
                rate: &mut self.rate,
                law: &mut self.law,
            }
        }
    }

    /// Runs `f` in an imagination of `sc` aiming at its first target, in
    /// fresh buffers.
    fn imagine<R>(
        sc: &Scenario<N, 1, 1>,
        f: impl FnOnce(&mut Imagination<'_, '_, N, 1, 1>) -> R,
    ) -> R {
        let target = sc.targets()[0];
        let mut buffers = Buffers::new();
        let mut s = buffers.scratch();
        f(&mut Imagination {
            scenario: sc,
            target: &target,
            s: &mut s,
        })
    }

    /// An edge toward the goal blocked partway by an obstacle is kept as
    /// far as it was checked clear (RRT's extend): the tree grows by one
    /// node, partway along the edge, clear, and the connection stops.
    #[test]
    fn a_blocked_edge_is_kept_as_far_as_it_is_clear() {
        let sc = elbow_and_ball();
        let mut search = Search::<N>::default();
        search.begin(&[0.0, 0.0], 1.0);
        search.goal = [1.2, 0.0];
        search.stage = Stage::Grow;
        // The goal tree's root is node 1 (planted by the first unit): the
        // dead end's root connects toward it.
        search.connecting = Some(Connection { from: 0, toward: 1 });
        imagine(&sc, |im| {
            let mut rng = Rng::seeded(1, &[]);
            let mut spent = 0;
            assert_eq!(
                grow_unit(&mut search, &mut rng, im, &mut spent),
                Slice::Working
            );
            assert_eq!(search.tree.len(), 3, "the goal's root and one node added");
            assert_eq!(search.tree.root_of(1), Root::Goal);
            assert_eq!(search.tree.node(1), &[1.2, 0.0]);
            let node = *search.tree.node(2);
            assert_eq!(search.tree.root_of(2), Root::DeadEnd);
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
        });
    }

    /// A waypoint given as a joint configuration is the search's goal
    /// configuration as it is, in one evaluation and no draw; one the arm
    /// cannot stand in (the elbow in the ball) fails the search at once.
    #[test]
    fn a_joint_goal_is_the_goal_configuration_as_it_is() {
        for (goal, clear) in [([-2.0f32, 0.5], true), ([0.62, 0.0], false)] {
            let mut sc = elbow_and_ball();
            sc.set_joint_goal(0, &goal).unwrap();
            let mut search = Search::<N>::default();
            search.begin(&[0.0, 0.0], 1.0);
            let mut rng = Rng::seeded(5, &[]);
            let mut spent = 0;
            let slice = imagine(&sc, |im| goal_unit(&mut search, &mut rng, im, &mut spent));
            assert_eq!(spent, 1);
            assert_eq!(search.draws, 0);
            if clear {
                assert_eq!(slice, Slice::Working);
                assert_eq!(search.stage, Stage::Trunk);
                assert_eq!(search.goal, goal);
            } else {
                assert_eq!(slice, Slice::Failed);
            }
        }
    }

    /// Runs the certification until it ends (or 1 000 units).
    fn certify(search: &mut Search<N>, sc: &Scenario<N, 1, 1>) -> Slice {
        imagine(sc, |im| {
            for _ in 0..1000 {
                let mut spent = 0;
                let slice = shortcut_unit(search, im, &mut spent);
                if slice != Slice::Working || search.stage != Stage::Shortcut {
                    return slice;
                }
            }
            Slice::Working
        })
    }

    /// The trees met across the ball (the edge checks missed it, as they
    /// may a thin obstacle between two checks): the certification's sweep
    /// does not, and the dead end side's meeting node is pruned and the
    /// trees grow again. The same path round the other way is certified
    /// and found as it is.
    #[test]
    fn a_path_through_an_obstacle_is_pruned_before_the_walk() {
        let sc = elbow_and_ball();
        for (goal, through) in [([1.2f32, 0.0], true), ([-0.5, 0.0], false)] {
            let mut search = Search::<N>::default();
            search.begin(&[0.0, 0.0], 1.0);
            let meeting = search.tree.grow(&goal, 0, 0.5).unwrap();
            let goal_root = search.tree.plant_goal(&goal, 0.0).unwrap();
            search.found(meeting, goal_root);
            assert_eq!(search.path(), &[0, goal_root as u8]);
            let slice = certify(&mut search, &sc);
            if through {
                assert_eq!(slice, Slice::Working);
                assert_eq!(search.stage, Stage::Grow);
                assert!(search.tree.is_pruned(meeting));
                assert!(!search.tree.is_pruned(goal_root));
            } else {
                assert_eq!(slice, Slice::Found);
                assert_eq!(search.path(), &[0, goal_root as u8]);
                assert!(!search.tree.is_pruned(meeting));
            }
        }
    }

    /// Joined trees give one path: the dead end's chain to the meeting
    /// configuration, then the goal tree's chain from it to its root.
    #[test]
    fn joined_trees_give_one_path_from_the_dead_end_to_the_goal() {
        let mut s = Search::<3>::default();
        s.begin(&[0.0; 3], 2.0);
        let goal = s.tree.plant_goal(&[3.0, 0.0, 0.0], 0.0).unwrap();
        let a = s.tree.grow(&[1.0, 0.0, 0.0], 0, 1.0).unwrap();
        let meeting = s.tree.grow(&[1.5, 0.0, 0.0], a, 1.0).unwrap();
        let b = s.tree.grow(&[2.0, 0.0, 0.0], goal, 1.0).unwrap();
        let across = s.tree.grow(&[1.5, 0.0, 0.0], b, 1.0).unwrap();
        s.found(meeting, across);
        assert_eq!(s.path(), &[0, a as u8, across as u8, b as u8, goal as u8]);
        assert_eq!(s.path_node(4), Some(&[3.0, 0.0, 0.0]));
        assert_eq!(s.stage, Stage::Shortcut);
    }

    #[test]
    fn a_found_path_starts_at_the_dead_end_and_clears_in_place() {
        let mut s = Search::<3>::default();
        s.begin(&[1.0, 2.0, 3.0], 2.0);
        s.found(0, 0);
        assert_eq!(s.path(), &[0]);
        assert_eq!(s.path_node(0), Some(&[1.0, 2.0, 3.0]));
        assert_eq!(s.stage, Stage::Shortcut);
        s.clear();
        assert!(s.tree.is_empty() && s.path().is_empty());
        assert_eq!(s.path_node(0), None);
        assert_eq!(s.stage, Stage::Goal);
    }
}
