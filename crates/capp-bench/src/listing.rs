//! The paper's own method as its listing (CAPP.c) computes it, in Rust: the
//! baseline the planner's cost is compared with, on the same scenarios.
//!
//! What one step of the listing does (see `shared/docs/algorithm.md`, section 5):
//!
//! * forward kinematics by 4 x 4 homogeneous products `T_k = T_{k-1} A_k`, each
//!   `A_k` (eq. 5) built from fresh `cos`/`sin` of its `theta` and `alpha`;
//! * every Jacobian column and the obstacle gradient by **central differences**:
//!   each joint moved by `+-DELTA`, the **whole chain** recomputed for each (so
//!   `2 n + 1` chains of `n` products a step, O(n^2));
//! * the potential (eq. 26) over **every** point / obstacle pair (no influence
//!   cut-off), each `C` (eq. 25) by three `powf` calls on
//!   `(p - c) / (s + margin)` (margins 6.0 at joints, 3.0 at link mid-points);
//! * the rate `metric_i (J_4^T e_4)_i / |e_4| + 10 sum_k (J_k^T r_Tk)_i`,
//!   normalised, the component along `mu_hat` removed, each revolute rate
//!   clipped to 0.175, and an Euler step `q += h rate`.
//!
//! Kinder to the baseline than the listing itself: `f32` (the C code used
//! `double`), no `malloc` in the loop, the obstacle rotation done correctly
//! (`x = R^T (p - c)`, the same work as the listing's in-place rotation), and
//! clamping into the joint limits.

use capp_core::math::Vec3;
use capp_core::obstacle::{Obstacle, PointKind};
use capp_core::{JointKind, Scenario};

/// Joint perturbation of the central differences (the listing's 0.005 rad or in).
pub const DELTA: f32 = 0.005;
/// The listing's weight of the orientation terms.
pub const ORIENTATION_WEIGHT: f32 = 10.0;
/// The listing's clip on each revolute rate.
pub const RATE_CLIP: f32 = 0.175;

type Mat4 = [[f32; 4]; 4];

/// The end-effector pose (columns `r_n1..r_n4`) and the potential at one configuration.
#[derive(Clone, Copy, Debug, Default)]
pub struct Evaluation {
    /// `r_n1, r_n2, r_n3` (orientation) and `r_n4` (position).
    pub columns: [Vec3; 4],
    /// Potential `P` of eq. 26 over every pair.
    pub potential: f32,
}

/// The listing's planner state: the joint vector and its Jacobian buffers.
#[derive(Clone, Debug)]
pub struct Listing<const N: usize> {
    n: usize,
    q: [f32; N],
    /// `d r_ni / d q_j` for the four columns, per joint.
    jacobian: [[Vec3; 4]; N],
    /// `dP/dq` by central differences.
    mu: [f32; N],
    rate: [f32; N],
}

/// `A = Rot_z(theta) Trans_z(d) Trans_x(a) Rot_x(alpha)` (eq. 5), trig recomputed.
fn link_transform(alpha: f32, theta: f32, a: f32, d: f32) -> Mat4 {
    let (ct, st) = (libm::cosf(theta), libm::sinf(theta));
    let (ca, sa) = (libm::cosf(alpha), libm::sinf(alpha));
    [
        [ct, -st * ca, st * sa, a * ct],
        [st, ct * ca, -ct * sa, a * st],
        [0.0, sa, ca, d],
        [0.0, 0.0, 0.0, 1.0],
    ]
}

fn multiply(x: &Mat4, y: &Mat4) -> Mat4 {
    let mut out = [[0.0; 4]; 4];
    for (i, row) in out.iter_mut().enumerate() {
        for (j, cell) in row.iter_mut().enumerate() {
            *cell = (0..4).map(|k| x[i][k] * y[k][j]).sum();
        }
    }
    out
}

fn translation(t: &Mat4) -> Vec3 {
    Vec3::new(t[0][3], t[1][3], t[2][3])
}

/// `C - 1` of eq. 25 with `powf`, inflated by the margin of `kind`, over
/// every axis. The listing knows only super-ellipsoids: another shape is
/// measured as the core measures it.
fn cost(obstacle: &Obstacle, p: &Vec3, kind: PointKind, margins: [f32; 2]) -> f32 {
    let Some(s) = obstacle.source().super_ellipsoid() else {
        return obstacle.clearance_uncut(p, kind, &[]);
    };
    let margin = margins[kind as usize];
    let x = obstacle.rotation().transpose() * (p - obstacle.centre());
    let mut c = -1.0;
    for axis in 0..3 {
        let u = libm::fabsf(x[axis]) / (s.semi_axes[axis] + margin);
        c += libm::powf(u, s.exponents[axis]);
    }
    c
}

