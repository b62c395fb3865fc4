//! General joints: a fixed transform from the previous joint's frame, then a
//! motion about or along the joint's own axis (a URDF `<joint>`: `<origin>`
//! and `<axis>`). A DH row (eq. 5) is one way to build a joint; this is the
//! other, for robots no DH table describes.
//!
//! ```text
//! F_j = T_{j-1} O_j              the joint's frame at q_j = 0 (T_{-1} = the base)
//! T_j = F_j Rot(axis_j, q_j)     revolute, q_j in radians
//! T_j = F_j Trans(q_j axis_j)    prismatic, q_j in length units
//! end = T_{n-1} tool
//! ```
//!
//! At validation each joint's frame is turned once so that its axis is its
//! `z` (`align_z`): with `A_j` taking `z` onto `axis_j`, the stored origin
//! is `A_{j-1}^T O_j A_j` and the stored tool `A_{n-1}^T tool`, and the
//! motion becomes a rotation about (a slide along) `z`. The chain is then
//! "fixed transform, rotate about z", about 81 flops a joint, with no
//! per-step normalisation (`A_j` is exact for axes along `x`, `y` or `z`,
//! the usual URDF case; otherwise within `f32` rounding).

use crate::math::{is_rotation, Mat3, Vec3};

/// A rigid transform: `p -> rotation p + translation`.
#[derive(Clone, Copy, Debug, PartialEq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub struct Placement {
    /// Rotation, row by row (orthonormal, determinant +1).
    pub rotation: [[f32; 3]; 3],
    /// Translation, length units.
    pub translation: [f32; 3],
}

impl Placement {
    /// The identity: no rotation, no translation.
    pub const IDENTITY: Placement = Placement {
        rotation: [[1.0, 0.0, 0.0], [0.0, 1.0, 0.0], [0.0, 0.0, 1.0]],
        translation: [0.0; 3],
    };

    /// The rotation as a matrix.
    pub fn rotation_matrix(&self) -> Mat3 {
        let r = &self.rotation;
        Mat3::new(
            r[0][0], r[0][1], r[0][2], r[1][0], r[1][1], r[1][2], r[2][0], r[2][1], r[2][2],
        )
    }

    /// The translation as a vector.
    pub fn translation_vector(&self) -> Vec3 {
        crate::math::vec3(self.translation)
    }

    /// Whether every entry is finite.
    pub fn is_finite(&self) -> bool {
        self.rotation.iter().flatten().all(|x| x.is_finite())
            && self.translation.iter().all(|x| x.is_finite())
    }

    /// Whether this is exactly [`Placement::IDENTITY`].
    pub fn is_identity(&self) -> bool {
        *self == Placement::IDENTITY
    }
}

impl Default for Placement {
    fn default() -> Self {
        Placement::IDENTITY
    }
}

/// Where a general joint sits and what it moves about: its fixed transform
/// from the previous joint's frame (for the first joint, from the base), and
/// its axis in its own frame (a URDF joint's `<origin>` and `<axis>`).
#[derive(Clone, Copy, Debug, PartialEq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub struct JointOrigin {
    /// The transform from the previous joint's (moved) frame to this joint's
    /// frame at `q = 0`.
    pub placement: Placement,
    /// The axis the joint turns about or slides along, in its own frame; any
    /// length above [`MIN_AXIS_LENGTH`] (it is normalised).
    pub axis: [f32; 3],
}

/// Shortest accepted axis vector (before normalisation).
pub const MIN_AXIS_LENGTH: f32 = 1.0e-3;

/// Largest deviation from orthonormality accepted in a rotation (entries of
/// `R^T R - I` and the determinant's distance from 1): a rotation computed in
/// `f64` and rounded to `f32` is within 1e-7.
pub const ROTATION_TOLERANCE: f32 = 1.0e-4;

/// A validated transform, in the form the forward pass uses.
#[derive(Clone, Copy, Debug, PartialEq)]
pub(crate) struct Transform {
    pub(crate) rotation: Mat3,
    pub(crate) translation: Vec3,
}

impl Default for Transform {
    fn default() -> Self {
        Transform {
            rotation: Mat3::identity(),
            translation: Vec3::zeros(),
        }
    }
}

/// Why a placement was refused.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub(crate) enum PlacementFault {
    NotFinite,
    NotRotation,
    TooFar,
    ZeroAxis,
}

