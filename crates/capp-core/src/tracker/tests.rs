//! The tracker against independent computations: the settling change
//! summed tick by tick, the limits read back from the positions' own
//! differences (in `f64`), the stop simulated to rest.

use super::limits::DriveLimits;
use super::profile::{
    acceleration_for, braking_speed, settle_change, stopping_span, stopping_travel, viable,
};
use super::{turnaround_ticks, DriveState, MAX_TURNAROUND_TICKS};
use crate::escape::rng::Rng;
use std::vec;
use std::vec::Vec;

/// Uniform in `[lo, hi)`.
fn range(rng: &mut Rng, lo: f32, hi: f32) -> f32 {
    lo + (hi - lo) * 0.5 * (rng.uniform() + 1.0)
}

fn random_limits(rng: &mut Rng) -> DriveLimits {
    let max_rate = range(rng, 0.05, 3.0);
    let max_accel = max_rate / range(rng, 0.05, 1.5);
    DriveLimits {
        max_rate,
        max_accel,
        max_jerk: max_accel / range(rng, 0.02, 0.5),
    }
}

/// `F(a)` the long way: take `a`, then step the acceleration toward zero by
/// `u` a tick, summing the velocity changes, in `f64`.
fn settle_by_ticks(a: f64, u: f64, dt: f64) -> f64 {
    let mut acc = a;
    let mut change = 0.0;
    loop {
        change += acc * dt;
        if acc == 0.0 {
            return change;
        }
        acc = if acc.abs() <= u {
            0.0
        } else {
            acc - u * acc.signum()
        };
    }
}

#[test]
fn settle_change_is_the_sum_over_ticks_and_its_inverse_inverts_it() {
    let mut rng = Rng::seeded(7, &[]);
    for _ in 0..2000 {
        let dt = range(&mut rng, 0.001, 0.2);
        let u = range(&mut rng, 0.01, 20.0) * dt;
        let a = rng.uniform() * range(&mut rng, 0.0, 40.0) * u;
        let by_ticks = settle_by_ticks(a as f64, u as f64, dt as f64);
        let closed = settle_change(a, u, dt) as f64;
        assert!(
            (closed - by_ticks).abs() <= 1e-4 * by_ticks.abs() + 1e-9,
            "a {a} u {u} dt {dt}: {closed} vs {by_ticks}"
        );
        let back = acceleration_for(settle_change(a, u, dt), u, dt);
        assert!((back - a).abs() <= 1e-4 * (a.abs() + u), "{a} -> {back}");
        // Increasing.
        let b = a + 0.01 * u;
        assert!(settle_change(b, u, dt) > settle_change(a, u, dt));
    }
}

/// Positions in `f64` from a run of ticks, and their backward differences
/// with rest before the first row: the largest `|v|/V`, `|a|/A`, `|j|/J`.
fn worst_ratios(rows: &[f64], l: &DriveLimits, dt: f64) -> (f64, f64, f64) {
    let at = |k: isize| rows[k.max(0) as usize];
    let (mut rv, mut ra, mut rj) = (0.0f64, 0.0f64, 0.0f64);
    for k in 0..rows.len() as isize {
        let v = |k: isize| (at(k) - at(k - 1)) / dt;
        let a = |k: isize| (v(k) - v(k - 1)) / dt;
        let j = (a(k) - a(k - 1)) / dt;
        rv = rv.max(v(k).abs() / l.max_rate as f64);
        ra = ra.max(a(k).abs() / l.max_accel as f64);
        rj = rj.max(j.abs() / l.max_jerk as f64);
    }
    (rv, ra, rj)
}

#[test]
fn any_target_sequence_keeps_rate_acceleration_and_jerk_within_limits() {
    let mut rng = Rng::seeded(11, &[]);
    const N: usize = 6;
    for _ in 0..200 {
        let limits: Vec<DriveLimits> = (0..N).map(|_| random_limits(&mut rng)).collect();
        let dt = range(&mut rng, 0.005, 0.1);
        let mut state = DriveState::<N>::at_rest(N);
        let mut rows: Vec<[f64; N]> = vec![[0.0; N]];
        let mut target = [0.0f32; N];
        for tick in 0..400 {
            // Targets jump at random times, beyond the limits too, or brake.
            if tick % 7 == 0 || rng.uniform() > 0.8 {
                for (t, l) in target.iter_mut().zip(&limits) {
                    *t = rng.uniform() * 1.5 * l.max_rate;
                }
            }
            state = if rng.uniform() > 0.9 {
                state.braking(&limits, dt)
            } else {
                state.toward(&limits, dt, &target)
            };
            let mut row = *rows.last().unwrap();
            for (q, &v) in row.iter_mut().zip(state.velocity()) {
                *q += v as f64 * dt as f64;
            }
            rows.push(row);
        }
        for (j, l) in limits.iter().enumerate() {
            let column: Vec<f64> = rows.iter().map(|r| r[j]).collect();
            let (rv, ra, rj) = worst_ratios(&column, l, dt as f64);
            assert!(rv <= 1.0 + 1e-4, "rate {rv}");
            assert!(ra <= 1.0 + 1e-4, "acceleration {ra}");
            assert!(rj <= 1.0 + 1e-3, "jerk {rj}");
        }
    }
}

