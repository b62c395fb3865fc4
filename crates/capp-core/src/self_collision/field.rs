//! What the checked link pairs add to one configuration's obstacle field:
//! a potential term per close pair with its exact joint-space gradient, the
//! closest pair, and each link's room for conservative advancement.
//!
//! For a pair of links `a`, `b` with closest chord points `p_a` (fraction
//! `s` along link `a`) and `p_b` (fraction `t`), `d = |p_a - p_b|`, the gap
//! `g = d - r_a - r_b` and the clearance `c = g / l`, `l = CLEARANCE_SCALE (r_a + r_b)`:
//!
//! ```text
//! P_ab = 1 / c                                    (eq. 26's shape, c for C - 1)
//! dP_ab/dq = -1 / (c^2 l) n . (J_{p_a} - J_{p_b}),   n = (p_a - p_b) / d
//! ```
//!
//! (the closest points move with their links; to first order the distance
//! changes only along `n`). So the pair is two point forces, `f_a = -n / (c^2
//! l)` at `p_a` and `f_b = -f_a` at `p_b`, and `mu += sum J^T f` is the same
//! backward sweep as the obstacles' ([`crate::avoidance`]): each link keeps
//! the sum of its forces `F` and of `t f` (`S`), whose moment about its
//! pivot is `(o_end - o_pivot) x S`. O(n + pairs), no finite differences.
//!
//! Conservative advancement: a pair is safe for a step when the two links'
//! travel bounds add up to at most `fraction` of its gap. Each link gets
//! half the gap of each close pair, and `k r_k` against the pairs the broad
//! phase found farther than `k (r_a + r_b)`, `k = INFLUENCE CLEARANCE_SCALE`: any two
//! links' shares then add up to at most their gap. The shares go into the
//! same per-link room the obstacles use ([`crate::step_size::advancement`]).

use super::segment::closest_points;
use super::{LinkCapsules, CLEARANCE_SCALE, INFLUENCE};
use crate::kinematics::Frames;
use crate::math::{max, min, Vec3};
use crate::robot::{JointKind, Robot};

/// The closest checked pair of links.
#[derive(Clone, Copy, Debug, PartialEq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub struct LinkPair {
    /// `c = gap / (CLEARANCE_SCALE (r_a + r_b))`: > 0 apart, dimensionless (as `C - 1`).
    pub clearance: f32,
    /// The capsules' distance (chords' distance less both radii), length
    /// units; negative when they overlap.
    pub gap: f32,
    /// The two links (0-based, the lower first).
    pub links: [u8; 2],
}

/// Most link pairs an evaluation keeps for the tracker's relative test
/// ([`link_pairs`]'s `close`); pairs beyond it give rooms as before.
pub const MAX_CLOSE_PAIRS: usize = 64;

/// The link pairs near enough to be measured, for the tracker's relative
/// test ([`crate::tracker::clearance`]).
pub type ClosePairs = heapless::Vec<LinkPair, MAX_CLOSE_PAIRS>;

/// A measured pair: kept in `close` (the tracker bounds its relative
/// motion) while there is room, else each of its links' rooms lowered to
/// half its gap (and link `pressed`'s own room with it).
fn keep_or_share(
    close: &mut Option<&mut ClosePairs>,
    room_sq: &mut [f32],
    field: &mut SelfField,
    pressed: usize,
    pair: LinkPair,
) {
    if close.as_mut().is_some_and(|c| c.push(pair).is_ok()) {
        return;
    }
    let share = 0.5 * max(pair.gap, 0.0);
    for k in pair.links.map(usize::from) {
        if let Some(room) = room_sq.get_mut(k) {
            *room = min(*room, share * share);
        }
        if k == pressed {
            field.pressed_room_sq = min(field.pressed_room_sq, share * share);
        }
    }
}

/// What the link pairs say about one configuration.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub struct SelfField {
    /// The pairs' part of the potential: `sum 1 / c` over the pairs within
    /// [`INFLUENCE`].
    pub potential: f32,
    /// The closest pair the narrow phase tested, if any.
    pub closest: Option<LinkPair>,
    /// Pairs within influence.
    pub active_pairs: u16,
    /// Whether no two checked capsules overlap.
    pub clear: bool,
    /// The square of the room of link `pressed` against its link pairs
    /// alone (length units squared; infinity when it has none): the
    /// obstacles' nearest link slides along its half-space and checks
    /// everything else against this ([`crate::avoidance::HalfSpace`]).
    pub pressed_room_sq: f32,
}

