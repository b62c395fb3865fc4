//! An independent check of a joint trajectory against a problem.
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
//! origin `o_1..o_n` and `points_per_link` interior points per link, at every
//! row of the trajectory.
//!
//! Per row: finite values, joint limits, recorded end-effector position against
//! the exact one, clearance of every point from every obstacle. Between rows:
//! `|q[k+1] - q[k]| <= h[k+1] max_rate (1 + 1e-4)` per joint, plus two `f32`
//! ulps of the values (the trajectory is stored in `f32`). Row 0 must be the
//! problem's start configuration.
//!
//! [`Geometry`] is the same obstacle and avoidance-point model prepared once
//! for repeated queries of single configurations (`capp-suite`'s sampling
//! planner and its dense re-checks between rows use it). Sines, cosines and
//! real powers go through `libm` and integer exponents through repeated
//! squaring, so a clearance is the same number on every machine: case
//! generation and certification that depend on it repeat bit for bit.

use std::fmt;

use capp_core::{Joint, JointKind};

use crate::problem::Problem;
use crate::trajectory::Trajectory;

/// Relative slack of the rate check.
pub const RATE_SLACK: f64 = 1.0e-4;

/// What kind of rule a row broke.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum ViolationKind {
    /// Wrong joint count, or row 0 is not the start configuration.
    Shape,
    /// A NaN or infinite value.
    NotFinite,
    /// A joint outside its limits.
    JointLimit,
    /// A joint moved faster than its rate limit.
    RateLimit,
    /// An avoidance point inside an inflated obstacle.
    Collision,
    /// The recorded end-effector position disagrees with the exact kinematics.
    Kinematics,
}

impl fmt::Display for ViolationKind {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        f.write_str(match self {
            ViolationKind::Shape => "shape",
            ViolationKind::NotFinite => "not finite",
            ViolationKind::JointLimit => "joint limit",
            ViolationKind::RateLimit => "rate limit",
            ViolationKind::Collision => "collision",
            ViolationKind::Kinematics => "kinematics",
        })
    }
}

/// One broken rule.
#[derive(Clone, Debug, PartialEq)]
pub struct Violation {
    /// Line in the trajectory file.
    pub line: usize,
    /// Step number.
    pub step: u64,
    /// Which rule.
    pub kind: ViolationKind,
    /// Details.
    pub message: String,
}

/// The result of a check.
#[derive(Clone, Debug, PartialEq)]
pub struct CheckReport {
    /// Rows checked.
    pub rows: usize,
    /// Every violation found.
    pub violations: Vec<Violation>,
    /// Smallest `C - 1` of any point / obstacle pair: value, step, point, obstacle (1-based).
    pub min_clearance: Option<(f64, u64, usize, usize)>,
    /// Largest difference between recorded and exact end-effector positions.
    pub max_position_mismatch: f64,
    /// Exact final position error to the target.
    pub final_position_error: f64,
    /// Exact final orientation error (root sum square of column errors), if the target has one.
    pub final_orientation_error: Option<f64>,
    /// Whether the final configuration is within the target's tolerances.
    pub reaches_target: bool,
}

impl CheckReport {
    /// Whether the trajectory broke no rule.
    pub fn accepted(&self) -> bool {
        self.violations.is_empty()
    }

    /// Whether a violation of `kind` was found.
    pub fn has(&self, kind: ViolationKind) -> bool {
        self.violations.iter().any(|v| v.kind == kind)
    }
}

