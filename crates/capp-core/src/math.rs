//! Small numeric helpers shared by the modules: 3-vectors, rotations from
//! 1-2-3 Euler angles, rotation checks, and the joint angles' sine and cosine.
//! Every transcendental is either `libm` or [`sin_cos`], written in `f32`
//! operations only: IEEE `f32` arithmetic rounds the same everywhere, so the
//! host and a Cortex-M4F compute the same bits.

use nalgebra::{Matrix3, Vector3};

/// A 3-vector of `f32` (positions in length units, directions unitless).
pub type Vec3 = Vector3<f32>;
/// A 3 x 3 matrix of `f32` (rotations: columns are the frame's unit axes).
pub type Mat3 = Matrix3<f32>;

/// The square root, correctly rounded (IEEE 754) on every target, so the
/// host and the board compute the same bits.
///
/// On a hard-float Arm target (the Cortex-M4F boards, `eabihf`) this is
/// the FPU's `vsqrt.f32`: one instruction, where `libm::sqrtf` (which has
/// no Arm implementation) runs about 55 integer instructions. Elsewhere it
/// is `libm::sqrtf` (on x86-64 the SSE `sqrtss`). IEEE 754 requires the
/// square root correctly rounded, as it does `+ - * /`, so the two agree
/// to the bit; the QEMU tests that compare the board's trajectories with
/// the host's (`tests/`) check it end to end.
///
/// Why hand-written: `f32::sqrt` is `std`-only, `core::f32::math::sqrt`
/// is unstable, and `libm` has no Arm implementation. The inline assembly
/// in `vsqrt` and the C library's `sqrtf` behind [`sqrt_inline`] are the
/// crate's only `unsafe` items.
#[inline(always)]
pub fn sqrt(x: f32) -> f32 {
    #[cfg(all(target_arch = "arm", target_abi = "eabihf"))]
    {
        vsqrt(x)
    }
    #[cfg(not(all(target_arch = "arm", target_abi = "eabihf")))]
    {
        libm::sqrtf(x)
    }
}

/// `vsqrt.f32` on `x`. Rust lets inline assembly name a single-precision
/// register only on targets with double-precision VFP (`vfp2`), which the
/// Cortex-M4F's FPU is not, so the value passes in a core register and the
/// scratch register `s0` is saved and restored around the instruction.
#[cfg(all(target_arch = "arm", target_abi = "eabihf"))]
#[allow(unsafe_code)]
#[inline(never)]
fn vsqrt(x: f32) -> f32 {
    let mut bits = x.to_bits();
    // SAFETY: registers only, apart from the push and pop of `s0`, which
    // leave it and the stack pointer as they were.
    unsafe {
        core::arch::asm!(
            "vpush {{s0}}",
            "vmov s0, {bits}",
            "vsqrt.f32 s0, s0",
            "vmov {bits}, s0",
            "vpop {{s0}}",
            bits = inout(reg) bits,
            options(pure, nomem, preserves_flags)
        );
    }
    f32::from_bits(bits)
}

/// [`sqrt`] written inline, for the pair loops that take a root a pair:
/// 4 instructions a root on the board against 11 for [`sqrt`]'s call.
///
/// On the board this is `sqrtf` of the C library, which LLVM knows: on an
/// FPU with a square root its `PartiallyInlineLibCalls` pass writes the
/// call as `vsqrt.f32` inline, and keeps a call (to `compiler_builtins`'
/// `sqrtf`, `libm`'s code) only for a NaN result, where C would set
/// `errno`. The same correctly rounded root as [`sqrt`], so the same bits.
/// Not the default: the fallback call in every caller's code takes flash
/// (about 20 bytes a root) and, inside a loop whose registers are all
/// taken, makes the loop dearer where the root is not even reached (the
/// obstacle pair loop: 380 instructions a PIPS + 8 step).
#[inline(always)]
pub fn sqrt_inline(x: f32) -> f32 {
    #[cfg(all(target_arch = "arm", target_abi = "eabihf"))]
    {
        #[allow(unsafe_code)]
        unsafe extern "C" {
            safe fn sqrtf(x: f32) -> f32;
        }
        sqrtf(x)
    }
    #[cfg(not(all(target_arch = "arm", target_abi = "eabihf")))]
    {
        libm::sqrtf(x)
    }
}