#[test]
fn from_rest_the_joints_move_along_the_target_direction_and_arrive_together() {
    let mut rng = Rng::seeded(3, &[]);
    const N: usize = 5;
    for _ in 0..100 {
        let limits: Vec<DriveLimits> = (0..N).map(|_| random_limits(&mut rng)).collect();
        let dt = 0.05;
        let target: Vec<f32> = limits.iter().map(|l| rng.uniform() * l.max_rate).collect();
        let settled = |s: &[f32], a: &[f32], t: &[f32]| {
            s.iter()
                .zip(a)
                .zip(t)
                .zip(&limits)
                .all(|(((&v, &a), &t), l)| {
                    (v - t).abs() <= 1e-4 * l.max_rate && a.abs() <= 1e-3 * l.max_accel
                })
        };
        // Each joint alone, as fast as its own limits allow.
        let mut slowest_alone = 0;
        for (l, &t) in limits.iter().zip(&target) {
            let mut alone = DriveState::<1>::at_rest(1);
            let mut ticks = 0;
            while (alone.velocity()[0] - t).abs() > 1e-4 * l.max_rate
                || alone.acceleration()[0].abs() > 1e-3 * l.max_accel
            {
                alone = alone.toward(&[*l], dt, &[t]);
                ticks += 1;
            }
            slowest_alone = slowest_alone.max(ticks);
        }
        let mut state = DriveState::<N>::at_rest(N);
        let mut ticks = 0;
        while !settled(state.velocity(), state.acceleration(), &target) {
            state = state.toward(&limits, dt, &target);
            ticks += 1;
            assert!(ticks < 1000);
            // Parallel to the target: v = s * target for one s.
            let s = state.velocity()[0] / target[0];
            for (j, (&v, &t)) in state.velocity().iter().zip(&target).enumerate() {
                assert!(
                    (v - s * t).abs() <= 1e-4 * limits[j].max_rate,
                    "tick {ticks}, joint {j}: {v} vs {s} x {t}"
                );
            }
        }
        // Together, and not much later than the slowest joint alone (phase
        // synchronisation is not always time-optimal: which joint limits the
        // fraction changes as the accelerations ramp).
        assert!(
            ticks as f32 <= 1.15 * slowest_alone as f32 + 1.0,
            "{ticks} ticks, slowest alone {slowest_alone}"
        );
    }
}

#[test]
fn from_rest_to_full_rate_takes_the_time_optimal_number_of_ticks() {
    // V 1, A 2 (0.5 s), J 20 (0.1 s), dt 0.05: ramp 2 ticks, hold, ramp 2.
    let l = DriveLimits::from_rate(1.0);
    let dt = 0.05;
    let mut state = DriveState::<1>::at_rest(1);
    let mut ticks = 0;
    while (state.velocity()[0] - 1.0).abs() > 1e-5 || state.acceleration()[0].abs() > 1e-4 {
        state = state.toward(&[l], dt, &[1.0]);
        ticks += 1;
        assert!(ticks < 100);
    }
    // Accelerations 1, 2 (x 9), 1, 0: the velocity 0.05, 0.1 x 9, 0.05 adds
    // up to 1 in 11 ticks and the acceleration is out in the 12th, the
    // continuous V / A + A / J = 0.6 s.
    assert_eq!(ticks, 12);
}

#[test]
fn a_stop_reaches_rest_within_its_travel_bound() {
    let mut rng = Rng::seeded(5, &[]);
    let mut loosest = 0.0f64;
    for _ in 0..20_000 {
        let l = random_limits(&mut rng);
        let dt = range(&mut rng, 0.005, 0.1);
        // A state reached by the model: toward random targets.
        let mut state = DriveState::<1>::at_rest(1);
        for _ in 0..(1 + (range(&mut rng, 0.0, 40.0) as usize)) {
            let t = rng.uniform() * l.max_rate;
            state = state.toward(&[l], dt, &[t]);
        }
        let (v0, a0) = (state.velocity()[0], state.acceleration()[0]);
        let bound = stopping_travel(v0, a0, &l, dt) as f64;
        let (below, above) = stopping_span(v0, a0, &l, dt);
        let (mut q, mut reach, mut lowest, mut highest) = (0.0f64, 0.0f64, 0.0f64, 0.0f64);
        let mut ticks = 0;
        while state.velocity()[0].abs() > 1e-6 * l.max_rate
            || state.acceleration()[0].abs() > 1e-5 * l.max_accel
        {
            state = state.braking(&[l], dt);
            q += state.velocity()[0] as f64 * dt as f64;
            reach = reach.max(q.abs());
            lowest = lowest.min(q);
            highest = highest.max(q);
            ticks += 1;
            assert!(ticks < 10_000, "no rest from v {v0}, a {a0}");
        }
        assert!(
            reach <= bound * (1.0 + 1e-4) + 1e-9,
            "v {v0} a {a0} {l:?} dt {dt}: went {reach}, bound {bound}"
        );
        assert!(
            -lowest <= below as f64 * (1.0 + 1e-4) + 1e-9,
            "v {v0} a {a0}: below {lowest} vs {below}"
        );
        assert!(
            highest <= above as f64 * (1.0 + 1e-4) + 1e-9,
            "v {v0} a {a0}: above {highest} vs {above}"
        );
        // How loose: the bound's excess over the stop, in ticks at the
        // rate limit (its discrete lag and the continuous stop it is built
        // on cost about a tick).
        let excess = (bound - reach) / (l.max_rate as f64 * dt as f64);
        loosest = loosest.max(excess);
    }
    assert!(
        loosest < 3.0,
        "bound up to {loosest} ticks at the rate limit beyond the stop"
    );
}

