//! One joint at a fixed control period: the discrete, jerk-limited motion
//! model every setpoint follows, the acceleration interval that keeps a
//! joint able to stop within its limits, and a bound on how far it travels
//! while stopping.
//!
//! ## The model
//!
//! Rows are `dt` seconds apart. Each tick the joint takes a new acceleration
//! `a'`, then `v' = v + a' dt` and `q' = q + v' dt`. So the backward
//! differences of the positions over `dt` (`v_k = (q_k - q_{k-1}) / dt`,
//! `a_k = (v_k - v_{k-1}) / dt`, `j_k = (a_k - a_{k-1}) / dt`, rest before
//! the first row) give back exactly `v` and `a`: the limits hold for the
//! positions a drive receives, not only for an internal profile. Jerk and
//! acceleration limits are the interval `a'` in `[a - u, a + u]` and
//! `[-A, A]`, with `u = J dt` the largest change of acceleration in a tick.
//!
//! ## Settling
//!
//! [`settle_change`] `F(a')`: the velocity change from taking `a'` now and
//! then ramping the acceleration back to zero as fast as the jerk allows
//! (`a' - u`, `a' - 2u`, ... , 0). With `m = floor(|a'| / u)`,
//! `F(a') = sign(a') dt ((m + 1) |a'| - u m (m + 1) / 2)`: odd, strictly
//! increasing and linear between the multiples of `u`, so its inverse
//! ([`acceleration_for`]) is one square root. `a' = F^-1(e)` is the
//! time-optimal first move toward a velocity `e` away (it arrives with zero
//! acceleration, without passing it), the discrete counterpart of
//! Ruckig's velocity interface (Berscheid and Kroger, RSS 2021).
//!
//! ## Always able to stop within the limits
//!
//! [`viable`] is `a'` in `[a - u, a + u]`, `[-A, A]` and `F(a')` in
//! `[-V - v, V - v]`: after any such choice the joint can still ramp its
//! acceleration to zero without passing `+-V`. It is never empty when the
//! state came from earlier choices in it (from rest, by induction:
//! `F(a - u)` is what remained of `F(a)` after this tick). This is the
//! discrete form of Ruckig's input rule `|a| <= sqrt(2 J (V - |v|))`.
//!
//! ## Stopping
//!
//! [`stopping_travel`] bounds how far the joint gets from where it is
//! while it brakes to rest at its limits (each tick `a' = F^-1(-v)` in the
//! viable interval): the rise while a forward acceleration ramps out, then
//! the continuous jerk-limited stop from the peak velocity `w` (`w (w / A +
//! A / J) / 2` with a phase at `-A`, `w sqrt(w / J)` without), plus one tick
//! at `w` for the discrete lag. A joint already decelerating harder than its
//! velocity needs cannot take that out in time and passes zero velocity:
//! the way back is bounded the same way. Tests check the bound against the
//! stop simulated tick by tick.

use crate::math::{floor_non_negative, max, min, sqrt};
use crate::tracker::limits::DriveLimits;

/// `x` within `[low, high]` as `x.max(low).min(high)` gives it (a NaN `x`
/// gives `low`), by compare and select: `f32::max` and `f32::min` are
/// calls on the Cortex-M4F ([`crate::math::max`]).
#[inline(always)]
pub fn clamp(x: f32, low: f32, high: f32) -> f32 {
    min(high, max(low, x))
}

/// The velocity change of taking `a` now and then ramping the acceleration
/// back to zero at the jerk limit (`u = J dt` per tick), per second times
/// seconds: `F(a)` of the module docs.
#[inline(never)]
pub fn settle_change(a: f32, u: f32, dt: f32) -> f32 {
    let x = a.abs();
    let m = floor_non_negative(x / u);
    let f = dt * ((m + 1.0) * x - 0.5 * u * m * (m + 1.0));
    if a < 0.0 {
        -f
    } else {
        f
    }
}

/// The acceleration `a` with [`settle_change`]`(a) = e`: the time-optimal
/// first move toward a velocity `e` away. Finite for finite `e`.
#[inline(never)]
pub fn acceleration_for(e: f32, u: f32, dt: f32) -> f32 {
    acceleration_for_inline(e, u, dt)
}

