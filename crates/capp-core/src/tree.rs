//! The escape's search at a dead end, in imagination (the arm holds still
//! while it runs; the planner does a bounded slice of it per step, see
//! `planner::search`): a goal configuration, then a tree in joint space
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
//!    the contact floor or no closer than where they come from). At most
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

use crate::math::max;
use crate::robot::Robot;

/// Configurations the tree can hold, the root included.
pub const TREE_NODES: usize = 255;
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
pub enum Stage {
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
    pub tree: Tree<N>,
    /// The goal configuration, once found.
    pub goal: [f32; N],
    /// The current descent's configuration.
    pub probe: [f32; N],
    /// What the search is doing.
    pub stage: Stage,
    /// Whether a descent is under way from `probe`, and its steps.
    pub probing: bool,
    /// Law steps of the current descent.
    pub probe_steps: u16,
    /// Descents started.
    pub descents: u16,
    /// Trunk steps taken, and the trunk's last node.
    pub trunk_steps: u16,
    /// The trunk's last node.
    pub base: u8,
    /// Extensions tried.
    pub extensions: u16,
    /// The node a greedy connection carries on from.
    pub connecting: Option<u8>,
    /// The path found (node indices, root first), shortened in place.
    pub path: [u8; TREE_NODES],
    /// Its length.
    pub path_len: u8,
    /// Shortcut: the path position the segment starts from, the one it
    /// tries to reach, the next position to write, the configuration of the
    /// segment to check next, and the checks spent.
    pub from: u8,
    /// See `from`.
    pub to: u8,
    /// See `from`.
    pub out: u8,
    /// See `from`.
    pub check: u16,
    /// See `from`.
    pub shortcut_checks: u16,
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
    pub fn found(&mut self, end: usize) {
        self.path_len = self.tree.path(end, &mut self.path) as u8;
        self.stage = Stage::Shortcut;
        self.from = 0;
        self.out = 1;
        self.to = self.path_len.saturating_sub(1);
        self.check = 1;
    }

    /// The path, shortened.
    pub fn path(&self) -> &[u8] {
        &self.path[..(self.path_len as usize).min(TREE_NODES)]
    }
}

/// The tree: configurations, their parents and their `V`.
#[derive(Clone, Debug)]
pub struct Tree<const N: usize> {
    q: [[f32; N]; TREE_NODES],
    parent: [u8; TREE_NODES],
    v: [f32; TREE_NODES],
    len: u8,
}

impl<const N: usize> Default for Tree<N> {
    fn default() -> Self {
        Tree {
            q: [[0.0; N]; TREE_NODES],
            parent: [0; TREE_NODES],
            v: [f32::INFINITY; TREE_NODES],
            len: 0,
        }
    }
}

impl<const N: usize> Tree<N> {
    /// [`Tree::default`] in place (a tree is kilobytes: never a temporary
    /// on a board's stack).
    pub fn clear(&mut self) {
        for q in self.q.iter_mut() {
            q.fill(0.0);
        }
        self.parent.fill(0);
        self.v.fill(f32::INFINITY);
        self.len = 0;
    }

    /// Empties the tree and plants `root` (value `v`).
    pub fn plant(&mut self, root: &[f32], v: f32) {
        self.len = 0;
        self.push(root, 0, v);
    }

    /// Nodes held.
    pub fn len(&self) -> usize {
        self.len as usize
    }

    /// Whether the tree holds no node.
    pub fn is_empty(&self) -> bool {
        self.len == 0
    }

    /// Whether the budget is spent.
    pub fn is_full(&self) -> bool {
        self.len() >= TREE_NODES
    }

    /// Adds `q` (value `v`) under `parent`; its index, or `None` when full.
    pub fn push(&mut self, q: &[f32], parent: usize, v: f32) -> Option<usize> {
        let i = self.len();
        let slot = self.q.get_mut(i)?;
        let n = q.len().min(N);
        slot[..n].copy_from_slice(&q[..n]);
        *self.parent.get_mut(i)? = parent.min(i) as u8;
        *self.v.get_mut(i)? = v;
        self.len += 1;
        Some(i)
    }

    /// Node `i`'s configuration (the root's when `i` is out of range).
    pub fn node(&self, i: usize) -> &[f32; N] {
        self.q.get(i).unwrap_or(&self.q[0])
    }