#[test]
fn the_viable_interval_is_never_empty_along_the_model() {
    let mut rng = Rng::seeded(9, &[]);
    for _ in 0..500 {
        let l = random_limits(&mut rng);
        let dt = range(&mut rng, 0.005, 0.1);
        let mut state = DriveState::<1>::at_rest(1);
        for _ in 0..200 {
            let (v, a) = (state.velocity()[0], state.acceleration()[0]);
            let (low, high) = viable(v, a, &l, dt);
            assert!(
                low <= high + 1e-5 * l.max_accel,
                "v {v} a {a}: {low} > {high}"
            );
            let t = rng.uniform() * 2.0 * l.max_rate;
            state = state.toward(&[l], dt, &[t]);
        }
    }
}

#[test]
fn targets_that_are_not_finite_are_read_as_rest() {
    let l = DriveLimits::from_rate(1.0);
    let mut state = DriveState::<2>::at_rest(2);
    for _ in 0..50 {
        state = state.toward(&[l, l], 0.05, &[f32::NAN, f32::INFINITY]);
        assert!(state.velocity().iter().all(|v| v.is_finite()));
    }
    assert!(state.is_at_rest(&[l, l], 1e-6));
}

#[test]
fn from_the_braking_speed_the_stop_fits_in_the_room() {
    let mut rng = Rng::seeded(13, &[]);
    for _ in 0..2000 {
        let l = random_limits(&mut rng);
        let dt = range(&mut rng, 0.005, 0.1);
        let room = range(&mut rng, 0.0, 2.0) * l.max_rate;
        let w = braking_speed(room, &l, dt).min(l.max_rate);
        let mut state = DriveState::<1>::at_rest(1);
        // Reach w first (positions do not matter), then measure.
        for _ in 0..10_000 {
            if (state.velocity()[0] - w).abs() <= 1e-6 * l.max_rate
                && state.acceleration()[0].abs() <= 1e-5 * l.max_accel
            {
                break;
            }
            state = state.toward(&[l], dt, &[w]);
        }
        let mut q = 0.0f64;
        state = state.toward(&[l], dt, &[w]);
        q += state.velocity()[0] as f64 * dt as f64;
        while state.velocity()[0].abs() > 1e-6 * l.max_rate
            || state.acceleration()[0].abs() > 1e-5 * l.max_accel
        {
            state = state.braking(&[l], dt);
            q += state.velocity()[0] as f64 * dt as f64;
        }
        assert!(
            q <= room as f64 * (1.0 + 1e-4) + 1e-6 * l.max_rate as f64,
            "room {room}, w {w}: {q}"
        );
    }
}

/// The tick and stop of `after` from `q`: the joint displacements at every
/// tick, and three points between each two (the joints move on straight
/// segments between ticks).
fn stop_samples<const N: usize>(
    after: &DriveState<N>,
    limits: &[DriveLimits],
    dt: f32,
) -> Vec<Vec<f32>> {
    let n = after.velocity().len();
    let mut x = vec![0.0f32; n];
    let mut out = vec![];
    let mut state = *after;
    loop {
        let before = x.clone();
        for (xj, &v) in x.iter_mut().zip(state.velocity()) {
            *xj += v * dt;
        }
        for s in [0.25f32, 0.5, 0.75, 1.0] {
            out.push(
                before
                    .iter()
                    .zip(&x)
                    .map(|(a, b)| a + (b - a) * s)
                    .collect(),
            );
        }
        if state.is_at_rest(limits, 0.0) || out.len() > 4 * 200 {
            return out;
        }
        state = state.braking(limits, dt);
    }
}

/// A random revolute chain of `n` links (metres, radians).
fn random_chain(rng: &mut Rng, n: usize) -> Vec<crate::Joint> {
    (0..n)
        .map(|_| {
            crate::Joint::revolute(
                rng.uniform() * 3.1,
                range(rng, 0.0, 0.6),
                range(rng, 0.0, 0.4),
                -3.0,
                3.0,
                range(rng, 0.3, 2.0),
            )
        })
        .collect()
}

/// Joints of the stop tests' arms.
const N: usize = 8;

