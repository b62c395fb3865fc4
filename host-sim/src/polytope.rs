//! Convex polytopes in `f64`, on the host: the convex hull of a point cloud
//! (a mesh's vertices: [`hull_vertices`]) and a hull's faces and signed
//! distance for the independent checker ([`Polytope`]).
//!
//! Written here rather than taken from a crate: the workspace's `nalgebra`
//! must keep exactly the features capp-core gives it (features unify across
//! the workspace and would change the core's host math, see
//! `crates/capp-urdf/Cargo.toml`), which rules out `parry3d` and
//! `parry3d-f64` (they enable nalgebra's `std`); and the checker must not
//! share code with the core's GJK ([`capp_core::obstacle::hull`]), so its
//! distances are a second opinion.
//!
//! [`hull_vertices`] is an incremental hull (Barber, Dobkin and Huhdanpaa,
//! "The Quickhull Algorithm for Convex Hulls", 1996, without the outside
//! sets): start from the tetrahedron of four extreme points, and for each
//! point outside the current hull by more than `HULL_TOLERANCE` times the
//! cloud's size, remove the faces it sees and join it to their horizon. A
//! point within that tolerance of the hull is taken as inside (the hull
//! then misses it by at most 1e-7 of the cloud's size, below `f32`
//! rounding of the vertices the core receives). Only the corners are
//! returned: a vertex that is the strict maximum of the mean of its
//! incident faces' normals, so points in the middle of a flat face or of a
//! straight edge are dropped.
//!
//! [`Polytope::new`] enumerates the faces of a hull of at most a few dozen
//! vertices exactly, `O(n^4)` once per scenario: every plane through three
//! vertices with every vertex on one side (within `1e-9` of the hull's
//! size) is a supporting plane, and the vertices on it, ordered round it,
//! its face polygon. Then, for a point `x` in the hull's frame,
//!
//! ```text
//! inside  (max_f  n_f . x - d_f <= 0):  sd(x) = max_f (n_f . x - d_f)
//! outside:                              sd(x) = min over the triangles of the
//!                                               faces with n_f . x > d_f of
//!                                               |x - closest point|
//! ```
//!
//! the exact signed distance (negative inside: minus the depth to the
//! nearest face). The closest point of a convex body lies on a face whose
//! plane has `x` in front, so the other faces are skipped.

use std::collections::HashMap;

/// A point or vector, length units.
pub type V3 = [f64; 3];

/// Outside tolerance of [`hull_vertices`], relative to the cloud's size.
const HULL_TOLERANCE: f64 = 1e-7;
/// On-plane tolerance of [`Polytope::new`], relative to the hull's size.
const FACE_TOLERANCE: f64 = 1e-9;

/// `a - b`.
pub(crate) fn sub(a: V3, b: V3) -> V3 {
    [a[0] - b[0], a[1] - b[1], a[2] - b[2]]
}

/// `a . b`.
pub(crate) fn dot(a: V3, b: V3) -> f64 {
    a[0] * b[0] + a[1] * b[1] + a[2] * b[2]
}

/// `a x b`.
pub(crate) fn cross(a: V3, b: V3) -> V3 {
    [
        a[1] * b[2] - a[2] * b[1],
        a[2] * b[0] - a[0] * b[2],
        a[0] * b[1] - a[1] * b[0],
    ]
}

fn norm(a: V3) -> f64 {
    dot(a, a).sqrt()
}

fn scaled(a: V3, s: f64) -> V3 {
    [a[0] * s, a[1] * s, a[2] * s]
}

/// The largest extent of `points` along an axis, length units.
pub(crate) fn spread(points: &[V3]) -> f64 {
    (0..3)
        .map(|a| {
            let (lo, hi) = points
                .iter()
                .fold((f64::INFINITY, f64::NEG_INFINITY), |(lo, hi), p| {
                    (lo.min(p[a]), hi.max(p[a]))
                });
            hi - lo
        })
        .fold(0.0, f64::max)
}

