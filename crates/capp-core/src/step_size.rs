//! How long a step is: the listing's rule and the bounds every candidate step
//! must respect before it is integrated.
//!
//! * [`listing`]: CAPP.c's rule, `h_max` far from the target,
//!   `|err / err_dot| h_max` when the last step's change would overshoot,
//!   `fine_step_fraction * h_max` within `fine_radius` (the first-order laws).
//! * [`descent_bound`]: never predict removing more than all of `V`: the
//!   Gauss-Newton step along the rate (first-order laws).
//! * [`stiffness_bound`]: no mode of the linearised error overshoots, so the
//!   rates do not chatter (first-order laws).
//! * [`advancement`]: conservative advancement, for every law: no avoidance
//!   point may travel, during the step, more than a fraction of its distance to
//!   the nearest inflated obstacle. A larger step cannot jump through anything.
//!
//! ## Conservative advancement
//!
//! The step moves the joints along the straight segment `q(s) = q + s dq`,
//! `s` in `[0, 1]`, `dq = h qdot` (what a joint controller interpolating
//! between setpoints does). A point `p` on link `k` then travels at most
//!
//! ```text
//! s |J_p dq| + s^2 Q_k,   Q_k = 1/2 sum_m |dq_m| (2 Phi_<m + |dq_m|) L_mk  +  sum_prismatic j |dq_j| Phi_<j
//! ```
//!
//! the first sum over the revolute joints `m <= k`, with `Phi_<m` the sum of
//! `|dq_i|` over the revolute joints before `m` and `L_mk` the chain length
//! from joint `m`'s pivot to the end of link `k` (prismatic links at their
//! longest: a bound on `|p - o_m|` in every configuration). Why: the path
//! length is at most `|p'(0)| + sup |p''| / 2`, and
//! `p'' = sum_ij dq_i dq_j d2p/dq_i dq_j` with `d2p/dq_i dq_j = z_i x (z_m x
//! (p - o_m))`, `m = max(i, j)` (Jacobi's identity), for two revolute joints;
//! `z_i x z_j` for a revolute `i` before a prismatic `j`; 0 otherwise. Grouped
//! by `m`, the revolute terms are `dq_m (2 w_<m + dq_m z_m) x (z_m x (p -
//! o_m))`. `J_p dq` is linear in `p` along a link (`v(x) = w x x + b`), so a
//! link's worst point is one of its ends (a link whose self-collision
//! capsule is a segment of its own, off its chord: one of the chord's and
//! the segment's four ends, with `L_mk` to the farther of them). The largest `s` with travel at most
//! `fraction` times the link's distance `D` solves the quadratic:
//! `s = 2 D / (A + sqrt(A^2 + 4 Q D))`. Each link's distance is the lower
//! bound of [`crate::obstacle::Contact::distance_sq`] (it holds for every
//! convex `C`), or the influence distance for a link no obstacle is near.

use crate::avoidance::HalfSpace;
use crate::kinematics::Frames;
use crate::math::{max, min, Vec3};
use crate::robot::{JointKind, Robot};
use crate::settings_field::{first_bad, non_negative, positive, SettingsField};
use crate::target::PoseError;

/// Fraction of the Gauss-Newton step taken by [`descent_bound`].
pub const STEP_FRACTION: f32 = 0.5;

/// The step sizes of the listing's rule ([`listing`]); the planner's
/// `Settings` holds them at its top level (`crate::Settings::step_rule`).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct StepRule {
    /// Largest integration step `h_max`, seconds (the listing's `step`).
    pub time_step_s: f32,
    /// Position error (length units) under which the step is cut to
    /// `fine_step_fraction * time_step_s`.
    pub fine_radius: f32,
    /// Fraction of the step used inside `fine_radius`, in `(0, 1]`.
    pub fine_step_fraction: f32,
}

impl StepRule {
    /// Checks each value's range.
    pub fn validate(&self) -> Result<(), SettingsField> {
        first_bad(&[
            (positive(self.time_step_s), SettingsField::TimeStep),
            (non_negative(self.fine_radius), SettingsField::FineRadius),
            (
                positive(self.fine_step_fraction) && self.fine_step_fraction <= 1.0,
                SettingsField::FineStepFraction,
            ),
        ])
    }
}

