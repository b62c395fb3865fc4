//! A convex polytope of at most `k` corners that encloses a point cloud:
//! what a CAD mesh becomes when its convex hull has more corners than the
//! core's hulls take (`capp_core::obstacle::MAX_HULL_VERTICES`).
//!
//! The enclosure is an intersection of supporting half-spaces of the cloud
//! (each plane has every point on or behind it), so it holds the whole
//! cloud: a plan that keeps its margins from the enclosure keeps them from
//! the part. A polytope cut by `F` planes in general position has at most
//! `2F - 4` corners (each corner on three planes, Euler's formula), so `k`
//! corners allow `(k + 4) / 2` planes: 18 for 32.
//!
//! The planes are chosen greedily, each where the enclosure is worst: start
//! from the cloud's box along the frame's axes (six supporting planes), then
//! repeatedly take the enclosure's corner farthest beyond one of the hull's
//! face planes and cut it off with that plane (which supports the cloud),
//! until the planes are spent or every corner is on the hull to rounding.
//! Cutting the worst corner is the "plane-cutting" refinement of a bounding
//! polytope (as a k-DOP is refined toward the hull; see Klosowski et al.,
//! "Efficient collision detection using bounding volume hierarchies of
//! k-DOPs", 1998, for fixed directions); the hull's own faces are the
//! candidates, so a part with few large faces (a box with fillets, a
//! bracket) keeps them exactly.
//!
//! A round part (a ball, a fillet all round) has many faces that few planes
//! fit badly (18 planes round a ball leave corners a quarter of its radius
//! out). So a second enclosure is made too and the tighter kept: `k` of the
//! hull's corners spread over it (each next the corner farthest from those
//! taken), their hull grown about its centroid just enough to hold every
//! corner of the part's (round a ball, a sixth of its radius). Both are
//! measured the same way: the largest distance of a corner from the hull,
//! the farthest any point of the enclosure is from the part (the distance
//! to a convex set is convex, so its largest over a polytope is at a
//! corner).
//!
//! Written here rather than taken from a crate: a tight, conservative
//! enclosure with a corner budget is not what hull or decomposition crates
//! give (they simplify inward, or by error bounds, not by corners).

use crate::polytope::{cloud_hull, cross, dot, spread, sub, CloudHull, HullFailure, V3};

/// How far each plane is pushed out beyond the cloud, relative to its size:
/// the corners are rounded to `f32` for the core (a relative `6e-8`), and
/// the enclosure must still hold the cloud after that.
const SLACK: f64 = 1e-6;

/// Two corners closer than this (relative to the cloud's size) are one:
/// where more than three planes meet.
const MERGE: f64 = 1e-9;

/// A corner within this (relative) of the hull's face planes is on the hull:
/// no cut would take anything off.
const ON_HULL: f64 = 1e-7;

/// What [`enclose`] made of a cloud.
#[derive(Clone, Debug, PartialEq)]
pub struct Enclosure {
    /// The enclosure's corners (the cloud's frame, length units).
    pub corners: Vec<V3>,
    /// How many corners the cloud's own convex hull has.
    pub hull_corners: usize,
    /// The largest distance of an enclosure corner from the hull, length
    /// units: no point of the enclosure is farther from the part (0 when
    /// the hull itself fits).
    pub overshoot: f64,
}

impl Enclosure {
    /// Whether the enclosure is the hull itself.
    pub fn is_exact(&self) -> bool {
        self.corners.len() == self.hull_corners && self.overshoot == 0.0
    }
}

/// The cloud's hull when it has at most `max_corners` corners, else the
/// tighter of the two enclosures of at most `max_corners` (at least 8) the
/// module docs describe.
pub fn enclose(points: &[V3], max_corners: usize) -> Result<Enclosure, HullFailure> {
    let hull = cloud_hull(points)?;
    let hull_corners = hull.corners.len();
    if hull_corners <= max_corners {
        return Ok(Enclosure {
            corners: hull.corners,
            hull_corners,
            overshoot: 0.0,
        });
    }
    let size = spread(&hull.corners);
    let measured = |corners: Vec<V3>| {
        let overshoot = corners
            .iter()
            .map(|&c| hull.distance(c))
            .fold(0.0, f64::max);
        Enclosure {
            corners,
            hull_corners,
            overshoot,
        }
    };
    let cut = measured(by_planes(points, &hull, size, max_corners.max(8)));
    let grown = scaled_corners(&hull, size, max_corners.max(8)).map(measured);
    Ok(match grown {
        Some(grown) if grown.overshoot < cut.overshoot => grown,
        _ => cut,
    })
}