/// Why a point cloud has no hull.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum HullFailure {
    /// No points at all.
    Empty,
    /// A coordinate is NaN or infinite.
    NotFinite,
    /// The points span no volume (fewer than four that are not coplanar).
    Flat,
}

impl std::fmt::Display for HullFailure {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.write_str(match self {
            HullFailure::Empty => "it has no vertices",
            HullFailure::NotFinite => "a vertex is not finite",
            HullFailure::Flat => "its vertices span no volume (fewer than 4 that are not coplanar)",
        })
    }
}

/// A triangle of the incremental hull, counter-clockwise seen from outside.
struct Face {
    v: [usize; 3],
    normal: V3,
    offset: f64,
    alive: bool,
}

impl Face {
    fn new(points: &[V3], v: [usize; 3]) -> Face {
        let n = cross(
            sub(points[v[1]], points[v[0]]),
            sub(points[v[2]], points[v[0]]),
        );
        let normal = scaled(n, 1.0 / norm(n));
        Face {
            v,
            normal,
            offset: dot(normal, points[v[0]]),
            alive: true,
        }
    }

    fn height(&self, p: V3) -> f64 {
        dot(self.normal, p) - self.offset
    }
}

/// The corners of the convex hull of `points` (deduplicated, in no
/// particular order): see the module docs.
pub fn hull_vertices(points: &[V3]) -> Result<Vec<V3>, HullFailure> {
    cloud_hull(points).map(|hull| hull.corners)
}

/// A boundary triangle of a [`CloudHull`]: its corners (counter-clockwise
/// seen from outside) and its plane, `normal . x = offset` (outward unit
/// normal, length units).
#[derive(Clone, Debug, PartialEq)]
pub struct HullTriangle {
    /// The triangle's corners.
    pub corners: [V3; 3],
    /// Outward unit normal.
    pub normal: V3,
    /// `normal . x` on the plane, length units.
    pub offset: f64,
}

/// The convex hull of a point cloud, as [`cloud_hull`] builds it.
#[derive(Clone, Debug, PartialEq)]
pub struct CloudHull {
    /// Its corners ([`hull_vertices`]).
    pub corners: Vec<V3>,
    /// Its boundary, triangulated (points in the middle of a face or an
    /// edge may be triangle corners).
    pub triangles: Vec<HullTriangle>,
}

impl CloudHull {
    /// The distance from `x` to the hull, 0 inside: the least over the
    /// triangles whose plane has `x` in front (see the module docs).
    pub fn distance(&self, x: V3) -> f64 {
        self.triangles
            .iter()
            .filter(|t| dot(t.normal, x) > t.offset)
            .map(|t| triangle_distance(x, t.corners))
            .reduce(f64::min)
            .unwrap_or(0.0)
    }
}

