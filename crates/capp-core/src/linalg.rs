//! The one dense solve the planner does: a 6 x 6 symmetric positive definite
//! system, by `L D L^T` factorisation in place (Cholesky without square roots).
//!
//! Task space has six coordinates (end-effector position, length units, and
//! orientation, radians), so whatever the joint count the damped
//! least-squares law ([`crate::control::damped`]) solves `6 x 6`: about a
//! hundred multiply-adds, six square roots, no pivoting. Fixed-size arrays and
//! constant loop bounds: no allocation, no index that can fail.

// Index loops read as the textbook algorithm; the bounds are constants.
#![allow(clippy::needless_range_loop)]

/// A symmetric 6 x 6 matrix, rows of `f32`; only the lower triangle
/// (`a[i][j]`, `j <= i`) is read by [`factor`].
pub type Sym6 = [[f32; 6]; 6];

/// A task-space 6-vector: linear part first (length units), angular part last.
pub type Vec6 = [f32; 6];

/// Factorises `a` in place as `L D L^T` (Cholesky without square roots,
/// each 14 cycles on the Cortex-M4F's FPU): the
/// strict lower triangle becomes the unit lower-triangular `L`, the diagonal
/// becomes `D`; the strict upper triangle is left as it was. Returns `false`,
/// leaving `a` partly overwritten, when a pivot of `D` is not positive and
/// finite: `a` was not positive definite (or held NaN).
pub fn factor(a: &mut Sym6) -> bool {
    for j in 0..6 {
        let mut d = a[j][j];
        for k in 0..j {
            d -= a[j][k] * a[j][k] * a[k][k];
        }
        if !(d > 0.0 && d.is_finite()) {
            return false;
        }
        a[j][j] = d;
        for i in j + 1..6 {
            let mut s = a[i][j];
            for k in 0..j {
                s -= a[i][k] * a[j][k] * a[k][k];
            }
            a[i][j] = s / d;
        }
    }
    true
}

/// Solves `L D L^T x = b` in place (`b` becomes `x`), the factor from [`factor`].
pub fn solve(f: &Sym6, b: &mut Vec6) {
    for i in 0..6 {
        let mut s = b[i];
        for k in 0..i {
            s -= f[i][k] * b[k];
        }
        b[i] = s;
    }
    for i in 0..6 {
        b[i] /= f[i][i];
    }
    for i in (0..6).rev() {
        let mut s = b[i];
        for k in i + 1..6 {
            s -= f[k][i] * b[k];
        }
        b[i] = s;
    }
}

/// Updates the factor `f` of `A` ([`factor`]) in place to the factor of
/// `A + alpha v v^T`, in O(36) (Gill, Golub, Murray and Saunders, "Methods
/// for modifying matrix factorizations", 1974, method C1); a negative
/// `alpha` removes a term (a downdate). Returns `false`, leaving `f` partly
/// updated, when a pivot would not stay positive and finite (the result would
/// not be positive definite, or rounding made it look so).
pub fn update(f: &mut Sym6, alpha: f32, v: &Vec6) -> bool {
    let mut w = *v;
    let mut alpha = alpha;
    for j in 0..6 {
        let p = w[j];
        let d = f[j][j];
        let updated = d + alpha * p * p;
        if !(updated > 0.0 && updated.is_finite()) {
            return false;
        }
        let beta = p * alpha / updated;
        alpha *= d / updated;
        f[j][j] = updated;
        for i in j + 1..6 {
            w[i] -= p * f[i][j];
            f[i][j] += beta * w[i];
        }
    }
    true
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A fixed SPD matrix: `B B^T + I` for a made-up `B`.
    fn spd() -> Sym6 {
        let mut b = [[0.0f32; 6]; 6];
        for (i, row) in b.iter_mut().enumerate() {
            for (j, x) in row.iter_mut().enumerate() {
                *x = ((i * 7 + j * 3) % 5) as f32 - 2.0 + 0.1 * i as f32;
            }
        }
        let mut a = [[0.0f32; 6]; 6];
        for i in 0..6 {
            for j in 0..6 {
                a[i][j] = (0..6).map(|k| b[i][k] * b[j][k]).sum::<f32>();
            }
            a[i][i] += 1.0;
        }
        a
    }

    #[test]
    fn a_rank_one_update_or_downdate_gives_the_factor_of_the_changed_matrix() {
        let a = spd();
        let v = [0.7, -1.2, 0.4, 2.0, -0.3, 1.1];
        for alpha in [2.5f32, -0.05] {
            let mut changed = a;
            for i in 0..6 {
                for j in 0..6 {
                    changed[i][j] += alpha * v[i] * v[j];
                }
            }
            let mut direct = changed;
            assert!(factor(&mut direct));
            let mut updated = a;
            assert!(factor(&mut updated));
            assert!(update(&mut updated, alpha, &v));
            for i in 0..6 {
                for j in 0..=i {
                    let scale = direct[i][i].abs().max(1.0);
                    assert!(
                        (updated[i][j] - direct[i][j]).abs() < 1e-4 * scale,
                        "alpha {alpha}: [{i}][{j}] {} vs {}",
                        updated[i][j],
                        direct[i][j]
                    );
                }
            }
        }
        // Removing more than is there: refused, not a wrong factor.
        let mut f = a;
        assert!(factor(&mut f));
        assert!(!update(&mut f, -1.0e4, &v));
    }

    #[test]
    fn solves_a_symmetric_positive_definite_system() {
        let a = spd();
        let x_true = [1.0, -2.0, 0.5, 3.0, -1.5, 0.25];
        let mut b = [0.0f32; 6];
        for i in 0..6 {
            b[i] = (0..6).map(|j| a[i][j] * x_true[j]).sum();
        }
        let mut l = a;
        assert!(factor(&mut l));
        // L D L^T reproduces A.
        for i in 0..6 {
            for j in 0..=i {
                let unit = |r: usize, c: usize| if r == c { 1.0 } else { l[r][c] };
                let ldlt: f32 = (0..=j).map(|k| unit(i, k) * l[k][k] * unit(j, k)).sum();
                assert!((ldlt - a[i][j]).abs() < 1e-3 * a[i][i].abs().max(1.0));
            }
        }
        solve(&l, &mut b);
        for (x, t) in b.iter().zip(x_true) {
            assert!((x - t).abs() < 1e-3, "{x} vs {t}");
        }
    }

    #[test]
    fn refuses_what_is_not_positive_definite() {
        let mut a = spd();
        a[3][3] = -1.0;
        assert!(!factor(&mut a));
        let mut a = spd();
        a[5][2] = f32::NAN;
        assert!(!factor(&mut a));
        let mut z = [[0.0f32; 6]; 6];
        assert!(!factor(&mut z));
    }
}
