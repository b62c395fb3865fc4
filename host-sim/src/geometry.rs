//! The independent `f64` model of the robot and obstacles, used by
//! `capp check` ([`crate::check`]), the renderers ([`crate::render`]) and
//! `capp-suite`'s checker and sampling planner.
//!
//! Nothing here uses the planner's kinematics, obstacles or potential: the
//! forward kinematics are 4x4 `f64` products of the DH matrices (eq. 5,
//! `A = Rot_z(theta) Trans_z(d) Trans_x(a) Rot_x(alpha)`), and each obstacle is
//! evaluated directly from eq. 25 in `f64`:
//!
//! ```text
//! x = R^T (p - c),  R = Rz(rz) Ry(ry) Rx(rx)
//! C(p) = |x/(a+m)|^kx + |y/(b+m)|^ky + |z/(c+m)|^kz ,  collision when C <= 1
//! ```
//!
//! with the margin `m` of the point's kind (joint origins: `joint_margin`;
//! interior link points: `link_margin`). Avoidance points are every frame
//! origin `o_1..o_n` and `points_per_link` interior points per link.
//!
//! [`Geometry`] is the obstacle and avoidance-point model prepared once
//! for repeated queries of single configurations (`capp-suite`'s sampling
//! planner and its dense re-checks between rows use it). Sines, cosines and
//! real powers go through `libm` and integer exponents through repeated
//! squaring, so a clearance is the same number on every machine: case
//! generation and certification that depend on it repeat bit for bit.

use capp_core::{Joint, JointKind};

use crate::problem::Problem;

type M4 = [[f64; 4]; 4];

fn mul(a: &M4, b: &M4) -> M4 {
    let mut c = [[0.0; 4]; 4];
    for (i, row) in c.iter_mut().enumerate() {
        for (j, v) in row.iter_mut().enumerate() {
            *v = (0..4).map(|k| a[i][k] * b[k][j]).sum();
        }
    }
    c
}

/// Eq. 5: the DH link transform.
fn dh(theta: f64, d: f64, a: f64, alpha: f64) -> M4 {
    let (st, ct) = libm::sincos(theta);
    let (sa, ca) = libm::sincos(alpha);
    [
        [ct, -st * ca, st * sa, a * ct],
        [st, ct * ca, -ct * sa, a * st],
        [0.0, sa, ca, d],
        [0.0, 0.0, 0.0, 1.0],
    ]
}

/// Frame origins `o_0..o_n` and the end transform, in `f64`.
pub fn forward(problem: &Problem, q: &[f64]) -> (Vec<[f64; 3]>, M4) {
    forward_chain(&problem.joints, q)
}

/// [`forward`] for a bare chain of joints.
pub fn forward_chain(joints: &[Joint], q: &[f64]) -> (Vec<[f64; 3]>, M4) {
    let mut t: M4 = [
        [1.0, 0.0, 0.0, 0.0],
        [0.0, 1.0, 0.0, 0.0],
        [0.0, 0.0, 1.0, 0.0],
        [0.0, 0.0, 0.0, 1.0],
    ];
    let mut origins = Vec::with_capacity(joints.len() + 1);
    origins.push([0.0; 3]);
    for (joint, &qj) in joints.iter().zip(q) {
        let (theta, d) = match joint.kind {
            JointKind::Revolute => (qj, joint.d as f64),
            JointKind::Prismatic => (joint.theta as f64, qj),
        };
        t = mul(&t, &dh(theta, d, joint.a as f64, joint.alpha as f64));
        origins.push([t[0][3], t[1][3], t[2][3]]);
    }
    (origins, t)
}

/// `R = Rz(rz) Ry(ry) Rx(rx)`.
pub fn rotation(e: [f64; 3]) -> [[f64; 3]; 3] {
    let (sx, cx) = libm::sincos(e[0]);
    let (sy, cy) = libm::sincos(e[1]);
    let (sz, cz) = libm::sincos(e[2]);
    [
        [cz * cy, cz * sy * sx - sz * cx, cz * sy * cx + sz * sx],
        [sz * cy, sz * sy * sx + cz * cx, sz * sy * cx - cz * sx],
        [-sy, cy * sx, cy * cx],
    ]
}

/// An obstacle in `f64`, ready to evaluate.
struct Shape {
    centre: [f64; 3],
    axes: [f64; 3],
    exponents: [f64; 3],
    r: [[f64; 3]; 3],
}

