//! Conservative advancement for a tick and the stop after it.
//!
//! A tracked tick is taken only if every configuration the arm passes
//! through, during the tick and during the stop at the limits from the
//! tick's end, keeps every link point within `fraction` of its link's room
//! ([`crate::evaluation::Evaluation::distance_sq`]: the distance to every
//! inflated obstacle, and the link's share of the gap to every checked link)
//! of where it is now. The stop is simulated tick by tick (each joint
//! braking alone, [`super::DriveState::braking`]); between ticks the joints
//! move on straight segments.
//!
//! For a joint displacement `x` from the current configuration `q`, a point
//! `p` of link `k` moves by at most
//!
//! ```text
//! |p(q + x) - p(q)| <= |J_p(q) x| + Q_k(|x|)
//! ```
//!
//! whatever path led there: the Taylor remainder of `p` about `q` depends
//! only on `x`, and [`crate::step_size`]'s second-order bound `Q_k` (grown
//! with each `|x_m|`) bounds it along the straight segment from `q`. `J_p x`
//! is linear in `p` along a link, so a link's worst point is one of its
//! ends (of its chord, or of its capsule's own segment when it has one:
//! [`crate::kinematics::Frames::capsule`]), and linear in `x`, so along each straight segment of the stop it is
//! largest at one of the segment's ends: the ticks. So the test takes, per
//! link, the largest first-order travel over the ticks of the stop and
//! `Q_k` of each joint's largest excursion.
//!
//! A link clears its stop by either of two certificates, and its margin is
//! the better one's: the *ball* (every point moves less than its room,
//! in any direction), or, when the evaluation gave the link a half-space
//! of its nearest obstacle with both ends inside, the *plane* (each end
//! moves toward the plane, `-n . J x` over the ticks, less than its
//! distance from it, and every point less than its room from the other
//! obstacles). The plane lets a link slide along a surface it is close to;
//! the ball clears a link whose plane, tilted away from it, holds one end
//! nearer than the obstacle itself.

use super::limits::DriveLimits;
use super::DriveState;
use crate::avoidance::HalfSpace;
use crate::kinematics::Frames;
use crate::math::{max, min, Vec3};
use crate::robot::{JointKind, Robot};
use crate::self_collision::field::{LinkPair, MAX_CLOSE_PAIRS};
use crate::step_size::SecondOrder;

/// [`stop_margin`] is exact below this margin (at and above it, the true
/// margin is at least this, and may be below the value returned): the tick
/// grows its speed by up to its square root.
pub const EXACT_MARGIN: f32 = 2.25;

/// Most ticks of a stop the test simulates; a stop that has not reached
/// rest by then is not cleared.
pub const MAX_STOP_TICKS: usize = 128;

/// The term that bound a [`stop_margin`] when it was a link end moving
/// toward its obstacle's half-space: the one direction the tick can take out
/// of its velocity target to slide along the surface instead (the other
/// terms bound a travel in any direction).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Approach {
    /// The link (0-based joint).
    pub link: usize,
    /// The link's end that approaches, where it is now (world frame),
    /// length units.
    pub point: Vec3,
    /// The half-space's outward unit normal (world frame).
    pub normal: Vec3,
}

/// [`stop_margin`]'s answer.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct StopMargin {
    /// The least room over need (at least 1: clear).
    pub margin: f32,
    /// The term that set it, when a link end's approach to its half-space.
    pub approach: Option<Approach>,
}

/// Whether the tick to `after` (the drive state at the tick's end) and the
/// stop from there keep every link within `fraction` of its room
/// (`distance_sq`, its square, one per link) and every pair of `pairs`
/// within `fraction` of its gap, from the configuration of `frames`.
#[allow(clippy::too_many_arguments)]
pub fn stop_is_clear<const N: usize>(
    robot: &Robot<N>,
    frames: &Frames<N>,
    distance_sq: &[f32],
    planes: &[Option<HalfSpace>],
    pairs: &[LinkPair],
    after: &DriveState<N>,
    limits: &[DriveLimits],
    dt: f32,
    fraction: f32,
) -> bool {
    let mut travel = [0.0f32; N];
    let n = robot.len().min(N);
    after.excursion(limits, dt, &mut travel[..n]);
    stop_margin(
        robot,
        frames,
        distance_sq,
        planes,
        pairs,
        after,
        &travel[..n],
        limits,
        dt,
        fraction,
    )
    .margin
        >= 1.0
}

