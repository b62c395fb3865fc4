//! Test support: an f64 model of the arm written from the paper's equations,
//! independent of the crate's f32 code, a small seeded random source, the
//! test robots, and `run_checked`, which runs a plan and checks its
//! invariants at every step.
#![allow(dead_code)]
#![allow(clippy::needless_range_loop)] // matrix formulas read best indexed

use capp_core::escape::EscapeState;
use capp_core::*;

/// SplitMix64: tiny, seeded, reproducible.
pub struct Rng(pub u64);

impl Rng {
    pub fn next_u64(&mut self) -> u64 {
        self.0 = self.0.wrapping_add(0x9E37_79B9_7F4A_7C15);
        let mut z = self.0;
        z = (z ^ (z >> 30)).wrapping_mul(0xBF58_476D_1CE4_E5B9);
        z = (z ^ (z >> 27)).wrapping_mul(0x94D0_49BB_1331_11EB);
        z ^ (z >> 31)
    }
    /// Uniform in [lo, hi).
    pub fn uniform(&mut self, lo: f64, hi: f64) -> f64 {
        lo + (hi - lo) * (self.next_u64() >> 11) as f64 / (1u64 << 53) as f64
    }
    pub fn below(&mut self, n: usize) -> usize {
        (self.next_u64() % n as u64) as usize
    }
}

pub type V3 = [f64; 3];
pub type M3 = [[f64; 3]; 3];

pub fn sub(a: V3, b: V3) -> V3 {
    [a[0] - b[0], a[1] - b[1], a[2] - b[2]]
}
pub fn add(a: V3, b: V3) -> V3 {
    [a[0] + b[0], a[1] + b[1], a[2] + b[2]]
}
pub fn scale(a: V3, k: f64) -> V3 {
    [a[0] * k, a[1] * k, a[2] * k]
}
pub fn dot(a: V3, b: V3) -> f64 {
    a[0] * b[0] + a[1] * b[1] + a[2] * b[2]
}
pub fn mat_vec(m: &M3, v: V3) -> V3 {
    [dot(m[0], v), dot(m[1], v), dot(m[2], v)]
}
pub fn transpose(m: &M3) -> M3 {
    let mut t = [[0.0; 3]; 3];
    for i in 0..3 {
        for j in 0..3 {
            t[i][j] = m[j][i];
        }
    }
    t
}
pub fn mat_mul(a: &M3, b: &M3) -> M3 {
    let mut c = [[0.0; 3]; 3];
    for i in 0..3 {
        for j in 0..3 {
            c[i][j] = (0..3).map(|k| a[i][k] * b[k][j]).sum();
        }
    }
    c
}

/// Every frame of a chain in f64: origins o_0..o_n and rotations R_0..R_n.
pub struct Chain64 {
    pub origins: Vec<V3>,
    pub rotations: Vec<M3>,
}

/// Eq. 5-6 in f64, 4x4 homogeneous products as the paper writes them
/// (general joints: [`fk64_tool`]).
pub fn fk64(joints: &[Joint], q: &[f64]) -> Chain64 {
    if joints.first().is_some_and(|j| j.origin.is_some()) {
        return fk64_tool(joints, &robot::Placement::IDENTITY, q);
    }
    fk64_dh(joints, q)
}

/// [`fk64`] for a DH chain.
fn fk64_dh(joints: &[Joint], q: &[f64]) -> Chain64 {
    let mut t = [[0.0f64; 4]; 4];
    for (i, row) in t.iter_mut().enumerate() {
        row[i] = 1.0;
    }
    let mut origins = vec![[0.0; 3]];
    let mut rotations = vec![[[1.0, 0.0, 0.0], [0.0, 1.0, 0.0], [0.0, 0.0, 1.0]]];
    for (j, &v) in joints.iter().zip(q) {
        let (theta, d) = match j.kind {
            JointKind::Revolute => (v, j.d as f64),
            JointKind::Prismatic => (j.theta as f64, v),
        };
        let (alpha, a) = (j.alpha as f64, j.a as f64);
        let (ca, sa, ct, st) = (alpha.cos(), alpha.sin(), theta.cos(), theta.sin());
        let m = [
            [ct, -st * ca, st * sa, a * ct],
            [st, ct * ca, -ct * sa, a * st],
            [0.0, sa, ca, d],
            [0.0, 0.0, 0.0, 1.0],
        ];
        let mut next = [[0.0f64; 4]; 4];
        for r in 0..4 {
            for c in 0..4 {
                next[r][c] = (0..4).map(|k| t[r][k] * m[k][c]).sum();
            }
        }
        t = next;
        origins.push([t[0][3], t[1][3], t[2][3]]);
        rotations.push([
            [t[0][0], t[0][1], t[0][2]],
            [t[1][0], t[1][1], t[1][2]],
            [t[2][0], t[2][1], t[2][2]],
        ]);
    }
    Chain64 { origins, rotations }
}