/// The intersection of at most `(max_corners + 4) / 2` supporting planes
/// of `points` (module docs): its corners.
fn by_planes(points: &[V3], hull: &CloudHull, size: f64, max_corners: usize) -> Vec<V3> {
    let max_planes = (max_corners + 4) / 2;
    // The cloud's support along `n` (every point, not just the hull's
    // triangles: the hull leaves points within 1e-7 of its size outside).
    let support = |n: V3| points.iter().map(|&p| dot(n, p)).fold(f64::MIN, f64::max);
    let mut planes: Vec<(V3, f64)> = Vec::with_capacity(max_planes);
    for axis in 0..3 {
        for sign in [1.0, -1.0] {
            let mut n = [0.0; 3];
            n[axis] = sign;
            planes.push((n, support(n)));
        }
    }
    while planes.len() < max_planes {
        let corners = intersect(&planes, size);
        let worst = first_largest(corners.iter().filter_map(|&c| farthest_plane(hull, c)));
        match worst {
            Some((excess, t)) if excess > ON_HULL * size => {
                let n = hull.triangles[t].normal;
                planes.push((n, support(n)));
            }
            _ => break,
        }
    }
    // Pushed out by the slack, then cut down to the corner budget should
    // rounding have split a corner where four planes nearly meet.
    for plane in &mut planes {
        plane.1 += SLACK * size;
    }
    let mut corners = intersect(&planes, size);
    while corners.len() > max_corners && planes.len() > 6 {
        planes.pop();
        corners = intersect(&planes, size);
    }
    corners
}

/// `max_corners` of the hull's corners spread over it (each next the one
/// farthest from those taken), their hull grown about its centroid until
/// it holds every corner of the cloud's (`None` when they span no
/// volume): the enclosure a round part gets, whose many faces a few
/// planes fit badly.
fn scaled_corners(hull: &CloudHull, size: f64, max_corners: usize) -> Option<Vec<V3>> {
    let corners = &hull.corners;
    let first = corners.first().copied()?;
    let mut taken = vec![first];
    let mut nearest: Vec<f64> = corners.iter().map(|&c| distance_sq(c, first)).collect();
    while taken.len() < max_corners {
        let Some((_, far)) = first_largest(nearest.iter().copied().zip(0..)) else {
            break;
        };
        let pick = corners[far];
        taken.push(pick);
        for (d, &c) in nearest.iter_mut().zip(corners) {
            *d = d.min(distance_sq(c, pick));
        }
    }
    let inner = cloud_hull(&taken).ok()?;
    let n = taken.len() as f64;
    let centre = [0, 1, 2].map(|a| taken.iter().map(|p| p[a]).sum::<f64>() / n);
    // The least scale about the centre with every corner of the cloud's
    // hull behind every (scaled) face plane, plus the slack: every plane
    // at least `SLACK * size` farther out (the shallowest moves least).
    let (mut scale, mut shallowest) = (1.0f64, f64::INFINITY);
    for t in &inner.triangles {
        let depth = t.offset - dot(t.normal, centre);
        if depth <= 0.0 {
            return None;
        }
        shallowest = shallowest.min(depth);
        for &c in corners {
            scale = scale.max(dot(t.normal, sub(c, centre)) / depth);
        }
    }
    let grow = scale + SLACK * size / shallowest;
    Some(
        inner
            .corners
            .iter()
            .map(|&p| [0, 1, 2].map(|a| centre[a] + grow * (p[a] - centre[a])))
            .collect(),
    )
}

/// `|a - b|^2`.
fn distance_sq(a: V3, b: V3) -> f64 {
    let d = sub(a, b);
    dot(d, d)
}

/// The hull face plane `corner` is farthest beyond, and by how much
/// (`None`: behind every plane).
fn farthest_plane(hull: &CloudHull, corner: V3) -> Option<(f64, usize)> {
    first_largest(
        hull.triangles
            .iter()
            .zip(0..)
            .map(|(tri, t)| (dot(tri.normal, corner) - tri.offset, t))
            .filter(|&(excess, _)| excess > 0.0),
    )
}

/// The first of the `(value, index)` pairs with the largest value (`None`
/// for none).
fn first_largest(pairs: impl Iterator<Item = (f64, usize)>) -> Option<(f64, usize)> {
    pairs.min_by(|a, b| b.0.total_cmp(&a.0))
}

/// The corners of the intersection of the half-spaces `n . x <= offset`
/// (bounded: the axis planes are among them): every point where three
/// planes meet that no plane has in front, with points closer than
/// [`MERGE`] times `size` taken as one.
fn intersect(planes: &[(V3, f64)], size: f64) -> Vec<V3> {
    let merge = MERGE * size;
    let mut corners: Vec<V3> = Vec::new();
    for i in 0..planes.len() {
        for j in i + 1..planes.len() {
            for k in j + 1..planes.len() {
                let Some(x) = meet(planes[i], planes[j], planes[k]) else {
                    continue;
                };
                let inside = planes
                    .iter()
                    .all(|&(n, offset)| dot(n, x) <= offset + merge * 10.0);
                let known = corners.iter().any(|&c| distance_sq(c, x) <= merge * merge);
                if inside && !known {
                    corners.push(x);
                }
            }
        }
    }
    corners
}

