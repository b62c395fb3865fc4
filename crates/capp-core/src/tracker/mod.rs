//! How fast: the tracker between the laws and the drives. The laws choose
//! where to go (a joint rate); the tracker turns that into motion a joint
//! drive can follow, at a fixed control period, within each joint's rate,
//! acceleration and jerk limits ([`limits::DriveLimits`]), always able to
//! stop within them (issue 22).
//!
//! * [`profile`]: one joint: the discrete model (the positions' own
//!   differences are the velocity and acceleration), the time-optimal move
//!   toward a velocity, the interval of accelerations after which the joint
//!   can still stop within its limits, and a bound on its stopping travel;
//! * [`clearance`]: conservative advancement for a tick and the stop after
//!   it;
//! * [`slide`]: a velocity target less one point's approach to a surface;
//! * [`DriveState`]: every joint's velocity and acceleration, the next tick
//!   toward the law's rates (time-synchronised), the next tick of a stop,
//!   and each joint's travel bound for the tick and the stop after it.
//!
//! ## Synchronisation
//!
//! A joint alone moves toward its target velocity as fast as its limits
//! allow; left at that, a joint with more headroom gets there first and the
//! arm's motion leaves the direction the law chose. So [`DriveState::toward`]
//! removes the same fraction `rho` of every joint's velocity error in a
//! tick: `rho` is the least of the fractions the joints could remove alone,
//! and each joint's acceleration is `rho e_j / dt` within its viable
//! interval. From rest the velocity then moves along the straight line to
//! the target (tested), as Ruckig's phase synchronisation does (Berscheid
//! and Kroger, RSS 2021). A joint whose own best move goes against its error
//! (it must first take out an acceleration the other way) is left out of
//! `rho` and moves alone.
//!
//! ## Stopping
//!
//! A stop ([`DriveState::braking`]) is every joint braking alone, as fast as
//! its limits allow: a synchronised stop would hold the faster joints back
//! and let them travel farther than [`profile::stopping_travel`] says.
//! Each joint moves one way only during a stop, within that bound, whatever
//! the other joints do; conservative advancement over those per-joint
//! travels covers every configuration of the stop.

pub mod clearance;
pub mod limits;
pub mod profile;
pub mod slide;

use crate::math::{max, min};
use limits::DriveLimits;

/// Every joint's velocity (per second) and acceleration (per second
/// squared) after the last tick: with the joint positions, the state the
/// next tick starts from.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct DriveState<const N: usize> {
    n: usize,
    velocity: [f32; N],
    acceleration: [f32; N],
}

impl<const N: usize> DriveState<N> {
    /// `n` joints (at most `N`) at rest.
    pub fn at_rest(n: usize) -> Self {
        DriveState {
            n: n.min(N),
            velocity: [0.0; N],
            acceleration: [0.0; N],
        }
    }

    /// The joints' velocities, per second.
    pub fn velocity(&self) -> &[f32] {
        &self.velocity[..self.n.min(N)]
    }

    /// The joints' accelerations, per second squared.
    pub fn acceleration(&self) -> &[f32] {
        &self.acceleration[..self.n.min(N)]
    }

    /// How much of the velocity target `target` this state (a tick toward
    /// `share` of it) reached: `share`, or less where the limits held every
    /// joint below it (the largest `|v_j / target_j|` over the joints with a
    /// target). From rest the jerk limit holds the first tick to the same
    /// small motion whatever the share above a few percent, so a refused
    /// tick's next try is cut from the speed it reached, not from the one
    /// it was aimed at.
    pub fn reached_share(&self, target: &[f32], share: f32) -> f32 {
        let mut reached: Option<f32> = None;
        for (&v, &t) in self.velocity().iter().zip(target) {
            if t == 0.0 {
                continue;
            }
            let r = (v / t).abs();
            if r.is_nan() {
                return share;
            }
            reached = Some(max(reached.unwrap_or(0.0), r));
        }
        // No joint aimed anywhere, or NaN: the share as it was.
        match reached {
            Some(r) if r < share => r,
            _ => share,
        }
    }

    /// Whether every joint's `|velocity|` is at most `fraction` of its rate
    /// limit and its acceleration at most `fraction` of its limit.
    pub fn is_at_rest(&self, limits: &[DriveLimits], fraction: f32) -> bool {
        self.velocity()
            .iter()
            .zip(self.acceleration())
            .zip(limits)
            .all(|((v, a), l)| {
                v.abs() <= fraction * l.max_rate && a.abs() <= fraction * l.max_accel
            })
    }

    /// The next tick toward the velocities `target` (per second; each
    /// clamped to its rate limit), time-synchronised (module docs).
    /// `limits` and `target` hold one value per joint.
    #[inline(never)]
    pub fn toward(&self, limits: &[DriveLimits], dt: f32, target: &[f32]) -> Self {
        let n = self.n.min(N);
        let mut next = *self;
        // Per joint: its own best move toward its target and its viable
        // interval ([`profile::toward`]'s parts, kept for the second pass),
        // and the fraction of its velocity error it could remove alone.
        let mut alone = [0.0f32; N];
        let mut low = [0.0f32; N];
        let mut high = [0.0f32; N];
        let mut rho = 1.0f32;
        for ((((&v, &a), l), &t), (own, (lo, hi))) in self.velocity[..n]
            .iter()
            .zip(&self.acceleration[..n])
            .zip(limits)
            .zip(target)
            .zip(alone.iter_mut().zip(low.iter_mut().zip(high.iter_mut())))
        {
            let e = clamp_rate(t, l) - v;
            (*lo, *hi) = profile::viable(v, a, l, dt);
            let wanted = profile::acceleration_for((v + e) - v, l.max_jerk * dt, dt);
            *own = profile::clamp(wanted, *lo, *hi);
            if e.abs() > SETTLED * l.max_rate {
                let fraction = *own * dt / e;
                if fraction > 0.0 {
                    rho = min(rho, fraction);
                }
            }
        }
        for (((((v, a), l), &t), (&v0, own)), (&lo, &hi)) in next.velocity[..n]
            .iter_mut()
            .zip(&mut next.acceleration[..n])
            .zip(limits)
            .zip(target)
            .zip(self.velocity[..n].iter().zip(&alone))
            .zip(low.iter().zip(&high))
        {
            let e = clamp_rate(t, l) - v0;
            let synced = if own * e > 0.0 {
                profile::clamp(rho * e / dt, lo, hi)
            } else {
                *own
            };
            *a = if synced.is_finite() { synced } else { lo };
            *v = v0 + *a * dt;
        }
        next
    }

