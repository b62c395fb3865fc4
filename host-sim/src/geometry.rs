//! The independent `f64` model of the robot and obstacles, used by
//! `capp check` ([`crate::check`]), the run summary, the renderers
//! ([`crate::render`]) and `capp-suite`'s checker and sampling planner.
//!
//! Nothing here uses the planner's kinematics, obstacles, potential or link
//! capsules (only the scenario's list of checked link pairs): the
//! forward kinematics are 4x4 `f64` products of the DH matrices (eq. 5,
//! `A = Rot_z(theta) Trans_z(d) Trans_x(a) Rot_x(alpha)`), or for general
//! (URDF) joints of each joint's origin and Rodrigues' rotation about its
//! raw axis ([`forward_chain`]), and each obstacle is
//! evaluated directly from eq. 25 in `f64`:
//!
//! ```text
//! x = R^T (p - c),  R = Rz(rz) Ry(ry) Rx(rx)
//! C(p) = |x/(a+m)|^kx + |y/(b+m)|^ky + |z/(c+m)|^kz ,  collision when C <= 1
//! ```
//!
//! with the margin `m` of the point's kind (joint origins: `joint_margin`;
//! interior link points: `link_margin`). A primitive or a convex hull is
//! measured on its exact signed distance `d` (a hull's by its enumerated
//! faces, [`crate::polytope::Polytope`], not the core's GJK) as
//! `C = ((d + rho) / (m + rho))^2`, `rho` its inradius (a hull's: half its
//! smallest width along its frame's axes), so `C <= 1` exactly when
//! `d <= m`: margins are true distances. Avoidance points are every frame
//! origin `o_1..o_n` and `points_per_link` interior points per link.
//!
//! Self-collision: link `k` (0-based, DH link `k + 1`) is the capsule of
//! radius `r_k` round its segment `s_k` ([`Pose::capsules`]): the chord
//! `o_k -> o_{k+1}` (the last ends at the end effector), or, when the
//! scenario gives link segments (`Problem::links`' `segments`, general
//! joints only: [`link_segment`]), the segment `T_k a_k -> T_k b_k` fixed
//! in the body joint `k` moves (`T_k`, its frame after the motion,
//! [`joint_frames`]; `a_k`, `b_k` in length units). For every pair of links
//! the scenario checks ([`Problem::pair_table`], the scenario's definition,
//! as the margins are), the capsules' *gap* is
//!
//! ```text
//! gap_ab = dist(s_a, s_b) - r_a - r_b      (length units; < 0: overlap)
//! ```
//!
//! with [`segment_distance`], this module's own `f64` segment-to-segment
//! distance (the minimum over the parameter square: the lines' common
//! perpendicular when it meets both segments, else the best of the four
//! endpoint-to-segment distances; no code of the planner's).
//!
//! Between two configurations `a`, `b` on the straight joint-space segment
//! `q(t) = a + t (b - a)`, no point of link `k`'s capsule segment (nor of
//! its chord) travels farther than
//!
//! ```text
//! delta_k = sum_{j <= k} |b_j - a_j| w_jk,
//! w_jk = l_j + ... + l_k (revolute joint j),  1 (prismatic joint j)
//! ```
//!
//! with `l_i` how far from pivot `o_i` a point of link `i`'s capsule
//! segment can lie ([`link_reach`]):
//!
//! ```text
//! l_i = chord_i                                          (a chord)
//! l_i = max(chord_i, max(|a_i|, |b_i|) + slide_i)        (a segment a_i -> b_i)
//! ```
//!
//! `chord_i` the longest chord link `i` can have (`sqrt(a_i^2 + d_i^2)`,
//! `d_i` at its largest extension for a prismatic joint; a general joint's
//! distance to the next pivot, plus its largest extension when prismatic:
//! [`longest_links`]), `|a_i|` measured from the origin of `T_i`, which is
//! the pivot for a revolute joint and at most `slide_i`, the joint's
//! largest `|q|`, from it for a prismatic one (`slide_i = 0` when
//! revolute). A point of link `k` is within `l_j + ... + l_k` of pivot
//! `o_j` (the chords to `o_k`, then its reach from there), and joint `j`
//! turns about an axis through `o_j`, whence `w_jk`. A segment end may lie
//! farther from its pivot than the chord is long, so the chord alone would
//! not bound it. A pair's gap therefore moves by at most `delta_a + delta_b`
//! over the segment and stays at or above
//! `(gap(a) + gap(b) - delta_a - delta_b) / 2` all along it.
//! [`Geometry::sweep_links`] bisects the segment wherever that bound does
//! not keep a pair apart, until neither link of such a pair moves more than
//! [`SWEEP_FRACTION`] of the pair's smaller radius between the
//! configurations it evaluates (at most [`SWEEP_BUDGET`] of them per
//! segment): pairs far apart cost nothing, close ones are sampled densely.
//!
//! [`Geometry`] is the obstacle, avoidance-point and capsule model prepared
//! once for repeated queries of single configurations (`capp-suite`'s
//! sampling planner and its dense re-checks between rows use it). Sines,
//! cosines and real powers go through `libm` and integer exponents through
//! repeated squaring, so a clearance is the same number on every machine:
//! case generation and certification that depend on it repeat bit for bit.