/// The listing's step rule for the first-order laws: `h_max` far from the
/// target, `|err / err_dot| h_max` when the last step's change (`error_step`,
/// length units) would overshoot the error `err`, and `fine_step_fraction *
/// h_max` within `fine_radius`.
pub fn listing(settings: &StepRule, error: &PoseError, error_step: f32) -> f32 {
    let h_max = settings.time_step_s;
    let err = error.position;
    if err > settings.fine_radius {
        if err > error_step.abs() {
            h_max
        } else {
            (err / error_step).abs() * h_max
        }
    } else {
        settings.fine_step_fraction * h_max
    }
}

/// The largest step that does not predict removing more than all of `V`:
/// to first order `V(h) = V - h G.qdot`; the Gauss-Newton step along the rate,
/// `V(h) ~ 1/2 |e - h J qdot|^2`, is least at `h = G.qdot / |J qdot|^2`
/// (orientation rows weighted by `lambda^2`; `sum_i |w x u_i|^2 = 2 |w|^2`
/// for an orthonormal frame). `descent = G.qdot`, `(v, w)` the end-effector
/// twist of the rate. Returns [`STEP_FRACTION`] of it, or infinity when the
/// rate does not descend.
pub fn descent_bound(descent: f32, twist: (Vec3, Vec3), orientation_scale: f32) -> f32 {
    let (v, w) = twist;
    let speed_sq = v.dot(&v) + 2.0 * orientation_scale * orientation_scale * w.dot(&w);
    if descent > 0.0 && speed_sq > 0.0 {
        STEP_FRACTION * descent / speed_sq
    } else {
        f32::INFINITY
    }
}

/// No mode of the linearised error may overshoot: with `rate = gain o G`,
/// `e' = -J diag(gain) J^T e`, whose largest eigenvalue is at most the trace
/// `stiffness = sum_j gain_j |J_j|^2`. A step below its inverse makes every
/// mode decay without changing sign, so the rates do not chatter.
pub fn stiffness_bound(stiffness: f32) -> f32 {
    if stiffness > 0.0 {
        1.0 / stiffness
    } else {
        f32::INFINITY
    }
}

/// The second-order bound `Q_k` of the module docs, grown a joint at a time
/// (Phi_<m and the sums giving `Q_k`: sum a_m, sum a_m L_0m, the prismatic
/// sum): [`SecondOrder::link`] adds joint `k` moving by at most `size` and
/// gives `Q_k` of its link. The tracker's stop test uses the same sums
/// ([`crate::tracker::clearance`]).
#[derive(Clone, Copy, Debug, Default)]
pub(crate) struct SecondOrder {
    phi: f32,
    lever_sum: f32,
    lever_base: f32,
    sliding: f32,
    pivot_chain: f32,
}

impl SecondOrder {
    /// Joint `kind` moving by at most `size` (radians or length units),
    /// then `Q_k` of its link, whose chain length is `chain`.
    #[inline(always)]
    pub(crate) fn link(&mut self, kind: JointKind, size: f32, chain: f32) -> f32 {
        match kind {
            JointKind::Revolute => {
                let a = size * (2.0 * self.phi + size);
                self.lever_sum += a;
                self.lever_base += a * self.pivot_chain;
                self.phi += size;
            }
            JointKind::Prismatic => self.sliding += size * self.phi,
        }
        self.still(chain)
    }

    /// `Q` of a point at most `chain` along the chain (as `link` and
    /// `still` take it) from the base, for the joints added so far, without
    /// adding anything: a link's capsule points
    /// ([`crate::robot::Robot::set_link_segments`]) reach past its chord.
    #[inline(always)]
    pub(crate) fn at(&self, chain: f32) -> f32 {
        max(0.5 * (chain * self.lever_sum - self.lever_base), 0.0) + self.sliding
    }

    /// `Q_k` of the next link (chain length `chain`) when its joint does
    /// not move.
    #[inline(always)]
    pub(crate) fn still(&mut self, chain: f32) -> f32 {
        self.pivot_chain = chain;
        max(0.5 * (chain * self.lever_sum - self.lever_base), 0.0) + self.sliding
    }
}

