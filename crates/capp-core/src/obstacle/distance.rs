//! Signed distances of the CAD primitives (sphere, box, capsule, cylinder)
//! from a point in the shape's own frame, with their exact gradients.
//!
//! Each primitive is centred on its frame's origin; capsules and cylinders
//! run along the frame's z axis. [`signed_distance`] gives `d`, the
//! Euclidean distance from the point to the surface, negative inside (minus
//! the distance to the nearest face), and `n = grad d`, the unit outward
//! normal at the closest surface point (outside) or of the nearest face
//! (inside). Where two faces are equally near, or the point is on a
//! medial axis, one of them is chosen: the gradient of a one-sided
//! derivative, as a subgradient of a convex function should be.
//!
//! Closed forms, a few dozen flops each, no iteration: the pair code runs
//! them for every avoidance point within an obstacle's influence.

use super::Shape;
use crate::math::{max, min, sqrt_inline, vec3, Vec3};

/// A primitive in its own frame: sizes in length units.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum Primitive {
    /// A ball of `radius`.
    Sphere {
        /// Radius.
        radius: f32,
    },
    /// The box `|x_i| <= half_extents_i`.
    Cuboid {
        /// Half-extents along x, y, z.
        half_extents: Vec3,
    },
    /// The points within `radius` of the segment from `z = -half_length`
    /// to `z = +half_length`.
    Capsule {
        /// Radius.
        radius: f32,
        /// Half the segment's length.
        half_length: f32,
    },
    /// `x^2 + y^2 <= radius^2`, `|z| <= half_length` (flat ends).
    Cylinder {
        /// Radius.
        radius: f32,
        /// Half the length.
        half_length: f32,
    },
}

impl Primitive {
    /// The primitive a user's shape is, in this module's terms (half
    /// lengths); `None` for a super-ellipsoid (not measured on distance)
    /// and a hull (measured by [`super::hull::Hull::distance`]).
    pub fn of(shape: &Shape) -> Option<Primitive> {
        match *shape {
            Shape::SuperEllipsoid { .. } | Shape::Convex { .. } => None,
            Shape::Sphere { radius } => Some(Primitive::Sphere { radius }),
            Shape::Cuboid { half_extents } => Some(Primitive::Cuboid {
                half_extents: vec3(half_extents),
            }),
            Shape::Capsule { radius, length } => Some(Primitive::Capsule {
                radius,
                half_length: 0.5 * length,
            }),
            Shape::Cylinder { radius, length } => Some(Primitive::Cylinder {
                radius,
                half_length: 0.5 * length,
            }),
        }
    }

    /// Half-extents of the smallest box about the origin that holds the
    /// shape, length units.
    pub fn half_box(&self) -> Vec3 {
        match *self {
            Primitive::Sphere { radius } => Vec3::repeat(radius),
            Primitive::Cuboid { half_extents } => half_extents,
            Primitive::Capsule {
                radius,
                half_length,
            } => Vec3::new(radius, radius, half_length + radius),
            Primitive::Cylinder {
                radius,
                half_length,
            } => Vec3::new(radius, radius, half_length),
        }
    }

    /// The inradius: the largest ball the shape holds, so `d >= -inradius`
    /// everywhere, length units.
    pub fn inradius(&self) -> f32 {
        match *self {
            Primitive::Sphere { radius } | Primitive::Capsule { radius, .. } => radius,
            Primitive::Cuboid { half_extents } => half_extents.min(),
            Primitive::Cylinder {
                radius,
                half_length,
            } => min(radius, half_length),
        }
    }
}

/// `(d, grad d)` of `shape` at the local point `x` (see the module docs).
// Inlined: its one caller in the pair code then keeps `d` and `grad d` in
// registers.
#[inline(always)]
pub fn signed_distance(shape: &Primitive, x: &Vec3) -> (f32, Vec3) {
    match *shape {
        Primitive::Sphere { radius } => from_core(x, radius),
        Primitive::Capsule {
            radius,
            half_length,
        } => from_core(&from_segment(x, half_length), radius),
        Primitive::Cuboid { half_extents } => cuboid(x, &half_extents),
        Primitive::Cylinder {
            radius,
            half_length,
        } => cylinder(x, radius, half_length),
    }
}