/// The convex hull of `points`: its corners and its triangulated boundary
/// (see the module docs).
pub fn cloud_hull(points: &[V3]) -> Result<CloudHull, HullFailure> {
    if points.is_empty() {
        return Err(HullFailure::Empty);
    }
    if !points.iter().flatten().all(|c| c.is_finite()) {
        return Err(HullFailure::NotFinite);
    }
    let mut pts = points.to_vec();
    pts.sort_by(|a, b| {
        a[0].total_cmp(&b[0])
            .then(a[1].total_cmp(&b[1]))
            .then(a[2].total_cmp(&b[2]))
    });
    pts.dedup();
    let size = spread(&pts);
    let eps = HULL_TOLERANCE * size;
    if pts.len() < 4 || size <= 0.0 {
        return Err(HullFailure::Flat);
    }
    // The first tetrahedron: the lowest x, the point farthest from it,
    // the farthest from their line, the farthest from their plane.
    let i0 = 0;
    let far = |f: &dyn Fn(V3) -> f64| {
        (0..pts.len())
            .map(|i| (i, f(pts[i])))
            .fold(
                (0, f64::NEG_INFINITY),
                |best, c| if c.1 > best.1 { c } else { best },
            )
    };
    let (i1, _) = far(&|p| norm(sub(p, pts[i0])));
    let axis = sub(pts[i1], pts[i0]);
    let (i2, d2) = far(&|p| norm(cross(sub(p, pts[i0]), axis)) / norm(axis));
    if d2 <= eps {
        return Err(HullFailure::Flat);
    }
    let n = cross(axis, sub(pts[i2], pts[i0]));
    let n = scaled(n, 1.0 / norm(n));
    let (i3, d3) = far(&|p| dot(sub(p, pts[i0]), n).abs());
    if d3 <= eps {
        return Err(HullFailure::Flat);
    }
    let mut faces: Vec<Face> = Vec::new();
    let inner = scaled(
        [0, 1, 2].map(|a| pts[i0][a] + pts[i1][a] + pts[i2][a] + pts[i3][a]),
        0.25,
    );
    for tri in [[i0, i1, i2], [i0, i1, i3], [i0, i2, i3], [i1, i2, i3]] {
        let mut f = Face::new(&pts, tri);
        if f.height(inner) > 0.0 {
            f = Face::new(&pts, [tri[0], tri[2], tri[1]]);
        }
        faces.push(f);
    }
    // Directed edge (a, b) -> the face it bounds counter-clockwise.
    let mut edges: HashMap<(usize, usize), usize> = HashMap::new();
    for (i, f) in faces.iter().enumerate() {
        for k in 0..3 {
            edges.insert((f.v[k], f.v[(k + 1) % 3]), i);
        }
    }
    for p in 0..pts.len() {
        let visible: Vec<usize> = (0..faces.len())
            .filter(|&i| faces[i].alive && faces[i].height(pts[p]) > eps)
            .collect();
        if visible.is_empty() {
            continue;
        }
        let mut horizon = Vec::new();
        for &i in &visible {
            let v = faces[i].v;
            for k in 0..3 {
                let (a, b) = (v[k], v[(k + 1) % 3]);
                let across = edges.get(&(b, a)).copied();
                if across.is_some_and(|j| faces[j].height(pts[p]) <= eps) {
                    horizon.push((a, b));
                }
            }
        }
        for &i in &visible {
            faces[i].alive = false;
            let v = faces[i].v;
            for k in 0..3 {
                edges.remove(&(v[k], v[(k + 1) % 3]));
            }
        }
        for (a, b) in horizon {
            let f = Face::new(&pts, [a, b, p]);
            let i = faces.len();
            for k in 0..3 {
                edges.insert((f.v[k], f.v[(k + 1) % 3]), i);
            }
            faces.push(f);
        }
    }
    // Corners: the strict maxima of their incident faces' mean normal.
    let mut incident: HashMap<usize, V3> = HashMap::new();
    for f in faces.iter().filter(|f| f.alive) {
        for &v in &f.v {
            let s = incident.entry(v).or_insert([0.0; 3]);
            *s = [0, 1, 2].map(|a| s[a] + f.normal[a]);
        }
    }
    let used: Vec<usize> = {
        let mut u: Vec<usize> = incident.keys().copied().collect();
        u.sort_unstable();
        u
    };
    let corners = used
        .iter()
        .filter(|&&v| {
            let d = incident[&v];
            let top = dot(d, pts[v]);
            let eps_d = eps * norm(d);
            used.iter().all(|&u| u == v || dot(d, pts[u]) < top - eps_d)
        })
        .map(|&v| pts[v])
        .collect();
    let triangles = faces
        .iter()
        .filter(|f| f.alive)
        .map(|f| HullTriangle {
            corners: f.v.map(|v| pts[v]),
            normal: f.normal,
            offset: f.offset,
        })
        .collect();
    Ok(CloudHull { corners, triangles })
}