use capp_core::robot::Placement;
use capp_core::self_collision::pairs::PairStatus;
use capp_core::{Joint, JointKind};

use crate::polytope::{cross, dot, sub, Polytope, V3};
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
    forward_chain(&problem.joints, &problem.tool, q)
}

/// [`forward`] for a bare chain of joints and a tool: DH rows (eq. 5), or
/// general joints as URDF writes them (`T_j = T_{j-1} O_j M_j(q_j)`, `M`
/// Rodrigues' rotation about the normalised axis or a slide along it), then
/// `end = T_n tool`. The points are each joint's pivot (a general joint's
/// frame origin before its motion; DH: `o_0 = 0`, `o_1`, ...) and the end
/// effector: link `k` runs from point `k` to point `k + 1`.
pub fn forward_chain(joints: &[Joint], tool: &Placement, q: &[f64]) -> (Vec<[f64; 3]>, M4) {
    walk_chain(joints, tool, q, |_, _| {})
}

/// [`forward_chain`], calling `body(j, T_j)` with each general joint's
/// frame after its motion (the frame of the body it moves; never for a DH
/// row).
fn walk_chain(
    joints: &[Joint],
    tool: &Placement,
    q: &[f64],
    mut body: impl FnMut(usize, &M4),
) -> (Vec<[f64; 3]>, M4) {
    let mut t: M4 = [
        [1.0, 0.0, 0.0, 0.0],
        [0.0, 1.0, 0.0, 0.0],
        [0.0, 0.0, 1.0, 0.0],
        [0.0, 0.0, 0.0, 1.0],
    ];
    let mut origins = Vec::with_capacity(joints.len() + 1);
    let general = joints.first().is_some_and(|j| j.origin.is_some());
    if !general {
        origins.push([0.0; 3]);
    }
    for (j, (joint, &qj)) in joints.iter().zip(q).enumerate() {
        match joint.origin {
            None => {
                let (theta, d) = match joint.kind {
                    JointKind::Revolute => (qj, joint.d as f64),
                    JointKind::Prismatic => (joint.theta as f64, qj),
                };
                t = mul(&t, &dh(theta, d, joint.a as f64, joint.alpha as f64));
                origins.push([t[0][3], t[1][3], t[2][3]]);
            }
            Some(origin) => {
                t = mul(&t, &homogeneous(&origin.placement));
                origins.push([t[0][3], t[1][3], t[2][3]]);
                t = mul(&t, &motion(joint.kind, origin.axis, qj));
                body(j, &t);
            }
        }
    }
    if !tool.is_identity() || general {
        t = mul(&t, &homogeneous(tool));
        if general {
            origins.push([t[0][3], t[1][3], t[2][3]]);
        } else if let Some(last) = origins.last_mut() {
            *last = [t[0][3], t[1][3], t[2][3]];
        }
    }
    (origins, t)
}

/// The arm at one configuration, `f64`: what the obstacle and
/// self-collision checks read ([`pose`], [`Geometry::pose`]).
#[derive(Clone, Debug, PartialEq)]
pub struct Pose {
    /// The joints' pivots and the end effector, `o_0..o_n`, world, length
    /// units ([`forward_chain`]).
    pub origins: Vec<[f64; 3]>,
    /// The end effector's transform (`T_n tool`).
    pub end: M4,
    /// Each link's capsule segment, world, length units (the module docs'
    /// `s_k`): the chord `o_k -> o_{k+1}`, or the link's segment
    /// ([`link_segment`]) carried by its body's frame, `T_k a -> T_k b`.
    pub capsules: Vec<[V3; 2]>,
}

/// The arm of `problem` at `q` ([`Pose`]).
pub fn pose(problem: &Problem, q: &[f64]) -> Pose {
    pose_chain(&problem.joints, &problem.tool, &problem.links.segments, q)
}

/// [`pose`] for a bare chain, tool and link segments (`Problem::links`'
/// `segments`: empty, or per link its segment in its body's frame).
pub fn pose_chain(
    joints: &[Joint],
    tool: &Placement,
    segments: &[[[f32; 3]; 2]],
    q: &[f64],
) -> Pose {
    let mut placed: Vec<Option<[V3; 2]>> = vec![None; joints.len()];
    let (origins, end) = walk_chain(joints, tool, q, |j, t| {
        if let Some([a, b]) = link_segment(joints, segments, j) {
            placed[j] = Some([transform(t, a), transform(t, b)]);
        }
    });
    let capsules = origins
        .windows(2)
        .zip(placed)
        .map(|(chord, segment)| segment.unwrap_or([chord[0], chord[1]]))
        .collect();
    Pose {
        origins,
        end,
        capsules,
    }
}