/// R = Rz(rz) Ry(ry) Rx(rx), built from elementary rotations.
pub fn euler123(rx: f64, ry: f64, rz: f64) -> M3 {
    let rxm = [
        [1.0, 0.0, 0.0],
        [0.0, rx.cos(), -rx.sin()],
        [0.0, rx.sin(), rx.cos()],
    ];
    let rym = [
        [ry.cos(), 0.0, ry.sin()],
        [0.0, 1.0, 0.0],
        [-ry.sin(), 0.0, ry.cos()],
    ];
    let rzm = [
        [rz.cos(), -rz.sin(), 0.0],
        [rz.sin(), rz.cos(), 0.0],
        [0.0, 0.0, 1.0],
    ];
    mat_mul(&rzm, &mat_mul(&rym, &rxm))
}

/// Eq. 25 in f64 for an obstacle inflated by `margin`: C(p) (1 on the surface).
pub fn c64(s: &SuperEllipsoid, margin: f64, p: V3) -> f64 {
    let r = euler123(
        s.euler_123[0] as f64,
        s.euler_123[1] as f64,
        s.euler_123[2] as f64,
    );
    let centre = s.centre.map(|x| x as f64);
    let x = mat_vec(&transpose(&r), sub(p, centre));
    (0..3)
        .map(|i| (x[i].abs() / (s.semi_axes[i] as f64 + margin)).powf(s.exponents[i] as f64))
        .sum()
}

/// `C(p)` in f64 of any obstacle inflated by `margin`: eq. 25 for a
/// super-ellipsoid ([`c64`]); for a CAD primitive `((d + rho) / (margin +
/// rho))^2`, `d` its signed distance (from the closest point of the shape,
/// computed here by clamping, apart from the core's closed forms) and `rho`
/// its inradius.
/// A hull's `d` is [`hull_distance64`]'s and its `rho` half its smallest
/// axis-aligned width, as the core takes them; `hulls` are the scenario's.
pub fn solid_c64(s: &capp_core::Solid, hulls: &[Vec<V3>], margin: f64, p: V3) -> f64 {
    use capp_core::Shape as S;
    if let Some(se) = s.super_ellipsoid() {
        return c64(&se, margin, p);
    }
    let r = euler123(
        s.euler_123[0] as f64,
        s.euler_123[1] as f64,
        s.euler_123[2] as f64,
    );
    let x = mat_vec(&transpose(&r), sub(p, s.centre.map(|x| x as f64)));
    let len = |v: V3| (v[0] * v[0] + v[1] * v[1] + v[2] * v[2]).sqrt();
    let (d, rho) = match s.shape {
        S::Sphere { radius } => (len(x) - radius as f64, radius as f64),
        S::Capsule { radius, length } => {
            let l = length as f64 / 2.0;
            let axis = [0.0, 0.0, x[2].clamp(-l, l)];
            (len(sub(x, axis)) - radius as f64, radius as f64)
        }
        S::Cuboid { half_extents } => {
            let h = half_extents.map(|v| v as f64);
            let closest = [0, 1, 2].map(|i| x[i].clamp(-h[i], h[i]));
            let out = len(sub(x, closest));
            let depth = (0..3).map(|i| x[i].abs() - h[i]).fold(f64::MIN, f64::max);
            (
                if out > 0.0 { out } else { depth },
                h[0].min(h[1]).min(h[2]),
            )
        }
        S::Cylinder { radius, length } => {
            let (r, l) = (radius as f64, length as f64 / 2.0);
            let rho = x[0].hypot(x[1]);
            // The closest point of the solid, in the (radial, axial) plane.
            let (cr, cz) = (rho.min(r), x[2].clamp(-l, l));
            let out = (rho - cr).hypot(x[2] - cz);
            let depth = (rho - r).max(x[2].abs() - l);
            (if out > 0.0 { out } else { depth }, r.min(l))
        }
        S::Convex { hull } => {
            let vertices = &hulls[hull as usize];
            let width = (0..3)
                .map(|i| {
                    let (lo, hi) = vertices.iter().fold((f64::MAX, f64::MIN), |(lo, hi), v| {
                        (lo.min(v[i]), hi.max(v[i]))
                    });
                    hi - lo
                })
                .fold(f64::MAX, f64::min);
            (hull_distance64(vertices, x), 0.5 * width)
        }
        S::SuperEllipsoid { .. } => unreachable!("handled above"),
    };
    ((d + rho) / (margin + rho)).powi(2)
}

