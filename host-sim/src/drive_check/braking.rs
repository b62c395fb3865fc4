//! One joint's braking stop at its limits, tick by tick, in the checker's
//! discrete definitions ([`crate::drive_check`]): per tick of `dt`
//!
//! ```text
//! a_{n+1} = a_n + j dt,   |j| <= J,  |a_{n+1}| <= A
//! v_{n+1} = v_n + a_{n+1} dt
//! q_{n+1} = q_n + v_{n+1} dt
//! ```
//!
//! (the backward differences of the stop's positions are exactly these
//! `v`, `a`, `j`, so a stop never exceeds the limits the checker measures).
//!
//! The stop is the time-optimal greedy one: with `d = J dt` the most the
//! acceleration can change in a tick, each tick takes the most decelerating
//! next acceleration `a'` in `[a - d, a + d]` and `[-A, A]` such that
//! ramping the acceleration back to 0 by `d` per tick afterwards does not
//! carry the velocity past 0. For `v >= 0` (the other sign is its mirror)
//! and `a' in (-m d, -(m - 1) d]` that ramp takes `m` ticks, the last one
//! clamped at 0, and the velocity it ends at is
//!
//! ```text
//! v_end(a') = v + dt (m a' + d m (m - 1) / 2),
//! ```
//!
//! continuous and increasing in `a'`. Its root, for the `m` whose interval
//! holds it,
//!
//! ```text
//! a'* = -(v / dt + d m (m - 1) / 2) / m,
//! ```
//!
//! is clamped to the reachable interval. A root inside it lands the
//! velocity on 0 exactly as the acceleration reaches 0; one beyond its
//! decelerating end leaves `v_end > 0` (brake at the limit); one beyond the
//! other end means the state cannot stop without reversing (it was already
//! decelerating harder than the jerk limit can undo), and the stop then
//! continues from the reversed velocity by the same rule. The stop ends
//! when `|v|` and `|a|` are within 1e-9 of their limits (rounding).
//!
//! A state that is already beyond the acceleration limit (a trajectory that
//! breaks it) starts its stop from the acceleration clamped to `[-A, A]`:
//! the drive saturates; the excess is counted as an acceleration figure,
//! not here.

use crate::problem::JointDriveLimits;

/// Rounding below which a velocity or acceleration is zero, relative to its
/// limit.
const REST: f64 = 1.0e-9;

/// One joint's braking stop, advanced one tick at a time ([`Brake::tick`]).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Brake {
    v: f64,
    a: f64,
    max_rate: f64,
    max_accel: f64,
    max_jerk: f64,
    dt: f64,
}

impl Brake {
    /// The stop from velocity `v` and acceleration `a` (clamped to
    /// `[-max_accel, max_accel]`) at `limits`, in ticks of `dt`.
    pub fn new(v: f64, a: f64, limits: &JointDriveLimits, dt: f64) -> Self {
        Brake {
            v,
            a: a.clamp(-limits.max_accel, limits.max_accel),
            max_rate: limits.max_rate,
            max_accel: limits.max_accel,
            max_jerk: limits.max_jerk,
            dt,
        }
    }

    /// Velocity now.
    pub fn velocity(&self) -> f64 {
        self.v
    }

    /// Acceleration now.
    pub fn acceleration(&self) -> f64 {
        self.a
    }

    /// Whether the joint is at rest (velocity and acceleration zero to
    /// rounding).
    pub fn at_rest(&self) -> bool {
        self.v.abs() <= REST * self.max_rate && self.a.abs() <= REST * self.max_accel
    }

    /// One tick of the stop: the position change `v_{n+1} dt`, or `None`
    /// once at rest (or when the state is not finite).
    pub fn tick(&mut self) -> Option<f64> {
        if self.at_rest() || !(self.v.is_finite() && self.a.is_finite()) {
            return None;
        }
        let s = if self.v >= 0.0 { 1.0 } else { -1.0 };
        let (v, a) = (s * self.v, s * self.a);
        let (dt, d, limit) = (self.dt, self.max_jerk * self.dt, self.max_accel);
        let lo = (a - d).max(-limit);
        let hi = (a + d).min(limit);
        let next = root(v, d, dt, lo).clamp(lo, hi);
        let v_next = v + next * dt;
        self.v = s * v_next;
        self.a = s * next;
        Some(self.v * dt)
    }
}