/// Evaluates the checked pairs of `capsules` at `frames`: adds the pairs'
/// gradient to `mu` (`frames.len()` values) and lowers each link's
/// `room_sq` (length units squared) to its share of its pairs' gaps; the
/// share of link `pressed` alone is [`SelfField::pressed_room_sq`].
///
/// `far` (length units, 0 for none): pairs beyond the broad phase's spheres
/// but within `far` more of them are measured too, by the distance of their
/// spheres (one square root each), and pairs farther still give each link
/// `far / 2` more than its far room; so a link's room grows with its
/// distance from the others instead of stopping at its far room.
///
/// `close` (the tracker's): the measured pairs are kept there (gap, links)
/// instead of lowering the two links' rooms, while it has room; the
/// tracker bounds their relative motion instead of each link's own
/// ([`crate::tracker::clearance`]).
#[allow(clippy::too_many_arguments)]
pub fn link_pairs<const N: usize>(
    robot: &Robot<N>,
    frames: &Frames<N>,
    capsules: &LinkCapsules<N>,
    mu: &mut [f32],
    room_sq: &mut [f32],
    pressed: Option<u8>,
    far: f32,
    mut close: Option<&mut ClosePairs>,
) -> SelfField {
    let mut field = SelfField {
        clear: true,
        pressed_room_sq: f32::INFINITY,
        ..SelfField::default()
    };
    let pressed = pressed.map_or(usize::MAX, |k| k as usize);
    let n = capsules
        .n
        .min(frames.len())
        .min(mu.len())
        .min(room_sq.len());
    if n == 0 {
        return field;
    }
    let mut mid = [Vec3::zeros(); N];
    for (k, (m, (room, &far_room))) in mid
        .iter_mut()
        .zip(room_sq.iter_mut().zip(&capsules.far_room))
        .take(n)
        .enumerate()
    {
        let (start, end) = frames.capsule(k);
        *m = (start + end) * 0.5;
        let far_room = far_room + 0.5 * far;
        *room = min(*room, far_room * far_room);
        if k == pressed {
            field.pressed_room_sq = far_room * far_room;
        }
    }
    // Per link: the sum of the pair forces on it, and of `t f`.
    let mut force = [Vec3::zeros(); N];
    let mut sliding = [Vec3::zeros(); N];
    let mut closest = f32::INFINITY;
    // Zipped iterators, not indices: no bounds check, no panic path.
    let links = capsules
        .checked
        .iter()
        .zip(&capsules.reach)
        .zip(capsules.radius.iter().zip(&mid))
        .enumerate()
        .take(n);
    for (a, ((&checked, &reach_a), (&r_a, &m_a))) in links {
        let mut row = checked;
        while row != 0 {
            let b = row.trailing_zeros() as usize;
            row &= row - 1;
            let (Some(m_b), Some(&reach_b), Some(&r_b)) =
                (mid.get(b), capsules.reach.get(b), capsules.radius.get(b))
            else {
                continue;
            };
            // Broad phase: spheres round both capsules inflated by INFLUENCE clearance units.
            let reach = reach_a + reach_b;
            let centres_sq = (m_a - m_b).norm_squared();
            if b >= n {
                continue;
            }
            if centres_sq >= reach * reach {
                let outer = reach + far;
                if far > 0.0 && centres_sq < outer * outer {
                    // The capsules lie within their spheres of `reach`
                    // less the influence's share of the radii.
                    let inflation = INFLUENCE * CLEARANCE_SCALE * (r_a + r_b);
                    let gap = crate::math::sqrt_inline(centres_sq) - reach + inflation;
                    let pair = LinkPair {
                        clearance: f32::INFINITY,
                        gap,
                        links: [a as u8, b as u8],
                    };
                    keep_or_share(&mut close, room_sq, &mut field, pressed, pair);
                }
                continue;
            }
            let ((start_a, end_a), (start_b, end_b)) = (frames.capsule(a), frames.capsule(b));
            let pair = closest_points(&start_a, &end_a, &start_b, &end_b);
            let distance = crate::math::sqrt_inline(pair.distance_sq);
            let radii = r_a + r_b;
            let gap = distance - radii;
            let scale = CLEARANCE_SCALE * radii;
            let c = gap / scale;
            let measured = LinkPair {
                clearance: c,
                gap,
                links: [a as u8, b as u8],
            };
            keep_or_share(&mut close, room_sq, &mut field, pressed, measured);
            if c < closest {
                closest = c;
                field.closest = Some(measured);
            }
            if gap <= 0.0 || distance <= 0.0 {
                field.clear = false;
                continue;
            }
            if c >= INFLUENCE {
                continue;
            }
            field.active_pairs = field.active_pairs.saturating_add(1);
            field.potential += 1.0 / c;
            let f_a = (pair.on_first - pair.on_second) * (-1.0 / (c * c * scale * distance));
            if let (Some(fa), Some(sa)) = (force.get_mut(a), sliding.get_mut(a)) {
                *fa += f_a;
                *sa += f_a * pair.s;
            }
            if let (Some(fb), Some(sb)) = (force.get_mut(b), sliding.get_mut(b)) {
                *fb -= f_a;
                *sb -= f_a * pair.t;
            }
        }
    }
    if field.active_pairs > 0 {
        add_gradient(robot, frames, &force[..n], &sliding[..n], &mut mu[..n]);
    }
    field
}

