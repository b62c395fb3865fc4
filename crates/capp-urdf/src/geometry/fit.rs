//! Capsules that contain a point set: one, or up to four along a long mesh.
//!
//! **One capsule.** The axis u is the principal axis of the points (the
//! eigenvector of their covariance with the largest eigenvalue, through the
//! centroid c). Each point p has an axial coordinate t = (p - c).u and a
//! radial distance d = |p - c - t u|. For a radius r >= max d, a point is
//! inside the capsule whose segment spans [lo, hi] on the axis exactly when
//! the segment comes within s = sqrt(r^2 - d^2) of t, so the shortest segment
//! for that r is
//!
//! ```text
//! lo(r) = min (t + s),   hi(r) = max (t - s),   L(r) = max(hi - lo, 0)
//! ```
//!
//! (when lo > hi a single point of [hi, lo] does: a sphere). The radius is
//! the one, among a grid over [max d, max |p - c|] refined once around its
//! best point, that minimises the volume pi r^2 (L + 4/3 r). Both ends of
//! that range are candidates, so the result is never larger than the naive
//! capsule (segment over the projections' span, radius max d) nor than the
//! bounding sphere about the centroid. The final radius is the largest
//! distance from a point to the chosen segment, recomputed, so that every
//! point is inside whatever the rounding.
//!
//! **Several capsules.** The axis' span of the points is cut into n equal
//! slices, and each slice gets its own capsule around its vertices plus the
//! points where triangle edges cross the slice's two planes: a triangle's
//! part within a slab is the convex hull of those, so the capsules together
//! contain the mesh surface, not just its vertices.

use nalgebra::{Matrix3, Point3, SymmetricEigen, Unit, Vector3};

use crate::chain::Capsule;
use crate::geometry::CapsuleCount;

/// With [`CapsuleCount::Auto`], one more capsule must bring the total
/// volume below this fraction of the best so far to be taken.
pub(crate) const AUTO_GAIN: f64 = 0.8;

/// Grid points per pass of the radius search.
const GRID: usize = 32;

/// The capsules for a mesh: `points` its vertices, `faces` its triangles
/// (indices into `points`; may be empty). `points` must not be empty.
pub(crate) fn fit_mesh(
    points: &[Point3<f64>],
    faces: &[[usize; 3]],
    count: CapsuleCount,
) -> Vec<Capsule> {
    let fixed = |n| fit_split(points, faces, n);
    match count {
        CapsuleCount::One => fixed(1),
        CapsuleCount::Two => fixed(2),
        CapsuleCount::Three => fixed(3),
        CapsuleCount::Four => fixed(4),
        CapsuleCount::Auto => {
            let mut best = fixed(1);
            let mut best_volume = total_volume(&best);
            for n in 2..=4 {
                let next = fixed(n);
                let volume = total_volume(&next);
                if volume < AUTO_GAIN * best_volume {
                    (best, best_volume) = (next, volume);
                }
            }
            best
        }
    }
}

fn total_volume(capsules: &[Capsule]) -> f64 {
    capsules.iter().map(Capsule::volume).sum()
}

/// The smallest-volume capsule along the principal axis containing `points`
/// (not empty).
pub(crate) fn fit(points: &[Point3<f64>]) -> Capsule {
    let (c, u) = principal_axis(points);
    fit_along(points, &c, &u)
}

/// Centroid and principal axis. Any axis serves when the points do not
/// spread (one point, or all the same).
fn principal_axis(points: &[Point3<f64>]) -> (Point3<f64>, Unit<Vector3<f64>>) {
    let n = points.len() as f64;
    let c = Point3::from(points.iter().map(|p| p.coords).sum::<Vector3<f64>>() / n);
    let covariance = points
        .iter()
        .map(|p| {
            let v = p - c;
            v * v.transpose()
        })
        .sum::<Matrix3<f64>>()
        / n;
    let eigen = SymmetricEigen::new(covariance);
    let largest = eigen.eigenvalues.imax();
    let u = Unit::try_new(eigen.eigenvectors.column(largest).into_owned(), 1e-12)
        .filter(|u| u.iter().all(|x| x.is_finite()))
        .unwrap_or_else(Vector3::z_axis);
    (c, u)
}

/// Axial coordinate and radial distance of each point about the line c + t u.
fn axial(points: &[Point3<f64>], c: &Point3<f64>, u: &Unit<Vector3<f64>>) -> Vec<(f64, f64)> {
    points
        .iter()
        .map(|p| {
            let v = p - c;
            let t = v.dot(u);
            (t, (v - u.into_inner() * t).norm())
        })
        .collect()
}

/// [lo, hi] of the shortest segment for radius r (lo > hi: any point between).
fn span(coords: &[(f64, f64)], r: f64) -> (f64, f64) {
    coords
        .iter()
        .fold((f64::INFINITY, f64::NEG_INFINITY), |(lo, hi), &(t, d)| {
            let s = (r * r - d * d).max(0.0).sqrt();
            (lo.min(t + s), hi.max(t - s))
        })
}