impl Shape {
    /// `C(p) - 1` of the obstacle inflated by `margin` (eq. 25).
    fn clearance(&self, p: [f64; 3], margin: f64) -> f64 {
        let d = [
            p[0] - self.centre[0],
            p[1] - self.centre[1],
            p[2] - self.centre[2],
        ];
        let mut c = 0.0;
        for i in 0..3 {
            // x_i = (R^T d)_i = column i of R dotted with d.
            let x = self.r[0][i] * d[0] + self.r[1][i] * d[1] + self.r[2][i] * d[2];
            c += power(x.abs() / (self.axes[i] + margin), self.exponents[i]);
        }
        c - 1.0
    }
}

/// `x^k` for `x >= 0`: repeated squaring for integer `k` (the usual 2 and 8),
/// `libm::pow` otherwise.
fn power(x: f64, k: f64) -> f64 {
    if k.fract() == 0.0 && (1.0..=64.0).contains(&k) {
        let (mut base, mut e, mut acc) = (x, k as u32, 1.0);
        while e > 0 {
            if e & 1 == 1 {
                acc *= base;
            }
            base *= base;
            e >>= 1;
        }
        acc
    } else {
        libm::pow(x, k)
    }
}

/// The closest avoidance point / obstacle pair of one configuration.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Closest {
    /// `C - 1` of the pair (eq. 25 with the point's margin); `<= 0` is a collision.
    pub value: f64,
    /// Avoidance point id (0-based, the planner's numbering).
    pub point: usize,
    /// Obstacle index (0-based).
    pub obstacle: usize,
}

/// A problem's chain, obstacles and avoidance points, prepared once for
/// clearance queries of many configurations (independent of the planner,
/// like [`crate::check::check`]).
pub struct Geometry {
    joints: Vec<Joint>,
    shapes: Vec<Shape>,
    interior: usize,
    margins: [f64; 2],
}

impl Geometry {
    /// Prepares `problem`'s obstacles (with its margins and points per link).
    pub fn new(problem: &Problem) -> Self {
        let avoid = &problem.settings.avoidance;
        Geometry {
            joints: problem.joints.clone(),
            shapes: problem
                .obstacles
                .iter()
                .map(|o| Shape {
                    centre: o.centre.map(f64::from),
                    axes: o.semi_axes.map(f64::from),
                    exponents: o.exponents.map(f64::from),
                    r: rotation(o.euler_123.map(f64::from)),
                })
                .collect(),
            interior: avoid.points_per_link as usize,
            margins: [avoid.joint_margin as f64, avoid.link_margin as f64],
        }
    }

    /// Frame origins `o_0..o_n` and the end transform at `q`.
    pub fn forward(&self, q: &[f64]) -> (Vec<[f64; 3]>, M4) {
        forward_chain(&self.joints, q)
    }

    /// Calls `f(c, point, obstacle)` with `C - 1` of every avoidance point /
    /// obstacle pair of the configuration whose frame origins are `origins`,
    /// until `f` returns `false`.
    pub(crate) fn pairs(&self, origins: &[[f64; 3]], mut f: impl FnMut(f64, usize, usize) -> bool) {
        let interior = self.interior;
        for link in 0..origins.len().saturating_sub(1) {
            let (a, b) = (origins[link], origins[link + 1]);
            for i in 0..=interior {
                let (p, margin, id) = if i == interior {
                    (b, self.margins[0], link * (interior + 1) + interior)
                } else {
                    let t = (i + 1) as f64 / (interior + 1) as f64;
                    (
                        [
                            a[0] + (b[0] - a[0]) * t,
                            a[1] + (b[1] - a[1]) * t,
                            a[2] + (b[2] - a[2]) * t,
                        ],
                        self.margins[1],
                        link * (interior + 1) + i,
                    )
                };
                for (o, shape) in self.shapes.iter().enumerate() {
                    if !f(shape.clearance(p, margin), id, o) {
                        return;
                    }
                }
            }
        }
    }

    /// The closest pair at `q`; `None` without obstacles. A NaN clearance
    /// counts as the closest (a collision).
    pub fn clearance(&self, q: &[f64]) -> Option<Closest> {
        let (origins, _) = self.forward(q);
        let mut closest: Option<Closest> = None;
        self.pairs(&origins, |value, point, obstacle| {
            if closest.is_none_or(|c| value < c.value || value.is_nan()) {
                closest = Some(Closest {
                    value,
                    point,
                    obstacle,
                });
            }
            !value.is_nan()
        });
        closest
    }

    /// Whether every pair at `q` has `C - 1 > margin` (stops at the first that
    /// has not; NaN is not clear).
    pub fn is_clear(&self, q: &[f64], margin: f64) -> bool {
        let (origins, _) = self.forward(q);
        let mut clear = true;
        self.pairs(&origins, |value, _, _| {
            clear = value > margin;
            clear
        });
        clear
    }
}
