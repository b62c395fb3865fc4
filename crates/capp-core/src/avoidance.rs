//! Avoidance points on the arm, the workspace potential (eq. 26) and its exact
//! joint-space gradient `mu = dP/dq` (eq. 20).
//!
//! Points: on link `j` (from the pivot `o_j` to the next origin `o_{j+1}`), the
//! end point `o_{j+1}` (a joint, [`PointKind::Joint`]) and `m` interior points at
//! `t = i / (m + 1)`, `i = 1..m` ([`PointKind::Link`]); `m = 1` is the paper's
//! "joints and link mid-points". The base `o_0` never moves and is not a point.
//! Point ids run `j * (m + 1) + i`, the end point last (`i = m`).
//!
//! Potential, over the pairs within influence (see [`crate::obstacle`]):
//!
//! ```text
//! P = sum_j sum_i 1 / (C_j(p_i) - 1)                       (eq. 26)
//! f_i = dP/dp_i = - sum_j grad C_j(p_i) / (C_j(p_i) - 1)^2
//! ```
//!
//! `mu = sum_i J_{p_i}^T f_i` in one backward sweep, O(n + points x obstacles):
//! going from the last link to the first, keep the total force `F` of the
//! points beyond and its moment `N` about the current pivot; moving the
//! reference from `o_{j+1}` to `o_j` adds `(o_{j+1} - o_j) x F`. Then
//! `mu_j = z_j . N` (revolute) or `z_j . (F_beyond + sum t f)` (prismatic: a point
//! at fraction `t` of the sliding link moves `t` as far as its end).

use crate::kinematics::Frames;
use crate::math::{min, norm, Vec3};
use crate::obstacle::{Pair, PointKind, World};
use crate::robot::{JointKind, Robot};
use crate::settings_field::{first_bad, non_negative, positive, SettingsField};

/// Where the avoidance points are and how much room they need.
#[derive(Clone, Copy, Debug, PartialEq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub struct AvoidanceSettings {
    /// Clearance margin added to every semi-axis for joint points, length units (listing: 6.0 in).
    pub joint_margin: f32,
    /// Clearance margin for interior link points, length units (listing: 3.0 in).
    pub link_margin: f32,
    /// Interior points per link, 1 to 8 (1 = the mid-point, as the paper).
    pub points_per_link: u8,
    /// Obstacles farther than this outside a point's inflated obstacle do not
    /// constrain it, length units. The paper uses every obstacle (infinite).
    pub influence_distance: f32,
    /// `C - 1` of the closest pair below which the approaching motion is
    /// removed in full (see [`crate::projection`]); 0 gives the paper's rule.
    pub engage_clearance: f32,
    /// Conservative advancement, in `(0, 1]`: no avoidance point may travel
    /// in one step more than this fraction of its distance to the nearest
    /// inflated obstacle (see [`crate::step_size::advancement`]).
    pub advance_fraction: f32,
}

impl AvoidanceSettings {
    /// The listing's margins (6.0, 3.0), mid-points only, 24 length units of
    /// influence, the projection engaged below `C - 1 = 1`.
    pub const fn listing() -> Self {
        AvoidanceSettings {
            joint_margin: 6.0,
            link_margin: 3.0,
            points_per_link: 1,
            influence_distance: 24.0,
            engage_clearance: 1.0,
            advance_fraction: 1.0,
        }
    }

    /// Checks each value's range.
    pub fn validate(&self) -> Result<(), SettingsField> {
        first_bad(&[
            (
                non_negative(self.joint_margin)
                    && non_negative(self.link_margin)
                    && self.joint_margin <= 1e4
                    && self.link_margin <= 1e4,
                SettingsField::Margin,
            ),
            (
                (1..=8).contains(&self.points_per_link),
                SettingsField::PointsPerLink,
            ),
            (
                positive(self.influence_distance) && self.influence_distance <= 1e4,
                SettingsField::InfluenceDistance,
            ),
            (
                positive(self.advance_fraction) && self.advance_fraction <= 1.0,
                SettingsField::AdvanceFraction,
            ),
            (
                non_negative(self.engage_clearance) && self.engage_clearance <= 1e6,
                SettingsField::EngageClearance,
            ),
        ])
    }

