//! The escape search's trees: joint configurations, each with its parent,
//! its `V` and the tree it belongs to, in fixed-size arrays (no
//! allocation). Two trees share the arrays, as RRT-Connect grows them: one
//! rooted at the dead end (node 0), one at the goal configuration (a root is
//! its own parent). Nearest neighbour in seconds at the rate limits within
//! one tree, the path from a node to its root.

use crate::math::max;
use crate::robot::Robot;

/// Configurations the tree can hold, the root included.
pub const TREE_NODES: usize = 255;

/// Which of the two trees a node belongs to.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Root {
    /// Grown from the dead end (node 0).
    DeadEnd,
    /// Grown from the goal configuration.
    Goal,
}

impl Root {
    /// The other tree.
    pub fn other(self) -> Root {
        match self {
            Root::DeadEnd => Root::Goal,
            Root::Goal => Root::DeadEnd,
        }
    }
}

/// Words of the bit set that marks the goal tree's nodes.
const ROOT_WORDS: usize = TREE_NODES.div_ceil(32);

/// The trees: configurations, their parents, their `V` and which tree each
/// is in.
#[derive(Clone, Debug)]
pub struct Tree<const N: usize> {
    q: [[f32; N]; TREE_NODES],
    parent: [u8; TREE_NODES],
    v: [f32; TREE_NODES],
    /// Bit `i`: node `i` is in the goal tree.
    goal_side: [u32; ROOT_WORDS],
    /// Bit `i`: node `i` is pruned (an edge to it or above it failed).
    pruned: [u32; ROOT_WORDS],
    len: u8,
}