/// How much room the tick to `after` and the stop from there leave: the
/// least, over every link and pair of [`stop_is_clear`]'s test, of the room
/// it may use over the travel bound it needs (0 for a stop that does not
/// end within [`MAX_STOP_TICKS`], a room already used up, a value that is
/// not a number, or fewer `planes` than links). At least 1 means clear.
/// Below [`EXACT_MARGIN`] it is exact; from there on the true margin is
/// only known to be at least `EXACT_MARGIN`, and may be below the value
/// returned: a pair that each joint's travel bound alone clears with that
/// much to spare is left out of the least. The tick chooses how far to slow
/// its velocity target from a margin below 1, and how fast to speed up
/// from one above ([`crate::planner`]). `travel` must be each joint's
/// [`DriveState::excursion`] from `after` (the tick has it from its
/// joint-range check; [`stop_is_clear`] computes it): the pairs left out
/// are cleared by it, so a smaller one would leave out pairs the stop may
/// close.
#[allow(clippy::too_many_arguments)]
#[inline(never)]
pub fn stop_margin<const N: usize>(
    robot: &Robot<N>,
    frames: &Frames<N>,
    distance_sq: &[f32],
    planes: &[Option<HalfSpace>],
    pairs: &[LinkPair],
    after: &DriveState<N>,
    travel: &[f32],
    limits: &[DriveLimits],
    dt: f32,
    fraction: f32,
) -> StopMargin {
    let n = robot.len().min(N).min(distance_sq.len());
    // One plane entry per link (`None` for none), as the evaluation gives
    // them: fewer is a caller's error, which refuses the stop rather than
    // leave a link unchecked.
    if planes.len() < n {
        return StopMargin {
            margin: 0.0,
            approach: None,
        };
    }
    // The pairs whose gap the stop might close; the others, cleared with
    // [`EXACT_MARGIN`] to spare by each joint's travel bound alone
    // ([`pair_cleared`]), are not followed tick by tick (a margin below
    // `EXACT_MARGIN` is the same without them). In a block of its own, so
    // that the running sums' stack is the stop's arrays' too (the board's
    // stack budget).
    let travel = travel.get(..n).unwrap_or(travel);
    let mut watched = [false; MAX_CLOSE_PAIRS];
    {
        let sums = TravelSums::new(robot, travel);
        for (pair, w) in pairs.iter().zip(watched.iter_mut()) {
            *w = !pair_cleared(robot, frames, travel, &sums, pair, fraction / EXACT_MARGIN);
        }
    }
    // Squares of the largest travels, per link and per pair: square roots
    // once, at the end (the same bits: a correctly rounded root is
    // monotone).
    let mut first_sq = [0.0f32; N];
    let mut relative_sq = [0.0f32; MAX_CLOSE_PAIRS];
    let mut turn = [Vec3::zeros(); N];
    let mut shift = [Vec3::zeros(); N];
    // Each revolute joint's `z_j x o_j`, which every tick's field needs.
    let mut moment = [Vec3::zeros(); N];
    for (j, m) in moment[..n].iter_mut().enumerate() {
        *m = frames.axis(j).cross(&frames.pivot(j));
    }
    // Per link with a plane, the most either end moves toward it over the
    // ticks.
    let mut toward = [[0.0f32; 2]; N];
    let mut x = [0.0f32; N];
    let mut largest = [0.0f32; N];
    let mut state = *after;
    let mut ticks = 0;
    loop {
        for ((xj, big), &v) in x[..n]
            .iter_mut()
            .zip(&mut largest[..n])
            .zip(state.velocity())
        {
            *xj += v * dt;
            *big = max(*big, xj.abs());
        }
        first_order(
            robot,
            frames,
            &moment[..n],
            planes,
            &x[..n],
            &mut first_sq[..n],
            &mut toward[..n],
            &mut turn,
            &mut shift,
        );
        for ((pair, rel_sq), _) in pairs
            .iter()
            .zip(relative_sq.iter_mut())
            .zip(&watched)
            .filter(|(_, &w)| w)
        {
            let [a, b] = pair.links;
            let (a, b) = (a as usize, b as usize);
            if let (Some(wa), Some(wb), Some(ba), Some(bb)) =
                (turn.get(a), turn.get(b), shift.get(a), shift.get(b))
            {
                let (w, v) = (wb - wa, bb - ba);
                let at = |p: Vec3| (w.cross(&p) + v).norm_squared();
                let (start, end) = frames.capsule(b);
                let worst = max(at(start), at(end));
                *rel_sq = max(*rel_sq, worst);
            }
        }
        if state.is_at_rest(limits, 0.0) {
            break;
        }
        ticks += 1;
        if ticks > MAX_STOP_TICKS {
            return StopMargin {
                margin: 0.0,
                approach: None,
            };
        }
        state.brake(limits, dt);
    }
    // Second order: Q_k of the largest excursions (step_size's sums).
    // The least room over need, squared (a NaN anywhere gives 0).
    let mut least_sq = f32::INFINITY;
    // The term that set it, when a link end's approach to its half-space:
    // the link and the end (0 its pivot, 1 its far end).
    let mut bound: Option<(usize, usize)> = None;
    let mut q_sums = SecondOrder::default();
    for (k, ((joint, link), ((&size, &f_sq), &d_sq))) in robot
        .joints()
        .iter()
        .zip(robot.links())
        .zip(largest[..n].iter().zip(&first_sq[..n]).zip(distance_sq))
        .enumerate()
    {
        let mut second = q_sums.link(joint.kind, size, link.chain);
        if frames.has_segments() {
            second = q_sums.at(link.capsule_chain);
        }
        let travel = crate::math::sqrt(f_sq) + second;
        let travel_sq = travel * travel;
        // Two certificates, either of which clears the link alone: every
        // point stays within its room in every direction (the ball,
        // `d_sq`), or both ends stay short of the nearest obstacle's
        // half-space and every point within its room from the others (the
        // plane). The link's margin is the better of the two: a plane
        // tilted away from the link holds an end nearer than the obstacle
        // itself is (PIPS's bay: a truss link's pivot 1.9 in from the plane
        // of a payload 5.3 in away), and the ball clears a stop the plane
        // refuses.
        let ball_sq = ratio_sq(d_sq, travel_sq);
        let (mut link_sq, mut link_bound) = (ball_sq, None);
        if let Some(h) = planes.get(k).copied().flatten() {
            let normal = Vec3::new(h.normal[0], h.normal[1], h.normal[2]);
            let rooms = [frames.pivot(k), frames.link_end(k)].map(|p| normal.dot(&p) - h.offset);
            if rooms.iter().all(|&r| r > 0.0) {
                let mut plane_sq = ratio_sq(h.others_sq, travel_sq);
                let mut plane_bound = None;
                let toward = toward.get(k).copied().unwrap_or([f32::INFINITY; 2]);
                for (end, (&t, room)) in toward.iter().zip(rooms).enumerate() {
                    let need = t + second;
                    let end_sq = ratio_sq(room * room, need * need);
                    if end_sq < plane_sq {
                        (plane_sq, plane_bound) = (end_sq, Some((k, end)));
                    }
                }
                if plane_sq >= ball_sq {
                    (link_sq, link_bound) = (plane_sq, plane_bound);
                }
            }
        }
        if link_sq < least_sq {
            (least_sq, bound) = (link_sq, link_bound);
        }
    }
    for ((pair, &rel_sq), _) in pairs
        .iter()
        .zip(&relative_sq)
        .zip(&watched)
        .filter(|(_, &w)| w)
    {
        let need = crate::math::sqrt(rel_sq) + between(robot, &largest[..n], pair.links);
        let gap = max(pair.gap, 0.0);
        if lower(&mut least_sq, gap * gap, need * need) {
            bound = None;
        }
    }
    let approach = bound.and_then(|(k, end)| {
        let h = planes.get(k).copied().flatten()?;
        Some(Approach {
            link: k,
            point: if end == 0 {
                frames.pivot(k)
            } else {
                frames.link_end(k)
            },
            normal: Vec3::new(h.normal[0], h.normal[1], h.normal[2]),
        })
    });
    StopMargin {
        margin: fraction * crate::math::sqrt(least_sq),
        approach,
    }
}

