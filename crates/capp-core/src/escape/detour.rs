//! Detours round the obstacle that blocks a dead end: points beside it,
//! across the direction from the hand to the target, on a side the hand can
//! move toward; and which side of an obstacle a point is on (what the
//! reports name). Reads the obstacle only through its bounding-box extent
//! and its frame ([`Obstacle::box_extent`], [`Obstacle::side_of`]).

use crate::kinematics::Frames;
use crate::math::{norm, Vec3};
use crate::obstacle::Obstacle;
use crate::robot::Robot;

/// An obstacle is detoured around only when its inflated bounding box is
/// smaller than this fraction of the robot's reach (a floor or a wall is
/// not gone round).
pub const DETOUR_SIZE: f32 = 0.5;
/// Detour points around a blocking obstacle (two axes across the blocked
/// direction, both ways).
pub const DETOURS: usize = 4;
/// Which side of the blocking obstacle an escape passes: the axis of the
/// obstacle's own frame along which the walk's end point is farthest out (in
/// units of its semi-axes), and the sign.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub struct Side {
    /// The obstacle (0-based).
    pub obstacle: u8,
    /// 0, 1, 2 for its x, y, z axis.
    pub axis: u8,
    /// Whether on the axis' positive side.
    pub positive: bool,
}

/// Below this share of its average mobility the end effector counts as
/// unable to move along a direction (a planar arm out of its plane).
pub const IMMOBILE: f32 = 0.01;

/// Whether the end effector at `frames` can move along the unit direction
/// `u`: `|J_p^T u|^2` (what the joints can do along `u`) at least
/// [`IMMOBILE`] times its mean over directions, `trace(J_p J_p^T) / 3`. O(n).
pub fn mobile<const N: usize>(robot: &Robot<N>, frames: &Frames<N>, u: &Vec3) -> bool {
    let p = frames.end_position();
    let (mut along, mut total) = (0.0f32, 0.0f32);
    for (j, joint) in robot.joints().iter().enumerate().take(frames.len()) {
        let (column, _) = frames.column(j, joint.kind, &p);
        let a = column.dot(u);
        along += a * a;
        total += column.dot(&column);
    }
    along >= IMMOBILE * total / 3.0
}

/// The `which`-th best (shortest) detour round `obstacle` (index `index`)
/// for a hand at `hand` aiming at `target`: a point `margin` plus 5 % of
/// `reach` outside the obstacle's inflated bounding box, beside it across
/// the blocked direction, on a side the hand can move toward (`mobile`); `None` for an obstacle too big to go round, or when fewer
/// than `which + 1` such points exist.
pub fn detour(
    (obstacle, index): (&Obstacle, u8),
    (hand, target): (Vec3, Vec3),
    which: usize,
    reach: f32,
    margin: f32,
    mobile: impl Fn(&Vec3) -> bool,
) -> Option<(Vec3, Side)> {
    let size = obstacle.bounding_radius() + margin;
    if size > DETOUR_SIZE * reach {
        return None;
    }
    let centre = obstacle.centre();
    let mut blocked = target - hand;
    if blocked.norm_squared() <= f32::MIN_POSITIVE {
        blocked = centre - hand;
    }
    let d = blocked / norm(&blocked);
    // Two directions across d: away from the world z axis unless d is it.
    let helper = if d.z.abs() < 0.9 {
        Vec3::z()
    } else {
        Vec3::x()
    };
    let across = d.cross(&helper);
    let e1 = across / norm(&across);
    let e2 = d.cross(&e1);
    let mut points = [(f32::INFINITY, Vec3::zeros()); DETOURS];
    for (k, slot) in points.iter_mut().enumerate() {
        let u = match k {
            0 => e1,
            1 => -e1,
            2 => e2,
            _ => -e2,
        };
        // Support of the inflated box in direction u.
        let extent = obstacle.box_extent(&u, margin);
        if !mobile(&u) {
            continue;
        }
        let point = centre + u * (extent + margin + 0.05 * reach);
        *slot = (norm(&(point - hand)) + norm(&(target - point)), point);
    }
    // The which-th shortest (a tiny selection sort over four).
    for i in 0..DETOURS {
        for j in i + 1..DETOURS {
            if points[j].0 < points[i].0 {
                points.swap(i, j);
            }
        }
    }
    let (length, point) = *points.get(which)?;
    length
        .is_finite()
        .then(|| (point, side_of(obstacle, index, point)))
}

/// The side of `obstacle` (index `index`) that `point` is on.
pub fn side_of(obstacle: &Obstacle, index: u8, point: Vec3) -> Side {
    let (axis, positive) = obstacle.side_of(&point);
    Side {
        obstacle: index,
        axis,
        positive,
    }
}
