//! The one capsule the core checks for each URDF link: round its chord, or
//! round a segment of its own fixed in its body, whichever is smaller.
//!
//! A body's collision geometry arrives as several capsules (`capp-urdf`
//! fits them to meshes and primitives); the core checks one capsule per
//! link. Round the chord (from the joint's pivot to the next joint's) that
//! capsule must reach every part of a body lying off the line between its
//! joints: the UR5's upper arm sits 0.13 m along the shoulder axis from the
//! line between its shoulder and elbow pivots, so its chord capsule is 0.21
//! m thick round a body 0.10 m thick. A segment of the link's own
//! ([`capp_core::robot::Robot::set_link_segments`]) can lie along the body
//! instead.
//!
//! [`enclosing_capsule`] fits that segment: for each candidate axis (the
//! principal axis of the body capsules' ends, each body capsule's own axis,
//! the chord's direction), the line through the ends' centroid, the
//! smallest radius holding every body capsule round it, then the shortest
//! segment on the line that keeps every body capsule inside at that radius.
//! Every body capsule's segment lies within `R - r_i` of the result's
//! segment, so the result holds it (the distance to a segment is convex: a
//! capsule's farthest point from a segment is at one of its ends).
//! [`link_capsule`] keeps the chord unless the fitted capsule's volume is
//! under [`SEGMENT_GAIN`] of the chord capsule's.

use capp_urdf::{Body, Capsule};
use nalgebra::{Matrix3, Point3, Vector3};

/// A link's fitted segment replaces its chord only when its capsule's
/// volume is below this fraction of the chord capsule's: a body whose chord
/// runs through it keeps the chord (and the plan its bits).
pub const SEGMENT_GAIN: f64 = 0.8;

/// The capsule round a segment of its own that holds every capsule of
/// `body` (metres, in the body's frame), least in volume over the candidate
/// axes (module docs); `None` for a body without geometry.
pub fn enclosing_capsule(body: &Body, chord: (&Point3<f64>, &Point3<f64>)) -> Option<Capsule> {
    let ends: Vec<(Point3<f64>, f64)> = body
        .capsules
        .iter()
        .flat_map(|c| [(c.a, c.radius), (c.b, c.radius)])
        .collect();
    if ends.is_empty() {
        return None;
    }
    let centroid =
        Point3::from(ends.iter().map(|(p, _)| p.coords).sum::<Vector3<f64>>() / ends.len() as f64);
    let mut axes: Vec<Vector3<f64>> = Vec::new();
    let spread: Matrix3<f64> = ends
        .iter()
        .map(|(p, _)| {
            let d = p - centroid;
            d * d.transpose()
        })
        .sum();
    let eigen = spread.symmetric_eigen();
    axes.push(
        eigen
            .eigenvectors
            .column(eigen.eigenvalues.imax())
            .into_owned(),
    );
    axes.extend(body.capsules.iter().map(|c| c.b - c.a));
    axes.push(chord.1 - chord.0);
    axes.into_iter()
        .filter_map(|axis| axis.try_normalize(1e-12))
        .map(|axis| along(&ends, &centroid, &axis))
        .min_by(|a, b| a.volume().total_cmp(&b.volume()))
}

/// The capsule on the line through `centre` along the unit `axis` holding
/// every sphere of `ends` (centre, radius): the least radius about the line,
/// then the shortest segment at that radius.
fn along(ends: &[(Point3<f64>, f64)], centre: &Point3<f64>, axis: &Vector3<f64>) -> Capsule {
    // Each end's position along the line and distance from it.
    let placed: Vec<(f64, f64, f64)> = ends
        .iter()
        .map(|(p, r)| {
            let d = p - centre;
            let t = d.dot(axis);
            ((d - axis * t).norm(), t, *r)
        })
        .collect();
    let radius = placed
        .iter()
        .map(|&(off, _, r)| off + r)
        .fold(0.0, f64::max);
    // End i is held when the segment meets [t_i - s_i, t_i + s_i], the
    // stretch of the line within `radius - r_i` of it.
    let (mut lo, mut hi) = (f64::INFINITY, f64::NEG_INFINITY);
    for &(off, t, r) in &placed {
        let s = ((radius - r).powi(2) - off * off).max(0.0).sqrt();
        lo = lo.min(t + s);
        hi = hi.max(t - s);
    }
    if lo > hi {
        // One point meets every stretch: a ball.
        let mid = 0.5 * (lo + hi);
        (lo, hi) = (mid, mid);
    }
    Capsule {
        a: centre + axis * lo,
        b: centre + axis * hi,
        radius,
    }
}