/// The `a'` at which `v_end(a') = 0` (module docs), for `v >= 0`; `lo` when
/// the root is below it (every `a'` from `lo` up leaves `v_end >= 0`).
fn root(v: f64, d: f64, dt: f64, lo: f64) -> f64 {
    let mut m = 1.0f64;
    loop {
        let x = -(v / dt + d * m * (m - 1.0) / 2.0) / m;
        if x > -m * d {
            return x;
        }
        if -m * d <= lo {
            return lo;
        }
        m += 1.0;
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn limits(max_rate: f64, max_accel: f64, max_jerk: f64) -> JointDriveLimits {
        JointDriveLimits {
            max_rate,
            max_accel,
            max_jerk,
        }
    }

    /// `(v, a)` after each tick until rest, and the distance travelled.
    fn run(mut b: Brake) -> (Vec<(f64, f64)>, f64) {
        let (mut states, mut distance) = (Vec::new(), 0.0);
        while let Some(dq) = b.tick() {
            distance += dq;
            states.push((b.velocity(), b.acceleration()));
            assert!(states.len() < 10_000, "no stop");
        }
        (states, distance)
    }

    /// With `d = J dt` and `A = p d`, from `v0 = dt d p (p + k)` at zero
    /// acceleration the stop's accelerations are `-d x (1, 2, .., p, then p
    /// k more times, p - 1, .., 1, 0)`: `2p + k` ticks, and the distance is
    /// `dt` times the sum of the velocities, in closed form below.
    #[test]
    fn the_stop_from_full_rate_is_the_known_trapezoid() {
        for (p, k) in [(2usize, 8usize), (1, 0), (3, 5), (4, 1)] {
            let dt = 0.05;
            let d = 1.0;
            let jerk = d / dt;
            let accel = p as f64 * d;
            let v0 = dt * d * (p * (p + k)) as f64;
            let (states, distance) = run(Brake::new(v0, 0.0, &limits(v0, accel, jerk), dt));
            // The expected profile, built independently of the greedy rule.
            let mut steps: Vec<usize> = (1..=p).collect();
            steps.extend(std::iter::repeat_n(p, k));
            steps.extend((0..p).rev());
            assert_eq!(states.len(), 2 * p + k, "p {p} k {k}: {states:?}");
            let mut v = v0;
            let mut expected_distance = 0.0;
            for (n, (&m, &(vn, an))) in steps.iter().zip(&states).enumerate() {
                v -= dt * d * m as f64;
                expected_distance += v * dt;
                assert!(
                    (an + d * m as f64).abs() < 1e-9,
                    "tick {n}: a {an}, want -{m}d"
                );
                assert!((vn - v).abs() < 1e-9, "tick {n}: v {vn}, want {v}");
            }
            // Closed form: v_n = v0 - dt d S_n, S_n the partial sums of the
            // steps; sum of S_n over the 2p + k ticks.
            let n = (2 * p + k) as f64;
            let (pf, kf) = (p as f64, k as f64);
            // Ramp up: S_i = i (i + 1) / 2, i = 1..p.
            let up: f64 = pf * (pf + 1.0) * (pf + 2.0) / 6.0;
            // Plateau: S = p (p + 1) / 2 + p i, i = 1..k.
            let flat = kf * pf * (pf + 1.0) / 2.0 + pf * kf * (kf + 1.0) / 2.0;
            // Ramp down (p - 1, .., 1, 0): after i of its ticks, the total
            // less what is still to come, (p - i - 1)(p - i) / 2.
            let total = pf * (pf + kf);
            let down: f64 = (1..=p)
                .map(|i| {
                    let rest = pf - i as f64;
                    total - (rest - 1.0) * rest / 2.0
                })
                .sum();
            let closed = dt * (n * v0 - dt * d * (up + flat + down));
            assert!(
                (distance - closed).abs() < 1e-12 && (distance - expected_distance).abs() < 1e-12,
                "p {p} k {k}: {distance} vs {closed} vs {expected_distance}"
            );
            let last = states.last().unwrap();
            assert!(last.0.abs() < 1e-12 && last.1.abs() < 1e-12);
        }
    }

    /// A state a rounding away from the trapezoid's stops as far, within
    /// the rounding, in at most two more ticks (tiny corrections).
    #[test]
    fn the_stop_is_continuous_in_its_state() {
        let l = limits(1.0, 2.0, 20.0);
        let (exact, d0) = run(Brake::new(1.0, 0.0, &l, 0.05));
        for (dv, da) in [(1e-6, 4e-4), (-1e-6, -4e-4), (1e-7, -4e-4), (0.0, 1e-3)] {
            let (states, d) = run(Brake::new(1.0 + dv, da, &l, 0.05));
            assert!(states.len() <= exact.len() + 2, "{dv} {da}: {states:?}");
            assert!((d - d0).abs() < 1e-4, "{dv} {da}: {d} vs {d0}");
        }
    }

    /// From any state within the limits (and some beyond the acceleration
    /// limit), the stop's backward differences never exceed the limits, the
    /// stop ends at rest, and a state that can stop without reversing never
    /// reverses.
    #[test]
    fn stops_never_exceed_the_limits() {
        let l = limits(0.5, 1.0, 10.0);
        let dt = 0.05;
        let mut seed = 0x2545_F491u64;
        let mut uniform = || {
            seed ^= seed << 13;
            seed ^= seed >> 7;
            seed ^= seed << 17;
            (seed >> 11) as f64 / (1u64 << 53) as f64
        };
        for i in 0..2000 {
            let v = (2.0 * uniform() - 1.0) * l.max_rate;
            let a = (2.0 * uniform() - 1.0) * l.max_accel * if i % 10 == 0 { 3.0 } else { 1.0 };
            let b = Brake::new(v, a, &l, dt);
            let (mut pv, mut pa) = (b.velocity(), b.acceleration());
            let (states, _) = run(b);
            for &(vn, an) in &states {
                assert!(vn.abs() <= l.max_rate * (1.0 + 1e-9) + l.max_accel * dt);
                assert!(an.abs() <= l.max_accel * (1.0 + 1e-12));
                let j = (an - pa) / dt;
                assert!(
                    j.abs() <= l.max_jerk * (1.0 + 1e-9),
                    "v {v} a {a}: jerk {j}"
                );
                assert!(((vn - pv) / dt - an).abs() < 1e-9);
                (pv, pa) = (vn, an);
            }
            // Decelerating no harder than the jerk can undo: no reversal.
            let ramp = a * a / (2.0 * l.max_jerk) + a.abs() * dt;
            if v * a >= 0.0 || ramp < v.abs() {
                assert!(
                    states.iter().all(|&(vn, _)| vn * v >= -1e-12),
                    "v {v} a {a}: {states:?}"
                );
            }
        }
    }

    /// Time-optimal: from full rate at rest acceleration the stop takes the
    /// continuous-time minimum `R / A + A / J` rounded up to ticks, plus at
    /// most one.
    #[test]
    fn the_stop_is_as_short_as_the_limits_allow() {
        let dt = 0.05;
        for (r, a, j) in [(0.5, 1.0, 10.0), (2.0, 4.0, 40.0), (0.3, 2.0, 7.0)] {
            let (states, _) = run(Brake::new(r, 0.0, &limits(r, a, j), dt));
            // Continuous time: a trapezoid when the rate allows full
            // acceleration (r >= a^2 / j), else a triangle.
            let t = if r >= a * a / j {
                r / a + a / j
            } else {
                2.0 * (r / j).sqrt()
            };
            let ticks = states.len() as f64;
            assert!(
                ticks >= (t / dt).floor() && ticks <= (t / dt).ceil() + 2.0,
                "{r} {a} {j}: {ticks} ticks for {t} s"
            );
        }
    }
}