/// The distance from `x` to the convex hull of `vertices` (0 inside): the
/// least distance to a face triangle, a face being any triangle of three
/// vertices with every vertex on one side of its plane (by brute force, no
/// code of the core's GJK).
pub fn hull_distance64(vertices: &[V3], x: V3) -> f64 {
    let cross = |a: V3, b: V3| {
        [
            a[1] * b[2] - a[2] * b[1],
            a[2] * b[0] - a[0] * b[2],
            a[0] * b[1] - a[1] * b[0],
        ]
    };
    let n = vertices.len();
    let (mut best, mut inside) = (f64::INFINITY, true);
    for i in 0..n {
        for j in i + 1..n {
            for k in j + 1..n {
                let (a, b, c) = (vertices[i], vertices[j], vertices[k]);
                let normal = cross(sub(b, a), sub(c, a));
                let length = dot(normal, normal).sqrt();
                if length < 1e-12 {
                    continue;
                }
                let side = |p: V3| dot(normal, sub(p, a)) / length;
                let sides = vertices.iter().map(|&v| side(v));
                let (lo, hi) = sides.fold((0.0f64, 0.0f64), |(lo, hi), s| (lo.min(s), hi.max(s)));
                let tolerance = 1e-9 * (1.0 + dot(a, a).sqrt());
                if lo < -tolerance && hi > tolerance {
                    continue; // not a face
                }
                // Outward: away from the vertices.
                let out = if hi > tolerance { -side(x) } else { side(x) };
                if out > 0.0 {
                    inside = false;
                }
                best = best.min(triangle_distance64(x, a, b, c));
            }
        }
    }
    if inside {
        0.0
    } else {
        best
    }
}

/// The distance from `p` to triangle `abc`: to its plane where the
/// projection falls inside, else to the nearest edge.
fn triangle_distance64(p: V3, a: V3, b: V3, c: V3) -> f64 {
    let seg = |a: V3, b: V3| {
        let ab = sub(b, a);
        let t = (dot(sub(p, a), ab) / dot(ab, ab)).clamp(0.0, 1.0);
        let d = sub(p, add(a, scale(ab, t)));
        dot(d, d).sqrt()
    };
    let cross = |a: V3, b: V3| {
        [
            a[1] * b[2] - a[2] * b[1],
            a[2] * b[0] - a[0] * b[2],
            a[0] * b[1] - a[1] * b[0],
        ]
    };
    let n = cross(sub(b, a), sub(c, a));
    let nn = dot(n, n);
    let mut best = seg(a, b).min(seg(b, c)).min(seg(c, a));
    let s = dot(sub(p, a), n) / nn;
    let q = sub(p, scale(n, s));
    if [(a, b), (b, c), (c, a)]
        .iter()
        .all(|&(u, v)| dot(cross(sub(v, u), sub(q, u)), n) >= 0.0)
    {
        best = best.min(s.abs() * nn.sqrt());
    }
    best
}

