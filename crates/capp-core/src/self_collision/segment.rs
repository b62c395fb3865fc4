//! The closest points of two segments, in `f32`, with no panic path: the one
//! narrow-phase test of two link capsules (their distance is the segments'
//! distance less both radii).
//!
//! The method is the clamped solution of the two-parameter least-squares
//! problem (Ericson, *Real-Time Collision Detection*, 2005, sec. 5.1.9):
//! minimise `|p1 + s d1 - p2 - t d2|^2` over `s, t` in `[0, 1]`. Written here
//! rather than taken from `parry3d`: that crate's segment query is `f32`
//! and `no_std`, but it pulls its whole shape and `alloc`-free query stack
//! (and its own `nalgebra` version) into a firmware that needs twenty lines
//! of it; and these twenty lines must be bit-identical on the board and the
//! host, which they are (no fused operations, no library calls but [`crate::math::sqrt`]).

use crate::math::{max, min, Vec3};

/// The closest points of two segments.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Closest {
    /// Fraction along the first segment, in `[0, 1]`.
    pub s: f32,
    /// Fraction along the second segment, in `[0, 1]`.
    pub t: f32,
    /// The point on the first segment, length units.
    pub on_first: Vec3,
    /// The point on the second segment, length units.
    pub on_second: Vec3,
    /// Their squared distance, length units squared.
    pub distance_sq: f32,
}

/// Below this fraction of `|d1|^2 |d2|^2`, `|d1 x d2|^2` counts as parallel
/// (any `s` is then as good as another; 0 is taken, then `t` and `s` are
/// clamped in turn, which still gives a closest pair).
const PARALLEL: f32 = 1.0e-7;

/// Below this squared length (length units squared), a segment is a point.
const POINT_SQ: f32 = 1.0e-12;

fn unit(x: f32) -> f32 {
    min(max(x, 0.0), 1.0)
}

/// The closest points of the segments `p1 -> q1` and `p2 -> q2`. Either may
/// be a point. Finite inputs give finite outputs.
pub fn closest_points(p1: &Vec3, q1: &Vec3, p2: &Vec3, q2: &Vec3) -> Closest {
    let d1 = q1 - p1;
    let d2 = q2 - p2;
    let r = p1 - p2;
    let a = d1.dot(&d1);
    let e = d2.dot(&d2);
    let f = d2.dot(&r);
    let (s, t) = if a <= POINT_SQ && e <= POINT_SQ {
        (0.0, 0.0)
    } else if a <= POINT_SQ {
        (0.0, unit(f / e))
    } else {
        let c = d1.dot(&r);
        if e <= POINT_SQ {
            (unit(-c / a), 0.0)
        } else {
            let b = d1.dot(&d2);
            let denom = a * e - b * b;
            let s = if denom > PARALLEL * a * e {
                unit((b * f - c * e) / denom)
            } else {
                0.0
            };
            let t = (b * s + f) / e;
            if t < 0.0 {
                (unit(-c / a), 0.0)
            } else if t > 1.0 {
                (unit((b - c) / a), 1.0)
            } else {
                (s, t)
            }
        }
    };
    let on_first = p1 + d1 * s;
    let on_second = p2 + d2 * t;
    Closest {
        s,
        t,
        on_first,
        on_second,
        distance_sq: (on_first - on_second).norm_squared(),
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::escape::rng::Rng;

    /// The distance by brute force, in `f64`: a fine grid over `s` and the
    /// exact projection for `t` (the squared distance is convex in `t`).
    fn reference(p1: [f64; 3], q1: [f64; 3], p2: [f64; 3], q2: [f64; 3]) -> f64 {
        let at = |p: [f64; 3], q: [f64; 3], s: f64| [0, 1, 2].map(|i| p[i] + (q[i] - p[i]) * s);
        let dist = |x: [f64; 3], y: [f64; 3]| {
            ((x[0] - y[0]).powi(2) + (x[1] - y[1]).powi(2) + (x[2] - y[2]).powi(2)).sqrt()
        };
        let d2: [f64; 3] = [0, 1, 2].map(|i| q2[i] - p2[i]);
        let e: f64 = d2.iter().map(|x| x * x).sum();
        let mut best = f64::INFINITY;
        let steps = 4000;
        for k in 0..=steps {
            let x = at(p1, q1, k as f64 / steps as f64);
            let t = if e > 0.0 {
                ((0..3).map(|i| (x[i] - p2[i]) * d2[i]).sum::<f64>() / e).clamp(0.0, 1.0)
            } else {
                0.0
            };
            best = best.min(dist(x, at(p2, q2, t)));
        }
        best
    }

    #[test]
    fn agrees_with_a_brute_force_reference_on_random_segments() {
        let mut rng = Rng::seeded(7, &[]);
        for case in 0..400 {
            let mut v = || [rng.uniform(), rng.uniform(), rng.uniform()].map(|x| 10.0 * x);
            let (p1, mut q1, p2, mut q2) = (v(), v(), v(), v());
            // Some parallel, some degenerate, some crossing.
            match case % 5 {
                1 => q2 = [0, 1, 2].map(|i| p2[i] + (q1[i] - p1[i]) * 0.5),
                2 => q1 = p1,
                3 => q2 = p2,
                _ => {}
            }
            let f = |a: [f32; 3]| Vec3::new(a[0], a[1], a[2]);
            let c = closest_points(&f(p1), &f(q1), &f(p2), &f(q2));
            let g = |a: [f32; 3]| a.map(|x| x as f64);
            let want = reference(g(p1), g(q1), g(p2), g(q2));
            let got = crate::math::sqrt(c.distance_sq) as f64;
            // The grid over `s` is 1/4000 of a segment up to 35 long.
            assert!(
                (got - want).abs() <= 2e-3 + 1e-4 * want && got <= want + 1e-4 * (1.0 + want),
                "case {case}: {got} vs {want}"
            );
            assert!((0.0..=1.0).contains(&c.s) && (0.0..=1.0).contains(&c.t));
            // The points are where the fractions say.
            let on = f(p1) + (f(q1) - f(p1)) * c.s;
            assert!((on - c.on_first).norm() <= 1e-4);
        }
    }

    #[test]
    fn crossing_segments_touch_and_points_are_points() {
        let o = Vec3::zeros();
        let c = closest_points(
            &Vec3::new(-1.0, 0.0, 0.0),
            &Vec3::new(1.0, 0.0, 0.0),
            &Vec3::new(0.0, -1.0, 0.0),
            &Vec3::new(0.0, 1.0, 0.0),
        );
        assert_eq!(c.distance_sq, 0.0);
        assert_eq!((c.s, c.t), (0.5, 0.5));
        let p = Vec3::new(0.0, 0.0, 3.0);
        let c = closest_points(&o, &o, &p, &p);
        assert_eq!(c.distance_sq, 9.0);
    }
}
