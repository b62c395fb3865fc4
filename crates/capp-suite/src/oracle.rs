//! The oracle: RRT-Connect (Kuffner & LaValle 2000) in joint space, from the
//! start to the goal configuration, collision-checked by the independent
//! `f64` model of robot and obstacles ([`capp_sim::geometry::Geometry`]),
//! nothing of the planner's.
//!
//! * Metric: joint differences divided by the joint's rate limit, so lengths
//!   are seconds at the rate limits and the result does not depend on units;
//!   Euclidean for nearest neighbours and the extension step (`STEP_FRACTION`
//!   of the diagonal of the joint box), `max_j |dq_j| / rate_j` for the
//!   reported path time.
//! * Every edge is checked densely: no joint moves more than
//!   [`DENSE_STEP`] (0.01 rad or length unit)
//!   between checked configurations (coarse-to-fine order, so a blocked edge
//!   is found early); a configuration is free when every avoidance point has
//!   `C - 1 > 0` with the problem's margins and, when the scenario checks
//!   self-collision, every checked pair of link capsules a gap `> 0`.
//! * Self-collision along an edge is certified, not sampled: the links'
//!   motion bound ([`capp_sim::geometry`]) must prove every checked pair
//!   apart all along it, from the gaps at configurations bisected until the
//!   links move no more than a quarter of a capsule radius between them
//!   ([`Geometry::sweep_links`] with floor 0); an edge it cannot prove is
//!   refused (a pair passing within about a quarter radius of contact may be
//!   refused too), so no case is certified through a self-colliding path.
//! * Budget: a number of iterations, never a time, so a run repeats exactly on
//!   any machine. A case whose trees do not meet within it is *not certified*.
//! * The found path is re-checked densely, then shortened by random partial
//!   shortcuts (two random points on the path joined by a straight,
//!   densely checked segment), and the result re-checked densely again.

use std::time::Instant;

use capp_sim::geometry::Geometry;
use capp_sim::Problem;

use crate::metrics::{rate_time, rates, DENSE_STEP};
use crate::rng::Rng;

/// Extension step as a fraction of the joint box's diagonal (in seconds at the rate limits).
pub const STEP_FRACTION: f64 = 0.05;

/// The oracle's budget.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct Budget {
    /// RRT-Connect iterations (one sample, one extension, one connection attempt each).
    pub iterations: usize,
    /// Nodes in both trees together.
    pub nodes: usize,
    /// Shortcut attempts on a found path.
    pub shortcuts: usize,
}

impl Default for Budget {
    fn default() -> Self {
        Budget {
            iterations: 10_000,
            nodes: 40_000,
            shortcuts: 200,
        }
    }
}

/// What the oracle found.
#[derive(Clone, Debug, PartialEq)]
pub struct OracleResult {
    /// A collision-free path was found (and passed the dense re-check).
    pub solved: bool,
    /// Iterations used.
    pub iterations: usize,
    /// Nodes in both trees.
    pub nodes: usize,
    /// Wall time, milliseconds (search, shortcuts and re-checks).
    pub wall_ms: f64,
    /// Time of the path as found, at the rate limits, seconds.
    pub raw_time: Option<f64>,
    /// Time of the shortcut path at the rate limits, seconds.
    pub path_time: Option<f64>,
    /// The shortcut path, start first, goal last (empty when not solved).
    pub path: Vec<Vec<f64>>,
}

/// The configuration space of a problem, as the oracle sees it.
pub struct Space {
    geometry: Geometry,
    lo: Vec<f64>,
    hi: Vec<f64>,
    inv_rate: Vec<f64>,
    rates: Vec<f64>,
    /// Configurations checked so far.
    pub checks: usize,
}

impl Space {
    /// The joint box and obstacles of `problem`.
    pub fn new(problem: &Problem) -> Self {
        let rates = rates(problem);
        Space {
            geometry: Geometry::new(problem),
            lo: problem.joints.iter().map(|j| j.min as f64).collect(),
            hi: problem.joints.iter().map(|j| j.max as f64).collect(),
            inv_rate: rates.iter().map(|r| 1.0 / r).collect(),
            rates,
            checks: 0,
        }
    }

    fn within_limits(&self, q: &[f64]) -> bool {
        q.iter()
            .zip(self.lo.iter().zip(&self.hi))
            .all(|(x, (lo, hi))| x >= lo && x <= hi)
    }