/// Link `k`'s capsule segment in its body's frame (`T_k`, after joint `k`'s
/// motion), length units, when it has one: `segments[k]` for a general
/// joint; `None` for a chord (no segments, or a DH row).
pub fn link_segment(joints: &[Joint], segments: &[[[f32; 3]; 2]], k: usize) -> Option<[V3; 2]> {
    joints.get(k)?.origin?;
    segments.get(k).map(|s| s.map(|p| p.map(f64::from)))
}

/// `T p`: the point `p` of a frame `t` in world coordinates.
fn transform(t: &M4, p: V3) -> V3 {
    [0, 1, 2].map(|i| t[i][3] + (0..3).map(|k| t[i][k] * p[k]).sum::<f64>())
}

/// Each general joint's frame after its motion, world (`T_j` of
/// [`forward_chain`]: `T_j = T_{j-1} O_j M_j(q_j)`, lengths in the
/// scenario's unit): the frame of the rigid body joint `j` moves. Empty for
/// a DH table.
pub fn joint_frames(joints: &[Joint], q: &[f64]) -> Vec<M4> {
    let mut t: M4 = homogeneous(&Placement::IDENTITY);
    let mut frames = Vec::with_capacity(joints.len());
    for (joint, &qj) in joints.iter().zip(q) {
        let Some(origin) = joint.origin else {
            return Vec::new();
        };
        t = mul(
            &mul(&t, &homogeneous(&origin.placement)),
            &motion(joint.kind, origin.axis, qj),
        );
        frames.push(t);
    }
    frames
}

/// A URDF robot's collision capsules at `q`, world, in the scenario's
/// length unit, each `[ax, ay, az, bx, by, bz, radius]`, body by body: the
/// base's (`bodies[0]`, in the world frame: not checked by the planner),
/// then those joint `k` moves (`bodies[k + 1]`, which link `k`'s capsule
/// encloses). Empty for a robot without a URDF.
pub fn collision_capsules(problem: &Problem, q: &[f64]) -> Vec<[f64; 7]> {
    let Some(urdf) = &problem.urdf else {
        return Vec::new();
    };
    let frames = joint_frames(&problem.joints, q);
    let world = homogeneous(&Placement::IDENTITY);
    let s = urdf.per_metre;
    let place = |t: &M4, p: &nalgebra::Point3<f64>| transform(t, [p.x * s, p.y * s, p.z * s]);
    urdf.bodies
        .iter()
        .zip(std::iter::once(&world).chain(&frames))
        .flat_map(|(body, t)| {
            body.capsules.iter().map(move |c| {
                let (a, b) = (place(t, &c.a), place(t, &c.b));
                [a[0], a[1], a[2], b[0], b[1], b[2], c.radius * s]
            })
        })
        .collect()
}

/// A placement as a 4x4 homogeneous matrix.
fn homogeneous(p: &Placement) -> M4 {
    let mut m = [[0.0; 4]; 4];
    for ((row, r), &t) in m.iter_mut().zip(&p.rotation).zip(&p.translation) {
        for (x, &v) in row.iter_mut().zip(r) {
            *x = v as f64;
        }
        row[3] = t as f64;
    }
    m[3][3] = 1.0;
    m
}

/// A general joint's motion by `q` about (along) `axis`, normalised here:
/// Rodrigues' `R = cos q I + (1 - cos q) a a^T + sin q [a]x`.
fn motion(kind: JointKind, axis: [f32; 3], q: f64) -> M4 {
    let a = axis.map(|x| x as f64);
    let length = (a[0] * a[0] + a[1] * a[1] + a[2] * a[2]).sqrt();
    let a = a.map(|x| x / length);
    let mut m = [[0.0; 4]; 4];
    m[3][3] = 1.0;
    match kind {
        JointKind::Revolute => {
            let (s, c) = libm::sincos(q);
            let k = [[0.0, -a[2], a[1]], [a[2], 0.0, -a[0]], [-a[1], a[0], 0.0]];
            for (i, row) in m.iter_mut().take(3).enumerate() {
                for (j, x) in row.iter_mut().take(3).enumerate() {
                    let identity = if i == j { c } else { 0.0 };
                    *x = identity + (1.0 - c) * a[i] * a[j] + s * k[i][j];
                }
            }
        }
        JointKind::Prismatic => {
            for (i, row) in m.iter_mut().take(3).enumerate() {
                row[i] = 1.0;
                row[3] = a[i] * q;
            }
        }
    }
    m
}

