//! URDF's primitive `<collision>` shapes as capsules, in the shape's own
//! frame (the `<collision><origin>` frame). Each capsule contains its shape;
//! "containing, not tight" where the shape has edges.
//!
//! - sphere r: a = b = centre, radius r (exact);
//! - cylinder r, l (axis z, centred): segment z in [-l/2, l/2], radius r.
//!   This is the smallest capsule along the axis that contains it: the rim
//!   circles lie at the segment's ends at distance r. The rounded caps stick
//!   out past the flat ends by up to r;
//! - capsule r, l (URDF 1.2 / urdf-rs; l is the length between the two
//!   hemisphere centres): itself, segment z in [-l/2, l/2];
//! - box x y z (centred): a segment along the longest side, half-length half
//!   that side, radius half the diagonal of the other two sides, so the four
//!   corners at each end lie exactly on the end spheres.

use nalgebra::Point3;

use crate::chain::Capsule;
use crate::error::Problem;

/// A sphere of radius `r` at the origin.
pub(crate) fn sphere(r: f64) -> Result<Capsule, Problem> {
    let r = size(r, "sphere radius")?;
    Ok(Capsule {
        a: Point3::origin(),
        b: Point3::origin(),
        radius: r,
    })
}

/// A cylinder (or URDF capsule) of radius `r` along z from -l/2 to l/2.
pub(crate) fn along_z(r: f64, l: f64, shape: Shape) -> Result<Capsule, Problem> {
    let (radius_name, length_name) = match shape {
        Shape::Cylinder => ("cylinder radius", "cylinder length"),
        Shape::Capsule => ("capsule radius", "capsule length"),
    };
    let r = size(r, radius_name)?;
    let half = 0.5 * size(l, length_name)?;
    Ok(Capsule {
        a: Point3::new(0.0, 0.0, -half),
        b: Point3::new(0.0, 0.0, half),
        radius: r,
    })
}

/// Which round shape [`along_z`] reads, for the error messages.
#[derive(Debug, Clone, Copy)]
pub(crate) enum Shape {
    Cylinder,
    Capsule,
}

/// A box of sides `s` centred on the origin.
pub(crate) fn cuboid(s: [f64; 3]) -> Result<Capsule, Problem> {
    for side in s {
        size(side, "box size")?;
    }
    let long = (0..3).fold(0, |best, k| if s[k] > s[best] { k } else { best });
    let (i, j) = ((long + 1) % 3, (long + 2) % 3);
    let mut b = Point3::origin();
    b[long] = 0.5 * s[long];
    Ok(Capsule {
        a: Point3::from(-b.coords),
        b,
        radius: 0.5 * s[i].hypot(s[j]),
    })
}

fn size(value: f64, what: &'static str) -> Result<f64, Problem> {
    if !value.is_finite() {
        Err(Problem::NonFinite(what))
    } else if value < 0.0 {
        Err(Problem::NegativeSize(what))
    } else {
        Ok(value)
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use core::f64::consts::TAU;

    #[test]
    fn box_contains_its_corners_and_touches_them() {
        for s in [
            [0.3, 0.1, 0.2],
            [0.1, 0.5, 0.2],
            [0.1, 0.2, 0.7],
            [1.0, 1.0, 1.0],
        ] {
            let capsule = cuboid(s).unwrap();
            let mut farthest = 0.0_f64;
            for corner in 0..8 {
                let sign = |bit: usize| if corner >> bit & 1 == 1 { 0.5 } else { -0.5 };
                let p = Point3::new(sign(0) * s[0], sign(1) * s[1], sign(2) * s[2]);
                assert!(capsule.contains(&p, 1e-12), "{s:?} {p}");
                farthest = farthest.max(capsule.segment_distance(&p));
            }
            assert!(
                (farthest - capsule.radius).abs() < 1e-12,
                "{s:?} is tight at the corners"
            );
        }
    }

    #[test]
    fn cylinder_contains_its_rims_and_caps() {
        let (r, l) = (0.2, 0.9);
        let capsule = along_z(r, l, Shape::Cylinder).unwrap();
        for k in 0..64 {
            let angle = TAU * k as f64 / 64.0;
            for z in [-0.5 * l, 0.0, 0.5 * l] {
                for radial in [0.0, 0.5 * r, r] {
                    let p = Point3::new(radial * angle.cos(), radial * angle.sin(), z);
                    assert!(capsule.contains(&p, 1e-12), "{p}");
                }
            }
        }
        assert_eq!(capsule.radius, r);
    }

    #[test]
    fn sphere_and_capsule_are_themselves() {
        assert_eq!(sphere(0.5).unwrap().radius, 0.5);
        let capsule = along_z(0.1, 0.4, Shape::Capsule).unwrap();
        assert_eq!((capsule.b - capsule.a).norm(), 0.4);
    }

    #[test]
    fn bad_sizes_are_named() {
        assert_eq!(sphere(-1.0), Err(Problem::NegativeSize("sphere radius")));
        assert_eq!(
            along_z(0.1, f64::INFINITY, Shape::Cylinder),
            Err(Problem::NonFinite("cylinder length"))
        );
        assert_eq!(
            cuboid([1.0, f64::NAN, 1.0]),
            Err(Problem::NonFinite("box size"))
        );
    }
}