    /// Whether `q` is within limits, every point is outside every inflated
    /// obstacle and no two checked link capsules touch.
    pub fn free(&mut self, q: &[f64]) -> bool {
        self.checks += 1;
        self.within_limits(q) && self.geometry.is_free(q)
    }

    /// Whether the straight segment `a` -> `b` is free: `b`, and every point
    /// between at most [`DENSE_STEP`] apart per joint clear of the
    /// obstacles, and the link capsules proved apart all along it (`a` is
    /// taken as checked).
    pub fn segment_free(&mut self, a: &[f64], b: &[f64]) -> bool {
        if !self.free(b) {
            return false;
        }
        if !self.obstacles_free(a, b) {
            return false;
        }
        if !self.geometry.self_collision() {
            return true;
        }
        let (gaps_a, gaps_b) = (
            self.geometry.link_gaps(&self.geometry.pose(a)),
            self.geometry.link_gaps(&self.geometry.pose(b)),
        );
        let sweep = self.geometry.sweep_links(a, b, &gaps_a, &gaps_b, 0.0, true);
        self.checks += sweep.samples;
        sweep.certified
    }

    /// The obstacle part of [`Space::segment_free`], between the ends.
    fn obstacles_free(&mut self, a: &[f64], b: &[f64]) -> bool {
        let d = a
            .iter()
            .zip(b)
            .map(|(x, y)| (y - x).abs())
            .fold(0.0, f64::max);
        let steps = (d / DENSE_STEP).ceil() as usize;
        if steps < 2 {
            return true;
        }
        // Coarse to fine: odd multiples of s, for s = 2^k down to 1.
        let mut q = vec![0.0; a.len()];
        let mut s = steps.next_power_of_two();
        while s >= 1 {
            let mut i = s;
            while i < steps {
                let t = i as f64 / steps as f64;
                for (k, v) in q.iter_mut().enumerate() {
                    *v = a[k] + t * (b[k] - a[k]);
                }
                self.checks += 1;
                if !(self.within_limits(&q) && self.geometry.is_clear(&q, 0.0)) {
                    return false;
                }
                i += 2 * s;
            }
            s /= 2;
        }
        true
    }

    /// Squared rate-scaled distance.
    fn dist2(&self, a: &[f64], b: &[f64]) -> f64 {
        a.iter()
            .zip(b)
            .zip(&self.inv_rate)
            .map(|((x, y), w)| ((y - x) * w).powi(2))
            .sum()
    }

    fn sample(&self, rng: &mut Rng) -> Vec<f64> {
        self.lo
            .iter()
            .zip(&self.hi)
            .map(|(&lo, &hi)| rng.range(lo, hi))
            .collect()
    }

    /// The extension step, seconds.
    fn step(&self) -> f64 {
        STEP_FRACTION * libm::sqrt(self.dist2(&self.lo, &self.hi))
    }

    /// Time of a path at the rate limits.
    pub fn path_time(&self, path: &[Vec<f64>]) -> f64 {
        path.windows(2)
            .map(|w| rate_time(&self.rates, &w[0], &w[1]))
            .sum()
    }
}

struct Tree {
    n: usize,
    q: Vec<f64>,
    parent: Vec<usize>,
}

enum Grow {
    Trapped,
    Advanced(usize),
    Reached(usize),
}

impl Tree {
    fn new(root: &[f64]) -> Self {
        Tree {
            n: root.len(),
            q: root.to_vec(),
            parent: vec![0],
        }
    }

    fn len(&self) -> usize {
        self.parent.len()
    }

    fn node(&self, i: usize) -> &[f64] {
        &self.q[i * self.n..(i + 1) * self.n]
    }

    fn nearest(&self, space: &Space, q: &[f64]) -> usize {
        let mut best = (f64::INFINITY, 0);
        for i in 0..self.len() {
            let d = space.dist2(self.node(i), q);
            if d < best.0 {
                best = (d, i);
            }
        }
        best.1
    }

    fn extend(&mut self, space: &mut Space, target: &[f64], step: f64) -> Grow {
        let near = self.nearest(space, target);
        let from = self.node(near).to_vec();
        let d = libm::sqrt(space.dist2(&from, target));
        let reached = d <= step;
        let new: Vec<f64> = if reached {
            target.to_vec()
        } else {
            from.iter()
                .zip(target)
                .map(|(a, b)| a + (b - a) * step / d)
                .collect()
        };
        if !space.segment_free(&from, &new) {
            return Grow::Trapped;
        }
        self.q.extend_from_slice(&new);
        self.parent.push(near);
        let i = self.len() - 1;
        if reached {
            Grow::Reached(i)
        } else {
            Grow::Advanced(i)
        }
    }