    /// Margins indexed by [`PointKind`].
    pub fn margins(&self) -> [f32; 2] {
        [self.joint_margin, self.link_margin]
    }

    /// Avoidance points per link (interior points + the end point).
    pub fn points_per_link_total(&self) -> usize {
        self.points_per_link as usize + 1
    }
}

impl Default for AvoidanceSettings {
    fn default() -> Self {
        Self::listing()
    }
}

/// One avoidance point.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct AvoidancePoint {
    /// Id: `link * (points_per_link + 1) + index`.
    pub id: u16,
    /// Link (0-based joint) it rides on.
    pub link: u8,
    /// Fraction along the link from its pivot, in `(0, 1]`.
    pub t: f32,
    /// Joint or link point.
    pub kind: PointKind,
    /// World position, length units.
    pub position: Vec3,
}

/// The points of link `link`, interior ones first, end point last.
pub fn link_points<const N: usize>(
    frames: &Frames<N>,
    settings: &AvoidanceSettings,
    link: usize,
) -> impl Iterator<Item = AvoidancePoint> {
    let start = frames.pivot(link);
    let end = frames.link_end(link);
    let per = settings.points_per_link_total();
    let interior = settings.points_per_link as usize;
    (0..per).map(move |i| {
        let (t, kind) = if i == interior {
            (1.0, PointKind::Joint)
        } else {
            ((i + 1) as f32 / per as f32, PointKind::Link)
        };
        AvoidancePoint {
            id: (link * per + i) as u16,
            link: link as u8,
            t,
            kind,
            position: if i == interior {
                end
            } else {
                start + (end - start) * t
            },
        }
    })
}

/// Every avoidance point of the arm, from the base outwards.
pub fn points<'a, const N: usize>(
    frames: &'a Frames<N>,
    settings: &'a AvoidanceSettings,
) -> impl Iterator<Item = AvoidancePoint> + 'a {
    (0..frames.len()).flat_map(move |link| link_points(frames, settings, link))
}

/// The closest approach of any point to any obstacle.
#[derive(Clone, Copy, Debug, PartialEq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub struct Clearance {
    /// `C - 1` of the inflated obstacle (eq. 25): > 0 outside, dimensionless.
    pub value: f32,
    /// Avoidance point id (see module docs).
    pub point: u16,
    /// Obstacle index.
    pub obstacle: u8,
}

/// The nearest avoidance point / obstacle pair of the arm, as a half-space:
/// every point `y` with `normal . y > offset` is outside that obstacle
/// inflated by the larger of the two margins (so by either margin). From the convexity of
/// `C`: `C(y) >= C(p) + grad C(p) . (y - p)`, which exceeds 1 wherever
/// `grad C . (y - p) > 1 - C(p)`. Conservative advancement
/// ([`crate::step_size::advancement`]) lets that link slide along the
/// obstacle or move away from it, where a bound on its travel alone would
/// hold it still.
#[derive(Clone, Copy, Debug, PartialEq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub struct HalfSpace {
    /// The link (0-based joint) the nearest point is on.
    pub link: u8,
    /// Outward unit normal (world frame).
    pub normal: Vec3Data,
    /// The half-space is `normal . y > offset`, length units.
    pub offset: f32,
    /// Square of the lower bound on the distance from that link's points to
    /// every *other* obstacle (the influence distance's square if none is
    /// within it), length units squared.
    pub others_sq: f32,
}

/// A plain `[x, y, z]` (so that [`HalfSpace`] can derive `defmt::Format`).
pub type Vec3Data = [f32; 3];