fn volume(coords: &[(f64, f64)], r: f64) -> f64 {
    let (lo, hi) = span(coords, r);
    core::f64::consts::PI * r * r * ((hi - lo).max(0.0) + 4.0 / 3.0 * r)
}

/// The best radius on a grid of [from, to] (GRID + 1 points), and the grid step.
fn best_on_grid(coords: &[(f64, f64)], from: f64, to: f64) -> (f64, f64) {
    let step = (to - from) / GRID as f64;
    let mut best = (from, volume(coords, from));
    for k in 1..=GRID {
        let r = if k == GRID {
            to
        } else {
            from + step * k as f64
        };
        let v = volume(coords, r);
        if v < best.1 {
            best = (r, v);
        }
    }
    (best.0, step)
}

fn fit_along(points: &[Point3<f64>], c: &Point3<f64>, u: &Unit<Vector3<f64>>) -> Capsule {
    let coords = axial(points, c, u);
    let r_min = coords.iter().fold(0.0_f64, |m, &(_, d)| m.max(d));
    let r_max = coords
        .iter()
        .fold(r_min, |m, &(t, d)| m.max((t * t + d * d).sqrt()));
    let (coarse, step) = best_on_grid(&coords, r_min, r_max);
    let (r, _) = best_on_grid(
        &coords,
        (coarse - step).max(r_min),
        (coarse + step).min(r_max),
    );
    let (lo, hi) = span(&coords, r);
    let (lo, hi) = if lo > hi {
        let mid = 0.5 * (lo + hi);
        (mid, mid)
    } else {
        (lo, hi)
    };
    let mut capsule = Capsule {
        a: c + u.into_inner() * lo,
        b: c + u.into_inner() * hi,
        radius: 0.0,
    };
    capsule.radius = points
        .iter()
        .fold(0.0, |m: f64, p| m.max(capsule.segment_distance(p)));
    capsule
}

/// `n` capsules over `n` equal slices of the points' span on the principal
/// axis (fewer when a slice is empty; one when the points do not spread).
pub(crate) fn fit_split(points: &[Point3<f64>], faces: &[[usize; 3]], n: usize) -> Vec<Capsule> {
    let (c, u) = principal_axis(points);
    let t: Vec<f64> = points.iter().map(|p| (p - c).dot(&u)).collect();
    let (t_min, t_max) = t
        .iter()
        .fold((f64::INFINITY, f64::NEG_INFINITY), |(lo, hi), &x| {
            (lo.min(x), hi.max(x))
        });
    if n <= 1 || t_max <= t_min {
        return vec![fit_along(points, &c, &u)];
    }
    let plane = |i: usize| {
        if i == n {
            t_max
        } else {
            t_min + (t_max - t_min) * i as f64 / n as f64
        }
    };
    let mut capsules = Vec::with_capacity(n);
    for i in 0..n {
        let (from, to) = (plane(i), plane(i + 1));
        let mut slice: Vec<Point3<f64>> = points
            .iter()
            .zip(&t)
            .filter(|(_, &x)| from <= x && x <= to)
            .map(|(p, _)| *p)
            .collect();
        for face in faces {
            for (e0, e1) in [(face[0], face[1]), (face[1], face[2]), (face[2], face[0])] {
                for cut in [from, to] {
                    let (t0, t1) = (t[e0], t[e1]);
                    if (t0 - cut) * (t1 - cut) < 0.0 {
                        let w = (cut - t0) / (t1 - t0);
                        slice.push(points[e0] + (points[e1] - points[e0]) * w);
                    }
                }
            }
        }
        if !slice.is_empty() {
            capsules.push(fit(&slice));
        }
    }
    capsules
}

#[cfg(test)]
mod tests {
    use super::*;

    /// splitmix64: a seeded source for the random clouds.
    pub(crate) struct Rng(u64);
    impl Rng {
        fn next(&mut self) -> f64 {
            self.0 = self.0.wrapping_add(0x9E37_79B9_7F4A_7C15);
            let mut z = self.0;
            z = (z ^ (z >> 30)).wrapping_mul(0xBF58_476D_1CE4_E5B9);
            z = (z ^ (z >> 27)).wrapping_mul(0x94D0_49BB_1331_11EB);
            ((z ^ (z >> 31)) >> 11) as f64 / (1u64 << 53) as f64
        }
        fn range(&mut self, lo: f64, hi: f64) -> f64 {
            lo + (hi - lo) * self.next()
        }
    }

    fn cloud(rng: &mut Rng, n: usize) -> Vec<Point3<f64>> {
        let scale = Vector3::new(
            rng.range(0.01, 1.0),
            rng.range(0.01, 1.0),
            rng.range(0.01, 1.0),
        );
        let offset = Vector3::new(
            rng.range(-1.0, 1.0),
            rng.range(-1.0, 1.0),
            rng.range(-1.0, 1.0),
        );
        (0..n)
            .map(|_| {
                let v = Vector3::new(
                    rng.range(-1.0, 1.0),
                    rng.range(-1.0, 1.0),
                    rng.range(-1.0, 1.0),
                );
                Point3::from(v.component_mul(&scale) + offset)
            })
            .collect()
    }