/// A face of a [`Polytope`]: its outward unit normal, `n . x = offset` on
/// its plane, and its polygon (vertex indices, counter-clockwise seen from
/// outside, no three collinear).
#[derive(Clone, Debug, PartialEq)]
pub struct PolytopeFace {
    /// Outward unit normal.
    pub normal: V3,
    /// `normal . x` on the face's plane, length units.
    pub offset: f64,
    /// The polygon's vertices, indices into [`Polytope::vertices`].
    pub polygon: Vec<usize>,
}

/// A convex hull given by its vertices, with its faces enumerated once:
/// the checker's exact signed distance (module docs).
#[derive(Clone, Debug, PartialEq)]
pub struct Polytope {
    vertices: Vec<V3>,
    faces: Vec<PolytopeFace>,
}

impl Polytope {
    /// The hull of `vertices` (its frame, length units; at least four not
    /// coplanar, as the core's `Hull::new` requires, or no faces result).
    pub fn new(vertices: &[V3]) -> Polytope {
        let n = vertices.len();
        let tol = FACE_TOLERANCE * spread(vertices).max(f64::MIN_POSITIVE);
        let mut faces: Vec<PolytopeFace> = Vec::new();
        let mut seen: Vec<Vec<usize>> = Vec::new();
        for i in 0..n {
            for j in i + 1..n {
                for k in j + 1..n {
                    let c = cross(sub(vertices[j], vertices[i]), sub(vertices[k], vertices[i]));
                    let length = norm(c);
                    if length <= tol * tol {
                        continue;
                    }
                    let mut normal = scaled(c, 1.0 / length);
                    let mut offset = dot(normal, vertices[i]);
                    let heights: Vec<f64> =
                        vertices.iter().map(|v| dot(normal, *v) - offset).collect();
                    if heights.iter().all(|&h| h >= -tol) {
                        normal = scaled(normal, -1.0);
                        offset = -offset;
                    } else if !heights.iter().all(|&h| h <= tol) {
                        continue;
                    }
                    let on: Vec<usize> = (0..n).filter(|&m| heights[m].abs() <= tol).collect();
                    if seen.contains(&on) {
                        continue;
                    }
                    seen.push(on.clone());
                    let polygon = polygon(vertices, &on, normal);
                    if polygon.len() >= 3 {
                        faces.push(PolytopeFace {
                            normal,
                            offset,
                            polygon,
                        });
                    }
                }
            }
        }
        Polytope {
            vertices: vertices.to_vec(),
            faces,
        }
    }

    /// The vertices as given.
    pub fn vertices(&self) -> &[V3] {
        &self.vertices
    }

    /// The faces.
    pub fn faces(&self) -> &[PolytopeFace] {
        &self.faces
    }

    /// The corners: the vertices on some face polygon, in index order.
    pub fn corners(&self) -> Vec<usize> {
        let mut c: Vec<usize> = self.faces.iter().flat_map(|f| f.polygon.clone()).collect();
        c.sort_unstable();
        c.dedup();
        c
    }

    /// The signed distance from `x` (the hull's frame) to the surface,
    /// negative inside: module docs.
    pub fn signed_distance(&self, x: V3) -> f64 {
        let mut depth = f64::NEG_INFINITY;
        let mut outside = f64::INFINITY;
        for f in &self.faces {
            let h = dot(f.normal, x) - f.offset;
            depth = depth.max(h);
            if h > 0.0 {
                let p = &f.polygon;
                for k in 1..p.len() - 1 {
                    let t = [p[0], p[k], p[k + 1]].map(|i| self.vertices[i]);
                    outside = outside.min(triangle_distance(x, t));
                }
            }
        }
        if depth <= 0.0 {
            depth
        } else {
            outside
        }
    }
}