/// Checks a placement: finite, a proper rotation, a translation no longer
/// than `max_length`.
pub(crate) fn validate(p: &Placement, max_length: f32) -> Result<Transform, PlacementFault> {
    if !p.is_finite() {
        return Err(PlacementFault::NotFinite);
    }
    let rotation = p.rotation_matrix();
    if !is_rotation(&rotation, ROTATION_TOLERANCE) {
        return Err(PlacementFault::NotRotation);
    }
    let translation = p.translation_vector();
    if translation.iter().any(|x| x.abs() > max_length) {
        return Err(PlacementFault::TooFar);
    }
    Ok(Transform {
        rotation,
        translation,
    })
}

/// The unit axis, or why not.
pub(crate) fn unit_axis(axis: &[f32; 3]) -> Result<Vec3, PlacementFault> {
    if !axis.iter().all(|x| x.is_finite()) {
        return Err(PlacementFault::NotFinite);
    }
    // Scaled by the largest entry first, so that no square overflows.
    let largest = axis
        .iter()
        .fold(0.0f32, |m, x| crate::math::max(m, x.abs()));
    if largest < MIN_AXIS_LENGTH / 2.0 {
        return Err(PlacementFault::ZeroAxis);
    }
    let a = crate::math::vec3(*axis) / largest;
    let length = crate::math::norm(&a);
    if largest * length < MIN_AXIS_LENGTH {
        return Err(PlacementFault::ZeroAxis);
    }
    Ok(a / length)
}

/// A rotation `A` with `A z = axis` (`axis` a unit vector): the columns
/// `(x', y', axis)` of a right-handed orthonormal basis. Exact (no rounding)
/// when `axis` is `+-x`, `+-y` or `+-z`.
pub(crate) fn align_z(axis: &Vec3) -> Mat3 {
    // A helper direction far from the axis, then Gram-Schmidt.
    let helper = if axis.x.abs() > 0.9 {
        Vec3::y()
    } else {
        Vec3::x()
    };
    let x = helper - axis * axis.dot(&helper);
    let x = x / crate::math::norm(&x);
    let y = axis.cross(&x);
    Mat3::from_columns(&[x, y, *axis])
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn align_z_takes_z_onto_the_axis_and_is_exact_on_the_coordinate_axes() {
        for axis in [
            Vec3::x(),
            Vec3::y(),
            Vec3::z(),
            -Vec3::x(),
            -Vec3::y(),
            -Vec3::z(),
        ] {
            let a = align_z(&axis);
            assert_eq!(a * Vec3::z(), axis);
            assert!(a.iter().all(|x| *x == 0.0 || x.abs() == 1.0));
            assert!(is_rotation(&a, 0.0));
        }
        let mut seed = 7u32;
        for _ in 0..1000 {
            let mut r = || {
                seed = seed.wrapping_mul(1_664_525).wrapping_add(1_013_904_223);
                (seed >> 8) as f32 / (1u32 << 24) as f32 * 2.0 - 1.0
            };
            let v = Vec3::new(r(), r(), r());
            if crate::math::norm(&v) < 0.1 {
                continue;
            }
            let axis = v / crate::math::norm(&v);
            let a = align_z(&axis);
            assert!((a * Vec3::z() - axis).norm() < 1e-6);
            assert!(is_rotation(&a, 1e-5));
        }
    }

    #[test]
    fn placements_are_checked() {
        assert!(validate(&Placement::IDENTITY, 10.0).is_ok());
        let mut p = Placement::IDENTITY;
        p.rotation[0][0] = 2.0;
        assert_eq!(validate(&p, 10.0), Err(PlacementFault::NotRotation));
        let mut p = Placement::IDENTITY;
        p.rotation[2][2] = -1.0; // a reflection
        assert_eq!(validate(&p, 10.0), Err(PlacementFault::NotRotation));
        let mut p = Placement::IDENTITY;
        p.translation[1] = f32::NAN;
        assert_eq!(validate(&p, 10.0), Err(PlacementFault::NotFinite));
        let mut p = Placement::IDENTITY;
        p.translation[1] = 11.0;
        assert_eq!(validate(&p, 10.0), Err(PlacementFault::TooFar));
        assert_eq!(unit_axis(&[0.0; 3]), Err(PlacementFault::ZeroAxis));
        assert_eq!(unit_axis(&[0.0, 0.0, 2.0]), Ok(Vec3::z()));
    }
}