    /// The next tick of a stop at the limits: every joint brakes alone.
    pub fn braking(&self, limits: &[DriveLimits], dt: f32) -> Self {
        let mut next = *self;
        next.brake(limits, dt);
        next
    }

    /// [`DriveState::braking`] in place (no copy of the state: the stop
    /// test takes a dozen of these per candidate).
    #[inline(never)]
    pub fn brake(&mut self, limits: &[DriveLimits], dt: f32) {
        let n = self.n.min(N);
        for ((v, a), l) in self.velocity[..n]
            .iter_mut()
            .zip(&mut self.acceleration[..n])
            .zip(limits)
        {
            *a = profile::braking(*v, *a, l, dt);
            *v += *a * dt;
        }
    }

    /// With [`crate::Motion::Stepped`]: the step just taken moved at `rate`
    /// (per second) for `h` seconds; the velocity becomes `rate` and the
    /// acceleration its change over `h` (both 0 for a step not taken,
    /// `h = 0`), what the stream reports of a stepped plan.
    pub fn record_step(&mut self, rate: &[f32], h: f32) {
        let n = self.n.min(N);
        let taken = h > 0.0;
        for ((v, a), &r) in self.velocity[..n]
            .iter_mut()
            .zip(&mut self.acceleration[..n])
            .zip(rate.iter().chain(core::iter::repeat(&0.0)))
        {
            if taken {
                *a = (r - *v) / h;
                *v = r;
            } else {
                (*v, *a) = (0.0, 0.0);
            }
        }
    }

    /// Joint `j` of this tick takes, instead, the next tick of its stop from
    /// `from` (the state this tick started at).
    pub fn brake_joint(&mut self, j: usize, from: &Self, limits: &DriveLimits, dt: f32) {
        if let (Some(v), Some(a), Some(&v0), Some(&a0)) = (
            self.velocity.get_mut(j),
            self.acceleration.get_mut(j),
            from.velocity.get(j),
            from.acceleration.get(j),
        ) {
            *a = profile::braking(v0, a0, limits, dt);
            *v = v0 + *a * dt;
        }
    }

    /// The positions one tick on: `q_next = q + v dt`.
    pub fn advance(&self, q: &[f32], dt: f32, q_next: &mut [f32]) {
        for ((next, &qj), &v) in q_next.iter_mut().zip(q).zip(self.velocity()) {
            *next = qj + v * dt;
        }
    }

    /// Each joint's bound on how far it gets from where it was before the
    /// tick that ended in this state: the tick (`v dt`) and then the stop at
    /// the limits ([`profile::stopping_span`], either side), into `travel`.
    pub fn excursion(&self, limits: &[DriveLimits], dt: f32, travel: &mut [f32]) {
        for (((out, &v), &a), l) in travel
            .iter_mut()
            .zip(self.velocity())
            .zip(self.acceleration())
            .zip(limits)
        {
            *out = excursion_of(v, profile::stopping_span(v, a, l, dt), dt);
        }
    }
}

/// A joint's excursion ([`DriveState::excursion`]) at velocity `v` from
/// its stopping span `(below, above)` ([`profile::stopping_span`]).
#[inline(always)]
pub fn excursion_of(v: f32, (below, above): (f32, f32), dt: f32) -> f32 {
    let step = v * dt;
    max((step - below).abs(), (step + above).abs())
}

/// The ticks of `dt` seconds the slowest of `limits` takes to turn around
/// ([`DriveLimits::turnaround_s`]), rounded up: how long a tracked arm's
/// velocity lags a law that reverses. At most [`MAX_TURNAROUND_TICKS`]; 0
/// for a period that is not positive.
pub fn turnaround_ticks(limits: &[DriveLimits], dt: f32) -> u32 {
    let slowest = limits
        .iter()
        .map(DriveLimits::turnaround_s)
        .fold(0.0f32, max);
    let ticks = slowest / dt;
    if dt.is_nan() || dt <= 0.0 || ticks.is_nan() || ticks <= 0.0 {
        return 0;
    }
    let ticks = min(ticks, MAX_TURNAROUND_TICKS as f32);
    let whole = crate::math::floor_non_negative(ticks);
    // `as` saturates: the value is in [0, MAX_TURNAROUND_TICKS] anyway.
    whole as u32 + u32::from(whole < ticks)
}

/// The most ticks [`turnaround_ticks`] returns (limits that would take
/// longer: the stall test still ends).
pub const MAX_TURNAROUND_TICKS: u32 = 4_096;

/// A velocity error below this fraction of the rate limit is settled.
const SETTLED: f32 = 1.0e-6;

fn clamp_rate(v: f32, l: &DriveLimits) -> f32 {
    if v.is_finite() {
        profile::clamp(v, -l.max_rate, l.max_rate)
    } else {
        0.0
    }
}

#[cfg(test)]
mod tests;