/// Whether the stop cannot bring the pair's later link within its share of
/// the gap, by each joint's travel bound alone ([`pair_need`]); the
/// coarser [`TravelSums::need_bound`] first, which clears most pairs (over
/// PIPS + 8's tracked ticks, 96 % of the pairs cleared at all) in a few
/// instructions instead of a pass over the joints between the links with a
/// square root each.
#[inline(never)]
fn pair_cleared<const N: usize>(
    robot: &Robot<N>,
    frames: &Frames<N>,
    travel: &[f32],
    sums: &TravelSums<N>,
    pair: &LinkPair,
    fraction: f32,
) -> bool {
    let room = fraction * max(pair.gap, 0.0);
    let [a, b] = pair.links;
    // NaN anywhere: not cleared.
    room >= sums.need_bound(robot, a as usize, b as usize)
        || room >= pair_need(robot, frames, travel, pair.links)
}

/// How far the stop may bring link `links[1]` toward link `links[0]` by
/// each joint's travel bound alone: joint `j` stays within `travel[j]` of
/// where it is over the tick and the stop, so a point `p` of link `b`
/// moves against link `a` by at most `sum_{a < j <= b} travel_j |c_j(p)|`
/// to first order (`c_j(p) = z_j x (p - o_j)`, revolute; `z_j`,
/// prismatic), a bound of what the simulated stop finds (the triangle
/// inequality), plus the same second-order term ([`between`]).
pub(super) fn pair_need<const N: usize>(
    robot: &Robot<N>,
    frames: &Frames<N>,
    travel: &[f32],
    links: [u8; 2],
) -> f32 {
    let (a, b) = (links[0] as usize, links[1] as usize);
    let (start, end) = frames.capsule(b);
    let ends = [start, end];
    let mut reach = [0.0f32; 2];
    for j in a + 1..=b {
        let (Some(joint), Some(&s)) = (robot.joints().get(j), travel.get(j)) else {
            break;
        };
        let (z, o) = (frames.axis(j), frames.pivot(j));
        for (r, p) in reach.iter_mut().zip(&ends) {
            let lever = match joint.kind {
                JointKind::Revolute => {
                    let c = z.cross(&(p - o));
                    crate::math::sqrt_inline(c.dot(&c))
                }
                JointKind::Prismatic => 1.0,
            };
            *r += s * lever;
        }
    }
    max(reach[0], reach[1]) + between(robot, travel, links)
}