/// The robot of `joints` (DH) and their drive limits (the defaults from
/// each rate); with `segments`, as general joints whose capsules are
/// segments of their own, up to 0.5 off their chords and beyond their ends.
fn arm_of(
    rng: &mut Rng,
    joints: &[crate::Joint],
    segments: bool,
) -> (crate::Robot<N>, Vec<DriveLimits>) {
    let limits = joints
        .iter()
        .map(|j| DriveLimits::from_rate(j.max_rate))
        .collect();
    if !segments {
        return (crate::Robot::<N>::new(joints).unwrap(), limits);
    }
    let mut general = joints.to_vec();
    let tool = crate::robot::general_from_dh(joints, &mut general);
    let mut robot = crate::Robot::<N>::new_with_tool(&general, &tool).unwrap();
    let ends: Vec<[[f32; 3]; 2]> = joints
        .iter()
        .map(|_| [0, 1].map(|_| [0, 1, 2].map(|_| 0.5 * rng.uniform())))
        .collect();
    robot.set_link_segments(&ends).unwrap();
    (robot, limits)
}

/// A random 3- to 7-joint chain at a random configuration, moving: a few
/// ticks from rest toward random velocities (the stop tests' state).
struct MovingArm {
    n: usize,
    robot: crate::Robot<N>,
    limits: Vec<DriveLimits>,
    q: Vec<f32>,
    dt: f32,
    after: DriveState<N>,
    frames: crate::kinematics::Frames<N>,
}

impl MovingArm {
    fn random(rng: &mut Rng) -> Self {
        let n = 3 + (range(rng, 0.0, 5.0) as usize);
        let joints = random_chain(rng, n);
        // Half the arms as general joints whose capsules are segments of
        // their own.
        let segments = rng.uniform() > 0.0;
        let (robot, limits) = arm_of(rng, &joints, segments);
        let q: Vec<f32> = (0..n).map(|_| rng.uniform() * 2.0).collect();
        let dt = 0.05;
        let mut after = DriveState::<N>::at_rest(n);
        let target: Vec<f32> = limits.iter().map(|l| rng.uniform() * l.max_rate).collect();
        for _ in 0..(1 + range(rng, 0.0, 15.0) as usize) {
            after = after.toward(&limits, dt, &target);
        }
        let mut frames = crate::kinematics::Frames::<N>::default();
        crate::kinematics::forward_kinematics(&robot, &q, &mut frames);
        MovingArm {
            n,
            robot,
            limits,
            q,
            dt,
            after,
            frames,
        }
    }
}

/// Soundness of [`stop_is_clear`]: for each link alone given a room just
/// under how far its points really go during the tick and the stop (forward
/// kinematics at every tick and between ticks), the test must refuse; and
/// the same for a pair's gap under how far the later link moves when only
/// the joints between the two move. A bound below the truth on any link or
/// pair fails here.
#[test]
fn a_cleared_stop_never_moves_a_link_farther_than_its_room() {
    use super::clearance::stop_is_clear;
    use crate::kinematics::{forward_kinematics, Frames};
    use crate::self_collision::field::LinkPair;
    let mut rng = Rng::seeded(17, &[]);
    let (mut refused, mut pairs_refused) = (0, 0);
    for _ in 0..150 {
        let MovingArm {
            n,
            robot,
            limits,
            q,
            dt,
            after,
            frames,
        } = MovingArm::random(&mut rng);
        let points = |f: &Frames<N>, k: usize| {
            let (start, end) = f.capsule(k);
            [
                f.pivot(k),
                (f.pivot(k) + f.link_end(k)) * 0.5,
                f.link_end(k),
                start,
                (start + end) * 0.5,
                end,
            ]
        };
        // How far each link's points go, and link b under joints a+1..=b alone.
        let samples = stop_samples(&after, &limits, dt);
        let mut travel = vec![0.0f32; n];
        let (a, b) = (0usize, n - 1);
        let mut relative = 0.0f32;
        let mut moved = Frames::<N>::default();
        for x in &samples {
            let qx: Vec<f32> = q.iter().zip(x).map(|(q, x)| q + x).collect();
            forward_kinematics(&robot, &qx, &mut moved);
            for (k, t) in travel.iter_mut().enumerate() {
                for (p0, p1) in points(&frames, k).iter().zip(points(&moved, k)) {
                    *t = t.max((p1 - p0).norm());
                }
            }
            let partial: Vec<f32> = q
                .iter()
                .zip(x)
                .enumerate()
                .map(|(m, (q, x))| if m > a { q + x } else { *q })
                .collect();
            forward_kinematics(&robot, &partial, &mut moved);
            // A pair's gap is between capsules: the last three points.
            for (p0, p1) in points(&frames, b).iter().zip(points(&moved, b)).skip(3) {
                relative = relative.max((p1 - p0).norm());
            }
        }
        let roomy = [f32::INFINITY; N];
        assert!(stop_is_clear(
            &robot,
            &frames,
            &roomy[..n],
            &[None; N][..n],
            &[],
            &after,
            &limits,
            dt,
            1.0
        ));
        for k in 0..n {
            if travel[k] < 1e-4 {
                continue;
            }
            let mut rooms = [f32::INFINITY; N];
            rooms[k] = (0.99 * travel[k]).powi(2);
            assert!(
                !stop_is_clear(
                    &robot,
                    &frames,
                    &rooms[..n],
                    &[None; N][..n],
                    &[],
                    &after,
                    &limits,
                    dt,
                    1.0
                ),
                "link {k} goes {} but was cleared with room {}",
                travel[k],
                0.99 * travel[k]
            );
            refused += 1;
        }
        if relative > 1e-4 {
            let pair = LinkPair {
                clearance: 1.0,
                gap: 0.99 * relative,
                links: [a as u8, b as u8],
            };
            assert!(
                !stop_is_clear(
                    &robot,
                    &frames,
                    &roomy[..n],
                    &[None; N][..n],
                    &[pair],
                    &after,
                    &limits,
                    dt,
                    1.0
                ),
                "link {b} moves {relative} against link {a} but was cleared with gap {}",
                0.99 * relative
            );
            pairs_refused += 1;
        }
    }
    assert!(
        refused > 200 && pairs_refused > 50,
        "{refused} links, {pairs_refused} pairs tested"
    );
}