/// [`acceleration_for`] inline: [`braking`]'s, which the stop test runs for
/// every joint at every tick of every stop it simulates.
#[inline(always)]
fn acceleration_for_inline(e: f32, u: f32, dt: f32) -> f32 {
    let x = e.abs() / (dt * u);
    // Largest m with m (m + 1) / 2 <= x.
    // (`max` with 0 first: a NaN gives 0.)
    let m = max(
        0.0,
        floor_non_negative(0.5 * (crate::math::sqrt_inline(1.0 + 8.0 * x) - 1.0)),
    );
    let a = e.abs() / (dt * (m + 1.0)) + 0.5 * u * m;
    if e < 0.0 {
        -a
    } else {
        a
    }
}

/// The accelerations a joint at velocity `v` (per second) and acceleration
/// `a` (per second squared) may take this tick and still stop within its
/// limits: `(low, high)`. When rounding (or a state from outside the model)
/// leaves it empty, the interval the jerk and acceleration limits allow,
/// narrowed toward stopping.
#[inline(never)]
pub fn viable(v: f32, a: f32, limits: &DriveLimits, dt: f32) -> (f32, f32) {
    let u = limits.max_jerk * dt;
    let jerk_low = max(-limits.max_accel, a - u);
    let jerk_high = min(limits.max_accel, a + u);
    let low = max(jerk_low, acceleration_for(-limits.max_rate - v, u, dt));
    let high = min(jerk_high, acceleration_for(limits.max_rate - v, u, dt));
    if low <= high {
        (low, high)
    } else {
        // Brake as hard as the jerk allows, in the direction that slows.
        let brake = if v > 0.0 { jerk_low } else { jerk_high };
        (brake, brake)
    }
}

/// The acceleration that moves a joint toward the velocity `target` (per
/// second) fastest, within [`viable`].
#[inline(never)]
pub fn toward(v: f32, a: f32, target: f32, limits: &DriveLimits, dt: f32) -> f32 {
    let (low, high) = viable(v, a, limits, dt);
    let wanted = acceleration_for(target - v, limits.max_jerk * dt, dt);
    clamp(wanted, low, high)
}

/// The acceleration of a joint's next tick of braking to rest: [`toward`]
/// velocity 0, in one [`acceleration_for`] instead of three. Toward rest
/// the stop limits of [`viable`] never bind: `F(a') = -v` lies within
/// `[-V - v, V - v]`, so the move is `F^-1(-v)` within the jerk and
/// acceleration limits alone (and where [`viable`] is empty, that is the
/// side it brakes to as well).
#[inline]
pub fn braking(v: f32, a: f32, limits: &DriveLimits, dt: f32) -> f32 {
    if v == 0.0 && a == 0.0 {
        return 0.0;
    }
    let u = limits.max_jerk * dt;
    let low = max(-limits.max_accel, a - u);
    let high = min(limits.max_accel, a + u);
    clamp(acceleration_for_inline(-v, u, dt), low, high)
}

/// A bound on how far (length units or radians) a joint at velocity `v`
/// and acceleration `a` gets from where it is while it brakes to rest at its
/// limits (the module docs), either way: the larger of [`stopping_span`]'s
/// two sides.
#[inline(never)]
pub fn stopping_travel(v: f32, a: f32, limits: &DriveLimits, dt: f32) -> f32 {
    let (below, above) = stopping_span(v, a, limits, dt);
    below.max(above)
}

/// Bounds on how far below and above where it is a joint at velocity `v`
/// and acceleration `a` gets while it brakes to rest at its limits: the
/// forward bound on the side it moves to, and on the other side the way
/// back when an acceleration against the motion is too large to take out
/// before the velocity passes zero. Both include [`ROUNDING`].
#[inline(never)]
pub fn stopping_span(v: f32, a: f32, limits: &DriveLimits, dt: f32) -> (f32, f32) {
    let down = v < 0.0 || (v == 0.0 && a < 0.0);
    let (w0, forward) = if down { (-v, -a) } else { (v, a) };
    let u = limits.max_jerk * dt;
    let ahead = if forward >= 0.0 {
        // While a forward acceleration ramps out: `F(a - u)` more speed,
        // at most `ceil(a / u) - 1` ticks more.
        let (rise, rise_ticks) = if forward > 0.0 {
            let rest = max(0.0, forward - u);
            (settle_change(rest, u, dt), libm::ceilf(forward / u) - 1.0)
        } else {
            (0.0, 0.0)
        };
        let w = w0 + rise;
        w * dt * (max(0.0, rise_ticks) + 1.0) + stop_from(w, limits)
    } else {
        decelerating(w0, forward, limits, dt)
    };
    // An acceleration against the motion larger than the velocity can
    // absorb: ramped out from the next tick (`a + u`, `a + 2u`, ...), the
    // velocity passes zero by at most `-(v + F(a + u))`, within
    // `ceil(|a| / u) + 1` ticks.
    let back_speed = if forward < 0.0 {
        max(0.0, -(w0 + settle_change(min(0.0, forward + u), u, dt)))
    } else {
        0.0
    };
    let back = if back_speed > 0.0 {
        back_speed * dt * (libm::ceilf(-forward / u) + 2.0) + stop_from(back_speed, limits)
    } else {
        0.0
    };
    // f32 rounding of speeds near zero.
    let slack = ROUNDING * limits.max_rate * dt;
    if down {
        (ahead + slack, back + slack)
    } else {
        (back + slack, ahead + slack)
    }
}