/// `mu += J^T f` for the point forces summed per link (`force`) and
/// weighted by their fraction along it (`sliding`): the backward sweep of
/// [`crate::avoidance`].
fn add_gradient<const N: usize>(
    robot: &Robot<N>,
    frames: &Frames<N>,
    force: &[Vec3],
    sliding: &[Vec3],
    mu: &mut [f32],
) {
    let mut total = Vec3::zeros();
    let mut moment = Vec3::zeros();
    let segments = frames.has_segments();
    for (j, ((m, f), s)) in mu.iter_mut().zip(force).zip(sliding).enumerate().rev() {
        let pivot = frames.pivot(j);
        let chord = frames.link_end(j) - pivot;
        // Reference from this link's end to its pivot, then its own forces.
        moment += chord.cross(&total);
        let beyond = total;
        // A force `f` at the point `start + t (end - start)` of the
        // capsule's segment has the moment `(start - o) x f + t (end -
        // start) x f` about the pivot `o`: the chord's start is the pivot.
        // A prismatic joint moves its whole body (a segment of its own)
        // along `z`, but only the far end of its chord.
        let own = if segments {
            let (start, end) = frames.capsule(j);
            moment += (start - pivot).cross(f) + (end - start).cross(s);
            *f
        } else {
            moment += chord.cross(s);
            *s
        };
        total += f;
        let z = frames.axis(j);
        *m += match robot.joints().get(j).map(|joint| joint.kind) {
            Some(JointKind::Prismatic) => z.dot(&(beyond + own)),
            _ => z.dot(&moment),
        };
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::kinematics::forward_kinematics;
    use crate::robot::Joint;
    use crate::self_collision::pairs::PairTable;

    /// A planar-ish snake of `n` revolute joints with alternating axes and
    /// one prismatic joint, folded so that far links come close.
    fn snake<const N: usize>() -> Robot<N> {
        let mut joints = [Joint::revolute(0.0, 1.0, 0.0, -2.5, 2.5, 1.0); 8];
        for (i, j) in joints.iter_mut().enumerate() {
            j.alpha = if i % 2 == 0 { 0.3 } else { -0.3 };
        }
        joints[3] = Joint::prismatic(0.2, 0.3, 0.1, 0.5, 1.5, 1.0);
        Robot::new(&joints).unwrap()
    }

    fn capsules<const N: usize>(robot: &Robot<N>) -> LinkCapsules<N> {
        let radius = [0.1f32; 8];
        let table = PairTable::<N>::adjacency(robot, &radius, &[]);
        LinkCapsules::new(robot, &radius, table.checked_rows()).unwrap()
    }

    /// The snake as general joints (its DH rows turned into origins and
    /// axes), each link's capsule a segment of its own off its chord: up to
    /// 0.35 from it, across and beyond it (the prismatic link's too).
    fn snake_with_segments<const N: usize>() -> Robot<N> {
        let dh = snake::<N>();
        let mut general = [Joint::revolute(0.0, 1.0, 0.0, -1.0, 1.0, 1.0); 8];
        let tool = crate::robot::general_from_dh(dh.joints(), &mut general);
        let mut robot = Robot::new_with_tool(&general, &tool).unwrap();
        let segments: [[[f32; 3]; 2]; 8] = core::array::from_fn(|k| {
            let s = 0.1 * (k % 3) as f32;
            [[-0.2 - s, 0.15, 0.1 * s], [0.3, -0.1 - s, 0.25]]
        });
        robot.set_link_segments(&segments).unwrap();
        robot
    }

    /// The potential's gradient against central differences of the
    /// potential, on random folded configurations where pairs are active.
    #[test]
    fn gradient_matches_finite_differences_of_the_potential() {
        gradient_matches_differences(&snake::<8>());
    }

    /// The same with capsules round segments of their own: the forces act
    /// off the chords (and a prismatic joint moves its whole body).
    #[test]
    fn gradient_matches_finite_differences_with_link_segments() {
        let robot = snake_with_segments::<8>();
        assert!(robot.has_link_segments());
        gradient_matches_differences(&robot);
    }

    fn gradient_matches_differences(robot: &Robot<8>) {
        let robot = robot.clone();
        let caps = capsules(&robot);
        let mut rng = crate::escape::rng::Rng::seeded(3, &[]);
        let mut frames = Frames::<8>::default();
        let potential = |q: &[f32], frames: &mut Frames<8>| {
            forward_kinematics(&robot, q, frames);
            let (mut mu, mut room) = ([0.0; 8], [f32::INFINITY; 8]);
            link_pairs(&robot, frames, &caps, &mut mu, &mut room, None, 0.0, None)
        };
        let mut tested = 0;
        for _ in 0..400 {
            let q: [f32; 8] = core::array::from_fn(|i| {
                let j = robot.joints()[i];
                0.5 * (j.min + j.max) + 0.5 * (j.max - j.min) * rng.uniform()
            });
            forward_kinematics(&robot, &q, &mut frames);
            let (mut mu, mut room) = ([0.0; 8], [f32::INFINITY; 8]);
            let field = link_pairs(&robot, &frames, &caps, &mut mu, &mut room, None, 0.0, None);
            if field.active_pairs == 0 || !field.clear || field.closest.unwrap().clearance < 0.3 {
                continue;
            }
            tested += 1;
            for j in 0..8 {
                let h = 1e-3f32;
                let (mut up, mut down) = (q, q);
                up[j] += h;
                down[j] -= h;
                let (pu, pd) = (potential(&up, &mut frames), potential(&down, &mut frames));
                // Skip where a pair enters or leaves the influence band.
                if pu.active_pairs != field.active_pairs || pd.active_pairs != field.active_pairs {
                    continue;
                }
                let fd = (pu.potential - pd.potential) / (2.0 * h);
                let scale = 1.0 + fd.abs().max(mu[j].abs());
                assert!(
                    (fd - mu[j]).abs() <= 2e-2 * scale,
                    "joint {j}: exact {} vs differences {fd}",
                    mu[j]
                );
            }
        }
        assert!(
            tested >= 20,
            "only {tested} configurations had active pairs"
        );
    }

    /// The rooms: any two checked links' shares add up to at most their gap
    /// (from an independent brute-force distance).
    #[test]
    fn rooms_of_two_links_never_add_up_to_more_than_their_gap() {
        rooms_within_gaps(&snake::<8>());
        rooms_within_gaps(&snake_with_segments::<8>());
    }

    fn rooms_within_gaps(robot: &Robot<8>) {
        let robot = robot.clone();
        let caps = capsules(&robot);
        let mut rng = crate::escape::rng::Rng::seeded(5, &[]);
        let mut frames = Frames::<8>::default();
        for _ in 0..300 {
            let q: [f32; 8] = core::array::from_fn(|i| {
                let j = robot.joints()[i];
                0.5 * (j.min + j.max) + 0.5 * (j.max - j.min) * rng.uniform()
            });
            forward_kinematics(&robot, &q, &mut frames);
            let (mut mu, mut room) = ([0.0; 8], [f32::INFINITY; 8]);
            let field = link_pairs(&robot, &frames, &caps, &mut mu, &mut room, None, 0.0, None);
            for a in 0..8 {
                for b in a + 1..8 {
                    if !caps.is_checked(a, b) {
                        continue;
                    }
                    // Brute force over both capsules' segments.
                    let ((pa, ea), (pb, eb)) = (frames.capsule(a), frames.capsule(b));
                    let mut best = f32::INFINITY;
                    for i in 0..=200 {
                        let x = pa + (ea - pa) * (i as f32 / 200.0);
                        for k in 0..=200 {
                            let y = pb + (eb - pb) * (k as f32 / 200.0);
                            best = best.min((x - y).norm());
                        }
                    }
                    let gap = best - 0.2;
                    let shares = crate::math::sqrt(room[a]) + crate::math::sqrt(room[b]);
                    assert!(
                        shares <= gap.max(0.0) + 1e-3,
                        "links {a} {b}: {shares} > {gap}"
                    );
                    if gap < -1e-3 {
                        assert!(!field.clear);
                    }
                }
            }
        }
    }
}