/// [`stop_margin`](super::clearance::stop_margin), below
/// [`EXACT_MARGIN`](super::clearance::EXACT_MARGIN) (refused or cleared),
/// is the room the test needs, as a ratio: with every room scaled by `1 /
/// margin` (a hair more) the same tick and stop are cleared, and with a
/// hair less refused, for a link's own room and for a pair's gap alike.
/// The tick sizes its next candidate from it, and its speed-up after a
/// taken tick. (From `EXACT_MARGIN` on the true margin is only known to be
/// at least that: pairs the joints' travel bounds clear by that much are
/// not followed, so the value may name more room than the stop leaves;
/// with them left out from a margin of 1, this test fails.)
#[test]
fn the_stop_margin_is_the_share_of_room_the_stop_needs() {
    use super::clearance::{stop_is_clear, stop_margin};
    use crate::self_collision::field::LinkPair;
    let mut rng = Rng::seeded(29, &[]);
    let mut tested = 0;
    for _ in 0..120 {
        let MovingArm {
            n,
            robot,
            limits,
            q: _,
            dt,
            after,
            frames,
        } = MovingArm::random(&mut rng);
        let mut rooms = [0.0f32; N];
        for r in rooms[..n].iter_mut() {
            *r = range(&mut rng, 0.01, 0.5);
        }
        let gap = range(&mut rng, 0.01, 0.5);
        let pair = [LinkPair {
            clearance: 1.0,
            gap,
            links: [0, (n - 1) as u8],
        }];
        let fraction = range(&mut rng, 0.3, 1.0);
        let check = |scale: f32| {
            let rooms_sq: Vec<f32> = rooms[..n].iter().map(|r| (r * scale).powi(2)).collect();
            let scaled = [LinkPair {
                gap: gap * scale,
                ..pair[0]
            }];
            stop_is_clear(
                &robot,
                &frames,
                &rooms_sq,
                &[None; N][..n],
                &scaled,
                &after,
                &limits,
                dt,
                fraction,
            )
        };
        let rooms_sq: Vec<f32> = rooms[..n].iter().map(|r| r * r).collect();
        let mut travel = vec![0.0f32; n];
        after.excursion(&limits, dt, &mut travel);
        let margin = stop_margin(
            &robot,
            &frames,
            &rooms_sq,
            &[None; N][..n],
            &pair,
            &after,
            &travel,
            &limits,
            dt,
            fraction,
        )
        .margin;
        assert!(margin >= 0.0, "margin {margin}");
        // Exact below EXACT_MARGIN, clear or not (the tick's growth reads
        // margins above 1 too).
        if !(margin > 1e-3 && margin < super::clearance::EXACT_MARGIN) {
            continue;
        }
        assert!(
            check(1.001 / margin),
            "margin {margin}: not cleared with the room it names"
        );
        assert!(
            !check(0.999 / margin),
            "margin {margin}: cleared with less room than it names"
        );
        tested += 1;
    }
    assert!(tested > 80, "{tested} states tested");
}

/// A half-space of link `k`'s nearest obstacle: unit normal `normal`
/// (normalised here), both of the link's ends `room` or more inside it (the
/// nearer end exactly `room`), every other obstacle `others` away.
fn plane_of<const M: usize>(
    frames: &crate::kinematics::Frames<M>,
    k: usize,
    normal: [f32; 3],
    room: f32,
    others: f32,
) -> crate::avoidance::HalfSpace {
    let normal = crate::math::Vec3::from(normal).normalize();
    let offset = normal
        .dot(&frames.pivot(k))
        .min(normal.dot(&frames.link_end(k)))
        - room;
    crate::avoidance::HalfSpace {
        link: k as u8,
        normal: [normal.x, normal.y, normal.z],
        offset,
        others_sq: others * others,
    }
}