/// What the obstacles say about one configuration.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct ObstacleField {
    /// Potential `P` of eq. 26 over the pairs within influence.
    pub potential: f32,
    /// Closest pair within influence, if any.
    pub clearance: Option<Clearance>,
    /// Pairs within influence.
    pub active_pairs: u16,
    /// Whether every point is strictly outside every inflated obstacle.
    pub clear: bool,
    /// The nearest pair's half-space, when it has one.
    pub nearest: Option<HalfSpace>,
}

/// Evaluates the potential and writes `mu = dP/dq` into `mu` (`frames.len()`
/// values) and, per link, the square of a lower bound on the distance from
/// any of its avoidance points to any inflated obstacle into `distance_sq`
/// (length units squared; the influence distance's square when no obstacle
/// is within it, infinity when there are none; see
/// [`crate::obstacle::Contact::distance_sq`]).
///
/// `planes` (the tracker's, one per link): each link's half-space against
/// its nearest obstacle, as [`ObstacleField::nearest`] is for the arm's
/// nearest link (`None` where it has none).
pub fn potential_gradient<const N: usize>(
    robot: &Robot<N>,
    frames: &Frames<N>,
    obstacles: World<'_>,
    settings: &AvoidanceSettings,
    mu: &mut [f32],
    distance_sq: &mut [f32],
    mut planes: Option<&mut [Option<HalfSpace>]>,
) -> ObstacleField {
    let mut force = Vec3::zeros();
    let mut moment = Vec3::zeros();
    let n = frames.len().min(mu.len()).min(distance_sq.len());
    // Nothing to hit: no bound. Otherwise a link no obstacle is near is at
    // least the influence distance from all of them.
    let influence_sq = if obstacles.is_empty() {
        f32::INFINITY
    } else {
        settings.influence_distance * settings.influence_distance
    };
    // The field's sums, kept in locals (not in the returned value) while
    // the pairs go by. `closest` starts at infinity: a pair within the
    // potential's influence has a finite `C - 1`, so the first one is kept.
    let mut potential = 0.0;
    let mut active_pairs = 0u32;
    let mut clear = true;
    let (mut closest, mut closest_point, mut closest_obstacle) = (f32::INFINITY, 0u16, 0u8);
    // The nearest pair of the arm: link, point id, obstacle, and that link's
    // distance to every other obstacle.
    let mut nearest: Option<(u8, u16, u8, f32)> = None;
    let mut nearest_sq = influence_sq;
    for j in (0..n).rev() {
        let pivot = frames.pivot(j);
        moment += (frames.link_end(j) - pivot).cross(&force);
        let beyond = force;
        let mut sliding_force = Vec3::zeros();
        // The link's nearest pair (distance, obstacle, point) and its
        // distance to the other obstacles.
        let (mut link_sq, mut link_obstacle, mut link_point) = (influence_sq, u8::MAX, 0u16);
        let mut others_sq = influence_sq;
        for point in link_points(frames, settings, j) {
            let mut f = Vec3::zeros();
            for (index, obstacle) in obstacles.iter().enumerate() {
                let index = index as u8;
                // The link's nearest pair and its distance to the others.
                let mut nearer = |distance_sq: f32| {
                    if distance_sq < link_sq {
                        if index != link_obstacle {
                            others_sq = link_sq;
                        }
                        (link_sq, link_obstacle, link_point) = (distance_sq, index, point.id);
                    } else if index != link_obstacle {
                        others_sq = min(others_sq, distance_sq);
                    }
                };
                let (clearance, gradient) =
                    match obstacle.pair(&point.position, point.kind, obstacles.hulls) {
                        Pair::Far => continue,
                        Pair::Beyond { distance_sq } => {
                            // Beyond the potential's cut-off: only the distance counts.
                            nearer(distance_sq);
                            continue;
                        }
                        Pair::Inside { clearance, .. } => {
                            nearer(0.0);
                            (clearance, None)
                        }
                        Pair::Near {
                            clearance,
                            gradient,
                            distance_sq,
                        } => {
                            nearer(distance_sq);
                            (clearance, Some(gradient))
                        }
                    };
                // Within the potential's influence: `clearance` is finite.
                active_pairs += 1;
                if clearance < closest {
                    (closest, closest_point, closest_obstacle) = (clearance, point.id, index);
                }
                let Some(gradient) = gradient else {
                    clear = false;
                    continue;
                };
                let inv = 1.0 / clearance;
                potential += inv;
                f -= gradient * (inv * inv);
            }
            force += f;
            moment += (point.position - pivot).cross(&f);
            sliding_force += f * point.t;
        }
        distance_sq[j] = link_sq;
        if let Some(plane) = planes.as_mut().and_then(|p| p.get_mut(j)) {
            *plane = if link_obstacle != u8::MAX {
                half_space(
                    frames,
                    obstacles,
                    settings,
                    j as u8,
                    link_point,
                    link_obstacle,
                    others_sq,
                )
            } else {
                None
            };
        }
        if link_sq < nearest_sq && link_obstacle != u8::MAX {
            nearest_sq = link_sq;
            nearest = Some((j as u8, link_point, link_obstacle, others_sq));
        }
        let z = frames.axis(j);
        // `get`, not `[j]`: no panic path (the frames are the robot's, so it is always `Some`).
        mu[j] = match robot.joints().get(j).map(|joint| joint.kind) {
            Some(JointKind::Prismatic) => z.dot(&(beyond + sliding_force)),
            _ => z.dot(&moment),
        };
    }
    ObstacleField {
        potential,
        clearance: (active_pairs > 0).then_some(Clearance {
            value: closest,
            point: closest_point,
            obstacle: closest_obstacle,
        }),
        active_pairs: active_pairs.min(u16::MAX as u32) as u16,
        clear,
        nearest: nearest.and_then(|(link, point, obstacle, others_sq)| {
            half_space(
                frames, obstacles, settings, link, point, obstacle, others_sq,
            )
        }),
    }
}