/// Per joint `k`, the sums of the travel bounds of joints `0..=k`, the
/// revolute joints' (radians) and the prismatic joints' (length units)
/// apart: [`pair_cleared`]'s first, coarser bound.
pub(super) struct TravelSums<const N: usize> {
    revolute: [f32; N],
    prismatic: [f32; N],
    /// How many joints are summed.
    joints: usize,
}

impl<const N: usize> TravelSums<N> {
    pub(super) fn new(robot: &Robot<N>, travel: &[f32]) -> Self {
        let mut sums = TravelSums {
            revolute: [0.0; N],
            prismatic: [0.0; N],
            joints: 0,
        };
        let (mut revolute, mut prismatic) = (0.0f32, 0.0f32);
        for (((joint, &s), r), p) in robot
            .joints()
            .iter()
            .zip(travel)
            .zip(sums.revolute.iter_mut())
            .zip(sums.prismatic.iter_mut())
        {
            match joint.kind {
                JointKind::Revolute => revolute += s,
                JointKind::Prismatic => prismatic += s,
            }
            (*r, *p) = (revolute, prismatic);
            sums.joints += 1;
        }
        sums
    }

    /// An upper bound of the need [`pair_cleared`] computes for link `b`
    /// when the joints `a + 1 ..= b` move (infinity for links out of order
    /// or beyond the joints summed), from `L`, link `b`'s `capsule_chain`
    /// less link `a`'s `chain` (the chain's length from `o_{a+1}` on, so at
    /// least `|p - o_j|` for every point `p` of link `b` and `j > a`), and
    /// the sums `T` of the revolute
    /// and `S` of the prismatic joints' travels over `a + 1 ..= b`. First
    /// order: a revolute joint's lever `|z_j x (p - o_j)|` is at most `L`, a
    /// prismatic joint's is 1: `L T + S`. Second order ([`between`]'s
    /// sums): `sum a_m = T^2` and every `a_m` weighs at most `L`, the sliding
    /// term at most `S T`: `L T^2 / 2 + S T`. The running sums' differences
    /// and the rounding of the exact sums are covered by relative slacks far
    /// above f32's rounding over 64 terms (1e-5 of the sums, 1e-4 of the
    /// bound), so a pair this clears the exact need clears too.
    pub(super) fn need_bound(&self, robot: &Robot<N>, a: usize, b: usize) -> f32 {
        let links = robot.links();
        let (Some(link_a), Some(link_b), Some(&ra), Some(&rb), Some(&pa), Some(&pb)) = (
            links.get(a),
            links.get(b),
            self.revolute.get(a),
            self.revolute.get(b),
            self.prismatic.get(a),
            self.prismatic.get(b),
        ) else {
            return f32::INFINITY;
        };
        if a >= b || b >= self.joints {
            return f32::INFINITY;
        }
        const SUMS: f32 = 1.0e-5;
        let lever = link_b.capsule_chain - link_a.chain + SUMS * link_b.capsule_chain;
        let turning = rb - ra + SUMS * rb;
        let sliding = pb - pa + SUMS * pb;
        let first = lever * turning + sliding;
        let second = (0.5 * lever * turning + sliding) * turning;
        (first + second) * (1.0 + 1.0e-4)
    }
}