/// Two certificates clear a link's stop, either alone: its points within
/// its room in every direction (the ball), or its ends short of the
/// nearest obstacle's half-space and its points within their room from the
/// others (the plane). The plane's is sound on its own (forward kinematics
/// at every tick and between: a plane just inside the deepest point's
/// approach is refused), and the link's margin is the better of the two,
/// to the bit: a tilted plane that holds an end nearer than the ball's
/// room does not refuse a stop the ball clears. (Before, a link with a
/// plane was held to the plane alone: `ball wins` cases then fail.)
#[test]
fn either_certificate_clears_a_link_and_the_margin_is_the_better_one() {
    use super::clearance::{stop_is_clear, stop_margin};
    use crate::kinematics::{forward_kinematics, Frames};
    let mut rng = Rng::seeded(41, &[]);
    let (mut ball_wins, mut plane_wins, mut refused) = (0, 0, 0);
    for _ in 0..200 {
        let MovingArm {
            n,
            robot,
            limits,
            q,
            dt,
            after,
            frames,
        } = MovingArm::random(&mut rng);
        let k = (range(&mut rng, 0.0, n as f32) as usize).min(n - 1);
        let normal = [0, 1, 2].map(|_| rng.uniform());
        // The plane's soundness: the deepest approach of the link's chord
        // (its ends and middle, the avoidance points lie between) toward it.
        let probe = plane_of(&frames, k, normal, 0.0, f32::INFINITY);
        let n_hat = crate::math::Vec3::from(probe.normal);
        let depth = |f: &Frames<N>| {
            [
                f.pivot(k),
                (f.pivot(k) + f.link_end(k)) * 0.5,
                f.link_end(k),
            ]
            .map(|p| n_hat.dot(&p) - probe.offset)
        };
        let start = depth(&frames);
        let mut approach = 0.0f32;
        let mut moved = Frames::<N>::default();
        for x in stop_samples(&after, &limits, dt) {
            let qx: Vec<f32> = q.iter().zip(&x).map(|(q, x)| q + x).collect();
            forward_kinematics(&robot, &qx, &mut moved);
            // How far below the nearer end's starting room the chord goes.
            let lowest = depth(&moved).into_iter().fold(f32::INFINITY, f32::min);
            approach = approach.max(start[0].min(start[2]) - lowest);
        }
        let mut rooms = [f32::INFINITY; N];
        let mut planes = [None; N];
        let clear = |rooms: &[f32; N], planes: &[Option<crate::avoidance::HalfSpace>; N]| {
            stop_is_clear(
                &robot,
                &frames,
                &rooms[..n],
                &planes[..n],
                &[],
                &after,
                &limits,
                dt,
                1.0,
            )
        };
        if approach > 1e-4 {
            rooms[k] = 0.0;
            planes[k] = Some(plane_of(&frames, k, normal, 0.99 * approach, f32::INFINITY));
            assert!(
                !clear(&rooms, &planes),
                "link {k} approaches its plane by {approach} but was cleared with room {}",
                0.99 * approach
            );
            refused += 1;
        }
        // The margin with both certificates against each alone.
        let ball_room = range(&mut rng, 0.01, 0.5);
        let plane = plane_of(
            &frames,
            k,
            normal,
            range(&mut rng, 0.005, 0.3),
            ball_room + range(&mut rng, 0.0, 0.5),
        );
        let mut travel = vec![0.0f32; n];
        after.excursion(&limits, dt, &mut travel);
        let margin = |room: f32, plane: Option<crate::avoidance::HalfSpace>| {
            let mut rooms = [f32::INFINITY; N];
            rooms[k] = room * room;
            let mut planes = [None; N];
            planes[k] = plane;
            stop_margin(
                &robot,
                &frames,
                &rooms[..n],
                &planes[..n],
                &[],
                &after,
                &travel,
                &limits,
                dt,
                1.0,
            )
            .margin
        };
        let (ball, alone, both) = (
            margin(ball_room, None),
            margin(0.0, Some(plane)),
            margin(ball_room, Some(plane)),
        );
        assert_eq!(
            both.to_bits(),
            ball.max(alone).to_bits(),
            "link {k}: ball {ball}, plane {alone}, both {both}"
        );
        if ball > alone {
            ball_wins += 1;
        } else if alone > ball {
            plane_wins += 1;
        }
    }
    assert!(
        refused > 60 && ball_wins > 30 && plane_wins > 30,
        "{refused} planes refused, ball better {ball_wins}, plane better {plane_wins}"
    );
}

/// [`profile::braking`] is [`profile::toward`] velocity 0, to the bit, on
/// every state the model reaches (random moves toward random velocities
/// from rest), for random limits.
#[test]
fn braking_is_the_move_toward_rest() {
    use super::profile;
    let mut rng = Rng::seeded(31, &[]);
    let mut compared = 0;
    for _ in 0..200 {
        let l = DriveLimits {
            max_rate: range(&mut rng, 0.1, 4.0),
            max_accel: range(&mut rng, 0.2, 20.0),
            max_jerk: range(&mut rng, 1.0, 400.0),
        };
        let dt = range(&mut rng, 0.001, 0.1);
        let (mut v, mut a) = (0.0f32, 0.0f32);
        for _ in 0..40 {
            let target = range(&mut rng, -1.2, 1.2) * l.max_rate;
            a = profile::toward(v, a, target, &l, dt);
            v += a * dt;
            let fast = profile::braking(v, a, &l, dt);
            let slow = profile::toward(v, a, 0.0, &l, dt);
            assert_eq!(
                fast.to_bits(),
                slow.to_bits(),
                "v {v} a {a} {l:?} dt {dt}: {fast} != {slow}"
            );
            compared += 1;
        }
    }
    assert_eq!(compared, 8000);
}