impl fmt::Display for CheckReport {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        const SHOWN: usize = 20;
        for v in self.violations.iter().take(SHOWN) {
            writeln!(
                f,
                "line {} (step {}): {}: {}",
                v.line, v.step, v.kind, v.message
            )?;
        }
        if self.violations.len() > SHOWN {
            writeln!(f, "... and {} more", self.violations.len() - SHOWN)?;
        }
        writeln!(
            f,
            "{}: {} rows, {} violations",
            if self.accepted() {
                "ACCEPTED"
            } else {
                "REJECTED"
            },
            self.rows,
            self.violations.len()
        )?;
        match self.min_clearance {
            Some((c, step, point, obstacle)) => writeln!(
                f,
                "minimum clearance C-1 = {c:.5} at step {step} (point {point}, obstacle {obstacle})"
            )?,
            None => writeln!(f, "no obstacles")?,
        }
        writeln!(
            f,
            "largest recorded/exact end-effector mismatch: {:.2e}",
            self.max_position_mismatch
        )?;
        write!(f, "final position error {:.5}", self.final_position_error)?;
        if let Some(o) = self.final_orientation_error {
            write!(f, ", orientation error {o:.5}")?;
        }
        writeln!(
            f,
            ": {}",
            if self.reaches_target {
                "target reached"
            } else {
                "target not reached"
            }
        )
    }
}

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
/// like [`check`]).
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
    fn pairs(&self, origins: &[[f64; 3]], mut f: impl FnMut(f64, usize, usize) -> bool) {
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

/// Checks `trajectory` against `problem`.
pub fn check(problem: &Problem, trajectory: &Trajectory) -> CheckReport {
    let n = problem.joints.len();
    let mut violations = Vec::new();
    let mut report = CheckReport {
        rows: trajectory.rows.len(),
        violations: Vec::new(),
        min_clearance: None,
        max_position_mismatch: 0.0,
        final_position_error: f64::INFINITY,
        final_orientation_error: None,
        reaches_target: false,
    };
    if trajectory.joints != n {
        report.violations.push(Violation {
            line: 1,
            step: 0,
            kind: ViolationKind::Shape,
            message: format!(
                "the trajectory has {} joint columns, the robot {n} joints",
                trajectory.joints
            ),
        });
        return report;
    }
    let geometry = Geometry::new(problem);
    let scale = 1.0
        + problem
            .joints
            .iter()
            .map(|j| {
                j.a.abs() as f64
                    + j.d.abs() as f64
                    + match j.kind {
                        JointKind::Prismatic => j.min.abs().max(j.max.abs()) as f64,
                        JointKind::Revolute => 0.0,
                    }
            })
            .sum::<f64>();
    let position_tolerance = 1.0e-4 * scale;
    let ulp = f32::EPSILON as f64;

    let mut push = |line, step, kind, message: String| {
        violations.push(Violation {
            line,
            step,
            kind,
            message,
        })
    };

    if let Some(first) = trajectory.rows.first() {
        for (j, (&q, &s)) in first.q.iter().zip(&problem.start).enumerate() {
            if (q - s as f64).abs() > 2.0 * ulp * (1.0 + (s as f64).abs()) {
                push(
                    first.line,
                    first.step,
                    ViolationKind::Shape,
                    format!(
                        "row 0 is not the start configuration: {} is {q}, the start {s}",
                        problem.joint_label(j)
                    ),
                );
            }
        }
    }

    let mut last_origins = Vec::new();
    let mut last_end = None;
    for (k, row) in trajectory.rows.iter().enumerate() {
        if !row.q.iter().all(|x| x.is_finite()) || !row.h.is_finite() {
            push(
                row.line,
                row.step,
                ViolationKind::NotFinite,
                "a joint value or the step size is not finite".into(),
            );
            continue;
        }
        for (j, (joint, &q)) in problem.joints.iter().zip(&row.q).enumerate() {
            let (lo, hi) = (joint.min as f64, joint.max as f64);
            let slack = ulp * lo.abs().max(hi.abs()).max(1.0);
            if q < lo - slack || q > hi + slack {
                push(
                    row.line,
                    row.step,
                    ViolationKind::JointLimit,
                    format!(
                        "{} = {q} is outside its limits [{lo}, {hi}]",
                        problem.joint_label(j)
                    ),
                );
            }
        }
        if k > 0 {
            let prev = &trajectory.rows[k - 1];
            for (j, joint) in problem.joints.iter().enumerate() {
                let moved = (row.q[j] - prev.q[j]).abs();
                let allowed = row.h.max(0.0) * joint.max_rate as f64 * (1.0 + RATE_SLACK)
                    + 2.0 * ulp * row.q[j].abs().max(prev.q[j].abs());
                if moved > allowed {
                    push(
                        row.line,
                        row.step,
                        ViolationKind::RateLimit,
                        format!(
                            "{} moved {moved:.6} in a step of {} s; its rate limit allows {:.6}",
                            problem.joint_label(j),
                            row.h,
                            row.h * joint.max_rate as f64
                        ),
                    );
                }
            }
        }
        let (origins, end) = forward(problem, &row.q);
        if let Some(p) = row.position {
            let e = ((p[0] - end[0][3]).powi(2)
                + (p[1] - end[1][3]).powi(2)
                + (p[2] - end[2][3]).powi(2))
            .sqrt();
            report.max_position_mismatch = report.max_position_mismatch.max(e);
            if e > position_tolerance {
                push(
                    row.line,
                    row.step,
                    ViolationKind::Kinematics,
                    format!("recorded end-effector position is {e:.6} from the exact one"),
                );
            }
        }
        geometry.pairs(&origins, |c, id, o| {
            if report.min_clearance.is_none_or(|m| c < m.0) {
                report.min_clearance = Some((c, row.step, id + 1, o + 1));
            }
            if c.is_nan() || c <= 0.0 {
                push(
                    row.line,
                    row.step,
                    ViolationKind::Collision,
                    format!(
                        "{} is inside obstacle {}{} (C-1 = {c:.5})",
                        problem.describe_point(id as u16),
                        o + 1,
                        problem.obstacle_label(o)
                    ),
                );
            }
            true
        });
        last_origins = origins;
        last_end = Some(end);
    }
    let _ = last_origins;
    if let (Some(end), Some(target)) = (last_end, problem.waypoints.last()) {
        let t = target.position.map(f64::from);
        report.final_position_error =
            ((t[0] - end[0][3]).powi(2) + (t[1] - end[1][3]).powi(2) + (t[2] - end[2][3]).powi(2))
                .sqrt();
        report.final_orientation_error = target.orientation.map(|rows| {
            let mut sum = 0.0;
            for (i, row) in rows.iter().enumerate() {
                for (j, &r) in row.iter().enumerate() {
                    sum += (r as f64 - end[i][j]).powi(2);
                }
            }
            sum.sqrt()
        });
        let s = &problem.settings;
        let slack = 1.0 + 1.0e-3;
        let last = problem.waypoints.len().saturating_sub(1);
        let joint_goal = problem.joint_goals.iter().find(|(w, _)| *w == last);
        report.reaches_target = match (joint_goal, trajectory.rows.last()) {
            // A joint-space target: every joint within a twentieth of a time
            // step of it at its rate limit.
            (Some((_, goal)), Some(row)) => {
                row.q
                    .iter()
                    .zip(goal)
                    .zip(&problem.joints)
                    .all(|((&q, &g), joint)| {
                        (q - g as f64).abs() / joint.max_rate as f64
                            <= 0.05 * s.time_step_s as f64 * slack
                    })
            }
            _ => {
                report.final_position_error <= s.position_tolerance as f64 * slack
                    && report
                        .final_orientation_error
                        .is_none_or(|o| o <= s.orientation_tolerance as f64 * slack)
            }
        };
    }
    report.violations = violations;
    report
}