/// The half-space of [`HalfSpace`] at avoidance point `point` (on `link`)
/// against `obstacle` inflated by the larger of the two margins (so it holds
/// for every point of the link, of either kind), or `None` when the point is
/// inside that inflation (no such half-space) or out of its influence.
#[inline(never)]
fn half_space<const N: usize>(
    frames: &Frames<N>,
    obstacles: World<'_>,
    settings: &AvoidanceSettings,
    link: u8,
    point: u16,
    obstacle: u8,
    others_sq: f32,
) -> Option<HalfSpace> {
    let larger = if settings.joint_margin >= settings.link_margin {
        PointKind::Joint
    } else {
        PointKind::Link
    };
    let (at, normal, depth) =
        surface_normal(frames, obstacles, settings, point, obstacle, Some(larger))?;
    Some(HalfSpace {
        link,
        normal: [normal.x, normal.y, normal.z],
        offset: normal.dot(&at.position) - depth,
        others_sq,
    })
}

/// At avoidance point `point` against `obstacle` inflated by the margin of
/// `kind` (the point's own with `None`): the point (its link and world
/// position), the unit normal `grad C / |grad C|` (eq. 25) and the lower bound `(C - 1) / |grad
/// C|` on its distance to that inflation (length units); `None` when the
/// point is on or inside it, or out of its influence.
// Not inlined: one copy of the pair code for its two callers.
#[inline(never)]
pub fn surface_normal<const N: usize>(
    frames: &Frames<N>,
    obstacles: World<'_>,
    settings: &AvoidanceSettings,
    point: u16,
    obstacle: u8,
    kind: Option<PointKind>,
) -> Option<(AvoidancePoint, Vec3, f32)> {
    let per = settings.points_per_link_total().max(1);
    let link = point as usize / per;
    let at = link_points(frames, settings, link).nth(point as usize - link * per)?;
    let contact = obstacles.get(obstacle as usize)?.contact(
        &at.position,
        kind.unwrap_or(at.kind),
        obstacles.hulls,
    )?;
    let slope = norm(&contact.gradient);
    if !(contact.clearance > 0.0 && contact.clearance.is_finite() && slope > 0.0) {
        return None;
    }
    Some((at, contact.gradient / slope, contact.clearance / slope))
}