#[test]
fn turnaround_ticks_cover_the_slowest_joints_reversal() {
    // Full rate one way to full rate the other: 2 v / A at full acceleration
    // plus A / J for its ramps; in ticks, rounded up, for the slowest joint.
    let mut rng = Rng::seeded(31, &[]);
    for _ in 0..1_000 {
        let n = range(&mut rng, 1.0, 7.0) as usize;
        let limits: Vec<DriveLimits> = (0..n).map(|_| random_limits(&mut rng)).collect();
        let dt = range(&mut rng, 0.001, 0.2);
        let slowest = limits
            .iter()
            .map(|l| {
                let (v, a, j) = (l.max_rate as f64, l.max_accel as f64, l.max_jerk as f64);
                2.0 * v / a + a / j
            })
            .fold(0.0f64, f64::max);
        let ticks = turnaround_ticks(&limits, dt) as f64;
        let exact = slowest / dt as f64;
        assert!(
            ticks >= exact * (1.0 - 1e-5) && ticks < exact * (1.0 + 1e-5) + 1.0,
            "{ticks} ticks for {exact}"
        );
    }
    let l = DriveLimits::from_rate(1.0);
    // The defaults: 2 x 0.5 s + 0.1 s = 1.1 s, 22 ticks of 0.05 s (23 if the
    // quotient rounds above 22).
    assert!((22..=23).contains(&turnaround_ticks(&[l], 0.05)));
    assert_eq!(turnaround_ticks(&[l], 0.0), 0);
    assert_eq!(turnaround_ticks(&[l], -0.05), 0);
    assert_eq!(turnaround_ticks(&[l], f32::NAN), 0);
    assert_eq!(turnaround_ticks(&[], 0.05), 0);
    assert_eq!(turnaround_ticks(&[l], 1e-30), MAX_TURNAROUND_TICKS);
}

/// [`super::slide::slide`] against forward kinematics: a point of a random
/// link, a random normal and a random velocity target within the rates;
/// moved a little along the slid target, the point goes along the surface
/// (its motion along the normal a small fraction of what the target gave
/// it), every joint stays within its rate, and a target that did not
/// approach is left as it was.
#[test]
fn a_slid_target_moves_the_point_along_the_surface_not_into_it() {
    use super::clearance::Approach;
    use super::slide::slide;
    use crate::kinematics::{forward_kinematics, Frames};
    use crate::math::Vec3;
    let mut rng = Rng::seeded(23, &[]);
    let (mut slid, mut left) = (0, 0);
    for _ in 0..400 {
        let MovingArm {
            n,
            robot,
            limits,
            q,
            frames,
            ..
        } = MovingArm::random(&mut rng);
        let link = (range(&mut rng, 0.0, n as f32) as usize).min(n - 1);
        let t = range(&mut rng, 0.0, 1.0);
        let on = |f: &Frames<N>| f.pivot(link) + (f.link_end(link) - f.pivot(link)) * t;
        let normal = Vec3::new(rng.uniform(), rng.uniform(), rng.uniform()).normalize();
        let approach = Approach {
            link,
            point: on(&frames),
            normal,
        };
        let aim: Vec<f32> = limits.iter().map(|l| rng.uniform() * l.max_rate).collect();
        // The point's motion along the normal for a displacement eps * x.
        let eps = 1e-3;
        let mut moved = Frames::<N>::default();
        let mut along = |x: &[f32]| {
            let qx: Vec<f32> = q.iter().zip(x).map(|(q, x)| q + eps * x).collect();
            forward_kinematics(&robot, &qx, &mut moved);
            normal.dot(&(on(&moved) - on(&frames))) / eps
        };
        let before = along(&aim);
        let mut after_aim = aim.clone();
        if slide(&robot, &limits, &frames, &approach, &mut after_aim) {
            slid += 1;
            assert!(before < 1e-2, "slid a target that moved away: {before}");
            let after = along(&after_aim);
            let speed = aim.iter().map(|a| a * a).sum::<f32>().sqrt();
            assert!(
                after.abs() <= 0.02 * before.abs() + 1e-3 * speed.max(1.0),
                "still approaching: {after} (was {before})"
            );
            for (a, l) in after_aim.iter().zip(&limits) {
                assert!(
                    a.abs() <= l.max_rate * (1.0 + 1e-6),
                    "{a} over {}",
                    l.max_rate
                );
            }
        } else {
            left += 1;
            assert_eq!(after_aim, aim);
            assert!(before > -1e-2, "an approach left alone: {before}");
        }
    }
    assert!(slid > 100 && left > 100, "slid {slid}, left {left}");
}