/// The longest chord each link can have, length units (`chord_k` of the
/// module docs): DH `sqrt(a^2 + d^2)` (`d` at its largest extension for a
/// prismatic joint); a general link the distance to the next joint's
/// origin (or the tool's), plus a prismatic joint's largest extension; the
/// tool lengthens the last link.
pub fn longest_links(joints: &[Joint], tool: &Placement) -> Vec<f64> {
    let norm = |t: [f32; 3]| {
        t.iter()
            .map(|&x| (x as f64) * (x as f64))
            .sum::<f64>()
            .sqrt()
    };
    let tool_length = norm(tool.translation);
    let n = joints.len();
    joints
        .iter()
        .enumerate()
        .map(|(k, j)| {
            let travel = (j.min.abs() as f64).max(j.max.abs() as f64);
            let next = match joints.get(k + 1).and_then(|next| next.origin) {
                Some(o) => norm(o.placement.translation),
                None if k + 1 == n => tool_length,
                None => 0.0,
            };
            match (j.origin, j.kind) {
                (Some(_), JointKind::Revolute) => next,
                (Some(_), JointKind::Prismatic) => next + travel,
                (None, kind) => {
                    let d = match kind {
                        JointKind::Revolute => j.d.abs() as f64,
                        JointKind::Prismatic => travel,
                    };
                    let tool = if k + 1 == n { tool_length } else { 0.0 };
                    (j.a as f64).hypot(d) + tool
                }
            }
        })
        .collect()
}

/// How far from its joint's pivot any point of each link's capsule
/// segment can lie, length units (`l_k` of the module docs): the longest
/// chord ([`longest_links`]), or for a link with a segment `a -> b`
/// ([`link_segment`]) the larger of that and `max(|a|, |b|)` plus a
/// prismatic joint's largest extension (`a`, `b` are measured from the
/// joint's frame after its motion, which a slide moves off the pivot).
pub fn link_reach(joints: &[Joint], tool: &Placement, segments: &[[[f32; 3]; 2]]) -> Vec<f64> {
    let norm = |p: V3| dot(p, p).sqrt();
    longest_links(joints, tool)
        .into_iter()
        .enumerate()
        .map(|(k, chord)| match link_segment(joints, segments, k) {
            Some([a, b]) => {
                let joint = &joints[k];
                let slide = match joint.kind {
                    JointKind::Revolute => 0.0,
                    JointKind::Prismatic => (joint.min.abs() as f64).max(joint.max.abs() as f64),
                };
                chord.max(norm(a).max(norm(b)) + slide)
            }
            None => chord,
        })
        .collect()
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

/// `a + t (b - a)`.
fn along(a: V3, b: V3, t: f64) -> V3 {
    [
        a[0] + t * (b[0] - a[0]),
        a[1] + t * (b[1] - a[1]),
        a[2] + t * (b[2] - a[2]),
    ]
}

/// The parameter in `[0, 1]` of the point of segment `a -> b` nearest `p`
/// (0 for a segment of zero length).
fn nearest_on(p: V3, a: V3, b: V3) -> f64 {
    let ab = sub(b, a);
    let l2 = dot(ab, ab);
    if l2 > 0.0 {
        (dot(sub(p, a), ab) / l2).clamp(0.0, 1.0)
    } else {
        0.0
    }
}

/// The distance between two segments and where it is attained.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct SegmentDistance {
    /// The smallest distance between a point of each.
    pub distance: f64,
    /// Where on the first segment, `0..=1` from its start.
    pub s: f64,
    /// Where on the second segment, `0..=1` from its start.
    pub t: f64,
}

/// The distance between segments `p0 -> p1` and `q0 -> q1` (either may have
/// zero length), in `f64`.
///
/// `|P(s) - Q(t)|`, `P(s) = p0 + s u`, `Q(t) = q0 + t v`, is convex over the
/// square `[0, 1]^2`, so its minimum is either inside, where `P(s) - Q(t)`
/// is the lines' common perpendicular `n = u x v`:
///
/// ```text
/// s = ((w x v) . n) / |n|^2,   t = ((w x u) . n) / |n|^2,   w = q0 - p0
/// ```
///
/// (accepted when both lie in `[0, 1]`; none when the lines are parallel,
/// whose minimum is then also on the boundary), or on an edge of the
/// square, where one parameter is 0 or 1: an endpoint against the other
/// segment, nearest point by clamped projection. The answer is the least of
/// those five candidates, each an actual pair of points, so it is never
/// below the true distance; the perpendicular's points are polished by two
/// rounds of alternating clamped projection (each can only shorten the
/// pair), which keeps nearly parallel segments accurate.
pub fn segment_distance(p0: V3, p1: V3, q0: V3, q1: V3) -> SegmentDistance {
    let pair = |s: f64, t: f64| {
        let d = sub(along(p0, p1, s), along(q0, q1, t));
        SegmentDistance {
            distance: dot(d, d),
            s,
            t,
        }
    };
    let mut best = pair(0.0, nearest_on(p0, q0, q1));
    let mut keep = |c: SegmentDistance| {
        if c.distance < best.distance {
            best = c;
        }
    };
    keep(pair(1.0, nearest_on(p1, q0, q1)));
    keep(pair(nearest_on(q0, p0, p1), 0.0));
    keep(pair(nearest_on(q1, p0, p1), 1.0));
    let (u, v) = (sub(p1, p0), sub(q1, q0));
    let n = cross(u, v);
    let nn = dot(n, n);
    if nn > 0.0 {
        let w = sub(q0, p0);
        let (mut s, mut t) = (dot(cross(w, v), n) / nn, dot(cross(w, u), n) / nn);
        if (0.0..=1.0).contains(&s) && (0.0..=1.0).contains(&t) {
            for _ in 0..2 {
                t = nearest_on(along(p0, p1, s), q0, q1);
                s = nearest_on(along(q0, q1, t), p0, p1);
            }
            keep(pair(s, t));
        }
    }
    best.distance = best.distance.sqrt();
    best
}