/// The vertices `on` a plane of unit normal `normal`, as the convex polygon
/// they bound, counter-clockwise about `normal` (monotone chain in the
/// plane; collinear points dropped).
fn polygon(vertices: &[V3], on: &[usize], normal: V3) -> Vec<usize> {
    let helper = if normal[0].abs() < 0.6 {
        [1.0, 0.0, 0.0]
    } else {
        [0.0, 1.0, 0.0]
    };
    let u = cross(normal, helper);
    let u = scaled(u, 1.0 / norm(u));
    let w = cross(normal, u);
    let mut pts: Vec<(f64, f64, usize)> = on
        .iter()
        .map(|&i| (dot(vertices[i], u), dot(vertices[i], w), i))
        .collect();
    pts.sort_by(|a, b| a.0.total_cmp(&b.0).then(a.1.total_cmp(&b.1)));
    let turn = |o: &(f64, f64, usize), a: &(f64, f64, usize), b: &(f64, f64, usize)| {
        (a.0 - o.0) * (b.1 - o.1) - (a.1 - o.1) * (b.0 - o.0)
    };
    let mut chain: Vec<(f64, f64, usize)> = Vec::new();
    for pass in 0..2 {
        let start = chain.len();
        let ordered: Vec<_> = if pass == 0 {
            pts.clone()
        } else {
            pts.iter().rev().cloned().collect()
        };
        for p in ordered {
            while chain.len() >= start + 2
                && turn(&chain[chain.len() - 2], &chain[chain.len() - 1], &p) <= 0.0
            {
                chain.pop();
            }
            chain.push(p);
        }
        chain.pop();
    }
    // (u, w, normal) is right-handed, so counter-clockwise in (u, w) is
    // counter-clockwise seen from outside.
    chain.into_iter().map(|p| p.2).collect()
}

/// The distance from `x` to the triangle `t` (Ericson, "Real-Time Collision
/// Detection", 2005, 5.1.5: the closest point by Voronoi regions).
pub fn triangle_distance(x: V3, t: [V3; 3]) -> f64 {
    let [a, b, c] = t;
    let (ab, ac, ap) = (sub(b, a), sub(c, a), sub(x, a));
    let (d1, d2) = (dot(ab, ap), dot(ac, ap));
    if d1 <= 0.0 && d2 <= 0.0 {
        return norm(ap);
    }
    let bp = sub(x, b);
    let (d3, d4) = (dot(ab, bp), dot(ac, bp));
    if d3 >= 0.0 && d4 <= d3 {
        return norm(bp);
    }
    let vc = d1 * d4 - d3 * d2;
    if vc <= 0.0 && d1 >= 0.0 && d3 <= 0.0 {
        let v = d1 / (d1 - d3);
        return norm(sub(ap, scaled(ab, v)));
    }
    let cp = sub(x, c);
    let (d5, d6) = (dot(ab, cp), dot(ac, cp));
    if d6 >= 0.0 && d5 <= d6 {
        return norm(cp);
    }
    let vb = d5 * d2 - d1 * d6;
    if vb <= 0.0 && d2 >= 0.0 && d6 <= 0.0 {
        let w = d2 / (d2 - d6);
        return norm(sub(ap, scaled(ac, w)));
    }
    let va = d3 * d6 - d5 * d4;
    if va <= 0.0 && (d4 - d3) >= 0.0 && (d5 - d6) >= 0.0 {
        let w = (d4 - d3) / ((d4 - d3) + (d5 - d6));
        return norm(sub(bp, scaled(sub(c, b), w)));
    }
    let denom = 1.0 / (va + vb + vc);
    let (v, w) = (vb * denom, vc * denom);
    norm(sub(ap, [0, 1, 2].map(|i| ab[i] * v + ac[i] * w)))
}

#[cfg(test)]
mod tests {
    use super::*;

    fn cube(h: f64) -> Vec<V3> {
        let mut v = Vec::new();
        for x in [-h, h] {
            for y in [-h, h] {
                for z in [-h, h] {
                    v.push([x, y, z]);
                }
            }
        }
        v
    }

    /// A small deterministic generator (xorshift), values in [-1, 1).
    fn random(state: &mut u64) -> f64 {
        *state ^= *state << 13;
        *state ^= *state >> 7;
        *state ^= *state << 17;
        (*state >> 11) as f64 / (1u64 << 52) as f64 - 1.0
    }