/// `x` less its nearest point of the segment from `z = -half_length` to
/// `z = +half_length` (a capsule's core).
#[inline(always)]
pub fn from_segment(x: &Vec3, half_length: f32) -> Vec3 {
    Vec3::new(x.x, x.y, x.z - clamp(x.z, half_length))
}

/// `x` less its nearest point of the box `|x_i| <= half_i`: zero inside,
/// each component the excess beyond a face, signed as `x`.
#[inline(always)]
pub fn from_box(x: &Vec3, half: &Vec3) -> Vec3 {
    Vec3::new(
        beyond(x.x, half.x),
        beyond(x.y, half.y),
        beyond(x.z, half.z),
    )
}

/// Twice [`from_box`], to the bit (twice a float is exact): each
/// component `2 (v - clamp(v, -h, h))` as `(v - h) + |v - h|` (twice the
/// excess beyond `+h`, or `+0`) plus `(v + h) - |v + h|` (twice the excess
/// beyond `-h`, or `+0`). At most one of the two is not `+0`, and `v + h`
/// rounds as `-(|v| - h)` for `v < -h` (rounding is symmetric), so each
/// component is twice [`from_box`]'s, `+0` within the slab (`+0 + +0`) and
/// NaN for a NaN `v`.
///
/// Float operations alone, seven an axis: on the Cortex-M4F [`from_box`]'s
/// integer operations also move each value to a core register and back.
#[inline(always)]
pub fn twice_from_box(x: &Vec3, half: &Vec3) -> Vec3 {
    let twice = |v: f32, h: f32| {
        let (above, below) = (v - h, v + h);
        (above + above.abs()) + (below - below.abs())
    };
    Vec3::new(twice(x.x, half.x), twice(x.y, half.y), twice(x.z, half.z))
}

/// `v - clamp(v, -h, h)` for `h > 0`, to the bit (`+0` within the slab, NaN
/// for a NaN `v`), as `|v| - h` where that is positive, signed as `v`.
///
/// Integer operations on the bits, no comparison: on the Cortex-M4F a
/// float comparison is a `vcmp`, a `vmrs` and a conditional move, and a
/// clamp two of them; here `|v| - h` is a positive float exactly when its
/// bits less one are a non-negative integer (`+0` gives -1; `-0` cannot
/// occur, as `|v| >= +0` and `h > 0`). The sign is taken from `v`, and
/// rounding is symmetric, so `-(|v| - h)` is `v + h` as the clamp rounds it.
#[inline(always)]
fn beyond(v: f32, h: f32) -> f32 {
    let excess = (v.abs() - h).to_bits();
    let not_positive = ((excess as i32).wrapping_sub(1) >> 31) as u32;
    f32::from_bits((excess | (v.to_bits() & 0x8000_0000)) & !not_positive)
}

/// `v` clamped to `[-h, h]` (`max` and `min`, not `f32::clamp`: that has a
/// panic path).
#[inline(always)]
fn clamp(v: f32, h: f32) -> f32 {
    min(max(v, -h), h)
}

/// A ball of `radius` about the origin, the point `v` from its core:
/// `|v| - radius` along `v / |v|` (`+z` at the centre itself).
#[inline(always)]
fn from_core(v: &Vec3, radius: f32) -> (f32, Vec3) {
    let r = sqrt_inline(v.dot(v));
    if r > 0.0 {
        (r - radius, v / r)
    } else {
        (-radius, Vec3::z())
    }
}

/// `+1` or `-1` by the sign bit of `x`.
fn sign(x: f32) -> f32 {
    if x.is_sign_negative() {
        -1.0
    } else {
        1.0
    }
}