/// An obstacle in `f64`, ready to evaluate.
struct Shape {
    centre: [f64; 3],
    r: [[f64; 3]; 3],
    form: Form,
}

/// What an obstacle is in its own frame, `f64`.
enum Form {
    /// Eq. 25: semi-axes and exponents.
    SuperEllipsoid { axes: [f64; 3], exponents: [f64; 3] },
    /// A primitive by its closest point ([`closest_point`]) and inradius.
    Primitive {
        shape: capp_core::Shape,
        inradius: f64,
    },
    /// A convex hull by its exact signed distance ([`Polytope`]) and half
    /// its smallest width along its frame's axes (the core's `rho`).
    Hull { polytope: Polytope, half_width: f64 },
}

impl Shape {
    /// Obstacle `o`; `hulls` are the problem's ([`hull_polytopes`]).
    fn new(o: &capp_core::Solid, hulls: &[Polytope]) -> Shape {
        use capp_core::Shape as S;
        let form = match o.shape {
            S::Convex { hull } => {
                // A hull the problem lacks is refused by validation; an empty
                // one measures nothing (every distance infinite).
                let polytope = hulls
                    .get(hull as usize)
                    .cloned()
                    .unwrap_or_else(|| Polytope::new(&[]));
                let half_width = 0.5
                    * (0..3)
                        .map(|a| {
                            let v = polytope.vertices();
                            let hi = v.iter().map(|p| p[a]).fold(f64::NEG_INFINITY, f64::max);
                            let lo = v.iter().map(|p| p[a]).fold(f64::INFINITY, f64::min);
                            hi - lo
                        })
                        .fold(f64::INFINITY, f64::min);
                Form::Hull {
                    polytope,
                    half_width,
                }
            }
            S::SuperEllipsoid {
                semi_axes,
                exponents,
            } => Form::SuperEllipsoid {
                axes: semi_axes.map(f64::from),
                exponents: exponents.map(f64::from),
            },
            shape => Form::Primitive {
                shape,
                inradius: match shape {
                    S::Sphere { radius } | S::Capsule { radius, .. } => radius as f64,
                    S::Cuboid { half_extents: h } => {
                        h.iter().fold(f64::INFINITY, |m, &x| m.min(x as f64))
                    }
                    S::Cylinder { radius, length } => (radius as f64).min(0.5 * length as f64),
                    S::SuperEllipsoid { .. } | S::Convex { .. } => 0.0,
                },
            },
        };
        Shape {
            centre: o.centre.map(f64::from),
            r: rotation(o.euler_123.map(f64::from)),
            form,
        }
    }

    /// `C(p) - 1` of the obstacle inflated by `margin`: eq. 25 for a
    /// super-ellipsoid; for a primitive the same rebuilt on its signed
    /// distance `d`, `((d + rho) / (margin + rho))^2 - 1` (`rho` its
    /// inradius), negative exactly when `d < margin`.
    fn clearance(&self, p: [f64; 3], margin: f64) -> f64 {
        let x = to_local(self.centre, &self.r, p);
        match &self.form {
            Form::SuperEllipsoid { axes, exponents } => {
                let mut c = 0.0;
                for i in 0..3 {
                    c += power(x[i].abs() / (axes[i] + margin), exponents[i]);
                }
                c - 1.0
            }
            Form::Primitive { shape, inradius } => {
                let u = (signed_distance(shape, &[], x) + inradius) / (margin + inradius);
                u * u - 1.0
            }
            Form::Hull {
                polytope,
                half_width,
            } => {
                let u = (polytope.signed_distance(x) + half_width) / (margin + half_width);
                u * u - 1.0
            }
        }
    }
}

/// The world point `p` in the frame of a shape at `centre` turned by `r`
/// ([`rotation`]): `R^T (p - centre)`.
pub fn to_local(centre: [f64; 3], r: &[[f64; 3]; 3], p: [f64; 3]) -> [f64; 3] {
    let d = [p[0] - centre[0], p[1] - centre[1], p[2] - centre[2]];
    // x_i = (R^T d)_i = column i of R dotted with d.
    std::array::from_fn(|i| r[0][i] * d[0] + r[1][i] * d[1] + r[2][i] * d[2])
}