/// `least_sq` lowered to [`ratio_sq`]`(room_sq, need_sq)`. Returns whether
/// it went lower.
#[inline]
fn lower(least_sq: &mut f32, room_sq: f32, need_sq: f32) -> bool {
    let ratio = ratio_sq(room_sq, need_sq);
    let before = *least_sq;
    *least_sq = min(*least_sq, ratio);
    *least_sq < before
}

/// `room_sq / need_sq`: infinity for no need, 0 for a NaN or a negative
/// ratio (so a bad value is never clear).
#[inline]
fn ratio_sq(room_sq: f32, need_sq: f32) -> f32 {
    if need_sq == 0.0 && room_sq >= 0.0 {
        return f32::INFINITY;
    }
    let ratio = room_sq / need_sq;
    if ratio >= 0.0 {
        ratio
    } else {
        0.0
    }
}

/// The second-order bound `Q` of link `b`'s travel when only the joints
/// `a + 1 ..= b` move, each by at most `excursion` (step_size's sums from
/// joint `a + 1` on).
#[inline(never)]
fn between<const N: usize>(robot: &Robot<N>, excursion: &[f32], links: [u8; 2]) -> f32 {
    let (a, b) = (links[0] as usize, links[1] as usize);
    let (joints, chain) = (robot.joints(), robot.links());
    let end = (b + 1)
        .min(joints.len())
        .min(chain.len())
        .min(excursion.len());
    let mut q_sums = SecondOrder::default();
    let mut second = 0.0f32;
    // Before joint `a` nothing moves: the sums would stay 0 and `still`
    // only record the chain, which link `a`'s overwrites.
    for m in a.min(end)..end {
        let (Some(joint), Some(link), Some(&size)) =
            (joints.get(m), chain.get(m), excursion.get(m))
        else {
            break;
        };
        second = if m > a {
            q_sums.link(joint.kind, size, link.chain)
        } else {
            q_sums.still(link.chain)
        };
        // Link b's capsule may reach past its chord.
        if m == b && robot.has_link_segments() {
            second = q_sums.at(link.capsule_chain);
        }
    }
    second
}

/// Per link, `first_sq[k] = max(first_sq[k], |J x|^2)` at the link's two
/// ends: the velocity field of the displacement `x` (`v(p) = w x p + b`),
/// one pass, with each revolute joint's `z_j x o_j` in `moment`; its prefix
/// sums up to each joint into `turn` (`w`) and `shift` (`b`). Per link with
/// a half-space in `planes`, `toward[k] = max(toward[k], -normal . v)` at
/// its pivot and at its far end (in that order), `normal` the half-space's
/// outward normal: how far each end moves toward the plane.
#[allow(clippy::too_many_arguments)]
fn first_order<const N: usize>(
    robot: &Robot<N>,
    frames: &Frames<N>,
    moment: &[Vec3],
    planes: &[Option<HalfSpace>],
    x: &[f32],
    first_sq: &mut [f32],
    toward: &mut [[f32; 2]],
    turn: &mut [Vec3; N],
    shift: &mut [Vec3; N],
) {
    let mut w = Vec3::zeros();
    let mut b = Vec3::zeros();
    let mut start_sq = 0.0f32;
    let segments = frames.has_segments();
    for (j, ((((joint, &step), (out, t)), (tw, sb)), (m, plane))) in robot
        .joints()
        .iter()
        .zip(x)
        .zip(first_sq.iter_mut().zip(toward.iter_mut()))
        .zip(turn.iter_mut().zip(shift.iter_mut()))
        .zip(moment.iter().zip(planes))
        .enumerate()
    {
        match joint.kind {
            JointKind::Revolute => {
                w += frames.axis(j) * step;
                b -= m * step;
            }
            JointKind::Prismatic => b += frames.axis(j) * step,
        }
        (*tw, *sb) = (w, b);
        let end = w.cross(&frames.link_end(j)) + b;
        let end_sq = end.norm_squared();
        *out = max(*out, max(start_sq, end_sq));
        start_sq = end_sq;
        if segments {
            // The capsule's own ends, off the chord.
            let (start, end) = frames.capsule(j);
            let ends_sq = max(
                (w.cross(&start) + b).norm_squared(),
                (w.cross(&end) + b).norm_squared(),
            );
            *out = max(*out, ends_sq);
        }
        if let Some(h) = plane {
            let normal = Vec3::new(h.normal[0], h.normal[1], h.normal[2]);
            let start = w.cross(&frames.pivot(j)) + b;
            t[0] = max(t[0], -normal.dot(&start));
            t[1] = max(t[1], -normal.dot(&end));
        }
    }
}
