//! Small numeric helpers shared by the modules: 3-vectors, rotations from
//! 1-2-3 Euler angles, rotation checks. All transcendentals through `libm`.

use nalgebra::{Matrix3, Vector3};

/// A 3-vector of `f32` (positions in length units, directions unitless).
pub type Vec3 = Vector3<f32>;
/// A 3 x 3 matrix of `f32` (rotations: columns are the frame's unit axes).
pub type Mat3 = Matrix3<f32>;

/// Euclidean length, through `libm::sqrtf` (correctly rounded on every target).
#[inline]
pub fn norm(v: &Vec3) -> f32 {
    libm::sqrtf(v.dot(v))
}

/// Euclidean length of a joint-space vector.
#[inline]
pub fn norm_slice(v: &[f32]) -> f32 {
    libm::sqrtf(dot_slice(v, v))
}

/// Dot product of two joint-space vectors (of the shorter length).
#[inline]
pub fn dot_slice(a: &[f32], b: &[f32]) -> f32 {
    a.iter().zip(b).map(|(x, y)| x * y).sum()
}

/// `Vec3` from an array.
#[inline]
pub fn vec3(a: [f32; 3]) -> Vec3 {
    Vec3::new(a[0], a[1], a[2])
}

/// Rotation from 1-2-3 Euler angles (radians): `R = Rz(rz) Ry(ry) Rx(rx)`, as
/// CAPP.c builds it. A vector in the rotated (obstacle) frame maps to the world
/// as `R x`; the world point `p` is `x = R^T (p - c)` in the obstacle's frame.
pub fn rotation_123(rx: f32, ry: f32, rz: f32) -> Mat3 {
    let (sx, cx) = libm::sincosf(rx);
    let (sy, cy) = libm::sincosf(ry);
    let (sz, cz) = libm::sincosf(rz);
    Mat3::new(
        cz * cy,
        cz * sy * sx - sz * cx,
        cz * sy * cx + sz * sx,
        sz * cy,
        sz * sy * sx + cz * cx,
        sz * sy * cx - cz * sx,
        -sy,
        cy * sx,
        cy * cx,
    )
}

/// Whether `r` is a proper rotation (orthonormal, determinant +1) to `tolerance`
/// in every entry of `R^T R - I` and in the determinant.
pub fn is_rotation(r: &Mat3, tolerance: f32) -> bool {
    if !r.iter().all(|x| x.is_finite()) {
        return false;
    }
    let rtr = r.transpose() * r;
    let off = (rtr - Mat3::identity())
        .iter()
        .all(|x| x.abs() <= tolerance);
    off && (r.determinant() - 1.0).abs() <= tolerance
}

/// Whether every entry is finite.
#[inline]
pub fn all_finite(v: &[f32]) -> bool {
    v.iter().all(|x| x.is_finite())
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn rotation_123_matches_product_of_elementary_rotations() {
        let (rx, ry, rz) = (0.3f32, -0.7f32, 1.1f32);
        let rxm = Mat3::new(
            1.0,
            0.0,
            0.0,
            0.0,
            rx.cos(),
            -rx.sin(),
            0.0,
            rx.sin(),
            rx.cos(),
        );
        let rym = Mat3::new(
            ry.cos(),
            0.0,
            ry.sin(),
            0.0,
            1.0,
            0.0,
            -ry.sin(),
            0.0,
            ry.cos(),
        );
        let rzm = Mat3::new(
            rz.cos(),
            -rz.sin(),
            0.0,
            rz.sin(),
            rz.cos(),
            0.0,
            0.0,
            0.0,
            1.0,
        );
        let expect = rzm * rym * rxm;
        let got = rotation_123(rx, ry, rz);
        assert!((expect - got).abs().max() < 1e-6);
        assert!(is_rotation(&got, 1e-5));
    }

    #[test]
    fn reflections_are_not_rotations() {
        let mut m = Mat3::identity();
        m[(2, 2)] = -1.0;
        assert!(!is_rotation(&m, 1e-4));
        m[(2, 2)] = f32::NAN;
        assert!(!is_rotation(&m, 1e-4));
    }
}
