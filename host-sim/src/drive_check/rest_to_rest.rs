//! The least time any motion a drive can follow needs between two
//! configurations: each joint, alone, from rest to rest over its own
//! displacement at its rate, acceleration and jerk limits (continuous time).
//! No plan between the same configurations can be faster, whatever its path:
//! every joint must still make its move, and the slowest one sets the time.
//! The suite compares plans with it (issue 22's motion-time target: a plan
//! with unlimited acceleration is not a floor a drive can reach).
//!
//! The time-optimal rest-to-rest move under `|v| <= R`, `|a| <= A`,
//! `|j| <= J` is the classic seven-phase profile: jerk `+J, 0, -J` up to the
//! peak speed `v`, a cruise at `v`, the mirror down to rest. Up to `v` it
//! takes `v / A + A / J` when the acceleration reaches `A` (`v >= A^2 / J`)
//! and covers `v / 2` times that time; otherwise `2 sqrt(v / J)`, covering
//! `v sqrt(v / J)`. So, with `D` the distance:
//!
//! * cruise (`D >= 2 up(R)`, `up` the distance to reach `R`):
//!   `T = D / R + rise(R)`, `rise(v)` the time up to `v`;
//! * no cruise, `A` reached: `v^2 / A + v A / J = D`, `T = 2 rise(v)`;
//! * no cruise, `A` not reached: `2 v sqrt(v / J) = D`, `T = 4 sqrt(v / J)`.
//!
//! The planner works in ticks of `dt`, a little slower than this; the floor
//! is of continuous time, so it is a floor for the ticked plans too.

use crate::problem::JointDriveLimits;

/// The time to reach speed `v` from rest (and to stop from it) at the limits.
fn rise(v: f64, l: &JointDriveLimits) -> f64 {
    let (a, j) = (l.max_accel, l.max_jerk);
    if v * j >= a * a {
        v / a + a / j
    } else {
        2.0 * (v / j).sqrt()
    }
}

/// Seconds for one joint to move `distance` (its units; the sign does not
/// matter) from rest to rest within `limits` (module docs). 0 for no
/// distance; NaN for a non-finite distance or a limit that is not positive.
pub fn joint_s(distance: f64, l: &JointDriveLimits) -> f64 {
    let d = distance.abs();
    let (r, a, j) = (l.max_rate, l.max_accel, l.max_jerk);
    if !(d.is_finite() && r > 0.0 && a > 0.0 && j > 0.0) {
        return f64::NAN;
    }
    if d == 0.0 {
        return 0.0;
    }
    // Up to R and back down again covers R rise(R) (half of it each way).
    let full = r * rise(r, l);
    if d >= full {
        return d / r + rise(r, l);
    }
    // No cruise: the peak speed v < R, up and down in 2 rise(v).
    let v = if d * j * j >= 2.0 * a * a * a {
        // A reached (v >= A^2 / J, where D = 2 A^3 / J^2):
        // v^2 / A + v A / J - D = 0.
        let b = a / j;
        0.5 * a * (-b + (b * b + 4.0 * d / a).sqrt())
    } else {
        // 2 v sqrt(v / J) = D.
        (0.5 * d * j.sqrt()).powf(2.0 / 3.0)
    };
    2.0 * rise(v, l)
}

/// The floor of a whole move: the slowest joint's [`joint_s`] from `start`
/// to `end` (one value per joint, as `limits`).
pub fn floor_s(start: &[f64], end: &[f64], limits: &[JointDriveLimits]) -> f64 {
    start
        .iter()
        .zip(end)
        .zip(limits)
        .map(|((a, b), l)| joint_s(b - a, l))
        .fold(0.0, f64::max)
}

#[cfg(test)]
mod tests {
    use super::*;

    fn limits(r: f64, a: f64, j: f64) -> JointDriveLimits {
        JointDriveLimits {
            max_rate: r,
            max_accel: a,
            max_jerk: j,
        }
    }

    /// The seven-phase profile of duration `t`, as phases of constant jerk
    /// (jerk, seconds), from the peak speed it reaches: built from the
    /// phases' own definition, not from [`joint_s`]'s formulas.
    fn phases(v: f64, cruise_s: f64, l: &JointDriveLimits) -> Vec<(f64, f64)> {
        let (a, j) = (l.max_accel, l.max_jerk);
        // Time at the jerk limit to the peak acceleration, and at it.
        let (ramp, hold) = if v * j >= a * a {
            (a / j, v / a - a / j)
        } else {
            ((v / j).sqrt(), 0.0)
        };
        vec![
            (j, ramp),
            (0.0, hold),
            (-j, ramp),
            (0.0, cruise_s),
            (-j, ramp),
            (0.0, hold),
            (j, ramp),
        ]
    }