/// Travel [`stopping_span`] adds for the rounding of speeds near zero,
/// as a fraction of a tick at the rate limit.
pub const ROUNDING: f32 = 1.0e-5;

/// The highest speed (per second) from which a joint at zero acceleration
/// stops within `room` (radians or length units) taking one more tick at
/// that speed first: `w dt + w (w / A + A / J) / 2 <= room` (the stop with
/// a phase at `-A`, which bounds the one without: `(x + 1) / 2 >= sqrt x`).
/// The tracker's target near a goal or a joint limit, so the joint brakes
/// in time instead of at the last tick.
#[inline(never)]
pub fn braking_speed(room: f32, limits: &DriveLimits, dt: f32) -> f32 {
    if room.is_nan() || room <= 0.0 {
        return 0.0;
    }
    let accel = limits.max_accel;
    let b = 0.5 * accel / limits.max_jerk + dt;
    accel * (sqrt(b * b + 2.0 * room / accel) - b)
}

/// The forward part of a stop from speed `w0 > 0` with an acceleration
/// `-d < 0` against it. Every braking tick's acceleration is at most the
/// ramp-out's (`-d + u`, `-d + 2u`, ..., 0; by induction), so the speeds are
/// at most the ramp-out's: the first tick exactly, then (the ramp-out's
/// speeds are convex in the tick) under the chord to its end speed
/// `w0 + F(-d + u)` after `K = ceil(d / u)` ticks, then the stop from there.
#[inline(never)]
fn decelerating(w0: f32, forward: f32, limits: &DriveLimits, dt: f32) -> f32 {
    let u = limits.max_jerk * dt;
    let first = min(0.0, forward + u);
    let v1 = w0 + first * dt;
    if v1 <= 0.0 {
        return 0.0;
    }
    let ticks = max(1.0, libm::ceilf(-forward / u));
    let end = w0 + settle_change(first, u, dt);
    let chord = if end >= 0.0 {
        v1 * dt + (ticks - 1.0) * dt * 0.5 * (v1 + end) + end * dt + stop_from(end, limits)
    } else {
        // The chord from (1, v1) to (ticks, end) crosses zero at 1 + c.
        let c = (ticks - 1.0) * v1 / (v1 - end);
        v1 * dt + 0.5 * dt * v1 * c
    };
    // The stop already under way: the tail, after `d / J` seconds, of the
    // continuous stop from rest acceleration at `w0 + d^2 / 2J`, when that
    // stop's deceleration passes `d`; plus half a tick of discrete lag.
    let (d, jerk) = (-forward, limits.max_jerk);
    let virtual_speed = w0 + 0.5 * d * d / jerk;
    let peak = min(limits.max_accel, sqrt(jerk * virtual_speed));
    if d <= peak {
        let t1 = d / jerk;
        let under_way = stop_from(virtual_speed, limits)
            - (virtual_speed * t1 - jerk * t1 * t1 * t1 / 6.0)
            + 0.5 * w0 * dt;
        chord.min(under_way)
    } else {
        chord
    }
}

/// The continuous jerk-limited stop from speed `w` at zero acceleration:
/// `w (w / A + A / J) / 2` with a phase at `-A`, `w sqrt(w / J)` without.
#[inline(never)]
fn stop_from(w: f32, limits: &DriveLimits) -> f32 {
    let (jerk, accel) = (limits.max_jerk, limits.max_accel);
    if w * jerk >= accel * accel {
        0.5 * w * (w / accel + accel / jerk)
    } else {
        w * sqrt(w / jerk)
    }
}