/// Conservative advancement (module docs): the largest `h' <= h` for which no
/// avoidance point of any link travels more than `fraction` of that link's
/// obstacle distance (`distance_sq`, its square, one per link) when the
/// joints move by `h' rate`. `rate` and `distance_sq` hold one value per joint.
///
/// The link of the `nearest` pair, when its whole segment is inside that
/// pair's half-space, is bounded more finely: against that obstacle only the
/// motion *toward* it counts (`-normal . v` at either end, against each end's
/// room to the plane); against the others its travel, within `others_sq`. So
/// an arm pressed on a surface can slide along it or leave it, which a bound
/// on travel alone would not let it do.
///
/// Square roots only where a link might be bound: `(a + b)^2 <= 2 (a^2 + b^2)`
/// settles most links in squares (a square root is 14 cycles of the
/// Cortex-M4F's FPU, [`crate::math::sqrt`]).
pub fn advancement<const N: usize>(
    robot: &Robot<N>,
    frames: &Frames<N>,
    distance_sq: &[f32],
    nearest: Option<&HalfSpace>,
    rate: &[f32],
    h: f32,
    fraction: f32,
) -> f32 {
    // The velocity field of the links so far: v(x) = w x x + b, per unit s.
    let mut w = Vec3::zeros();
    let mut b = Vec3::zeros();
    let mut q_sums = SecondOrder::default();
    let mut start_v = Vec3::zeros();
    let mut scale = 1.0f32;
    let fraction_sq = fraction * fraction;
    let segments = frames.has_segments();
    for (j, ((joint, link), (&r, &d_sq))) in robot
        .joints()
        .iter()
        .zip(robot.links())
        .zip(rate.iter().zip(distance_sq))
        .enumerate()
    {
        let step = r * h;
        let size = step.abs();
        let z = frames.axis(j);
        match joint.kind {
            JointKind::Revolute => {
                w += z * step;
                b -= z.cross(&frames.pivot(j)) * step;
            }
            JointKind::Prismatic => b += z * step,
        }
        let mut second = q_sums.link(joint.kind, size, link.chain);
        let end_v = w.cross(&frames.link_end(j)) + b;
        let mut first_sq = max(start_v.norm_squared(), end_v.norm_squared());
        if segments {
            // The link's capsule has points off its chord: its segment's
            // ends move in the same field, and reach farther along it.
            let (start, end) = frames.capsule(j);
            let ends_sq = max(
                (w.cross(&start) + b).norm_squared(),
                (w.cross(&end) + b).norm_squared(),
            );
            first_sq = max(first_sq, ends_sq);
            second = q_sums.at(link.capsule_chain);
        }
        let pressed = nearest.filter(|h| h.link as usize == j);
        let (v0, v1) = (start_v, end_v);
        start_v = end_v;
        match pressed.and_then(|h| sliding_bound(h, frames, j, v0, v1, second, fraction)) {
            Some((s_toward, others_sq)) => {
                scale = min(scale, s_toward);
                scale = min(
                    scale,
                    travel_bound(first_sq, second, fraction_sq * others_sq),
                );
            }
            None => scale = min(scale, travel_bound(first_sq, second, fraction_sq * d_sq)),
        }
    }
    if scale.is_finite() {
        h * max(scale, 0.0)
    } else {
        0.0
    }
}

/// The largest `s <= 1` with `s first + s^2 second <= allowed` (first and
/// allowed given squared): 1 when the step fits, settled in squares when
/// `(a + b)^2 <= 2 (a^2 + b^2)` shows it.
fn travel_bound(first_sq: f32, second: f32, allowed_sq: f32) -> f32 {
    if 2.0 * (first_sq + second * second) <= allowed_sq {
        return 1.0;
    }
    let first = crate::math::sqrt(first_sq);
    let allowed = crate::math::sqrt(allowed_sq);
    largest_s(first, second, allowed)
}

/// `s first + s^2 second = allowed` solved for `s`, at most 1 (0 when
/// nothing is allowed).
fn largest_s(first: f32, second: f32, allowed: f32) -> f32 {
    if allowed <= 0.0 || allowed.is_nan() {
        return 0.0;
    }
    if first + second <= allowed {
        return 1.0;
    }
    let root = crate::math::sqrt(first * first + 4.0 * second * allowed);
    2.0 * allowed / (first + root)
}

