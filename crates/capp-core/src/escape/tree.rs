//! The escape search's tree: joint configurations, each with its parent and
//! its `V`, in fixed-size arrays (no allocation); nearest neighbour in
//! seconds at the rate limits, the path from the root to a node.

use crate::math::max;
use crate::robot::Robot;

/// Configurations the tree can hold, the root included.
pub const TREE_NODES: usize = 255;

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
    }
}