/// The problem's hulls with their faces enumerated ([`Polytope`]), by index.
pub fn hull_polytopes(problem: &Problem) -> Vec<Polytope> {
    problem
        .hulls
        .iter()
        .map(|h| Polytope::new(&h.iter().map(|v| v.map(f64::from)).collect::<Vec<_>>()))
        .collect()
}

/// The signed distance from the local point `x` to a primitive's or a
/// hull's surface (negative inside): outside, the distance to its closest
/// point; inside, minus the distance to the nearest face. `hulls` are the
/// problem's ([`hull_polytopes`]), which a `Convex` shape names; NaN for a
/// super-ellipsoid or a hull not in `hulls`.
pub fn signed_distance(shape: &capp_core::Shape, hulls: &[Polytope], x: [f64; 3]) -> f64 {
    use capp_core::Shape as S;
    let norm = |v: [f64; 3]| (v[0] * v[0] + v[1] * v[1] + v[2] * v[2]).sqrt();
    match *shape {
        S::Sphere { radius } => norm(x) - radius as f64,
        S::Capsule { radius, length } => {
            let l = 0.5 * length as f64;
            norm([x[0], x[1], x[2] - x[2].clamp(-l, l)]) - radius as f64
        }
        S::Cuboid { half_extents } => {
            let h = half_extents.map(f64::from);
            let closest: [f64; 3] = std::array::from_fn(|i| x[i].clamp(-h[i], h[i]));
            let outside = norm(std::array::from_fn(|i| x[i] - closest[i]));
            if outside > 0.0 {
                outside
            } else {
                (0..3)
                    .map(|i| x[i].abs() - h[i])
                    .fold(f64::NEG_INFINITY, f64::max)
            }
        }
        S::Cylinder { radius, length } => {
            let (r, l) = (radius as f64, 0.5 * length as f64);
            let rho = x[0].hypot(x[1]);
            let (radial, axial) = (rho - r, x[2].abs() - l);
            if radial > 0.0 || axial > 0.0 {
                radial.max(0.0).hypot(axial.max(0.0))
            } else {
                radial.max(axial)
            }
        }
        S::Convex { hull } => hulls
            .get(hull as usize)
            .map_or(f64::NAN, |p| p.signed_distance(x)),
        S::SuperEllipsoid { .. } => f64::NAN,
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

/// Most configurations [`Geometry::sweep_links`] evaluates between two
/// configurations: its work is bounded whatever the step.
pub const SWEEP_BUDGET: usize = 4096;

/// The part of the smaller capsule radius of a pair that its two links may
/// each travel between two configurations [`Geometry::sweep_links`]
/// evaluates, while the bound of the module docs does not keep the pair
/// apart.
pub const SWEEP_FRACTION: f64 = 0.25;

/// The capsules' gap of one checked pair of links.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct LinkGap {
    /// The capsule segments' distance less both radii, length units;
    /// negative when the capsules overlap.
    pub gap: f64,
    /// The two links, 0-based (DH links `a + 1`, `b + 1`), the lower first.
    pub links: (usize, usize),
}

/// What [`Geometry::sweep_links`] found between two configurations.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Sweep {
    /// The smallest gap of a checked pair at the configurations evaluated
    /// strictly between the two ends, and where (`t` in `(0, 1)`).
    pub worst: Option<(LinkGap, f64)>,
    /// Whether the motion bound proves every checked pair's gap stays at or
    /// above the floor all along the segment.
    pub certified: bool,
    /// Configurations evaluated.
    pub samples: usize,
    /// Whether [`SWEEP_BUDGET`] ran out before the spacing was as fine as
    /// [`SWEEP_FRACTION`] asks.
    pub truncated: bool,
}

/// The links' capsules and the checked pairs.
struct Links {
    /// Capsule radius per link.
    radius: Vec<f64>,
    /// The checked pairs, `a < b`.
    pairs: Vec<(usize, usize)>,
}

/// A problem's chain, obstacles, avoidance points and link capsules,
/// prepared once for clearance queries of many configurations (independent
/// of the planner, like [`crate::check::check`]).
pub struct Geometry {
    joints: Vec<Joint>,
    tool: Placement,
    /// Each link's capsule segment in its body's frame, or empty: chords
    /// (`Problem::links`' `segments`).
    segments: Vec<[[f32; 3]; 2]>,
    shapes: Vec<Shape>,
    interior: usize,
    margins: [f64; 2],
    /// `None` when self-collision is off (or the scenario's capsules are
    /// invalid: [`Problem::validate`] refuses those).
    links: Option<Links>,
    /// How far from its pivot a point of each link's capsule can lie
    /// (`l_k` of the module docs, [`link_reach`]).
    longest: Vec<f64>,
}