/// For the link `j` of the nearest pair's half-space `h`, with its ends
/// moving `v0` (pivot) and `v1` (end) per unit `s` and second-order travel
/// `second`: the largest `s` for which neither end comes more than
/// `fraction` of its room closer to the plane, and the squared distance left
/// to check the other obstacles against. `None` when an end is not inside
/// the half-space (the travel bound must do).
fn sliding_bound<const N: usize>(
    h: &HalfSpace,
    frames: &Frames<N>,
    j: usize,
    v0: Vec3,
    v1: Vec3,
    second: f32,
    fraction: f32,
) -> Option<(f32, f32)> {
    let normal = Vec3::new(h.normal[0], h.normal[1], h.normal[2]);
    let mut s = 1.0f32;
    for (x, v) in [(frames.pivot(j), v0), (frames.link_end(j), v1)] {
        let room = normal.dot(&x) - h.offset;
        if room <= 0.0 || room.is_nan() {
            return None;
        }
        s = min(
            s,
            largest_s(max(-normal.dot(&v), 0.0), second, fraction * room),
        );
    }
    Some((s, h.others_sq))
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::escape::rng::Rng;
    use crate::kinematics::forward_kinematics;
    use crate::robot::{general_from_dh, Joint};

    const N: usize = 8;

    /// A random revolute chain of 3-7 joints; half of them as general
    /// joints whose capsules are segments of their own, up to 0.5 off their
    /// chords.
    fn random_arm(rng: &mut Rng) -> Robot<N> {
        let n = 3 + ((rng.uniform() + 1.0) * 2.5) as usize;
        let joints: heapless::Vec<Joint, N> = (0..n)
            .map(|_| {
                Joint::revolute(
                    rng.uniform() * 3.1,
                    0.3 + 0.3 * rng.uniform(),
                    0.2 + 0.2 * rng.uniform(),
                    -3.0,
                    3.0,
                    1.0,
                )
            })
            .collect();
        if rng.uniform() > 0.0 {
            return Robot::new(&joints).unwrap();
        }
        let mut general = joints.clone();
        let tool = general_from_dh(&joints, &mut general);
        let mut robot = Robot::new_with_tool(&general, &tool).unwrap();
        let segments: heapless::Vec<[[f32; 3]; 2], N> = (0..n)
            .map(|_| [0, 1].map(|_| [0, 1, 2].map(|_| 0.5 * rng.uniform())))
            .collect();
        robot.set_link_segments(&segments).unwrap();
        robot
    }

    /// Soundness of [`advancement`]: along the step it allows, no point of
    /// a link's chord or capsule (sampled densely in the joints' motion)
    /// travels farther than its room; and it does not refuse everything.
    #[test]
    fn no_point_of_a_link_travels_farther_than_its_room() {
        let mut rng = Rng::seeded(23, &[]);
        let (mut segment_arms, mut bound) = (0, 0);
        for _ in 0..300 {
            let robot = random_arm(&mut rng);
            let n = robot.len();
            segment_arms += robot.has_link_segments() as usize;
            let q: heapless::Vec<f32, N> = (0..n).map(|_| 2.0 * rng.uniform()).collect();
            let rate: heapless::Vec<f32, N> = (0..n).map(|_| rng.uniform()).collect();
            let mut room_sq = [f32::INFINITY; N];
            let link = ((rng.uniform() + 1.0) * 0.5 * n as f32) as usize % n;
            room_sq[link] = (0.01 + 0.1 * (rng.uniform() + 1.0)).powi(2);
            let mut frames = Frames::<N>::default();
            forward_kinematics(&robot, &q, &mut frames);
            let h = advancement(&robot, &frames, &room_sq[..n], None, &rate, 0.5, 1.0);
            assert!(h > 0.0);
            bound += (h < 0.5) as usize;
            let points = |f: &Frames<N>| {
                let (start, end) = f.capsule(link);
                let chord = (f.pivot(link), f.link_end(link));
                [chord, (start, end)]
                    .map(|(a, b)| [0.0, 0.25, 0.5, 0.75, 1.0].map(|t| a + (b - a) * t))
            };
            let before = points(&frames);
            let mut moved = Frames::<N>::default();
            let mut travel = 0.0f32;
            for i in 1..=200 {
                let s = h * i as f32 / 200.0;
                let qs: heapless::Vec<f32, N> =
                    q.iter().zip(&rate).map(|(q, r)| q + s * r).collect();
                forward_kinematics(&robot, &qs, &mut moved);
                for (a, b) in before.iter().flatten().zip(points(&moved).iter().flatten()) {
                    travel = travel.max((b - a).norm());
                }
            }
            let room = room_sq[link].sqrt();
            assert!(
                travel <= room * 1.0001 + 1e-6,
                "link {link}: travel {travel} > room {room}"
            );
        }
        assert!(
            segment_arms > 100 && bound > 100,
            "{segment_arms} arms with segments, {bound} steps bound"
        );
    }
}