    fn naive(points: &[Point3<f64>]) -> Capsule {
        let (c, u) = principal_axis(points);
        let coords = axial(points, &c, &u);
        let lo = coords.iter().fold(f64::INFINITY, |m, &(t, _)| m.min(t));
        let hi = coords.iter().fold(f64::NEG_INFINITY, |m, &(t, _)| m.max(t));
        let radius = coords.iter().fold(0.0_f64, |m, &(_, d)| m.max(d));
        Capsule {
            a: c + u.into_inner() * lo,
            b: c + u.into_inner() * hi,
            radius,
        }
    }

    fn bounding_sphere(points: &[Point3<f64>]) -> Capsule {
        let (c, _) = principal_axis(points);
        let radius = points.iter().fold(0.0_f64, |m, p| m.max((p - c).norm()));
        Capsule { a: c, b: c, radius }
    }

    #[test]
    fn contains_every_point_and_beats_the_naive_fits() {
        let mut rng = Rng(7);
        for case in 0..300 {
            let n = 1 + case % 60;
            let points = cloud(&mut rng, n);
            let capsule = fit(&points);
            for p in &points {
                assert!(
                    capsule.contains(p, 1e-9),
                    "case {case}: {p} outside {capsule:?}"
                );
            }
            let v = capsule.volume();
            assert!(
                v <= naive(&points).volume() * (1.0 + 1e-9) + 1e-15,
                "case {case}"
            );
            assert!(
                v <= bounding_sphere(&points).volume() * (1.0 + 1e-9) + 1e-15,
                "case {case}"
            );
        }
    }

    #[test]
    fn a_line_of_points_gets_a_thin_capsule_along_it() {
        let points: Vec<_> = (0..11)
            .map(|i| Point3::new(0.1 * i as f64, 0.2 * i as f64, 0.0))
            .collect();
        let capsule = fit(&points);
        assert!(capsule.radius < 1e-9);
        let length = (capsule.b - capsule.a).norm();
        assert!((length - 5.0_f64.sqrt()).abs() < 1e-9);
    }

    #[test]
    fn one_point_is_a_zero_sphere() {
        let p = Point3::new(1.0, 2.0, 3.0);
        let capsule = fit(&[p]);
        assert_eq!((capsule.a, capsule.b, capsule.radius), (p, p, 0.0));
    }

    #[test]
    fn slices_contain_the_triangles_not_just_their_vertices() {
        // A long thin box with vertices only at its two ends: the middle
        // slices hold no vertex, only edge crossings.
        let mut points = Vec::new();
        for x in [0.0, 10.0] {
            for (y, z) in [(-0.1, -0.1), (0.1, -0.1), (0.1, 0.1), (-0.1, 0.1)] {
                points.push(Point3::new(x, y, z));
            }
        }
        let faces: Vec<[usize; 3]> = (0..4)
            .flat_map(|k| {
                let (a, b) = (k, (k + 1) % 4);
                [[a, b, a + 4], [b, b + 4, a + 4]]
            })
            .collect();
        let capsules = fit_split(&points, &faces, 4);
        assert_eq!(capsules.len(), 4);
        let mut rng = Rng(3);
        for face in &faces {
            for _ in 0..200 {
                let (mut w0, mut w1) = (rng.next(), rng.next());
                if w0 + w1 > 1.0 {
                    (w0, w1) = (1.0 - w0, 1.0 - w1);
                }
                let [a, b, c] = face.map(|i| points[i].coords);
                let p = Point3::from(a + (b - a) * w0 + (c - a) * w1);
                assert!(capsules.iter().any(|cap| cap.contains(&p, 1e-9)), "{p}");
            }
        }
        // A straight prism gains nothing from slicing; Auto keeps one.
        let one = fit_split(&points, &faces, 1);
        assert!(total_volume(&one) < total_volume(&capsules));
        assert_eq!(fit_mesh(&points, &faces, CapsuleCount::Auto).len(), 1);
    }

    #[test]
    fn auto_splits_a_bent_cloud() {
        // An L of two 5 m arms, 0.1 m thick.
        let mut points = Vec::new();
        for i in 0..=50 {
            let s = 0.1 * i as f64;
            for (dy, dz) in [(-0.05, -0.05), (0.05, 0.05)] {
                points.push(Point3::new(s, dy, dz));
                points.push(Point3::new(5.0 + dy, s, dz));
            }
        }
        let one = fit_mesh(&points, &[], CapsuleCount::One);
        let auto = fit_mesh(&points, &[], CapsuleCount::Auto);
        assert!(auto.len() > 1);
        assert!(total_volume(&auto) < AUTO_GAIN * total_volume(&one));
        for p in &points {
            assert!(auto.iter().any(|cap| cap.contains(p, 1e-9)));
        }
    }
}