/// Euclidean length, through [`sqrt`].
#[inline]
pub fn norm(v: &Vec3) -> f32 {
    sqrt(v.dot(v))
}

/// Euclidean length of a joint-space vector.
#[inline]
pub fn norm_slice(v: &[f32]) -> f32 {
    sqrt(dot_slice(v, v))
}

/// Dot product of two joint-space vectors (of the shorter length).
#[inline]
pub fn dot_slice(a: &[f32], b: &[f32]) -> f32 {
    a.iter().zip(b).map(|(x, y)| x * y).sum()
}

/// Largest `|x|` [`sin_cos`] reduces by Cody-Waite; beyond it, by `fmodf`.
pub const SIN_COS_FAST_RANGE: f32 = 8192.0;

/// `(sin x, cos x)` in `f32` arithmetic only, for the per-step joint angles.
///
/// `libm::sincosf` evaluates in `f64`, which a Cortex-M4F (single-precision
/// FPU) runs in software: about 1 800 instructions a call, most of forward
/// kinematics. Here: `x = j pi/2 + r` with `j` rounded, `r` by a three-part
/// Cody-Waite reduction (its first two products exact for `|j| < 2^13`,
/// which covers `SIN_COS_FAST_RANGE`), then Cephes'
/// minimax polynomials for `sin r` and `cos r` on `|r| <= pi/4` (error about
/// 1 ulp of the result, tested against `f64` below), and the quadrant `j mod 4`.
/// About 40 instructions on the M4F.
///
/// Beyond [`SIN_COS_FAST_RANGE`] (no joint angle gets there: revolute limits
/// and DH angles are within [`crate::robot::MAX_ANGLE`]) the angle is first
/// taken modulo the `f32` nearest `2 pi` (`fmodf`, exact): an error of
/// `x 2.8e-8` rad, under a quarter of `x`'s own ulp, so the input's rounding
/// already says more. NaN and infinities give NaN. Every angle of the core
/// goes through here, not `libm::sincosf`, which evaluates in `f64` and
/// takes 7 KB of the board's flash with the `f64` arithmetic it calls.
#[inline]
pub fn sin_cos(x: f32) -> (f32, f32) {
    // The three parts of pi/2: 8, 11 and 24 significant bits.
    const PIO2_HI: f32 = 1.570_312_5;
    const PIO2_MID: f32 = 4.837_513e-4;
    const PIO2_LO: f32 = 7.549_79e-8;
    let x = if x.abs() <= SIN_COS_FAST_RANGE {
        x
    } else {
        wrap_turns(x)
    };
    if x.is_nan() {
        return (f32::NAN, f32::NAN);
    }
    let half = if x < 0.0 { -0.5 } else { 0.5 };
    let j = (x * core::f32::consts::FRAC_2_PI + half) as i32;
    let jf = j as f32;
    let r = ((x - jf * PIO2_HI) - jf * PIO2_MID) - jf * PIO2_LO;
    let z = r * r;
    let sin_r = ((-1.951_529_6e-4 * z + 8.332_161e-3) * z - 1.666_665_5e-1) * z * r + r;
    let cos_r =
        ((2.443_315_7e-5 * z - 1.388_731_6e-3) * z + 4.166_664_6e-2) * z * z - 0.5 * z + 1.0;
    match j & 3 {
        0 => (sin_r, cos_r),
        1 => (cos_r, -sin_r),
        2 => (-sin_r, -cos_r),
        _ => (-cos_r, sin_r),
    }
}