    fn box_distance(x: V3, h: f64) -> f64 {
        let q: V3 = x.map(|c| c.abs() - h);
        let out = norm(q.map(|c| c.max(0.0)));
        out + q[0].max(q[1]).max(q[2]).min(0.0)
    }

    #[test]
    fn cube_has_six_square_faces_and_its_box_distance() {
        let p = Polytope::new(&cube(0.5));
        assert_eq!(p.faces().len(), 6);
        assert!(p.faces().iter().all(|f| f.polygon.len() == 4));
        assert_eq!(p.corners().len(), 8);
        let mut s = 7u64;
        for _ in 0..2000 {
            let x = [0, 1, 2].map(|_| 1.5 * random(&mut s));
            let (got, want) = (p.signed_distance(x), box_distance(x, 0.5));
            assert!((got - want).abs() < 1e-12, "{x:?}: {got} vs {want}");
        }
    }

    #[test]
    fn hull_of_a_cube_cloud_is_its_eight_corners() {
        // Corners, edge midpoints, face centres and inner points.
        let mut cloud = Vec::new();
        for i in 0..5 {
            for j in 0..5 {
                for k in 0..5 {
                    cloud.push([i, j, k].map(|c| c as f64 * 0.25 - 0.5));
                }
            }
        }
        let mut v = hull_vertices(&cloud).unwrap();
        v.sort_by(|a, b| a.partial_cmp(b).unwrap());
        let mut want = cube(0.5);
        want.sort_by(|a, b| a.partial_cmp(b).unwrap());
        assert_eq!(v, want);
    }

    #[test]
    fn hull_of_random_points_contains_them_all_and_its_corners_are_its_own() {
        let mut s = 99u64;
        for _ in 0..20 {
            let cloud: Vec<V3> = (0..300)
                .map(|_| [2.0 * random(&mut s), random(&mut s), 0.5 * random(&mut s)])
                .collect();
            let v = hull_vertices(&cloud).unwrap();
            let p = Polytope::new(&v);
            // Every corner found is a corner of the exact enumeration.
            assert_eq!(p.corners().len(), v.len());
            for x in &cloud {
                assert!(p.signed_distance(*x) <= 1e-9, "{x:?} outside");
            }
        }
    }

    #[test]
    fn flat_and_empty_clouds_are_refused() {
        assert_eq!(hull_vertices(&[]), Err(HullFailure::Empty));
        let square = [
            [0.0, 0.0, 0.0],
            [1.0, 0.0, 0.0],
            [0.0, 1.0, 0.0],
            [1.0, 1.0, 0.0],
        ];
        assert_eq!(hull_vertices(&square), Err(HullFailure::Flat));
        let line = [[0.0; 3], [1.0, 0.0, 0.0], [2.0, 0.0, 0.0], [3.0, 0.0, 0.0]];
        assert_eq!(hull_vertices(&line), Err(HullFailure::Flat));
        assert_eq!(
            hull_vertices(&[[f64::NAN, 0.0, 0.0]]),
            Err(HullFailure::NotFinite)
        );
    }

    #[test]
    fn triangle_distance_matches_brute_force() {
        let mut s = 3u64;
        for _ in 0..300 {
            let t = [0, 1, 2].map(|_| [0, 1, 2].map(|_| random(&mut s)));
            let x = [0, 1, 2].map(|_| 2.0 * random(&mut s));
            let mut best = f64::INFINITY;
            let steps = 200;
            for i in 0..=steps {
                for j in 0..=steps - i {
                    let (u, v) = (i as f64 / steps as f64, j as f64 / steps as f64);
                    let q = [0, 1, 2]
                        .map(|a| t[0][a] + u * (t[1][a] - t[0][a]) + v * (t[2][a] - t[0][a]));
                    best = best.min(norm(sub(x, q)));
                }
            }
            let got = triangle_distance(x, t);
            assert!(got <= best + 1e-12 && best - got < 0.02, "{got} vs {best}");
        }
    }
}