/// The point on all three planes `n . x = offset`, by Cramer's rule
/// (`None` when two of them are parallel or the three share a line).
fn meet(a: (V3, f64), b: (V3, f64), c: (V3, f64)) -> Option<V3> {
    let (bc, ca, ab) = (cross(b.0, c.0), cross(c.0, a.0), cross(a.0, b.0));
    let det = dot(a.0, bc);
    if det.abs() < 1e-9 {
        return None;
    }
    Some([0, 1, 2].map(|i| (a.1 * bc[i] + b.1 * ca[i] + c.1 * ab[i]) / det))
}

#[cfg(test)]
mod tests {
    use super::*;

    fn lcg(state: &mut u64) -> f64 {
        *state = state
            .wrapping_mul(6_364_136_223_846_793_005)
            .wrapping_add(1_442_695_040_888_963_407);
        ((*state >> 11) as f64) / ((1u64 << 53) as f64)
    }

    /// A cylinder of `segments` sides round z (radius `r`, half-height
    /// `h`), its axis through `centre`: a CAD part whose hull has `2
    /// segments` corners.
    fn cylinder(segments: usize, r: f64, h: f64, centre: V3) -> Vec<V3> {
        (0..2 * segments)
            .map(|i| {
                let angle = std::f64::consts::TAU * (i % segments) as f64 / segments as f64;
                [
                    centre[0] + r * angle.cos(),
                    centre[1] + r * angle.sin(),
                    centre[2] + if i < segments { h } else { -h },
                ]
            })
            .collect()
    }

    /// Whether every point is on or behind every face plane of the
    /// polytope of `corners` (its faces by the checker's own enumeration).
    fn holds(corners: &[V3], points: &[V3]) -> bool {
        let polytope = crate::polytope::Polytope::new(corners);
        assert!(!polytope.faces().is_empty());
        points.iter().all(|&p| polytope.signed_distance(p) <= 0.0)
    }

    #[test]
    fn a_hull_within_the_budget_is_kept_as_it_is() {
        let points = cylinder(12, 3.0, 5.0, [1.0, 2.0, 3.0]);
        let e = enclose(&points, 32).unwrap();
        assert_eq!(e.hull_corners, 24);
        assert_eq!(e.corners.len(), 24);
        assert!(e.is_exact());
    }

    #[test]
    fn a_fine_cylinder_is_enclosed_in_32_corners_that_hold_it_closely() {
        // 64 sides: a hull of 128 corners.
        let points = cylinder(64, 10.0, 20.0, [0.5, -1.0, 2.0]);
        let e = enclose(&points, 32).unwrap();
        assert_eq!(e.hull_corners, 128);
        assert!(e.corners.len() <= 32, "{}", e.corners.len());
        assert!(!e.is_exact());
        assert!(holds(&e.corners, &points));
        // Sixteen planes round the side of a circle of radius 10 (the
        // budget's 18 less the two ends) leave its corners 10 (1 / cos(pi /
        // 16) - 1) = 0.196 out at best: within 2.5 times that.
        assert!(e.overshoot > 0.0 && e.overshoot < 0.5, "{}", e.overshoot);
        // The overshoot is the largest corner distance, as the checker's
        // own distance measures it.
        let hull =
            crate::polytope::Polytope::new(&crate::polytope::hull_vertices(&points).unwrap());
        let largest = e
            .corners
            .iter()
            .map(|&c| hull.signed_distance(c))
            .fold(f64::MIN, f64::max);
        assert!(
            (largest - e.overshoot).abs() < 1e-9 * 40.0,
            "{largest} {}",
            e.overshoot
        );
        // And the core takes it.
        let f32_corners: Vec<[f32; 3]> = e.corners.iter().map(|c| c.map(|x| x as f32)).collect();
        assert!(capp_core::obstacle::Hull::new(&f32_corners).is_ok());
    }