/// `x` (beyond [`SIN_COS_FAST_RANGE`], or not finite) modulo the `f32`
/// nearest `2 pi`: within `(-2 pi, 2 pi)`, NaN for NaN and infinities.
#[cold]
#[inline(never)]
fn wrap_turns(x: f32) -> f32 {
    libm::fmodf(x, core::f32::consts::TAU)
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
    let (sx, cx) = sin_cos(rx);
    let (sy, cy) = sin_cos(ry);
    let (sz, cz) = sin_cos(rz);
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

/// The larger of `a` and `b` by one comparison (`a` when they are unordered).
///
/// `f32::max` and `f32::min` are calls to `fmaxf` / `fminf` on the
/// Cortex-M4F (its FPU has no `VMAXNM`): a dozen instructions each for NaN
/// rules the per-step code does not rely on. These are a compare and a select.
#[inline(always)]
pub fn max(a: f32, b: f32) -> f32 {
    if b > a {
        b
    } else {
        a
    }
}

/// The smaller of `a` and `b` by one comparison (`a` when they are unordered).
#[inline(always)]
pub fn min(a: f32, b: f32) -> f32 {
    if b < a {
        b
    } else {
        a
    }
}

/// `floor(x)` for `x >= 0` (and NaN, which it keeps) by a conversion to an
/// integer: `libm::floorf` is a call of some 25 instructions on the
/// Cortex-M4F (no rounding instruction in its FPU), this is a compare and
/// two conversions. Not for negative `x`.
#[inline(always)]
pub fn floor_non_negative(x: f32) -> f32 {
    // From 2^23 on every f32 is an integer (and infinity stays).
    if x < 8_388_608.0 {
        (x as u32) as f32
    } else {
        x
    }
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
    fn sin_cos_is_within_two_ulp_of_f64() {
        let mut worst = 0.0f64;
        let mut x = -20.0f32;
        while x <= 20.0 {
            let (s, c) = sin_cos(x);
            let (se, ce) = (x as f64).sin_cos();
            // Absolute error against ulps of 1: what FK's products see.
            worst = worst.max((s as f64 - se).abs()).max((c as f64 - ce).abs());
            x += 0.000_37;
        }
        assert!(worst < 2.0 * f32::EPSILON as f64, "worst error {worst}");
        // Across the Cody-Waite range.
        let mut x = 20.0f32;
        while x <= SIN_COS_FAST_RANGE {
            for y in [x, -x] {
                let (s, c) = sin_cos(y);
                let (se, ce) = (y as f64).sin_cos();
                let err = (s as f64 - se).abs().max((c as f64 - ce).abs());
                assert!(err < 2.0 * f32::EPSILON as f64, "{y}: error {err}");
            }
            x = x * 1.013 + 0.001;
        }
        // Beyond it: within the angle's own half ulp.
        let mut x = SIN_COS_FAST_RANGE.next_up();
        while x < 1.0e12 {
            for y in [x, -x] {
                let (s, c) = sin_cos(y);
                let (se, ce) = (y as f64).sin_cos();
                let err = (s as f64 - se).abs().max((c as f64 - ce).abs());
                let half_ulp = (y.abs().next_up() - y.abs()) as f64 / 2.0;
                assert!(
                    err <= half_ulp + 4.0 * f32::EPSILON as f64,
                    "{y}: error {err}"
                );
            }
            x = x * 1.07 + 0.3;
        }
        for x in [f32::INFINITY, f32::NEG_INFINITY, f32::NAN] {
            let (s, c) = sin_cos(x);
            assert!(s.is_nan() && c.is_nan());
        }
        assert_eq!(sin_cos(0.0), (0.0, 1.0));
    }

    #[test]
    fn floor_of_non_negative_values_is_libm_s() {
        let mut x = 0.0f32;
        let mut checked = 0;
        while x < 3.0e7 {
            for y in [x, x.next_up(), (x + 1.0).next_down()] {
                assert_eq!(
                    floor_non_negative(y).to_bits(),
                    libm::floorf(y).to_bits(),
                    "{y}"
                );
                checked += 1;
            }
            x = x * 1.37 + 0.11;
        }
        for y in [
            0.0,
            0.5,
            1.0,
            8_388_607.5,
            8_388_608.0,
            1.0e30,
            f32::INFINITY,
        ] {
            assert_eq!(floor_non_negative(y).to_bits(), libm::floorf(y).to_bits());
        }
        assert!(floor_non_negative(f32::NAN).is_nan());
        assert!(checked > 100);
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