    fn connect(&mut self, space: &mut Space, target: &[f64], step: f64) -> Grow {
        loop {
            match self.extend(space, target, step) {
                Grow::Advanced(_) => continue,
                other => return other,
            }
        }
    }

    /// Nodes from `i` back to the root.
    fn chain(&self, mut i: usize) -> Vec<Vec<f64>> {
        let mut out = vec![self.node(i).to_vec()];
        while i != 0 {
            i = self.parent[i];
            out.push(self.node(i).to_vec());
        }
        out
    }
}

/// Plans from `start` to `goal` in `problem`'s joint space.
pub fn rrt_connect(
    problem: &Problem,
    start: &[f64],
    goal: &[f64],
    budget: Budget,
    rng: &mut Rng,
) -> OracleResult {
    let started = Instant::now();
    let mut space = Space::new(problem);
    let step = space.step();
    let mut result = OracleResult {
        solved: false,
        iterations: 0,
        nodes: 2,
        wall_ms: 0.0,
        raw_time: None,
        path_time: None,
        path: Vec::new(),
    };
    let mut path = None;
    if space.free(start) && space.free(goal) {
        if space.segment_free(start, goal) {
            path = Some(vec![start.to_vec(), goal.to_vec()]);
        } else {
            let mut a = Tree::new(start);
            let mut b = Tree::new(goal);
            let mut a_is_start = true;
            while result.iterations < budget.iterations && a.len() + b.len() < budget.nodes {
                result.iterations += 1;
                let sample = space.sample(rng);
                let grown = match a.extend(&mut space, &sample, step) {
                    Grow::Trapped => None,
                    Grow::Advanced(i) | Grow::Reached(i) => Some(i),
                };
                if let Some(i) = grown {
                    let q = a.node(i).to_vec();
                    if let Grow::Reached(j) = b.connect(&mut space, &q, step) {
                        let (s, g) = if a_is_start { (&a, &b) } else { (&b, &a) };
                        let (si, gi) = if a_is_start { (i, j) } else { (j, i) };
                        let mut p = s.chain(si);
                        p.reverse();
                        p.extend(g.chain(gi).into_iter().skip(1));
                        path = Some(p);
                        break;
                    }
                }
                std::mem::swap(&mut a, &mut b);
                a_is_start = !a_is_start;
            }
            result.nodes = a.len() + b.len();
        }
    }
    if let Some(raw) = path {
        if dense_path_free(&mut space, &raw) {
            result.raw_time = Some(space.path_time(&raw));
            let short = shortcut(&mut space, raw.clone(), budget.shortcuts, rng);
            let path = if dense_path_free(&mut space, &short) {
                short
            } else {
                raw
            };
            result.path_time = Some(space.path_time(&path));
            result.path = path;
            result.solved = true;
        }
    }
    result.wall_ms = started.elapsed().as_secs_f64() * 1e3;
    result
}

/// Whether every vertex and every segment of `path` is free (dense).
pub fn dense_path_free(space: &mut Space, path: &[Vec<f64>]) -> bool {
    path.first().is_some_and(|q| space.free(q))
        && path.windows(2).all(|w| space.segment_free(&w[0], &w[1]))
}

fn lerp(a: &[f64], b: &[f64], t: f64) -> Vec<f64> {
    a.iter().zip(b).map(|(x, y)| x + t * (y - x)).collect()
}

/// Random partial shortcuts: two random points on the path, joined straight
/// when that segment is free.
fn shortcut(
    space: &mut Space,
    mut path: Vec<Vec<f64>>,
    tries: usize,
    rng: &mut Rng,
) -> Vec<Vec<f64>> {
    for _ in 0..tries {
        let segments = path.len() - 1;
        if segments < 2 {
            break;
        }
        let (mut s1, mut s2) = (rng.below(segments), rng.below(segments));
        if s1 == s2 {
            continue;
        }
        if s1 > s2 {
            std::mem::swap(&mut s1, &mut s2);
        }
        let a = lerp(&path[s1], &path[s1 + 1], rng.f64());
        let b = lerp(&path[s2], &path[s2 + 1], rng.f64());
        if space.segment_free(&a, &b) {
            let mut next = path[..=s1].to_vec();
            next.push(a);
            next.push(b);
            next.extend_from_slice(&path[s2 + 1..]);
            path = next;
        }
    }
    path
}