impl<const N: usize> Default for Tree<N> {
    fn default() -> Self {
        Tree {
            q: [[0.0; N]; TREE_NODES],
            parent: [0; TREE_NODES],
            v: [f32::INFINITY; TREE_NODES],
            goal_side: [0; ROOT_WORDS],
            pruned: [0; ROOT_WORDS],
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
        self.goal_side.fill(0);
        self.pruned.fill(0);
        self.len = 0;
    }

    /// Empties the trees and plants the dead end's, `root` (value `v`).
    pub fn plant(&mut self, root: &[f32], v: f32) {
        self.len = 0;
        self.goal_side.fill(0);
        self.pruned.fill(0);
        self.push(root, 0, v);
    }

    /// Plants the goal tree's root `q` (value `v`); its index, or `None`
    /// when full.
    pub fn plant_goal(&mut self, q: &[f32], v: f32) -> Option<usize> {
        let i = self.push(q, self.len(), v)?;
        set_bit(&mut self.goal_side, i);
        Some(i)
    }

    /// Adds `q` (value `v`) under `parent`, in `parent`'s tree; its index,
    /// or `None` when full.
    pub fn grow(&mut self, q: &[f32], parent: usize, v: f32) -> Option<usize> {
        let i = self.push(q, parent, v)?;
        if self.root_of(parent) == Root::Goal {
            set_bit(&mut self.goal_side, i);
        }
        Some(i)
    }

    /// Node `i`'s parent (itself for a root).
    pub fn parent(&self, i: usize) -> usize {
        self.parent.get(i).copied().unwrap_or(0) as usize
    }

    /// Prunes node `i` (not a root) and every node under it: they are
    /// never nearest again. One pass: parents have smaller indices.
    pub fn prune(&mut self, i: usize) {
        if self.parent(i) == i {
            return;
        }
        set_bit(&mut self.pruned, i);
        for k in i + 1..self.len() {
            if bit(&self.pruned, self.parent(k)) {
                set_bit(&mut self.pruned, k);
            }
        }
    }

    /// Whether node `i` is pruned.
    pub fn is_pruned(&self, i: usize) -> bool {
        bit(&self.pruned, i)
    }

    /// The tree node `i` is in.
    pub fn root_of(&self, i: usize) -> Root {
        if bit(&self.goal_side, i) {
            Root::Goal
        } else {
            Root::DeadEnd
        }
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

    /// Adds `q` (value `v`) under `parent` (itself, when `parent` is its
    /// index: a root); its index, or `None` when full. The node is in the
    /// dead end's tree unless marked.
    fn push(&mut self, q: &[f32], parent: usize, v: f32) -> Option<usize> {
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

    /// The node of tree `root` nearest `q` in seconds at the rate limits
    /// (the root of a sum of squares, each joint's distance over its rate
    /// limit), pruned nodes left out; node 0 when that tree has none.
    pub fn nearest(&self, robot: &Robot<N>, q: &[f32], root: Root) -> usize {
        let mut best = (0, f32::INFINITY);
        for (i, node) in self.q.iter().enumerate().take(self.len()) {
            if self.root_of(i) != root || self.is_pruned(i) {
                continue;
            }
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

    /// The path from node `end` to its tree's root as node indices, `end`
    /// first, written into `path` from position `at`; returns the position
    /// after the last written (positions past `path` are dropped).
    pub fn to_root(&self, end: usize, path: &mut [u8; TREE_NODES], at: usize) -> usize {
        let mut len = at;
        let mut i = end.min(self.len().saturating_sub(1));
        // At most TREE_NODES hops: parents always have smaller indices,
        // a root is its own parent.
        for _ in 0..TREE_NODES {
            if let Some(slot) = path.get_mut(len) {
                *slot = i as u8;
                len += 1;
            }
            let parent = self.parent(i);
            if parent == i {
                break;
            }
            i = parent;
        }
        len
    }

    /// The path from the root to node `end` as node indices, root first,
    /// into `path`; returns its length.
    pub fn path(&self, end: usize, path: &mut [u8; TREE_NODES]) -> usize {
        let len = self.to_root(end, path, 0);
        if let Some(p) = path.get_mut(..len) {
            p.reverse();
        }
        len
    }
}

/// Bit `i` of a node bit set.
fn bit(set: &[u32; ROOT_WORDS], i: usize) -> bool {
    set.get(i / 32).is_some_and(|w| (w >> (i % 32)) & 1 == 1)
}

/// Sets bit `i` of a node bit set.
fn set_bit(set: &mut [u32; ROOT_WORDS], i: usize) {
    if let Some(word) = set.get_mut(i / 32) {
        *word |= 1 << (i % 32);
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
        let a = t.grow(&[1.0, 0.0, 0.0], 0, 3.0).unwrap();
        let b = t.grow(&[0.0, 1.0, 0.0], 0, 5.0).unwrap();
        let c = t.grow(&[2.0, 0.0, 0.0], a, 1.0).unwrap();
        let mut path = [0u8; TREE_NODES];
        let len = t.path(c, &mut path);
        assert_eq!(&path[..len], &[0, a as u8, c as u8]);
        assert_eq!(t.path(b, &mut path), 2);
        assert_eq!(t.path(0, &mut path), 1);
        assert_eq!(t.lowest(), c);
        // Seconds at the rate limits: joint 2 (0.5 rad/s) counts four times joint 1.
        let r = robot();
        assert_eq!(t.nearest(&r, &[0.0, 0.0, 0.3], Root::DeadEnd), 0);
        assert_eq!(t.nearest(&r, &[1.9, 0.0, 0.0], Root::DeadEnd), c);
        assert_eq!(t.nearest(&r, &[0.1, 1.5, 0.0], Root::DeadEnd), b);
    }

    /// The goal tree shares the arrays: its nodes know their tree, nearest
    /// looks in one tree only, a path runs to its own root, and a pruned
    /// node takes its subtree with it (and a root is never pruned).
    #[test]
    fn two_trees_share_the_arrays_and_prune_whole_subtrees() {
        let r = robot();
        let mut t = Tree::<3>::default();
        t.plant(&[0.0; 3], 4.0);
        let goal = t.plant_goal(&[2.0, 0.0, 0.0], 0.0).unwrap();
        let a = t.grow(&[0.5, 0.0, 0.0], 0, 3.0).unwrap();
        let b = t.grow(&[1.5, 0.0, 0.0], goal, 1.0).unwrap();
        let c = t.grow(&[1.0, 0.1, 0.0], b, 1.0).unwrap();
        let d = t.grow(&[0.6, 1.5, 0.0], a, 2.0).unwrap();
        assert_eq!(
            [0, goal, a, b, c, d].map(|i| t.root_of(i)),
            [
                Root::DeadEnd,
                Root::Goal,
                Root::DeadEnd,
                Root::Goal,
                Root::Goal,
                Root::DeadEnd
            ]
        );
        // [1.1, 0, 0] is nearest `c` (goal tree), `a` among the dead end's.
        assert_eq!(t.nearest(&r, &[1.1, 0.0, 0.0], Root::Goal), c);
        assert_eq!(t.nearest(&r, &[1.1, 0.0, 0.0], Root::DeadEnd), a);
        let mut path = [0u8; TREE_NODES];
        let len = t.to_root(c, &mut path, 0);
        assert_eq!(&path[..len], &[c as u8, b as u8, goal as u8]);
        // Pruning `a` takes `d`; the dead end's root stays.
        t.prune(a);
        assert!(t.is_pruned(a) && t.is_pruned(d) && !t.is_pruned(b));
        assert_eq!(t.nearest(&r, &[0.6, 0.5, 0.0], Root::DeadEnd), 0);
        t.prune(goal);
        assert!(!t.is_pruned(goal));
        assert_eq!(t.nearest(&r, &[1.9, 0.0, 0.0], Root::Goal), goal);
        t.plant(&[0.0; 3], 1.0);
        assert!(!t.is_pruned(a) && t.root_of(1) == Root::DeadEnd);
    }

    #[test]
    fn a_full_tree_refuses_more_and_clears_in_place() {
        let mut t = Tree::<3>::default();
        t.plant(&[0.0; 3], 1.0);
        for i in 1..TREE_NODES {
            assert_eq!(t.grow(&[i as f32, 0.0, 0.0], i - 1, 1.0), Some(i));
        }
        assert!(t.is_full());
        assert_eq!(t.grow(&[0.0; 3], 0, 0.0), None);
        assert_eq!(t.plant_goal(&[0.0; 3], 0.0), None);
        let mut path = [0u8; TREE_NODES];
        assert_eq!(t.path(TREE_NODES - 1, &mut path), TREE_NODES);
        t.clear();
        assert!(t.is_empty());
    }
}