/// [`min_clearance64`] for obstacles of any shape ([`solid_c64`]).
pub fn min_clearance_solids64(
    joints: &[Joint],
    q: &[f64],
    obstacles: &[capp_core::Solid],
    hulls: &[Vec<V3>],
    margins: (f64, f64),
    interior: usize,
) -> f64 {
    let chain = fk64(joints, q);
    let mut m = f64::INFINITY;
    for (point, is_joint) in points64(&chain, interior) {
        let margin = if is_joint { margins.0 } else { margins.1 };
        for s in obstacles {
            m = m.min(solid_c64(s, hulls, margin, point) - 1.0);
        }
    }
    m
}

/// Avoidance points as the paper places them: per link, `interior` evenly
/// spaced points (link margin) and the far joint origin (joint margin).
pub fn points64(chain: &Chain64, interior: usize) -> Vec<(V3, bool)> {
    let mut out = Vec::new();
    for link in 1..chain.origins.len() {
        let (a, b) = (chain.origins[link - 1], chain.origins[link]);
        for i in 1..=interior {
            let t = i as f64 / (interior + 1) as f64;
            out.push((add(a, scale(sub(b, a), t)), false));
        }
        out.push((b, true));
    }
    out
}

/// Eq. 26 in f64 over every pair (no influence cut-off).
pub fn potential64(
    joints: &[Joint],
    q: &[f64],
    obstacles: &[SuperEllipsoid],
    margins: (f64, f64),
    interior: usize,
) -> f64 {
    let chain = fk64(joints, q);
    let mut p = 0.0;
    for (point, is_joint) in points64(&chain, interior) {
        let margin = if is_joint { margins.0 } else { margins.1 };
        for s in obstacles {
            p += 1.0 / (c64(s, margin, point) - 1.0);
        }
    }
    p
}

/// Smallest C - 1 over every pair, f64.
pub fn min_clearance64(
    joints: &[Joint],
    q: &[f64],
    obstacles: &[SuperEllipsoid],
    margins: (f64, f64),
    interior: usize,
) -> f64 {
    let solids: Vec<capp_core::Solid> = obstacles.iter().map(|&s| s.into()).collect();
    min_clearance_solids64(joints, q, &solids, &[], margins, interior)
}

/// A random chain of `n` joints, both kinds, lengths of a few units.
pub fn random_chain(rng: &mut Rng, n: usize) -> Vec<Joint> {
    (0..n)
        .map(|_| {
            let alpha = rng.uniform(-3.0, 3.0) as f32;
            let a = rng.uniform(-3.0, 6.0) as f32;
            if rng.below(4) == 0 {
                let lo = rng.uniform(-3.0, 1.0) as f32;
                Joint::prismatic(
                    alpha,
                    a,
                    rng.uniform(-3.0, 3.0) as f32,
                    lo,
                    lo + rng.uniform(1.0, 6.0) as f32,
                    1.0,
                )
            } else {
                let lo = rng.uniform(-3.0, -0.5) as f32;
                Joint::revolute(
                    alpha,
                    a,
                    rng.uniform(-2.0, 2.0) as f32,
                    lo,
                    lo + rng.uniform(1.0, 5.0) as f32,
                    0.5,
                )
            }
        })
        .collect()
}

/// A random configuration strictly inside the limits.
pub fn random_config(rng: &mut Rng, joints: &[Joint]) -> Vec<f32> {
    joints
        .iter()
        .map(|j| {
            let mid = 0.5 * (j.min + j.max) as f64;
            let half = 0.5 * (j.max - j.min) as f64;
            (mid + 0.9 * half * rng.uniform(-1.0, 1.0)) as f32
        })
        .collect()
}

/// End-effector pose of `q` as a waypoint (position, rotation rows), f64 FK rounded to f32.
pub fn pose_of(joints: &[Joint], q: &[f32]) -> ([f32; 3], [[f32; 3]; 3]) {
    let q64: Vec<f64> = q.iter().map(|&x| x as f64).collect();
    let chain = fk64(joints, &q64);
    let p = *chain.origins.last().unwrap();
    let r = *chain.rotations.last().unwrap();
    (p.map(|x| x as f32), r.map(|row| row.map(|x| x as f32)))
}

/// Room for PIPS (18 joints), 8 obstacles and 4 waypoints; smaller robots fit too.
pub type Sc = Scenario<18, 8, 4>;