/// [`DriveState::reached_share`]: from rest one tick toward a target far
/// above what the jerk limit allows reaches only a small share of it (the
/// largest `|v / target|`); a tick that reached its share, a target of
/// zeros or NaN give the share as it was.
#[test]
fn a_tick_from_rest_reaches_a_small_share_of_a_large_target() {
    let mut rng = Rng::seeded(29, &[]);
    for _ in 0..500 {
        let n = 1 + range(&mut rng, 0.0, 6.0) as usize;
        let limits: Vec<DriveLimits> = (0..n).map(|_| random_limits(&mut rng)).collect();
        let target: Vec<f32> = limits.iter().map(|l| rng.uniform() * l.max_rate).collect();
        let dt = range(&mut rng, 0.01, 0.1);
        let next = DriveState::<N>::at_rest(n).toward(&limits, dt, &target);
        let reached = next.reached_share(&target, 1.0);
        let expected = next
            .velocity()
            .iter()
            .zip(&target)
            .filter(|(_, t)| **t != 0.0)
            .map(|(v, t)| (v / t).abs())
            .fold(0.0f32, f32::max)
            .min(1.0);
        assert_eq!(reached, expected);
        assert!(reached <= 1.0);
        assert_eq!(next.reached_share(&vec![0.0; n], 0.5), 0.5);
        assert_eq!(next.reached_share(&vec![f32::NAN; n], 0.5), 0.5);
        // A joint with no target does not count.
        let mut some = target.clone();
        some[0] = 0.0;
        let others = next
            .velocity()
            .iter()
            .zip(&some)
            .filter(|(_, t)| **t != 0.0)
            .map(|(v, t)| (v / t).abs())
            .fold(None, |m: Option<f32>, r| Some(m.map_or(r, |m| m.max(r))));
        assert_eq!(
            next.reached_share(&some, 1.0),
            others.map_or(1.0, |r| r.min(1.0))
        );
    }
    // Settled on its target: the share it was aimed at.
    let limits = [DriveLimits::from_rate(1.0)];
    let mut state = DriveState::<N>::at_rest(1);
    for _ in 0..200 {
        state = state.toward(&limits, 0.05, &[0.5]);
    }
    assert_eq!(state.reached_share(&[1.0], 0.5), 0.5);
    assert!(
        DriveState::<N>::at_rest(1)
            .toward(&limits, 0.05, &[1.0])
            .reached_share(&[1.0], 1.0)
            < 0.1
    );
}

/// The coarse bound that clears most link pairs before the stop test sums
/// their levers ([`TravelSums::need_bound`](super::clearance::TravelSums))
/// is never below that exact sum
/// ([`pair_need`](super::clearance::pair_need)): over random chains of
/// revolute and prismatic joints (DH, and half as general joints with
/// capsule segments off their chords), at random configurations, moving,
/// for every pair of links. So a pair it clears the exact sum clears too,
/// and the stop test's margins are what they were without it. It is not
/// vacuous: within 4x of the exact need on some pairs of every arm family.
#[test]
fn the_coarse_pair_bound_is_never_below_the_exact_need() {
    use super::clearance::{pair_need, TravelSums};
    let mut rng = Rng::seeded(41, &[]);
    let (mut pairs, mut close) = (0, 0);
    for arm in 0..300 {
        let n = 2 + (range(&mut rng, 0.0, 7.0) as usize).min(N - 2);
        let joints: Vec<crate::Joint> = (0..n)
            .map(|_| {
                if rng.uniform() > 0.4 {
                    crate::Joint::prismatic(
                        rng.uniform() * 3.1,
                        range(&mut rng, 0.0, 0.6),
                        rng.uniform() * 3.1,
                        range(&mut rng, -0.5, 0.0),
                        range(&mut rng, 0.0, 0.8),
                        range(&mut rng, 0.05, 0.5),
                    )
                } else {
                    crate::Joint::revolute(
                        rng.uniform() * 3.1,
                        range(&mut rng, 0.0, 0.6),
                        range(&mut rng, 0.0, 0.4),
                        -3.0,
                        3.0,
                        range(&mut rng, 0.3, 2.0),
                    )
                }
            })
            .collect();
        let (robot, limits) = arm_of(&mut rng, &joints, arm % 2 == 1);
        let q: Vec<f32> = joints
            .iter()
            .map(|j| j.min + (j.max - j.min) * range(&mut rng, 0.0, 1.0))
            .collect();
        let mut after = DriveState::<N>::at_rest(n);
        let target: Vec<f32> = limits.iter().map(|l| rng.uniform() * l.max_rate).collect();
        for _ in 0..(1 + range(&mut rng, 0.0, 15.0) as usize) {
            after = after.toward(&limits, 0.05, &target);
        }
        let mut travel = vec![0.0f32; n];
        after.excursion(&limits, 0.05, &mut travel);
        let mut frames = crate::kinematics::Frames::<N>::default();
        crate::kinematics::forward_kinematics(&robot, &q, &mut frames);
        let sums = TravelSums::new(&robot, &travel);
        for b in 1..n {
            for a in 0..b {
                let exact = pair_need(&robot, &frames, &travel, [a as u8, b as u8]);
                let bound = sums.need_bound(&robot, a, b);
                assert!(
                    bound >= exact,
                    "arm {arm}, links {a}-{b}: bound {bound} below the exact need {exact}"
                );
                pairs += 1;
                if bound <= 4.0 * exact {
                    close += 1;
                }
            }
        }
    }
    assert!(
        pairs > 2_000 && close > pairs / 4,
        "{close} of {pairs} pairs within 4x"
    );
}