    /// Node `i`'s `V`.
    pub fn value(&self, i: usize) -> f32 {
        self.v.get(i).copied().unwrap_or(f32::INFINITY)
    }

    /// The node with the lowest `V`.
    pub fn lowest(&self) -> usize {
        let mut best = 0;
        for i in 1..self.len() {
            if self.value(i) < self.value(best) {
                best = i;
            }
        }
        best
    }

    /// The node nearest `q` in seconds at the rate limits (the root of a
    /// sum of squares, each joint's distance over its rate limit).
    pub fn nearest(&self, robot: &Robot<N>, q: &[f32]) -> usize {
        let mut best = (0, f32::INFINITY);
        for (i, node) in self.q.iter().enumerate().take(self.len()) {
            let d: f32 = robot
                .joints()
                .iter()
                .zip(node.iter().zip(q))
                .map(|(joint, (&a, &b))| {
                    let t = (a - b) / max(joint.max_rate, f32::MIN_POSITIVE);
                    t * t
                })
                .sum();
            if d < best.1 {
                best = (i, d);
            }
        }
        best.0
    }

    /// The path from the root to node `end` as node indices, root first,
    /// into `path`; returns its length.
    pub fn path(&self, end: usize, path: &mut [u8; TREE_NODES]) -> usize {
        let mut len = 0;
        let mut i = end.min(self.len().saturating_sub(1));
        // At most TREE_NODES hops: parents always have smaller indices.
        for _ in 0..TREE_NODES {
            if let Some(slot) = path.get_mut(len) {
                *slot = i as u8;
                len += 1;
            }
            if i == 0 {
                break;
            }
            i = self.parent.get(i).copied().unwrap_or(0) as usize;
        }
        if let Some(p) = path.get_mut(..len) {
            p.reverse();
        }
        len
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::robot::{Joint, Robot};

    fn robot() -> Robot<3> {
        let joint = |max_rate| Joint::revolute(0.0, 1.0, 0.0, -3.0, 3.0, max_rate);
        Robot::new(&[joint(1.0), joint(2.0), joint(0.5)]).unwrap()
    }

    #[test]
    fn a_path_runs_from_the_root_through_the_parents() {
        let mut t = Tree::<3>::default();
        t.plant(&[0.0; 3], 4.0);
        let a = t.push(&[1.0, 0.0, 0.0], 0, 3.0).unwrap();
        let b = t.push(&[0.0, 1.0, 0.0], 0, 5.0).unwrap();
        let c = t.push(&[2.0, 0.0, 0.0], a, 1.0).unwrap();
        let mut path = [0u8; TREE_NODES];
        let len = t.path(c, &mut path);
        assert_eq!(&path[..len], &[0, a as u8, c as u8]);
        assert_eq!(t.path(b, &mut path), 2);
        assert_eq!(t.path(0, &mut path), 1);
        assert_eq!(t.lowest(), c);
        // Seconds at the rate limits: joint 2 (0.5 rad/s) counts four times joint 1.
        let r = robot();
        assert_eq!(t.nearest(&r, &[0.0, 0.0, 0.3]), 0);
        assert_eq!(t.nearest(&r, &[1.9, 0.0, 0.0]), c);
        assert_eq!(t.nearest(&r, &[0.1, 1.5, 0.0]), b);
    }

    #[test]
    fn a_full_tree_refuses_more_and_clears_in_place() {
        let mut t = Tree::<3>::default();
        t.plant(&[0.0; 3], 1.0);
        for i in 1..TREE_NODES {
            assert_eq!(t.push(&[i as f32, 0.0, 0.0], i - 1, 1.0), Some(i));
        }
        assert!(t.is_full());
        assert_eq!(t.push(&[0.0; 3], 0, 0.0), None);
        let mut path = [0u8; TREE_NODES];
        assert_eq!(t.path(TREE_NODES - 1, &mut path), TREE_NODES);
        t.clear();
        assert!(t.is_empty());
        let mut s = Search::<3>::default();
        s.begin(&[1.0, 2.0, 3.0], 2.0);
        s.found(0);
        assert_eq!(s.path(), &[0]);
        s.clear();
        assert!(s.tree.is_empty() && s.path().is_empty());
    }
}