/// A valid scenario (panics on invalid input: the tests build valid ones).
pub fn scenario(
    joints: &[Joint],
    obstacles: &[SuperEllipsoid],
    waypoints: &[Waypoint],
    settings: Settings,
) -> Sc {
    Sc::new(
        Robot::new(joints).unwrap(),
        obstacles,
        &Mission::new(waypoints, settings).unwrap(),
    )
    .unwrap()
}

/// The planar arm: three revolute links of `10 k` in turning about z (every
/// point of it stays in the plane z = 0; its reach is `30 k`), limits
/// +-2.8 rad, 0.5 rad/s.
pub fn planar_scaled(k: f32) -> [Joint; 3] {
    [Joint::revolute(0.0, 10.0 * k, 0.0, -2.8, 2.8, 0.5); 3]
}

/// The planar arm in inches (`planar_scaled(1.0)`).
pub fn planar() -> [Joint; 3] {
    planar_scaled(1.0)
}

/// The planar arm's reach (its links stretched), inches.
pub const PLANAR_REACH: f32 = 30.0;

/// Default settings with the planar arm's avoidance, in units `k` times
/// inches: margins of 1 in (joints) and 0.5 in (links), influence 5 in.
pub fn planar_settings(k: f32) -> Settings {
    let mut s = Settings::default();
    s.avoidance.joint_margin = 1.0 * k;
    s.avoidance.link_margin = 0.5 * k;
    s.avoidance.influence_distance = 5.0 * k;
    s
}

/// Everything a run did, with the invariants checked at every step.
pub struct Run {
    pub outcome: Outcome,
    pub steps: u32,
    /// `V` at the start and after every step.
    pub v: Vec<f32>,
    /// Per step: joint rates and position error.
    pub rates: Vec<(Vec<f32>, f32)>,
    /// Steps taken while escaping a dead end (not descending).
    pub escape_steps: u32,
    /// The final configuration.
    pub joints: Vec<f32>,
    /// The final step's report.
    pub last: StepReport,
    /// The smallest checked link-pair gap seen (f64; infinity without capsules).
    pub min_link_gap: f64,
}

/// Runs to the end, checking after every step: limits, rate limits, finite
/// values (joints, rates, `V`, errors, time step), and (independently, in
/// f64) every avoidance point outside every inflated obstacle.
pub fn run_checked(sc: &Sc, start: &[f32]) -> Run {
    let joints = sc.robot().joints().to_vec();
    let s = sc.settings();
    let margins = (
        s.avoidance.joint_margin as f64,
        s.avoidance.link_margin as f64,
    );
    let interior = s.avoidance.points_per_link as usize;
    let obstacles: Vec<SuperEllipsoid> = sc
        .obstacles()
        .iter()
        .map(|o| o.source().super_ellipsoid().expect("a super-ellipsoid"))
        .collect();
    let mut planner = Planner::new(sc, start).unwrap();
    let mut previous = planner.joints().to_vec();
    let mut v = vec![planner.last_report().v];
    let mut rates = vec![];
    let mut escape_steps = 0;
    let mut min_link_gap = f64::INFINITY;
    let outcome = planner
        .run(sc, |p, r| {
            let q = p.joints();
            assert!(
                r.v.is_finite()
                    && r.position_error.is_finite()
                    && r.orientation_error.is_finite()
                    && r.time_step_s.is_finite(),
                "step {}: {r:?}",
                r.step
            );
            for (j, joint) in joints.iter().enumerate() {
                assert!(
                    q[j].is_finite() && p.rates()[j].is_finite(),
                    "step {}: joint {j} or its rate not finite",
                    r.step
                );
                assert!(
                    q[j] >= joint.min && q[j] <= joint.max,
                    "step {}: joint {j} = {} outside [{}, {}]",
                    r.step,
                    q[j],
                    joint.min,
                    joint.max
                );
                let moved = (q[j] - previous[j]).abs();
                // f32: the new value is rounded to its own precision, which
                // for a prismatic joint tens of units out is a few 1e-6.
                let rounding = 2.0 * f32::EPSILON * q[j].abs().max(previous[j].abs());
                let allowed = r.time_step_s * joint.max_rate * (1.0 + 1e-5) + 1e-6 + rounding;
                assert!(
                    moved <= allowed,
                    "step {}: joint {j} moved {moved} > {allowed}",
                    r.step
                );
            }
            if !obstacles.is_empty() {
                let q64: Vec<f64> = q.iter().map(|&x| x as f64).collect();
                let c = min_clearance64(&joints, &q64, &obstacles, margins, interior);
                assert!(
                    c > 0.0,
                    "step {}: an avoidance point is inside an inflated obstacle (C - 1 = {c})",
                    r.step
                );
            }
            if sc.capsules().is_on() {
                // Every row, and densely between rows: no two checked
                // capsules touch (f32 storage: a few 1e-6 of slack).
                for i in 1..=8 {
                    let f = i as f64 / 8.0;
                    let qi: Vec<f64> = previous
                        .iter()
                        .zip(q)
                        .map(|(&a, &b)| a as f64 + (b as f64 - a as f64) * f)
                        .collect();
                    let (gap, a, b) = min_link_gap64(sc, &qi);
                    min_link_gap = min_link_gap.min(gap);
                    assert!(
                        gap > -1e-5,
                        "step {}: links {a} and {b} overlap by {} (at {f} of the step)",
                        r.step,
                        -gap
                    );
                }
            }
            if !matches!(r.escape, EscapeState::Descending { .. }) {
                escape_steps += 1;
            }
            previous.copy_from_slice(q);
            v.push(r.v);
            rates.push((p.rates().to_vec(), r.position_error));
        })
        .unwrap();
    Run {
        outcome,
        steps: planner.last_report().step,
        v,
        rates,
        escape_steps,
        joints: planner.joints().to_vec(),
        last: *planner.last_report(),
        min_link_gap,
    }
}