#[inline(always)]
fn cuboid(x: &Vec3, half: &Vec3) -> (f32, Vec3) {
    let outside = from_box(x, half);
    let out_sq = outside.dot(&outside);
    if out_sq > 0.0 {
        let d = sqrt_inline(out_sq);
        return (d, outside / d);
    }
    // Inside (or on the surface): the nearest face is the least deep.
    let q = x.abs() - half;
    let axis = if q.x >= q.y && q.x >= q.z {
        0
    } else if q.y >= q.z {
        1
    } else {
        2
    };
    let mut n = Vec3::zeros();
    n[axis] = sign(x[axis]);
    (q[axis], n)
}

#[inline(always)]
fn cylinder(x: &Vec3, radius: f32, half_length: f32) -> (f32, Vec3) {
    let rho = sqrt_inline(x.x * x.x + x.y * x.y);
    let radial = if rho > 0.0 {
        Vec3::new(x.x / rho, x.y / rho, 0.0)
    } else {
        Vec3::x()
    };
    let axial = Vec3::new(0.0, 0.0, sign(x.z));
    let (dr, dz) = (rho - radius, x.z.abs() - half_length);
    match (dr > 0.0, dz > 0.0) {
        (true, true) => {
            // Beyond the rim: from the circle at the end.
            let d = sqrt_inline(dr * dr + dz * dz);
            (d, (radial * dr + axial * dz) / d)
        }
        (true, false) => (dr, radial),
        (false, true) => (dz, axial),
        // Inside: the nearer of the side and the end.
        (false, false) if dr >= dz => (dr, radial),
        (false, false) => (dz, axial),
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn shapes() -> [Primitive; 4] {
        [
            Primitive::Sphere { radius: 1.5 },
            Primitive::Cuboid {
                half_extents: Vec3::new(2.0, 0.5, 1.0),
            },
            Primitive::Capsule {
                radius: 0.5,
                half_length: 1.5,
            },
            Primitive::Cylinder {
                radius: 0.75,
                half_length: 1.25,
            },
        ]
    }

    /// Reproducible uniform numbers in [-1, 1).
    fn lcg(state: &mut u64) -> f32 {
        *state = state
            .wrapping_mul(6364136223846793005)
            .wrapping_add(1442695040888963407);
        ((*state >> 40) as f32 / (1u64 << 24) as f32) * 2.0 - 1.0
    }

    /// Whether the local point is inside the shape, by its definition.
    fn contains(shape: &Primitive, p: &[f64; 3]) -> bool {
        let [x, y, z] = *p;
        match *shape {
            Primitive::Sphere { radius } => x * x + y * y + z * z <= (radius as f64).powi(2),
            Primitive::Cuboid { half_extents: h } => {
                x.abs() <= h.x as f64 && y.abs() <= h.y as f64 && z.abs() <= h.z as f64
            }
            Primitive::Capsule {
                radius,
                half_length,
            } => {
                let l = half_length as f64;
                let dz = z - z.clamp(-l, l);
                x * x + y * y + dz * dz <= (radius as f64).powi(2)
            }
            Primitive::Cylinder {
                radius,
                half_length,
            } => x * x + y * y <= (radius as f64).powi(2) && z.abs() <= half_length as f64,
        }
    }

    /// The shape's support function `h(u) = max_{y in shape} u . y`, by its
    /// definition for each solid (f64).
    fn support(shape: &Primitive, u: &[f64; 3]) -> f64 {
        let planar = (u[0] * u[0] + u[1] * u[1]).sqrt();
        match *shape {
            Primitive::Sphere { radius } => radius as f64,
            Primitive::Cuboid { half_extents: h } => {
                u[0].abs() * h.x as f64 + u[1].abs() * h.y as f64 + u[2].abs() * h.z as f64
            }
            Primitive::Capsule {
                radius,
                half_length,
            } => radius as f64 + u[2].abs() * half_length as f64,
            Primitive::Cylinder {
                radius,
                half_length,
            } => planar * radius as f64 + u[2].abs() * half_length as f64,
        }
    }

    /// The signed distance of a convex body by brute force, an oracle that
    /// shares no code with the closed forms: `max_u (u . p - h(u))` over a
    /// grid of unit directions (holding the axes), inside and out.
    fn sampled_distance(shape: &Primitive, p: &[f64; 3]) -> f64 {
        let steps = 180;
        let mut best = f64::NEG_INFINITY;
        for i in 0..=steps {
            let theta = core::f64::consts::PI * i as f64 / steps as f64;
            for k in 0..2 * steps {
                let phi = core::f64::consts::PI * k as f64 / steps as f64;
                let u = [
                    theta.sin() * phi.cos(),
                    theta.sin() * phi.sin(),
                    theta.cos(),
                ];
                let value = u[0] * p[0] + u[1] * p[1] + u[2] * p[2] - support(shape, &u);
                best = best.max(value);
            }
        }
        best
    }

    /// The excess by integer operations is the clamp it replaced, to the
    /// bit: over random points at every scale, the faces themselves, the
    /// signed zeros, the infinities and NaN.
    #[test]
    fn the_excess_beyond_a_box_is_the_clamp_to_the_bit() {
        let by_clamp = |v: f32, h: f32| v - clamp(v, h);
        let mut rng = 23u64;
        for _ in 0..20_000 {
            let h = (lcg(&mut rng) + 1.5) * 10f32.powi((lcg(&mut rng) * 6.0) as i32);
            let v = lcg(&mut rng) * 3.0 * h;
            for v in [v, h, -h, h.next_up(), (-h).next_down(), h.next_down()] {
                let (a, b) = (beyond(v, h), by_clamp(v, h));
                assert_eq!(
                    a.to_bits(),
                    b.to_bits(),
                    "v {v:e}, h {h:e}: {a:e} against {b:e}"
                );
            }
        }
        for v in [
            0.0,
            -0.0,
            f32::INFINITY,
            f32::NEG_INFINITY,
            f32::MAX,
            -f32::MAX,
        ] {
            assert_eq!(
                beyond(v, 2.0).to_bits(),
                by_clamp(v, 2.0).to_bits(),
                "v {v:e}"
            );
        }
        assert!(beyond(f32::NAN, 2.0).is_nan() && by_clamp(f32::NAN, 2.0).is_nan());
    }

    #[test]
    fn distances_match_a_sampled_boundary_inside_and_out() {
        let mut rng = 11u64;
        for shape in shapes() {
            let h = shape.half_box() * 2.0;
            for _ in 0..40 {
                let x = Vec3::new(
                    lcg(&mut rng) * h.x,
                    lcg(&mut rng) * h.y,
                    lcg(&mut rng) * h.z,
                );
                let (d, _) = signed_distance(&shape, &x);
                let p = [x.x as f64, x.y as f64, x.z as f64];
                let expected = sampled_distance(&shape, &p);
                // A grid direction within 1 degree of the best misses by
                // at most |p| (1 - cos 1 deg), 6e-4 here.
                assert!(
                    (d as f64 - expected).abs() <= 1e-3,
                    "{shape:?} at {x:?}: {d} against {expected}"
                );
                assert_eq!(d <= 0.0, contains(&shape, &p) || d.abs() < 1e-5);
            }
        }
    }

    #[test]
    fn gradients_match_central_differences_away_from_edges() {
        let mut rng = 5u64;
        let step = 1e-3;
        for shape in shapes() {
            let h = shape.half_box() * 2.0;
            let mut checked = 0;
            while checked < 100 {
                let x = Vec3::new(
                    lcg(&mut rng) * h.x,
                    lcg(&mut rng) * h.y,
                    lcg(&mut rng) * h.z,
                );
                let (_, n) = signed_distance(&shape, &x);
                let diff: Vec3 = Vec3::from_fn(|i, _| {
                    let mut a = x;
                    let mut b = x;
                    a[i] += step;
                    b[i] -= step;
                    (signed_distance(&shape, &a).0 - signed_distance(&shape, &b).0) / (2.0 * step)
                });
                // Near a crease the two sides differ: skip points whose
                // one-sided differences disagree.
                let forward: Vec3 = Vec3::from_fn(|i, _| {
                    let mut a = x;
                    a[i] += step;
                    (signed_distance(&shape, &a).0 - signed_distance(&shape, &x).0) / step
                });
                if (forward - diff).norm() > 0.05 {
                    continue;
                }
                checked += 1;
                assert!(
                    (n.norm() - 1.0).abs() < 1e-5,
                    "{shape:?}: |n| = {}",
                    n.norm()
                );
                assert!(
                    (n - diff).norm() < 2e-2,
                    "{shape:?} at {x:?}: {n:?} against {diff:?}"
                );
            }
        }
    }

    #[test]
    fn the_gradient_points_to_the_closest_surface_point() {
        // Outside, p - d n is on the surface (d = 0 there) at distance d.
        let mut rng = 9u64;
        for shape in shapes() {
            let h = shape.half_box() * 3.0;
            for _ in 0..200 {
                let x = vec3([lcg(&mut rng), lcg(&mut rng), lcg(&mut rng)]).component_mul(&h);
                let (d, n) = signed_distance(&shape, &x);
                if d <= 0.0 {
                    continue;
                }
                let foot = x - n * d;
                let (on, _) = signed_distance(&shape, &foot);
                assert!(on.abs() < 1e-5, "{shape:?} at {x:?}: foot {foot:?} at {on}");
            }
        }
    }

    #[test]
    fn inradius_bounds_the_depth() {
        for shape in shapes() {
            let (d, _) = signed_distance(&shape, &Vec3::zeros());
            assert!((d + shape.inradius()).abs() < 1e-6, "{shape:?}: {d}");
        }
    }

    /// `from_box` and `twice_from_box` against `v - clamp(v, -h, h)` (and
    /// twice it) to the bit, over random values of six decades and the
    /// edge cases: signed zeros, the faces, one ulp either side, NaN.
    #[test]
    fn box_excess_is_the_clamps_residual_to_the_bit() {
        let residual = |v: f32, h: f32| v - v.max(-h).min(h);
        let mut state = 11u64;
        let mut values = heapless::Vec::<(f32, f32), 4096>::new();
        for h in [0.5f32, 1.0, 3.0e-3, 7.5e2] {
            for v in [0.0, -0.0, h, -h, 2.0 * h, -2.0 * h, 1.0e-30, -1.0e-30] {
                for w in [v, v.next_up(), v.next_down()] {
                    let _ = values.push((w, h));
                }
            }
        }
        while !values.is_full() {
            let h = libm::powf(10.0, 3.0 * lcg(&mut state)) + 1.0e-6;
            let v = libm::powf(10.0, 3.0 * lcg(&mut state)) * lcg(&mut state);
            let _ = values.push((v, h));
        }
        for &(v, h) in &values {
            let x = Vec3::new(v, -v, v * 0.5);
            let half = Vec3::new(h, h, h * 0.25);
            let once = from_box(&x, &half);
            let twice = twice_from_box(&x, &half);
            for i in 0..3 {
                let expected = residual(x[i], half[i]);
                assert_eq!(
                    once[i].to_bits(),
                    expected.to_bits(),
                    "{} beyond {}",
                    x[i],
                    half[i]
                );
                assert_eq!(
                    twice[i].to_bits(),
                    (2.0 * expected).to_bits(),
                    "{} beyond {}",
                    x[i],
                    half[i]
                );
            }
        }
        let nan = twice_from_box(&Vec3::new(f32::NAN, 0.0, 0.0), &Vec3::new(1.0, 1.0, 1.0));
        assert!(nan.x.is_nan() && nan.y == 0.0 && nan.z == 0.0);
    }
}