impl Links {
    fn new(problem: &Problem) -> Option<Links> {
        if !problem.links.enabled {
            return None;
        }
        let table = problem.pair_table().ok()?;
        let n = problem.joints.len();
        let pairs = (0..n)
            .flat_map(|a| (a + 1..n).map(move |b| (a, b)))
            .filter(|&(a, b)| table.status(a, b) == PairStatus::Checked)
            .collect();
        Some(Links {
            radius: problem.links.radius.iter().map(|&r| r as f64).collect(),
            pairs,
        })
    }

    /// The gap of checked pair `i` at `pose`: its capsule segments'
    /// distance less both radii.
    fn gap(&self, pose: &Pose, i: usize) -> f64 {
        let (a, b) = self.pairs[i];
        let ([a0, a1], [b0, b1]) = (pose.capsules[a], pose.capsules[b]);
        let d = segment_distance(a0, a1, b0, b1);
        d.distance - self.radius[a] - self.radius[b]
    }
}

impl Geometry {
    /// Prepares `problem`'s obstacles (with its margins and points per link).
    pub fn new(problem: &Problem) -> Self {
        let avoid = &problem.settings.avoidance;
        Geometry {
            joints: problem.joints.clone(),
            tool: problem.tool,
            segments: problem.links.segments.clone(),
            shapes: {
                let hulls = hull_polytopes(problem);
                problem
                    .obstacles
                    .iter()
                    .map(|o| Shape::new(o, &hulls))
                    .collect()
            },
            interior: avoid.points_per_link as usize,
            margins: [avoid.joint_margin as f64, avoid.link_margin as f64],
            links: Links::new(problem),
            longest: link_reach(&problem.joints, &problem.tool, &problem.links.segments),
        }
    }

    /// The arm at `q`: frame origins, end transform and link capsules.
    pub fn pose(&self, q: &[f64]) -> Pose {
        pose_chain(&self.joints, &self.tool, &self.segments, q)
    }

    /// Frame origins `o_0..o_n` at `q` (all the obstacle checks read).
    fn origins(&self, q: &[f64]) -> Vec<[f64; 3]> {
        forward_chain(&self.joints, &self.tool, q).0
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
        let origins = self.origins(q);
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
        let origins = self.origins(q);
        let mut clear = true;
        self.pairs(&origins, |value, _, _| {
            clear = value > margin;
            clear
        });
        clear
    }

    /// Whether self-collision is checked (the scenario enables it).
    pub fn self_collision(&self) -> bool {
        self.links.is_some()
    }

    /// The checked pairs of links (0-based, `a < b`); empty when
    /// self-collision is off.
    pub fn checked_pairs(&self) -> &[(usize, usize)] {
        self.links.as_ref().map_or(&[], |l| &l.pairs)
    }

    /// The gap of every checked pair (in [`Geometry::checked_pairs`]'
    /// order) of the arm at `pose` ([`Geometry::pose`]).
    pub fn link_gaps(&self, pose: &Pose) -> Vec<f64> {
        match &self.links {
            Some(l) => (0..l.pairs.len()).map(|i| l.gap(pose, i)).collect(),
            None => Vec::new(),
        }
    }

    /// The smallest of `gaps` (as [`Geometry::link_gaps`] gives them) and
    /// its pair; `None` without checked pairs. NaN counts as the smallest.
    pub fn worst_gap(&self, gaps: &[f64]) -> Option<LinkGap> {
        let pairs = self.checked_pairs();
        let mut worst: Option<LinkGap> = None;
        for (&gap, &links) in gaps.iter().zip(pairs) {
            if worst.is_none_or(|w| gap < w.gap || gap.is_nan()) {
                worst = Some(LinkGap { gap, links });
            }
        }
        worst
    }

    /// The closest checked pair of links at `q`; `None` when no pair is
    /// checked.
    pub fn closest_link_pair(&self, q: &[f64]) -> Option<LinkGap> {
        self.links.as_ref()?;
        self.worst_gap(&self.link_gaps(&self.pose(q)))
    }

    /// Whether `q` is free: every avoidance point has `C - 1 > 0` and every
    /// checked pair of capsules a gap `> 0` (NaN is not free).
    pub fn is_free(&self, q: &[f64]) -> bool {
        let pose = self.pose(q);
        let mut clear = true;
        self.pairs(&pose.origins, |value, _, _| {
            clear = value > 0.0;
            clear
        });
        clear
            && match &self.links {
                Some(l) => (0..l.pairs.len()).all(|i| l.gap(&pose, i) > 0.0),
                None => true,
            }
    }