/// Distance between the segments `a0 a1` and `b0 b1`, in f64, computed
/// independently of the core: for each point of the first segment the
/// closest point of the second is its clamped projection, and the distance
/// along the first is convex, so a ternary search over it converges.
pub fn segment_distance64(a0: V3, a1: V3, b0: V3, b1: V3) -> f64 {
    let db = sub(b1, b0);
    let e = dot(db, db);
    let at = |s: f64| {
        let x = add(a0, scale(sub(a1, a0), s));
        let t = if e > 0.0 {
            (dot(sub(x, b0), db) / e).clamp(0.0, 1.0)
        } else {
            0.0
        };
        let d = sub(x, add(b0, scale(db, t)));
        dot(d, d).sqrt()
    };
    let (mut lo, mut hi) = (0.0f64, 1.0f64);
    // (2/3)^64 of the segment: far below f32's resolution.
    for _ in 0..64 {
        let (m1, m2) = (lo + (hi - lo) / 3.0, hi - (hi - lo) / 3.0);
        if at(m1) <= at(m2) {
            hi = m2;
        } else {
            lo = m1;
        }
    }
    at(0.0).min(at(1.0)).min(at(0.5 * (lo + hi)))
}

/// The smallest capsule gap over the checked link pairs of `sc` at `q` (f64
/// kinematics; infinity without capsules), with its two links.
pub fn min_link_gap64(sc: &Sc, q: &[f64]) -> (f64, usize, usize) {
    let caps = sc.capsules();
    let joints = sc.robot().joints();
    let chain = fk64(joints, q);
    let o = &chain.origins;
    let mut best = (f64::INFINITY, 0, 0);
    for a in 0..caps.len() {
        for b in a + 1..caps.len() {
            if !caps.is_checked(a, b) {
                continue;
            }
            let gap = segment_distance64(o[a], o[a + 1], o[b], o[b + 1])
                - caps.radius(a) as f64
                - caps.radius(b) as f64;
            if gap < best.0 {
                best = (gap, a, b);
            }
        }
    }
    best
}

/// Distance from the hand of `q` (f64 forward kinematics) to `target`.
pub fn miss(joints: &[Joint], q: &[f32], target: [f32; 3]) -> f32 {
    let (p, _) = pose_of(joints, q);
    (0..3)
        .map(|i| (p[i] - target[i]).powi(2))
        .sum::<f32>()
        .sqrt()
}