    /// Integrates `phases` exactly (piecewise cubics): the final distance,
    /// speed and acceleration, the largest speed and acceleration, the time.
    fn integrate(phases: &[(f64, f64)]) -> (f64, f64, f64, f64, f64, f64) {
        let (mut x, mut v, mut a, mut t) = (0.0f64, 0.0f64, 0.0f64, 0.0f64);
        let (mut vmax, mut amax) = (0.0f64, 0.0f64);
        for &(j, s) in phases {
            // Sample inside the phase for the peaks (v is at most quadratic).
            for k in 1..=100 {
                let u = s * k as f64 / 100.0;
                vmax = vmax.max((v + a * u + 0.5 * j * u * u).abs());
                amax = amax.max((a + j * u).abs());
            }
            x += v * s + 0.5 * a * s * s + j * s * s * s / 6.0;
            v += a * s + 0.5 * j * s * s;
            a += j * s;
            t += s;
        }
        (x, v, a, vmax, amax, t)
    }

    #[test]
    fn the_floor_is_a_move_within_the_limits_that_covers_the_distance() {
        // Every regime: cruise with and without A reached, no cruise with
        // and without A reached; rates and limits over several decades.
        let mut seed = 0x2545_F491_4F6C_DD1Du64;
        let mut uniform = || {
            seed ^= seed << 13;
            seed ^= seed >> 7;
            seed ^= seed << 17;
            (seed >> 11) as f64 / (1u64 << 53) as f64
        };
        let mut regimes = [0usize; 4];
        for _ in 0..20_000 {
            let r = 10f64.powf(2.0 * uniform() - 1.0);
            let a = r / (0.05 + uniform());
            let j = a / (0.01 + 0.3 * uniform());
            let l = limits(r, a, j);
            let d = r * 10f64.powf(3.0 * uniform() - 2.5);
            let t = joint_s(d, &l);
            // The profile that time describes: find its peak speed and
            // cruise from the regime the distance is in.
            let full = r * rise(r, &l);
            let (v, cruise) = if d >= full {
                (r, (d - full) / r)
            } else {
                // The peak speed whose up-and-down covers d, by bisection on
                // the phases' own integral (independent of the closed form).
                let (mut lo, mut hi) = (0.0, r);
                for _ in 0..200 {
                    let mid = 0.5 * (lo + hi);
                    if integrate(&phases(mid, 0.0, &l)).0 < d {
                        lo = mid;
                    } else {
                        hi = mid;
                    }
                }
                (0.5 * (lo + hi), 0.0)
            };
            regimes[(d >= full) as usize * 2 + (v * j >= a * a) as usize] += 1;
            let (x, v_end, a_end, vmax, amax, total) = integrate(&phases(v, cruise, &l));
            assert!(
                (total - t).abs() <= 1e-9 * t.max(1.0),
                "{d} {l:?}: {total} vs {t}"
            );
            assert!((x - d).abs() <= 1e-9 * d, "{d} {l:?}: covers {x}");
            assert!(
                v_end.abs() <= 1e-9 * r && a_end.abs() <= 1e-9 * a,
                "ends at rest"
            );
            assert!(vmax <= r * (1.0 + 1e-9) && amax <= a * (1.0 + 1e-9));
            // Never under the single-limit floors (each a relaxation).
            assert!(t >= d / r * (1.0 - 1e-12));
            assert!(t >= 2.0 * (d / a).sqrt() * (1.0 - 1e-12));
            assert!(t >= (32.0 * d / j).cbrt() * (1.0 - 1e-12));
            // More distance never takes less time.
            assert!(joint_s(d * 1.01, &l) >= t);
        }
        assert!(regimes.iter().all(|&n| n > 100), "{regimes:?}");
    }

    #[test]
    fn known_moves_and_bad_input() {
        // The defaults for a rate of 1: A = 2 (0.5 s ramp), J = 20 (0.1 s).
        let l = limits(1.0, 2.0, 20.0);
        // Up to full rate takes 0.5 + 0.1 s and covers 0.3 each way.
        assert!((joint_s(0.6, &l) - 1.2).abs() < 1e-12);
        assert!((joint_s(10.0, &l) - 10.6).abs() < 1e-12);
        assert!((joint_s(-10.0, &l) - 10.6).abs() < 1e-12);
        assert_eq!(joint_s(0.0, &l), 0.0);
        assert!(joint_s(f64::NAN, &l).is_nan());
        assert!(joint_s(1.0, &limits(1.0, 0.0, 1.0)).is_nan());
        // The slowest joint sets a move's floor.
        let two = [l, limits(0.5, 1.0, 10.0)];
        let t = floor_s(&[0.0, 0.0], &[10.0, 1.0], &two);
        assert!((t - 10.6).abs() < 1e-12);
        let t = floor_s(&[0.0, 0.0], &[1.0, 10.0], &two);
        assert!((t - joint_s(10.0, &two[1])).abs() < 1e-12);
    }
}