    /// Per link, a bound on how far any point of its capsule segment (or
    /// its chord) travels along the straight joint-space segment `a -> b`
    /// (the module docs' `delta_k`), length units.
    pub fn link_motion(&self, a: &[f64], b: &[f64]) -> Vec<f64> {
        let n = self.joints.len();
        let mut delta = vec![0.0; n];
        for (j, joint) in self.joints.iter().enumerate() {
            let dq = (b[j] - a[j]).abs();
            // The lever of joint j on links j..: the chords from its pivot
            // out, the last one's reach to its capsule's farthest point.
            let mut lever = 0.0;
            for (k, d) in delta.iter_mut().enumerate().skip(j) {
                lever += self.longest[k];
                *d += dq
                    * match joint.kind {
                        JointKind::Revolute => lever,
                        JointKind::Prismatic => 1.0,
                    };
            }
        }
        delta
    }

    /// The checked pairs along the straight joint-space segment `a -> b`,
    /// whose ends have the gaps `gaps_a`, `gaps_b` ([`Geometry::link_gaps`]):
    /// bisects wherever the motion bound (module docs) leaves a pair's gap
    /// possibly below `floor`, until both links of every such pair move at
    /// most [`SWEEP_FRACTION`] of the smaller radius between evaluated
    /// configurations, or [`SWEEP_BUDGET`] configurations were evaluated.
    /// With `certify`, stops at the first sign that the bound cannot prove
    /// the floor (a gap evaluated below it, an interval at the finest
    /// spacing still in doubt, the budget spent): `certified` is then false.
    pub fn sweep_links(
        &self,
        a: &[f64],
        b: &[f64],
        gaps_a: &[f64],
        gaps_b: &[f64],
        floor: f64,
        certify: bool,
    ) -> Sweep {
        let mut sweep = Sweep {
            worst: None,
            certified: true,
            samples: 0,
            truncated: false,
        };
        let Some(links) = &self.links else {
            return sweep;
        };
        let delta = self.link_motion(a, b);
        let pairs: Vec<(usize, f64, f64)> = (0..links.pairs.len())
            .map(|i| (i, gaps_a[i], gaps_b[i]))
            .collect();
        let mut walk = Bisection {
            geometry: self,
            links,
            a,
            b,
            delta: &delta,
            floor,
            certify,
            sweep: &mut sweep,
        };
        walk.interval(0.0, 1.0, &pairs);
        sweep
    }
}

/// The state of one [`Geometry::sweep_links`].
struct Bisection<'a> {
    geometry: &'a Geometry,
    links: &'a Links,
    a: &'a [f64],
    b: &'a [f64],
    delta: &'a [f64],
    floor: f64,
    certify: bool,
    sweep: &'a mut Sweep,
}

impl Bisection<'_> {
    fn done(&self) -> bool {
        self.certify && !self.sweep.certified
    }

    /// `(pair, gap at t0, gap at t1)` of the pairs still in doubt on `[t0, t1]`.
    fn interval(&mut self, t0: f64, t1: f64, pairs: &[(usize, f64, f64)]) {
        let span = t1 - t0;
        let (mut doubt, mut coarse) = (Vec::new(), false);
        for &(i, g0, g1) in pairs {
            let (a, b) = self.links.pairs[i];
            let (da, db) = (self.delta[a] * span, self.delta[b] * span);
            // NaN never proves anything: it stays in doubt.
            if 0.5 * (g0 + g1 - da - db) >= self.floor {
                continue;
            }
            let fine = SWEEP_FRACTION * self.links.radius[a].min(self.links.radius[b]);
            coarse |= da > fine || db > fine;
            doubt.push((i, g0, g1));
        }
        if doubt.is_empty() {
            return;
        }
        if !coarse {
            // As fine as asked, and the bound still cannot prove the floor.
            self.sweep.certified = false;
            return;
        }
        if self.sweep.samples >= SWEEP_BUDGET {
            self.sweep.truncated = true;
            self.sweep.certified = false;
            return;
        }
        let tm = 0.5 * (t0 + t1);
        let q: Vec<f64> = self
            .a
            .iter()
            .zip(self.b)
            .map(|(x, y)| x + tm * (y - x))
            .collect();
        let pose = self.geometry.pose(&q);
        self.sweep.samples += 1;
        let mut left = Vec::with_capacity(doubt.len());
        let mut right = Vec::with_capacity(doubt.len());
        for &(i, g0, g1) in &doubt {
            let gm = self.links.gap(&pose, i);
            if self
                .sweep
                .worst
                .is_none_or(|(w, _)| gm < w.gap || gm.is_nan())
            {
                self.sweep.worst = Some((
                    LinkGap {
                        gap: gm,
                        links: self.links.pairs[i],
                    },
                    tm,
                ));
            }
            if gm.is_nan() || gm < self.floor {
                self.sweep.certified = false;
            }
            left.push((i, g0, gm));
            right.push((i, gm, g1));
        }
        if self.done() {
            return;
        }
        self.interval(t0, tm, &left);
        if self.done() {
            return;
        }
        self.interval(tm, t1, &right);
    }
}