/// Gives `sc` (PIPS) its capsules and the pairs checked with its pedestal
/// group and knuckles allowed, as the host's PIPS preset does.
pub fn pips_capsules(sc: &mut Sc) {
    use capp_core::pips;
    use capp_core::self_collision::pairs::{PairTable, SAMPLES};
    let allowed: Vec<(u8, u8)> = pips::allowed_pairs().collect();
    let radius = [pips::LINK_RADIUS; 18];
    let table =
        PairTable::<18>::new(sc.robot(), &radius, &allowed, &pips::home(), SAMPLES, 1).unwrap();
    sc.set_link_capsules(&radius, table.checked_rows()).unwrap();
}

/// 4x4 homogeneous product.
fn mul4(a: &[[f64; 4]; 4], b: &[[f64; 4]; 4]) -> [[f64; 4]; 4] {
    let mut c = [[0.0f64; 4]; 4];
    for r in 0..4 {
        for k in 0..4 {
            c[r][k] = (0..4).map(|i| a[r][i] * b[i][k]).sum();
        }
    }
    c
}

/// A placement as a 4x4 homogeneous matrix, in f64.
fn homogeneous(p: &robot::Placement) -> [[f64; 4]; 4] {
    let mut m = [[0.0f64; 4]; 4];
    for ((row, rotation), &t) in m.iter_mut().zip(&p.rotation).zip(&p.translation) {
        for (x, &r) in row.iter_mut().zip(rotation) {
            *x = r as f64;
        }
        row[3] = t as f64;
    }
    m[3][3] = 1.0;
    m
}

/// Any chain in f64 with a tool, written from the URDF convention, not from
/// the crate's `z`-aligned form: a general joint is `T_j = T_{j-1} O_j
/// M_j(q_j)` with `M` Rodrigues' rotation about the normalised raw axis (or a
/// translation along it), all 4x4 homogeneous products; a DH chain is
/// [`fk64`]; then `end = T_{n-1} tool`. `origins` are the pivots `o_0 ..
/// o_{n-1}` (a general joint's frame origin before its motion) and the end
/// effector, as [`capp_core::kinematics::Frames`] stores them.
pub fn fk64_tool(joints: &[Joint], tool: &robot::Placement, q: &[f64]) -> Chain64 {
    let tool4 = homogeneous(tool);
    let split = |t: &[[f64; 4]; 4]| -> (V3, M3) {
        (
            [t[0][3], t[1][3], t[2][3]],
            [
                [t[0][0], t[0][1], t[0][2]],
                [t[1][0], t[1][1], t[1][2]],
                [t[2][0], t[2][1], t[2][2]],
            ],
        )
    };
    if joints.first().is_some_and(|j| j.origin.is_none()) {
        let mut chain = fk64_dh(joints, q);
        let (o, r) = (
            *chain.origins.last().unwrap(),
            *chain.rotations.last().unwrap(),
        );
        let mut t = [[0.0f64; 4]; 4];
        for i in 0..3 {
            t[i][..3].copy_from_slice(&r[i]);
            t[i][3] = o[i];
        }
        t[3][3] = 1.0;
        let (o, r) = split(&mul4(&t, &tool4));
        *chain.origins.last_mut().unwrap() = o;
        *chain.rotations.last_mut().unwrap() = r;
        return chain;
    }
    let mut t = [[0.0f64; 4]; 4];
    for (i, row) in t.iter_mut().enumerate() {
        row[i] = 1.0;
    }
    let mut origins = Vec::new();
    let mut rotations = Vec::new();
    for (j, &v) in joints.iter().zip(q) {
        let origin = j.origin.expect("a general chain");
        t = mul4(&t, &homogeneous(&origin.placement));
        let (pivot, frame) = split(&t);
        origins.push(pivot);
        rotations.push(frame);
        let a = origin.axis.map(|x| x as f64);
        let len = dot(a, a).sqrt();
        let a = scale(a, 1.0 / len);
        let mut m = [[0.0f64; 4]; 4];
        m[3][3] = 1.0;
        match j.kind {
            JointKind::Revolute => {
                let (s, c) = v.sin_cos();
                let k = [[0.0, -a[2], a[1]], [a[2], 0.0, -a[0]], [-a[1], a[0], 0.0]];
                for r in 0..3 {
                    for col in 0..3 {
                        let identity = if r == col { 1.0 } else { 0.0 };
                        m[r][col] = identity * c + (1.0 - c) * a[r] * a[col] + s * k[r][col];
                    }
                }
            }
            JointKind::Prismatic => {
                for r in 0..3 {
                    m[r][r] = 1.0;
                    m[r][3] = a[r] * v;
                }
            }
        }
        t = mul4(&t, &m);
    }
    let (end, frame) = split(&mul4(&t, &tool4));
    origins.push(end);
    rotations.push(frame);
    Chain64 { origins, rotations }
}