    #[test]
    fn random_clouds_are_held_within_the_budget() {
        let mut state = 7u64;
        for case in 0..40 {
            let count = 40 + case * 7;
            let scale = [
                1.0 + 9.0 * lcg(&mut state),
                1.0 + 9.0 * lcg(&mut state),
                0.2 + 5.0 * lcg(&mut state),
            ];
            // Points on an ellipsoid (a rounded part: every point a corner)
            // and some inside.
            let points: Vec<V3> = (0..count)
                .map(|_| {
                    let z: f64 = 2.0 * lcg(&mut state) - 1.0;
                    let angle = std::f64::consts::TAU * lcg(&mut state);
                    let ring = (1.0 - z * z).sqrt();
                    let depth = if lcg(&mut state) < 0.2 {
                        lcg(&mut state)
                    } else {
                        1.0
                    };
                    [
                        scale[0] * depth * ring * angle.cos() + 3.0,
                        scale[1] * depth * ring * angle.sin() - 2.0,
                        scale[2] * depth * z,
                    ]
                })
                .collect();
            let hull = cloud_hull(&points).unwrap();
            let size = spread(&hull.corners);
            for budget in [8, 16, 32] {
                // Both candidates hold the cloud within the budget; the
                // enclosure is the tighter.
                let planes = by_planes(&points, &hull, size, budget);
                assert!(
                    planes.len() <= budget && holds(&planes, &points),
                    "case {case}"
                );
                if let Some(grown) = scaled_corners(&hull, size, budget) {
                    assert!(
                        grown.len() <= budget && holds(&grown, &points),
                        "case {case}"
                    );
                }
                let e = enclose(&points, budget).unwrap();
                assert!(
                    e.corners.len() <= budget,
                    "case {case}: {} > {budget}",
                    e.corners.len()
                );
                assert!(e.corners.len() >= 4);
                assert!(holds(&e.corners, &points), "case {case}, budget {budget}");
                let size = scale.iter().fold(0.0f64, |a, &b| a.max(b));
                assert!(e.overshoot.is_finite() && e.overshoot < 2.0 * size);
            }
        }
    }

    #[test]
    fn more_corners_fit_the_cloud_closer() {
        let points = cylinder(48, 10.0, 20.0, [0.0; 3]);
        let coarse = enclose(&points, 12).unwrap();
        let fine = enclose(&points, 32).unwrap();
        assert!(
            fine.overshoot < coarse.overshoot,
            "{} {}",
            fine.overshoot,
            coarse.overshoot
        );
    }

    #[test]
    fn a_box_with_rounded_edges_keeps_its_faces() {
        // A 20 x 10 x 6 box whose vertical edges are rounded (radius 1, 16
        // steps): its hull has 4 x 17 x 2 corners, and its six faces are
        // the enclosure's first six planes (the frame's axes), so the
        // enclosure is the box's, within the rounded corners.
        let mut points = Vec::new();
        for (cx, cy, start) in [
            (9.0, 4.0, 0.0),
            (-9.0, 4.0, 0.25),
            (-9.0, -4.0, 0.5),
            (9.0, -4.0, 0.75),
        ] {
            for step in 0..=16 {
                let angle = std::f64::consts::TAU * (start + 0.25 * step as f64 / 16.0);
                for z in [3.0, -3.0] {
                    points.push([cx + angle.cos(), cy + angle.sin(), z]);
                }
            }
        }
        let e = enclose(&points, 32).unwrap();
        assert!(e.hull_corners > 32);
        assert!(holds(&e.corners, &points));
        for c in &e.corners {
            assert!(
                c[0].abs() <= 10.0 + 1e-4 && c[1].abs() <= 5.0 + 1e-4 && c[2].abs() <= 3.0 + 1e-4,
                "{c:?}"
            );
        }
        // The rounded corners' chamfers: at most (sqrt 2 - 1) out, less with
        // the cuts.
        assert!(
            e.overshoot <= std::f64::consts::SQRT_2 - 1.0 + 1e-6,
            "{}",
            e.overshoot
        );
    }

    #[test]
    fn a_round_part_is_grown_from_its_corners_not_cut_by_planes() {
        // A ball of radius 10 tessellated finely (every point a corner):
        // 18 planes round a ball leave corners about a quarter of its
        // radius out (2.5), 32 of its own corners grown to hold it less
        // (1.6).
        let mut points = Vec::new();
        for j in 1..40 {
            let polar = std::f64::consts::PI * j as f64 / 40.0;
            for i in 0..80 {
                let azimuth = std::f64::consts::TAU * i as f64 / 80.0;
                points.push([
                    10.0 * polar.sin() * azimuth.cos(),
                    10.0 * polar.sin() * azimuth.sin(),
                    10.0 * polar.cos(),
                ]);
            }
        }
        points.extend([[0.0, 0.0, 10.0], [0.0, 0.0, -10.0]]);
        let hull = cloud_hull(&points).unwrap();
        let size = spread(&hull.corners);
        let overshoot = |corners: &[V3]| {
            corners
                .iter()
                .map(|&c| hull.distance(c))
                .fold(0.0, f64::max)
        };
        let cut = overshoot(&by_planes(&points, &hull, size, 32));
        let e = enclose(&points, 32).unwrap();
        assert!(holds(&e.corners, &points));
        assert!(e.corners.len() <= 32);
        assert!(e.overshoot < 0.7 * cut, "{} against {cut}", e.overshoot);
        assert!(e.overshoot < 2.0, "{}", e.overshoot);
    }
}