/// Pose and potential at `q`: the whole chain, every point, every obstacle.
pub fn evaluate<const N: usize, const M: usize, const W: usize>(
    scenario: &Scenario<N, M, W>,
    q: &[f32],
) -> Evaluation {
    let robot = scenario.robot();
    let avoidance = &scenario.settings().avoidance;
    let obstacles = scenario.obstacles();
    let mut t: Mat4 = [
        [1.0, 0.0, 0.0, 0.0],
        [0.0, 1.0, 0.0, 0.0],
        [0.0, 0.0, 1.0, 0.0],
        [0.0, 0.0, 0.0, 1.0],
    ];
    let mut previous = Vec3::zeros();
    let mut potential = 0.0;
    for (joint, &qj) in robot.joints().iter().zip(q) {
        let (theta, d) = match joint.kind {
            JointKind::Revolute => (qj, joint.d),
            JointKind::Prismatic => (joint.theta, qj),
        };
        t = multiply(&t, &link_transform(joint.alpha, theta, joint.a, d));
        let origin = translation(&t);
        let middle = (origin + previous) * 0.5;
        for obstacle in obstacles {
            potential += 1.0 / cost(obstacle, &origin, PointKind::Joint, avoidance.margins());
            potential += 1.0 / cost(obstacle, &middle, PointKind::Link, avoidance.margins());
        }
        previous = origin;
    }
    let column = |c: usize| Vec3::new(t[0][c], t[1][c], t[2][c]);
    Evaluation {
        columns: [column(0), column(1), column(2), column(3)],
        potential,
    }
}

impl<const N: usize> Listing<N> {
    /// Starts at `q` (`n` values).
    pub fn new(q: &[f32]) -> Self {
        let n = q.len().min(N);
        let mut state = Listing {
            n,
            q: [0.0; N],
            jacobian: [[Vec3::zeros(); 4]; N],
            mu: [0.0; N],
            rate: [0.0; N],
        };
        state.q[..n].copy_from_slice(&q[..n]);
        state
    }

    /// The joint vector.
    pub fn joints(&self) -> &[f32] {
        &self.q[..self.n]
    }

    /// `dP/dq` of the last step, by central differences.
    pub fn obstacle_gradient(&self) -> &[f32] {
        &self.mu[..self.n]
    }

    /// `d r_ni / d q_j` of the last step (`i` = 0..3: `r_n1, r_n2, r_n3, r_n4`).
    pub fn jacobian_column(&self, joint: usize, column: usize) -> Vec3 {
        self.jacobian[joint][column]
    }

    /// One step of the listing toward the scenario's first target. Returns the
    /// position error before the step, length units.
    pub fn step<const M: usize, const W: usize>(&mut self, scenario: &Scenario<N, M, W>) -> f32 {
        let n = self.n;
        let joints = scenario.robot().joints();
        let target = scenario.targets()[0];
        let here = evaluate(scenario, &self.q[..n]);
        for j in 0..n {
            let keep = self.q[j];
            self.q[j] = keep + DELTA;
            let plus = evaluate(scenario, &self.q[..n]);
            self.q[j] = keep - DELTA;
            let minus = evaluate(scenario, &self.q[..n]);
            self.q[j] = keep;
            for c in 0..4 {
                self.jacobian[j][c] = (plus.columns[c] - minus.columns[c]) / (2.0 * DELTA);
            }
            self.mu[j] = (plus.potential - minus.potential) / (2.0 * DELTA);
        }
        let e4 = target.position - here.columns[3];
        let error = libm::sqrtf(e4.dot(&e4));
        for ((joint, columns), rate) in joints.iter().zip(&self.jacobian).zip(&mut self.rate[..n]) {
            let mut r = joint.weight * columns[3].dot(&e4) / error;
            if let Some(rt) = &target.orientation {
                for (c, column) in columns.iter().take(3).enumerate() {
                    r += ORIENTATION_WEIGHT * column.dot(&rt.column(c).into_owned());
                }
            }
            *rate = r;
        }
        let size = libm::sqrtf(self.rate[..n].iter().map(|r| r * r).sum());
        let mu_sq: f32 = self.mu[..n].iter().map(|m| m * m).sum();
        if size > 0.0 {
            self.rate[..n].iter_mut().for_each(|r| *r /= size);
        }
        if mu_sq > 0.0 {
            let along: f32 = self.mu[..n]
                .iter()
                .zip(&self.rate[..n])
                .map(|(m, r)| m * r)
                .sum();
            let k = along / mu_sq;
            for (r, m) in self.rate[..n].iter_mut().zip(&self.mu[..n]) {
                *r -= k * m;
            }
        }
        let h = scenario.settings().time_step_s;
        for ((joint, q), &rate) in joints.iter().zip(&mut self.q[..n]).zip(&self.rate[..n]) {
            let r = match joint.kind {
                JointKind::Revolute => rate.clamp(-RATE_CLIP, RATE_CLIP),
                JointKind::Prismatic => rate,
            };
            *q = joint.clamp(*q + h * r);
        }
        error
    }
}