/// A random chain of `n` general joints (random origins, axes along a
/// coordinate axis half of the time and anywhere otherwise, of any length
/// above the minimum), both kinds, and a random tool.
pub fn random_general_chain(rng: &mut Rng, n: usize) -> (Vec<Joint>, robot::Placement) {
    let placement = |rng: &mut Rng| {
        let r = euler123(
            rng.uniform(-3.0, 3.0),
            rng.uniform(-1.5, 1.5),
            rng.uniform(-3.0, 3.0),
        );
        robot::Placement {
            rotation: r.map(|row| row.map(|x| x as f32)),
            translation: [0; 3].map(|_| rng.uniform(-2.0, 2.0) as f32),
        }
    };
    let joints = (0..n)
        .map(|_| {
            let p = placement(rng);
            let axis = if rng.below(2) == 0 {
                let mut a = [0.0f32; 3];
                a[rng.below(3)] = if rng.below(2) == 0 { 1.0 } else { -1.0 };
                a
            } else {
                let length = rng.uniform(0.5, 2.0);
                let v = [0; 3].map(|_| rng.uniform(-1.0, 1.0));
                let size = dot(v, v).sqrt().max(1e-3);
                v.map(|x| (x * length / size) as f32)
            };
            let origin = robot::JointOrigin { placement: p, axis };
            if rng.below(4) == 0 {
                let lo = rng.uniform(-1.0, 0.5) as f32;
                Joint::general(
                    JointKind::Prismatic,
                    origin,
                    lo,
                    lo + rng.uniform(0.5, 2.0) as f32,
                    1.0,
                )
            } else {
                let lo = rng.uniform(-3.0, -0.5) as f32;
                Joint::general(
                    JointKind::Revolute,
                    origin,
                    lo,
                    lo + rng.uniform(1.0, 5.0) as f32,
                    0.5,
                )
            }
        })
        .collect();
    (joints, placement(rng))
}

/// The same arm as a DH chain, as general joints and a tool: DH joint `k`
/// is `Rot_z(q) [Trans_z(d) Trans_x(a) Rot_x(alpha)]` (revolute) or
/// `Trans_z(q) [Rot_z(theta) Trans_x(a) Rot_x(alpha)]` (prismatic), so each
/// bracket becomes the next joint's origin (the last one the tool), every
/// axis is `z`, and the first origin is the identity.
pub fn dh_as_general(joints: &[Joint]) -> (Vec<Joint>, robot::Placement) {
    let fixed = |j: &Joint| -> robot::Placement {
        let (theta, d) = match j.kind {
            JointKind::Revolute => (0.0f64, j.d as f64),
            JointKind::Prismatic => (j.theta as f64, 0.0),
        };
        let (ca, sa) = ((j.alpha as f64).cos(), (j.alpha as f64).sin());
        let (ct, st) = (theta.cos(), theta.sin());
        let a = j.a as f64;
        // Rot_z(theta) Trans_z(d) Trans_x(a) Rot_x(alpha): eq. 5's matrix.
        robot::Placement {
            rotation: [
                [ct as f32, (-st * ca) as f32, (st * sa) as f32],
                [st as f32, (ct * ca) as f32, (-ct * sa) as f32],
                [0.0, sa as f32, ca as f32],
            ],
            translation: [(a * ct) as f32, (a * st) as f32, d as f32],
        }
    };
    let mut previous = robot::Placement::IDENTITY;
    let mut out = Vec::new();
    for j in joints {
        let origin = robot::JointOrigin {
            placement: previous,
            axis: [0.0, 0.0, 1.0],
        };
        out.push(Joint::general(j.kind, origin, j.min, j.max, j.max_rate).with_weight(j.weight));
        previous = fixed(j);
    }
    (out, previous)
}