/// Link `k`'s capsule: round its chord `pivot -> end` with the radius that
/// holds its body, or round a fitted segment ([`enclosing_capsule`]) when
/// that is under [`SEGMENT_GAIN`] of the chord capsule's volume. Metres, in
/// the body's frame; `None` for a body without geometry. The flag says
/// whether the segment is the link's own.
pub fn link_capsule(
    body: &Body,
    pivot: &Point3<f64>,
    end: &Point3<f64>,
) -> Option<(Capsule, bool)> {
    let chord = Capsule {
        a: *pivot,
        b: *end,
        radius: super::pivots::enclosing_radius(body, pivot, end)?,
    };
    let fitted = enclosing_capsule(body, (pivot, end))?;
    Some(if fitted.volume() < SEGMENT_GAIN * chord.volume() {
        (fitted, true)
    } else {
        (chord, false)
    })
}

#[cfg(test)]
mod tests {
    use super::*;

    fn body(capsules: &[Capsule]) -> Body {
        Body {
            links: vec!["link".into()],
            capsules: capsules.to_vec(),
        }
    }

    fn capsule(a: [f64; 3], b: [f64; 3], radius: f64) -> Capsule {
        Capsule {
            a: Point3::from(a),
            b: Point3::from(b),
            radius,
        }
    }

    /// Every body capsule's ends lie within the fitted capsule, less their
    /// radii (the containment the module docs prove).
    fn holds(outer: &Capsule, inner: &[Capsule]) -> bool {
        inner.iter().all(|c| {
            [c.a, c.b]
                .iter()
                .all(|p| outer.segment_distance(p) + c.radius <= outer.radius + 1e-9)
        })
    }

    #[test]
    fn one_capsule_is_its_own_fit() {
        // The UR5's upper arm, off its chord.
        let arm = capsule([0.001, -0.1313, 0.0004], [-0.0008, -0.131, 0.4246], 0.1006);
        let (pivot, end) = (Point3::origin(), Point3::new(0.0, -0.262, 0.425));
        let fit = enclosing_capsule(&body(&[arm]), (&pivot, &end)).unwrap();
        assert!((fit.radius - 0.1006).abs() < 1e-9, "{fit:?}");
        assert!((fit.volume() - arm.volume()).abs() < 1e-9 * arm.volume());
        let (chosen, own) = link_capsule(&body(&[arm]), &pivot, &end).unwrap();
        assert!(own && chosen.radius < 0.11, "{chosen:?}");
    }

    #[test]
    fn a_body_on_its_chord_keeps_the_chord() {
        let part = capsule([0.0, 0.0, 0.02], [0.0, 0.0, 0.38], 0.05);
        let (pivot, end) = (Point3::origin(), Point3::new(0.0, 0.0, 0.4));
        let (chosen, own) = link_capsule(&body(&[part]), &pivot, &end).unwrap();
        assert!(!own);
        assert_eq!((chosen.a, chosen.b), (pivot, end));
    }

    #[test]
    fn random_bodies_are_held_and_no_larger_than_the_chords() {
        let mut seed = 7u64;
        let mut uniform = move || {
            seed ^= seed << 13;
            seed ^= seed >> 7;
            seed ^= seed << 17;
            (seed >> 11) as f64 / (1u64 << 53) as f64 * 2.0 - 1.0
        };
        for _ in 0..500 {
            let parts: Vec<Capsule> = (0..1 + (uniform().abs() * 4.0) as usize)
                .map(|_| {
                    let a = [uniform(), uniform(), uniform()].map(|x| 0.3 * x);
                    let b = if uniform() > 0.0 {
                        a
                    } else {
                        [uniform(), uniform(), uniform()].map(|x| 0.3 * x)
                    };
                    capsule(a, b, 0.01 + 0.1 * uniform().abs())
                })
                .collect();
            let (pivot, end) = (
                Point3::from([uniform(), uniform(), uniform()].map(|x| 0.2 * x)),
                Point3::from([uniform(), uniform(), uniform()].map(|x| 0.4 * x)),
            );
            let fit = enclosing_capsule(&body(&parts), (&pivot, &end)).unwrap();
            assert!(holds(&fit, &parts), "{fit:?} misses {parts:?}");
            let (chosen, _) = link_capsule(&body(&parts), &pivot, &end).unwrap();
            assert!(holds(&chosen, &parts));
            let chord_radius =
                super::super::pivots::enclosing_radius(&body(&parts), &pivot, &end).unwrap();
            let chord = capsule(pivot.into(), end.into(), chord_radius);
            assert!(chosen.volume() <= chord.volume() * (1.0 + 1e-12));
        }
        assert!(link_capsule(&body(&[]), &Point3::origin(), &Point3::origin()).is_none());
    }
}
