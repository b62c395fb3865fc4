//! Obstacles: the paper's super-ellipsoids (eq. 25) and the CAD primitives
//! (sphere, box, capsule, cylinder) on true distances.
//!
//! Obstacle `j` has centre `c` and an orientation `R = Rz(rz) Ry(ry) Rx(rx)` from
//! 1-2-3 Euler angles (radians). A world point `p` is `x = R^T (p - c)` in the
//! obstacle's frame (CAPP.c rotated `p` about the world origin instead, and
//! cumulatively; that is its bug, not the method).
//!
//! **Super-ellipsoids.** Semi-axes `(a, b, c)` and exponents
//! `(k_x, k_y, k_z) >= 1`:
//!
//! ```text
//! C(p) = |x/a|^kx + |y/b|^ky + |z/c|^kz          (eq. 25)
//! ```
//!
//! is 1 on the surface, below 1 inside. Exponents 1 give an octahedron, 2 an
//! ellipsoid, 8 nearly a box. The absolute values make odd and real exponents
//! behave (the listing's `pow` without them only works for even integers).
//! Avoidance points see the obstacle *inflated* by a clearance margin for the
//! arm's thickness: the semi-axes grow by the margin of the point's kind
//! ([`PointKind`]), as the listing's `+6.0` at joints and `+3.0` at link
//! mid-points. Points farther than an influence distance outside the inflated
//! box are not evaluated at all (they are provably outside, `C > 1`).
//!
//! Integer exponents up to 32 take a multiply-only fast path; others use `powf`.
//! `C` is never NaN: terms are non-negative and an overflowing one is `inf`, and
//! any `C` above [`C_CUTOFF`] is treated as "out of influence".
//!
//! **Primitives** ([`Shape`]: sphere, box, capsule, cylinder) are measured by
//! their true signed distance `d(p)` to the surface ([`distance`]), so a
//! margin `m` is a distance: a point keeps `m` from every face, edge and
//! corner alike. Their `C` is the super-ellipsoid's rebuilt on distance,
//!
//! ```text
//! C(p) = ((d(p) + rho) / (m + rho))^2
//! ```
//!
//! with `rho` the shape's inradius: 1 exactly where `d = m`, below 1 closer,
//! convex (`d + rho >= 0` is convex and non-negative), and for a sphere of
//! radius `rho` it is the ellipsoid `|x|^2 / (rho + m)^2` itself, so the
//! potential (eq. 26), the projection and the engage threshold treat a
//! primitive as they treat the exponent-2 super-ellipsoid of its size. The
//! gradient is `2 (d + rho) / (m + rho)^2 grad d`, exact; the distance bound
//! is the distance itself, `d - m`, and points farther than the influence
//! distance from the inflated surface are out of influence. A sphere is
//! that ellipsoid to the bit (the same `C`, gradient, influence box and
//! distance bound: the larger of the convex bound `(C - 1) / |grad C|`, at
//! least half the distance and equal to it on the inflated surface, and
//! the distance to the inflated cube): its pair is the super-ellipsoid's,
//! with no square root and no call (0.9x an exponent-8 super-ellipsoid's
//! on the M4F; the primitives' own pair, out of line, cost 1.02x).

use crate::math::{max, rotation_123, vec3, Mat3, Vec3};

pub mod distance;
pub mod hull;
mod solid;

use distance::{from_segment, signed_distance, twice_from_box, Primitive};
pub use hull::{Hull, HullError, MAX_HULLS, MAX_HULL_VERTICES};
pub use solid::{Shape, Solid};

/// Largest `C` that still counts as "within influence"; the potential `1/(C-1)`
/// there is below `1e-6` and its gradient negligible.
pub const C_CUTOFF: f32 = 1.0e6;
/// Largest accepted exponent.
pub const MAX_EXPONENT: f32 = 64.0;
/// Smallest accepted semi-axis, length units.
pub const MIN_SEMI_AXIS: f32 = 1.0e-3;
/// Largest accepted semi-axis and centre coordinate, length units.
pub const MAX_EXTENT: f32 = 1.0e4;

/// A super-ellipsoid as a user describes it (not yet validated).
#[derive(Clone, Copy, Debug, PartialEq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub struct SuperEllipsoid {
    /// Centre `(x, y, z)`, length units.
    pub centre: [f32; 3],
    /// Semi-axes `(a, b, c)` along the obstacle's own axes, length units, > 0.
    pub semi_axes: [f32; 3],
    /// Exponents `(k_x, k_y, k_z)`, each in `[1, 64]`.
    pub exponents: [f32; 3],
    /// 1-2-3 Euler angles `(rx, ry, rz)`, radians: `R = Rz(rz) Ry(ry) Rx(rx)`.
    pub euler_123: [f32; 3],
}

impl SuperEllipsoid {
    /// An axis-aligned super-ellipsoid with the same exponent on every axis.
    pub fn aligned(centre: [f32; 3], semi_axes: [f32; 3], exponent: f32) -> Self {
        SuperEllipsoid {
            centre,
            semi_axes,
            exponents: [exponent; 3],
            euler_123: [0.0; 3],
        }
    }
}

/// Which parameter of an obstacle an error is about.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub enum ObstacleParameter {
    /// `centre`
    Centre,
    /// `semi_axes`
    SemiAxes,
    /// `exponents`
    Exponents,
    /// `euler_123`
    Orientation,
    /// A primitive's sizes (radius, length, half-extents).
    Size,
}

/// Why an obstacle was rejected. `obstacle` is 0-based.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub enum ObstacleError {
    /// More obstacles than the capacity `M`.
    TooMany {
        /// Capacity.
        capacity: usize,
    },
    /// A field holds NaN or infinity.
    NotFinite {
        /// The obstacle.
        obstacle: u8,
        /// The field.
        field: ObstacleParameter,
    },
    /// A semi-axis outside `[MIN_SEMI_AXIS, MAX_EXTENT]` (zero, negative, tiny or huge).
    SemiAxisOutOfRange {
        /// The obstacle.
        obstacle: u8,
    },
    /// A centre coordinate beyond `MAX_EXTENT`.
    CentreOutOfRange {
        /// The obstacle.
        obstacle: u8,
    },
    /// An exponent outside `[1, 64]`.
    ExponentOutOfRange {
        /// The obstacle.
        obstacle: u8,
    },
    /// A primitive's radius, length or half-extent outside
    /// `[MIN_SEMI_AXIS, MAX_EXTENT]`.
    SizeOutOfRange {
        /// The obstacle.
        obstacle: u8,
    },
    /// A convex obstacle names a hull the scenario does not have.
    NoSuchHull {
        /// The obstacle.
        obstacle: u8,
    },
    /// More hulls than [`MAX_HULLS`].
    TooManyHulls {
        /// Capacity.
        capacity: usize,
    },
    /// A hull's vertices were rejected. `hull` is 0-based.
    BadHull {
        /// The hull.
        hull: u8,
        /// Why.
        why: HullError,
    },
}

impl core::fmt::Display for ObstacleParameter {
    fn fmt(&self, f: &mut core::fmt::Formatter<'_>) -> core::fmt::Result {
        f.write_str(match self {
            ObstacleParameter::Centre => "centre",
            ObstacleParameter::SemiAxes => "semi-axes",
            ObstacleParameter::Exponents => "exponents",
            ObstacleParameter::Orientation => "orientation",
            ObstacleParameter::Size => "size",
        })
    }
}

impl core::fmt::Display for ObstacleError {
    fn fmt(&self, f: &mut core::fmt::Formatter<'_>) -> core::fmt::Result {
        match *self {
            ObstacleError::TooMany { capacity } => {
                write!(f, "more obstacles than the capacity of {capacity}")
            }
            ObstacleError::NotFinite { obstacle, field } => {
                write!(f, "obstacle {}: {field} is not finite", obstacle as u32 + 1)
            }
            ObstacleError::SemiAxisOutOfRange { obstacle } => write!(
                f,
                "obstacle {}: every semi-axis must be between {MIN_SEMI_AXIS} and {MAX_EXTENT}",
                obstacle as u32 + 1
            ),
            ObstacleError::CentreOutOfRange { obstacle } => write!(
                f,
                "obstacle {}: centre farther than {MAX_EXTENT} from the base",
                obstacle as u32 + 1
            ),
            ObstacleError::ExponentOutOfRange { obstacle } => write!(
                f,
                "obstacle {}: every exponent must be between 1 and {MAX_EXPONENT}",
                obstacle as u32 + 1
            ),
            ObstacleError::SizeOutOfRange { obstacle } => write!(
                f,
                "obstacle {}: every radius, length and half-extent must be between {MIN_SEMI_AXIS} and {MAX_EXTENT}",
                obstacle as u32 + 1
            ),
            ObstacleError::NoSuchHull { obstacle } => {
                write!(f, "obstacle {}: no such hull", obstacle as u32 + 1)
            }
            ObstacleError::TooManyHulls { capacity } => {
                write!(f, "more hulls than the capacity of {capacity}")
            }
            ObstacleError::BadHull { hull, why } => {
                write!(f, "hull {}: {why}", hull as u32 + 1)
            }
        }
    }
}

/// The two kinds of avoidance point, which see different clearance margins.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub enum PointKind {
    /// A joint (frame) origin: the listing's `+6.0` margin.
    Joint = 0,
    /// A point inside a link (its mid-point, or extra points): the listing's `+3.0`.
    Link = 1,
}

/// An exponent, sorted once into the fast integer path or the general one.
#[derive(Clone, Copy, Debug, PartialEq)]
enum Exponent {
    Integer(u8),
    Real(f32),
}

impl Exponent {
    fn new(k: f32) -> Self {
        if k == libm::floorf(k) && k <= 32.0 {
            Exponent::Integer(k as u8)
        } else {
            Exponent::Real(k)
        }
    }

    /// `(u^k, k u^(k-1))` for `u >= 0`.
    #[inline]
    fn power_and_slope(self, u: f32) -> (f32, f32) {
        match self {
            Exponent::Integer(k) => {
                let lower = powi(u, k - 1);
                (lower * u, k as f32 * lower)
            }
            Exponent::Real(k) => {
                let lower = libm::powf(u, k - 1.0);
                (lower * u, k * lower)
            }
        }
    }
}

/// `u^k` by squaring, `k` small. The common exponents (`k <= 8`, that is
/// `k_i <= 9`) are written out with the loop's own products in the loop's
/// order, so they give its bits without its branches.
#[inline]
fn powi(u: f32, k: u8) -> f32 {
    match k {
        0 => 1.0,
        1 => u,
        2 => u * u,
        3 => u * (u * u),
        4 => {
            let u2 = u * u;
            u2 * u2
        }
        5 => {
            let u2 = u * u;
            u * (u2 * u2)
        }
        6 => {
            let u2 = u * u;
            u2 * (u2 * u2)
        }
        7 => {
            let u2 = u * u;
            (u * u2) * (u2 * u2)
        }
        8 => {
            let u2 = u * u;
            let u4 = u2 * u2;
            u4 * u4
        }
        _ => powi_loop(u, k),
    }
}

/// `u^k` by squaring: the general case of [`powi`].
fn powi_loop(mut u: f32, mut k: u8) -> f32 {
    let mut acc = 1.0;
    while k > 0 {
        if k & 1 == 1 {
            acc *= u;
        }
        u *= u;
        k >>= 1;
    }
    acc
}

/// `C - 1`, `grad_p C` (world frame) and a distance bound at one avoidance point.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Contact {
    /// `C(p) - 1` of the inflated obstacle: positive outside, 0 on its
    /// surface; `+inf` when `C` is beyond [`C_CUTOFF`] (the pair is then out
    /// of the potential's influence, and `gradient` is zero).
    pub clearance: f32,
    /// Gradient of `C` with respect to the world point `p`, per length unit.
    pub gradient: Vec3,
    /// Square of a lower bound on the Euclidean distance from `p` to the
    /// inflated surface (0 inside), length units squared. The larger of two
    /// bounds that hold for every exponent `>= 1`:
    ///
    /// * `(C - 1) / |grad C|`: `C` is convex, so on the surface (`C = 1`)
    ///   `1 >= C(p) + grad C . (y - p)`, hence `|y - p| >= (C - 1) / |grad C|`;
    /// * the distance to the box `|x_i| <= semi-axis_i + margin`, which
    ///   holds the inflated super-ellipsoid.
    pub distance_sq: f32,
}

/// An obstacle's exponents, sorted once into the patterns the pair code runs
/// straight through (one dispatch a pair, not one an axis) and the general case.
#[derive(Clone, Copy, Debug, PartialEq)]
enum Powers {
    /// Exponent 2 on every axis (an ellipsoid; a sphere too, see
    /// [`Obstacle::new_in`]).
    Same2,
    /// Exponent 4 on every axis.
    Same4,
    /// Exponent 8 on every axis (nearly a box).
    Same8,
    /// Exponent 8 along x, 2 across it: a round cylinder with flat ends.
    CylinderX,
    /// Exponent 8 along y, 2 across it.
    CylinderY,
    /// Exponent 8 along z, 2 across it.
    CylinderZ,
    /// Anything else: each axis by its own [`Exponent`].
    Axes,
    /// Not a super-ellipsoid: a primitive, measured on distance (the
    /// obstacle's `primitive`, then always `Some`). A unit case: the
    /// primitive inside it made the enum 20 bytes and every
    /// super-ellipsoid pair 4 instructions slower.
    Primitive,
    /// A convex hull, measured on distance by GJK (the scenario's hull
    /// number `hull`).
    Hull,
    /// A box (the obstacle's `primitive` is a `Cuboid` of half-extents
    /// `half_box`): outside it, inline; inside, as [`Powers::Primitive`].
    Cuboid,
}

impl Powers {
    fn new(k: [f32; 3]) -> Self {
        match k {
            [2.0, 2.0, 2.0] => Powers::Same2,
            [4.0, 4.0, 4.0] => Powers::Same4,
            [8.0, 8.0, 8.0] => Powers::Same8,
            [8.0, 2.0, 2.0] => Powers::CylinderX,
            [2.0, 8.0, 2.0] => Powers::CylinderY,
            [2.0, 2.0, 8.0] => Powers::CylinderZ,
            _ => Powers::Axes,
        }
    }
}

/// For an even constant exponent `K`, on one axis (`x` the coordinate in
/// the obstacle's frame, `inv` the inverse inflated semi-axis): the term
/// `|x inv|^K` and the gradient's component `K |x inv|^(K-1) inv sign(x)`,
/// to the bit what [`Exponent::power_and_slope`] and the sign give
/// (`(slope * inv) * sign`), without the sign.
///
/// The powers run on the signed `s = x inv` instead of `u = |x| inv`: a
/// rounded product's magnitude does not depend on its factors' signs, so
/// `s^(K-1)` is `u^(K-1)` with the sign of `x` (odd power) and `s^(K-1) s` is
/// `u^K`. `x` must not be `-0`: at `x = 0` the gradient is `+0`, as
/// `(slope * inv) * 0` was.
#[inline(always)]
fn even_term_and_gradient<const K: u8>(x: f32, inv: f32) -> (f32, f32) {
    let s = x * inv;
    let lower = powi(s, K - 1);
    (lower * s, K as f32 * lower * inv)
}

/// `(u^k, k u^(k-1))` on each axis by its own exponent, as
/// `[term_x, slope_x, term_y, slope_y, term_z, slope_z]`. Out of line and
/// cold: the pair code's registers then need not survive `powf` calls.
#[cold]
#[inline(never)]
fn axes_powers(exponents: &[Exponent; 3], ux: f32, uy: f32, uz: f32) -> [f32; 6] {
    let [ex, ey, ez] = *exponents;
    let (tx, sx) = ex.power_and_slope(ux);
    let (ty, sy) = ey.power_and_slope(uy);
    let (tz, sz) = ez.power_and_slope(uz);
    [tx, sx, ty, sy, tz, sz]
}

/// One avoidance point against one obstacle, by case: what
/// [`Obstacle::contact`] gives, without its tests being made again.
#[derive(Clone, Copy, Debug, PartialEq)]
pub(crate) enum Pair {
    /// Outside the influence box (`contact` gives `None`).
    Far,
    /// Within the box, `C` beyond [`C_CUTOFF`] (or NaN): only the distance
    /// bound counts (`clearance` infinite, `gradient` zero).
    Beyond {
        /// As [`Contact::distance_sq`].
        distance_sq: f32,
    },
    /// On or inside the inflated surface, `C - 1 <= 0` (`distance_sq` 0).
    Inside {
        /// As [`Contact::clearance`].
        clearance: f32,
        /// As [`Contact::gradient`].
        gradient: Vec3,
    },
    /// Outside the inflated surface, within influence.
    Near {
        /// As [`Contact::clearance`], positive and finite.
        clearance: f32,
        /// As [`Contact::gradient`].
        gradient: Vec3,
        /// As [`Contact::distance_sq`].
        distance_sq: f32,
    },
}

/// The least `w` with `w * w > reach_sq` as rounded (infinity for an
/// infinite `reach_sq`). A point with `|r_i| > w` on any axis is outside
/// the sphere `r . r <= reach_sq` as computed: every rounded partial sum of
/// `r . r` is at least the rounded `r_i^2`, which is at least the rounded
/// `w * w`.
fn sphere_bound(reach_sq: f32) -> f32 {
    if !reach_sq.is_finite() {
        return f32::INFINITY;
    }
    let mut w = crate::math::sqrt(reach_sq);
    while w * w <= reach_sq {
        w = w.next_up();
    }
    w
}

/// What a point of one [`PointKind`] sees of an obstacle.
#[derive(Clone, Copy, Debug)]
struct Inflated {
    /// Squared radius of the sphere around the influence box.
    reach_sq: f32,
    /// Half-extents of a world-axis box around the influence region: the
    /// influence box itself for an aligned obstacle; for a rotated one the
    /// box around its sphere ([`sphere_bound`] on every axis).
    bound: Vec3,
    /// Half-extents of the influence box, `semi-axis + margin + influence`.
    reach: Vec3,
    /// `1 / (semi-axis + margin)`.
    inv: Vec3,
    /// `reach - influence` (the inflated semi-axes, as the box bound has
    /// always computed them).
    inner: Vec3,
    /// A primitive's margin `m`, length units (unused for super-ellipsoids).
    margin: f32,
    /// A primitive's `1 / (m + rho)` (unused for super-ellipsoids).
    inv_scale: f32,
}

/// `C - 1`, `grad C` and `d - m` of a ball of `radius` about the origin at
/// the local point `v` (a capsule's, `v` from its segment): with `rho =
/// radius`, `C = (|v| / (m + radius))^2`.
#[inline(always)]
fn round(v: &Vec3, radius: f32, inflated: &Inflated) -> (f32, Vec3, f32) {
    let inv_sq = inflated.inv_scale * inflated.inv_scale;
    let length_sq = v.dot(v);
    let gap = crate::math::sqrt_inline(length_sq) - radius - inflated.margin;
    (length_sq * inv_sq - 1.0, v * (2.0 * inv_sq), gap)
}

/// The case of [`Pair`] for a point within influence with `C - 1` =
/// `clearance` and `grad C` = `gradient` (world frame): inside, beyond the
/// cut-off (NaN too) or near; `distance_sq` (the bound's square) is
/// computed only outside.
#[inline(always)]
fn by_clearance(clearance: f32, gradient: Vec3, distance_sq: impl FnOnce() -> f32) -> Pair {
    if clearance <= 0.0 {
        return Pair::Inside {
            clearance,
            gradient,
        };
    }
    let distance_sq = distance_sq();
    #[allow(clippy::neg_cmp_op_on_partial_ord)]
    if !(clearance < C_CUTOFF) {
        return Pair::Beyond { distance_sq };
    }
    Pair::Near {
        clearance,
        gradient,
        distance_sq,
    }
}

/// Half-extents of the smallest box about the centre, in the obstacle's own
/// frame, that holds `s` (a super-ellipsoid's semi-axes), length units; a
/// hull's from `hulls`.
fn half_box(s: &Solid, hulls: &[Hull]) -> Vec3 {
    match s.shape {
        Shape::SuperEllipsoid { semi_axes, .. } => vec3(semi_axes),
        Shape::Convex { hull } => hulls
            .get(hull as usize)
            .map_or(Vec3::zeros(), |h| h.half_box()),
        ref shape => Primitive::of(shape).map_or(Vec3::zeros(), |p| p.half_box()),
    }
}

/// The obstacles of a scenario and the hulls its convex ones name: what the
/// pair code reads. Dereferences to the obstacles.
#[derive(Clone, Copy, Debug)]
pub struct World<'a> {
    /// The obstacles.
    pub obstacles: &'a [Obstacle],
    /// The hulls, by index ([`Shape::Convex`]).
    pub hulls: &'a [Hull],
}

impl<'a> World<'a> {
    /// Obstacles with no hulls (none of them convex).
    pub fn of(obstacles: &'a [Obstacle]) -> Self {
        World {
            obstacles,
            hulls: &[],
        }
    }
}

impl core::ops::Deref for World<'_> {
    type Target = [Obstacle];
    fn deref(&self) -> &[Obstacle] {
        self.obstacles
    }
}

/// A validated obstacle with everything a step needs precomputed; the data a
/// pair test reads for one [`PointKind`] is kept together.
#[derive(Clone, Copy, Debug)]
pub struct Obstacle {
    /// The centre with every `+0` coordinate stored as `-0`: `p - centre`
    /// is then the same subtraction, except that it never gives `-0`
    /// (`-0 - (+0)` is `-0`, `-0 - (-0)` is `+0`).
    centre: Vec3,
    /// Per [`PointKind`].
    inflated: [Inflated; 2],
    /// Whether `R` is the identity (no Euler angles): the rotations are skipped.
    aligned: bool,
    powers: Powers,
    exponents: [Exponent; 3],
    /// `R` (obstacle axes in world coordinates, as columns).
    rotation: Mat3,
    /// The primitive measured on distance; `None` for a super-ellipsoid
    /// and a hull.
    primitive: Option<Primitive>,
    /// A convex obstacle's hull, an index into the scenario's list.
    hull: u8,
    /// Half-extents of the box about the centre holding the shape, its
    /// own frame, length units.
    half_box: Vec3,
    /// A primitive's inradius `rho` (a hull's half-width), length units.
    inradius: f32,
    /// The influence distance, length units.
    influence: f32,
    source: Solid,
}

impl Obstacle {
    /// Validates `s` (as obstacle number `index`) and inflates it by the
    /// margins (joint, link) and the influence distance, all non-negative
    /// finite lengths already checked by the caller. Not a hull
    /// ([`Obstacle::new_in`]).
    pub fn new<S: Into<Solid> + Copy>(
        index: u8,
        s: &S,
        margins: [f32; 2],
        influence: f32,
    ) -> Result<Self, ObstacleError> {
        Self::new_in(index, s, &[], margins, influence)
    }

    /// [`Obstacle::new`] in a scenario with `hulls` (a convex obstacle
    /// names one of them).
    pub fn new_in<S: Into<Solid> + Copy>(
        index: u8,
        s: &S,
        hulls: &[Hull],
        margins: [f32; 2],
        influence: f32,
    ) -> Result<Self, ObstacleError> {
        let s: Solid = (*s).into();
        let obstacle = index;
        let not_finite = |field| ObstacleError::NotFinite { obstacle, field };
        let (sizes, count) = s.sizes();
        let sizes = &sizes[..count];
        let exponents = match s.shape {
            Shape::SuperEllipsoid { exponents, .. } => exponents,
            _ => [2.0; 3],
        };
        let size_field = match s.shape {
            Shape::SuperEllipsoid { .. } => ObstacleParameter::SemiAxes,
            _ => ObstacleParameter::Size,
        };
        if !s.centre.iter().all(|v| v.is_finite()) {
            return Err(not_finite(ObstacleParameter::Centre));
        }
        if !sizes.iter().all(|v| v.is_finite()) {
            return Err(not_finite(size_field));
        }
        if !exponents.iter().all(|v| v.is_finite()) {
            return Err(not_finite(ObstacleParameter::Exponents));
        }
        if !s.euler_123.iter().all(|v| v.is_finite()) {
            return Err(not_finite(ObstacleParameter::Orientation));
        }
        if !sizes
            .iter()
            .all(|&a| (MIN_SEMI_AXIS..=MAX_EXTENT).contains(&a))
        {
            return Err(match s.shape {
                Shape::SuperEllipsoid { .. } => ObstacleError::SemiAxisOutOfRange { obstacle },
                _ => ObstacleError::SizeOutOfRange { obstacle },
            });
        }
        if !s.centre.iter().all(|c| c.abs() <= MAX_EXTENT) {
            return Err(ObstacleError::CentreOutOfRange { obstacle });
        }
        if !exponents.iter().all(|&k| (1.0..=MAX_EXPONENT).contains(&k)) {
            return Err(ObstacleError::ExponentOutOfRange { obstacle });
        }
        let primitive = Primitive::of(&s.shape);
        let (hull, inradius) = match s.shape {
            Shape::Convex { hull } => match hulls.get(hull as usize) {
                Some(h) => (hull, h.half_width()),
                None => return Err(ObstacleError::NoSuchHull { obstacle }),
            },
            _ => (0, primitive.map_or(0.0, |p| p.inradius())),
        };
        let [rx, ry, rz] = s.euler_123;
        let rotation = rotation_123(rx, ry, rz);
        let axes = half_box(&s, hulls);
        // A sphere is the same turned any way: its rotation is skipped.
        let aligned = s.euler_123 == [0.0; 3] || matches!(s.shape, Shape::Sphere { .. });
        // Per margin, written out: `margins.map` compiled to an
        // out-of-line `try_map` of 700 bytes on the board.
        let inflate = |m: f32| {
            let inflated = axes.add_scalar(m);
            let reach = inflated.add_scalar(influence);
            let reach_sq = reach.dot(&reach);
            Inflated {
                reach_sq,
                bound: if aligned {
                    reach
                } else {
                    Vec3::repeat(sphere_bound(reach_sq))
                },
                reach,
                inv: inflated.map(|x| 1.0 / x),
                inner: reach.map(|r| r - influence),
                margin: m,
                inv_scale: 1.0 / (m + inradius),
            }
        };
        let inflated = [inflate(margins[0]), inflate(margins[1])];
        Ok(Obstacle {
            centre: vec3(s.centre.map(|c| if c == 0.0 { -0.0 } else { c })),
            inflated,
            aligned,
            powers: match (primitive, s.shape) {
                (Some(Primitive::Cuboid { .. }), _) => Powers::Cuboid,
                // A sphere of radius `r` is the ellipsoid of semi-axes `r`:
                // `C` rebuilt on its distance, `((d + r) / (m + r))^2 = |x|^2
                // / (m + r)^2`, is the ellipsoid's (its `inv` is `1 / (r +
                // m)` on every axis), so it takes the super-ellipsoid's pair
                // code, inline, with its influence box (a cube round the
                // ball of radius `r + m + influence`) and its distance bound.
                (Some(Primitive::Sphere { .. }), _) => Powers::Same2,
                (Some(_), _) => Powers::Primitive,
                (None, Shape::Convex { .. }) => Powers::Hull,
                (None, _) => Powers::new(exponents),
            },
            exponents: exponents.map(Exponent::new),
            rotation,
            primitive,
            hull,
            half_box: axes,
            inradius,
            influence,
            source: s,
        })
    }

    /// The obstacle as given.
    pub fn source(&self) -> &Solid {
        &self.source
    }

    /// Centre, world frame.
    pub fn centre(&self) -> Vec3 {
        vec3(self.source.centre)
    }

    /// Orientation `R`: the obstacle's axes as world-frame columns.
    pub fn rotation(&self) -> &Mat3 {
        &self.rotation
    }

    /// Radius of the sphere about the centre through the corners of the
    /// shape's bounding box (`|semi-axes|`), length units: its size, for
    /// deciding whether to go round it.
    pub fn bounding_radius(&self) -> f32 {
        let axes = &self.half_box;
        crate::math::sqrt(axes.iter().map(|a| a * a).sum::<f32>())
    }

    /// How far the shape's bounding box, inflated by `margin`, reaches from
    /// the centre along the world unit direction `u` (its support in `u`),
    /// length units: `sum_i |(R^T u)_i| (a_i + margin)`.
    pub fn box_extent(&self, u: &Vec3, margin: f32) -> f32 {
        let local = self.rotation.transpose() * u;
        local
            .iter()
            .zip(self.half_box.iter())
            .map(|(l, a)| l.abs() * (a + margin))
            .sum()
    }

    /// The side of the shape `point` is on: the axis of the obstacle's own
    /// frame (0, 1, 2 for x, y, z) along which it is farthest out in units
    /// of the semi-axes, and whether on that axis' positive side.
    pub fn side_of(&self, point: &Vec3) -> (u8, bool) {
        let x = self.rotation.transpose() * (point - self.centre());
        let axes = &self.half_box;
        let (mut axis, mut far, mut positive) = (0u8, f32::NEG_INFINITY, true);
        for (i, (&xi, &a)) in x.iter().zip(axes.iter()).enumerate() {
            let u = xi.abs() / max(a, f32::MIN_POSITIVE);
            if u > far {
                (axis, far, positive) = (i as u8, u, xi >= 0.0);
            }
        }
        (axis, positive)
    }

    /// `C(p) - 1`, its gradient and a distance bound for a point of `kind`, or
    /// `None` when the point is outside the influence region (then it is at
    /// least the influence distance from the inflated surface).
    /// `hulls` are the scenario's ([`World::hulls`]; a convex obstacle
    /// names one).
    #[inline(always)]
    pub fn contact(&self, p: &Vec3, kind: PointKind, hulls: &[Hull]) -> Option<Contact> {
        match self.pair(p, kind, hulls) {
            Pair::Far => None,
            Pair::Beyond { distance_sq } => Some(Contact {
                clearance: f32::INFINITY,
                gradient: Vec3::zeros(),
                distance_sq,
            }),
            Pair::Inside {
                clearance,
                gradient,
            } => Some(Contact {
                clearance,
                gradient,
                distance_sq: 0.0,
            }),
            Pair::Near {
                clearance,
                gradient,
                distance_sq,
            } => Some(Contact {
                clearance,
                gradient,
                distance_sq,
            }),
        }
    }

    /// [`Obstacle::contact`], sorted by case, so that a caller that
    /// inlines it branches once per pair instead of testing the
    /// [`Contact`] again.
    // Always inlined: most pairs end at the box test, which then costs a
    // dozen instructions instead of a call.
    #[inline(always)]
    pub(crate) fn pair(&self, p: &Vec3, kind: PointKind, hulls: &[Hull]) -> Pair {
        let inflated = match kind {
            PointKind::Joint => &self.inflated[0],
            PointKind::Link => &self.inflated[1],
        };
        // The world-axis box first, an axis at a time (most pairs end at the
        // first). For an aligned obstacle it is the influence box, the whole
        // test: a point inside it is inside its sphere (`|r_i| <= reach_i`
        // on every axis makes every rounded square, and so the rounded sum,
        // at most `reach_sq`), so the sphere test would only repeat it. For a
        // rotated one it only drops points the sphere test would drop.
        let bound = &inflated.bound;
        let rx = p.x - self.centre.x;
        if rx.abs() > bound.x {
            return Pair::Far;
        }
        let ry = p.y - self.centre.y;
        if ry.abs() > bound.y {
            return Pair::Far;
        }
        let rz = p.z - self.centre.z;
        if rz.abs() > bound.z {
            return Pair::Far;
        }
        let r = Vec3::new(rx, ry, rz);
        let x = if self.aligned {
            r
        } else {
            // The sphere test, before the rotation.
            if r.dot(&r) > inflated.reach_sq {
                return Pair::Far;
            }
            let reach = &inflated.reach;
            // R^T r by the columns of R (no stored transpose: 36 bytes an
            // obstacle), with -0 made +0 (as the aligned `r` never is).
            let x = self.rotation.tr_mul(&r).add_scalar(0.0);
            if x.x.abs() > reach.x || x.y.abs() > reach.y || x.z.abs() > reach.z {
                return Pair::Far;
            }
            x
        };
        let (ax, ay, az) = (x.x.abs(), x.y.abs(), x.z.abs());
        let inv = &inflated.inv;
        // Per axis the term `|x/a|^k` and the gradient's component
        // `k |x/a|^(k-1) sign(x) / a`. A primitive is one more case of the
        // same dispatch, so a super-ellipsoid's pair pays no test for it.
        let ((tx, gx), (ty, gy), (tz, gz)) = match self.powers {
            Powers::Primitive => {
                return match &self.primitive {
                    Some(primitive) => self.primitive_pair(primitive, inflated, &x),
                    None => Pair::Far,
                }
            }
            Powers::Hull => return self.hull_pair(hulls, inflated, &x),
            Powers::Cuboid => return self.cuboid_pair(inflated, &x),
            Powers::Same2 => (
                even_term_and_gradient::<2>(x.x, inv.x),
                even_term_and_gradient::<2>(x.y, inv.y),
                even_term_and_gradient::<2>(x.z, inv.z),
            ),
            Powers::Same4 => (
                even_term_and_gradient::<4>(x.x, inv.x),
                even_term_and_gradient::<4>(x.y, inv.y),
                even_term_and_gradient::<4>(x.z, inv.z),
            ),
            Powers::Same8 => (
                even_term_and_gradient::<8>(x.x, inv.x),
                even_term_and_gradient::<8>(x.y, inv.y),
                even_term_and_gradient::<8>(x.z, inv.z),
            ),
            Powers::CylinderX => (
                even_term_and_gradient::<8>(x.x, inv.x),
                even_term_and_gradient::<2>(x.y, inv.y),
                even_term_and_gradient::<2>(x.z, inv.z),
            ),
            Powers::CylinderY => (
                even_term_and_gradient::<2>(x.x, inv.x),
                even_term_and_gradient::<8>(x.y, inv.y),
                even_term_and_gradient::<2>(x.z, inv.z),
            ),
            Powers::CylinderZ => (
                even_term_and_gradient::<2>(x.x, inv.x),
                even_term_and_gradient::<2>(x.y, inv.y),
                even_term_and_gradient::<8>(x.z, inv.z),
            ),
            Powers::Axes => {
                let (ux, uy, uz) = (ax * inv.x, ay * inv.y, az * inv.z);
                let [tx, sx, ty, sy, tz, sz] = axes_powers(&self.exponents, ux, uy, uz);
                // d|x|/dx = sign(x); zero at x = 0 (the octahedron's kink).
                let sign = |x: f32| {
                    if x > 0.0 {
                        1.0
                    } else if x < 0.0 {
                        -1.0
                    } else {
                        0.0
                    }
                };
                (
                    (tx, sx * inv.x * sign(x.x)),
                    (ty, sy * inv.y * sign(x.y)),
                    (tz, sz * inv.z * sign(x.z)),
                )
            }
        };
        // The sum from 0 in axis order, as the loop it replaces (0 + t = t:
        // the terms are never -0).
        let c = tx + ty + tz;
        let local_gradient = Vec3::new(gx, gy, gz);
        let inner = &inflated.inner;
        let (ox, oy, oz) = (
            max(ax - inner.x, 0.0),
            max(ay - inner.y, 0.0),
            max(az - inner.z, 0.0),
        );
        let box_sq = ox * ox + oy * oy + oz * oz;
        // Within the cut-off (one comparison: NaN is beyond it too).
        let clearance = if c <= C_CUTOFF {
            c - 1.0
        } else {
            return Pair::Beyond {
                distance_sq: box_sq,
            };
        };
        let gradient = if self.aligned {
            local_gradient
        } else {
            self.rotation * local_gradient
        };
        if clearance <= 0.0 {
            return Pair::Inside {
                clearance,
                gradient,
            };
        }
        let slope_sq = local_gradient.dot(&local_gradient);
        let convex_sq = if slope_sq > 0.0 {
            clearance * clearance / slope_sq
        } else {
            box_sq
        };
        Pair::Near {
            clearance,
            gradient,
            distance_sq: max(convex_sq, box_sq),
        }
    }

    /// [`Obstacle::pair`] for a primitive, the local point `x` within its
    /// influence box: `C` rebuilt on the signed distance (see the module
    /// docs).
    // Out of line and cold: the super-ellipsoid pair code it is called from
    // keeps its registers (inlined, it made every super-ellipsoid pair 11
    // instructions slower; `cold` saves 110 a PIPS + 8 step).
    #[cold]
    #[inline(never)]
    fn primitive_pair(&self, primitive: &Primitive, inflated: &Inflated, x: &Vec3) -> Pair {
        let (clearance, local_gradient, gap) = match *primitive {
            // Round about a segment: `d + rho = |v|` (`rho` the radius), so
            // `C = |v|^2 / (m + rho)^2` and `grad C = 2 v / (m + rho)^2`, no
            // division; the root only for the distance.
            Primitive::Capsule {
                radius,
                half_length,
            } => round(&from_segment(x, half_length), radius, inflated),
            _ => {
                let (d, normal) = signed_distance(primitive, x);
                let (clearance, gradient) = self.rebuilt(d, &normal, inflated);
                (clearance, gradient, d - inflated.margin)
            }
        };
        self.primitive_tail(clearance, local_gradient, gap)
    }

    /// [`Obstacle::pair`] for a box, the local point `x` within its
    /// influence box. Outside the box, from its closest point: `o` the
    /// excess on each axis (signed as `x`), `d = |o|`, `grad C = 2 u inv o /
    /// d`, one division; inside (or a point not finite), the cold
    /// [`Obstacle::primitive_pair`] (the signed distance, as for every
    /// primitive).
    // Inline in `pair`, its excess by float operations alone
    // ([`twice_from_box`], seven an axis, no comparison): M4F, `step_count`,
    // 113.9 instructions a pair in the loop of pairs against the exponent-8
    // super-ellipsoid's 118.9 (136.2 / 137.2 each alone). Measured and not
    // kept: the excess by integer operations (118.8 / 116.8, 150.3 / 141.4:
    // every value moved to a core register and back); by float `max` and
    // `copysign` (123.9 / 118.9); out of line with the answer in
    // registers (a `repr(C)` struct of four floats, AAPCS-VFP): 133.8 /
    // 114.8, the loop's registers saved round the call; out of line and
    // cold, the answer through memory, 43 dearer. Inline code shares the
    // registers of the planner's pair loop: a PIPS + 8 step (no box in it)
    // is 55 854 instructions with this, 55 421 with the integer excess,
    // 54 919 with the box out of line.
    #[inline(always)]
    fn cuboid_pair(&self, inflated: &Inflated, x: &Vec3) -> Pair {
        // Twice the excess `o` and twice `d = |o|`, exactly (scaling by 2
        // commutes with rounding, the root's too): `o2 / d2 = o / d`.
        let o2 = twice_from_box(x, &self.half_box);
        let out_sq4 = o2.dot(&o2);
        #[allow(clippy::neg_cmp_op_on_partial_ord)]
        if !(out_sq4 > 0.0) {
            return match &self.primitive {
                Some(primitive) => self.primitive_pair(primitive, inflated, x),
                None => Pair::Far,
            };
        }
        let d = 0.5 * crate::math::sqrt_inline(out_sq4);
        let u = (d + self.inradius) * inflated.inv_scale;
        self.primitive_tail(
            u * u - 1.0,
            o2 * (u * inflated.inv_scale / d),
            d - inflated.margin,
        )
    }

    /// [`Obstacle::pair`] for a hull, the local point `x` within its
    /// influence box: `C` rebuilt on the GJK distance `d` (0 inside), `rho`
    /// the hull's half-width; the distance bound from GJK's lower bound.
    #[cold]
    #[inline(never)]
    fn hull_pair(&self, hulls: &[Hull], inflated: &Inflated, x: &Vec3) -> Pair {
        let Some(hull) = hulls.get(self.hull as usize) else {
            return Pair::Far;
        };
        let d = hull.distance(x);
        let (clearance, gradient) = self.rebuilt(d.distance, &d.normal, inflated);
        self.primitive_tail(clearance, gradient, d.lower_bound - inflated.margin)
    }

    /// The cases of [`Pair`] from a primitive's `C - 1`, `grad C` (local
    /// frame) and `d - m`.
    #[inline(always)]
    fn primitive_tail(&self, clearance: f32, local_gradient: Vec3, gap: f32) -> Pair {
        // One comparison: NaN (a point not finite) is out of influence too.
        #[allow(clippy::neg_cmp_op_on_partial_ord)]
        if !(gap <= self.influence) {
            return Pair::Far;
        }
        let gradient = if self.aligned {
            local_gradient
        } else {
            self.rotation * local_gradient
        };
        by_clearance(clearance, gradient, || {
            // `max(gap, 0)` (the sign bit clears a negative gap: no float
            // comparison), squared.
            let bits = gap.to_bits();
            let distance = f32::from_bits(bits & !(((bits as i32) >> 31) as u32));
            distance * distance
        })
    }

    /// `C - 1` and `grad C` (local frame) of a primitive from its signed
    /// distance `d` and `grad d`: `C = ((d + rho) / (m + rho))^2`.
    #[inline(always)]
    fn rebuilt(&self, d: f32, normal: &Vec3, inflated: &Inflated) -> (f32, Vec3) {
        let u = (d + self.inradius) * inflated.inv_scale;
        (u * u - 1.0, normal * (2.0 * u * inflated.inv_scale))
    }

    /// `C(p) - 1` with no influence cut-off (for reporting and checks; may
    /// be `inf`); `hulls` as for [`Obstacle::contact`].
    pub fn clearance_uncut(&self, p: &Vec3, kind: PointKind, hulls: &[Hull]) -> f32 {
        let x = self.rotation.tr_mul(&(p - self.centre()));
        if let Shape::Convex { hull } = self.source.shape {
            let d = hulls
                .get(hull as usize)
                .map_or(f32::INFINITY, |h| h.distance(&x).distance);
            return self
                .rebuilt(d, &Vec3::zeros(), &self.inflated[kind as usize])
                .0;
        }
        if let Some(primitive) = &self.primitive {
            let (d, normal) = signed_distance(primitive, &x);
            return self.rebuilt(d, &normal, &self.inflated[kind as usize]).0;
        }
        let inv = &self.inflated[kind as usize].inv;
        let mut c = 0.0;
        for axis in 0..3 {
            c += self.exponents[axis]
                .power_and_slope(x[axis].abs() * inv[axis])
                .0;
        }
        c - 1.0
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn unit_ball(exponent: f32) -> Obstacle {
        Obstacle::new(
            0,
            &SuperEllipsoid::aligned([1.0, 2.0, 3.0], [1.0, 2.0, 4.0], exponent),
            [0.0, 0.0],
            100.0,
        )
        .unwrap()
    }

    #[test]
    fn surface_points_have_zero_clearance() {
        for k in [1.0, 2.0, 2.5, 8.0] {
            let o = unit_ball(k);
            for p in [[2.0, 2.0, 3.0], [1.0, 4.0, 3.0], [1.0, 2.0, -1.0]] {
                let c = o.contact(&vec3(p), PointKind::Joint, &[]).unwrap();
                assert!(c.clearance.abs() < 1e-6, "k={k} p={p:?} {c:?}");
            }
            let inside = o
                .contact(&vec3([1.2, 2.1, 3.0]), PointKind::Joint, &[])
                .unwrap();
            assert!(inside.clearance < 0.0);
        }
    }

    #[test]
    fn orientation_is_about_the_centre_not_the_world_origin() {
        // A long thin box rotated 90 degrees about z: its long axis becomes world y.
        let s = SuperEllipsoid {
            centre: [10.0, 0.0, 0.0],
            semi_axes: [5.0, 1.0, 1.0],
            exponents: [2.0; 3],
            euler_123: [0.0, 0.0, core::f32::consts::FRAC_PI_2],
        };
        let o = Obstacle::new(0, &s, [0.0, 0.0], 10.0).unwrap();
        let along_y = o
            .contact(&vec3([10.0, 4.0, 0.0]), PointKind::Joint, &[])
            .unwrap();
        assert!(
            along_y.clearance < 0.0,
            "inside along the rotated long axis"
        );
        let along_x = o
            .contact(&vec3([14.0, 0.0, 0.0]), PointKind::Joint, &[])
            .unwrap();
        assert!(along_x.clearance > 0.0, "outside across it");
    }

    #[test]
    fn margins_inflate_by_point_kind() {
        let o = Obstacle::new(
            0,
            &SuperEllipsoid::aligned([0.0; 3], [1.0; 3], 2.0),
            [6.0, 3.0],
            1.0,
        )
        .unwrap();
        let p = vec3([5.0, 0.0, 0.0]);
        assert!(o.contact(&p, PointKind::Joint, &[]).unwrap().clearance < 0.0);
        assert!(o.contact(&p, PointKind::Link, &[]).unwrap().clearance > 0.0);
    }

    #[test]
    fn large_exponents_and_far_points_give_no_nan() {
        let o = Obstacle::new(
            0,
            &SuperEllipsoid::aligned([0.0; 3], [MIN_SEMI_AXIS; 3], MAX_EXPONENT),
            [0.0, 0.0],
            MAX_EXTENT,
        )
        .unwrap();
        for p in [
            [0.5, 0.0, 0.0],
            [1.0e4, 0.0, 0.0],
            [3.0e38, 0.0, 1.0],
            [0.0; 3],
        ] {
            if let Some(c) = o.contact(&vec3(p), PointKind::Link, &[]) {
                assert!(!c.clearance.is_nan() && c.gradient.iter().all(|g| g.is_finite()));
                assert!(!c.distance_sq.is_nan());
            }
            assert!(!o.clearance_uncut(&vec3(p), PointKind::Link, &[]).is_nan());
        }
    }

    /// Reproducible uniform numbers in [-1, 1).
    fn lcg(state: &mut u64) -> f32 {
        *state = state
            .wrapping_mul(6364136223846793005)
            .wrapping_add(1442695040888963407);
        ((*state >> 40) as f32 / (1u64 << 24) as f32) * 2.0 - 1.0
    }

    #[test]
    fn distance_bound_never_exceeds_the_distance_and_is_tight_at_a_face() {
        // For points around obstacles of every shape, every point within the
        // bound of p is outside the inflated obstacle (C > 1): the bound is
        // a true lower bound on the distance.
        let mut rng = 7u64;
        for exponents in [
            [1.0, 1.0, 1.0],
            [2.0; 3],
            [8.0, 2.0, 2.0],
            [2.5, 8.0, 3.0],
            [32.0; 3],
        ] {
            let s = SuperEllipsoid {
                centre: [1.0, -2.0, 0.5],
                semi_axes: [3.0, 1.0, 2.0],
                exponents,
                euler_123: [0.3, -0.2, 0.9],
            };
            let o = Obstacle::new(0, &s, [0.5, 0.25], 20.0).unwrap();
            for _ in 0..200 {
                let p = o.centre() + vec3([lcg(&mut rng), lcg(&mut rng), lcg(&mut rng)]) * 9.0;
                let Some(c) = o.contact(&p, PointKind::Joint, &[]) else {
                    continue;
                };
                if c.clearance <= 0.0 {
                    assert_eq!(c.distance_sq, 0.0);
                    continue;
                }
                let d = c.distance_sq.sqrt();
                for _ in 0..200 {
                    let dir = vec3([lcg(&mut rng), lcg(&mut rng), lcg(&mut rng)]);
                    let len = dir.norm();
                    if len == 0.0 {
                        continue;
                    }
                    let y = p + dir * (0.999 * d * lcg(&mut rng).abs() / len);
                    assert!(
                        o.clearance_uncut(&y, PointKind::Joint, &[]) > -1e-5,
                        "k={exponents:?} p={p:?} bound {d} reaches inside"
                    );
                }
            }
        }
        // A box face: the bound is the distance itself.
        let o = Obstacle::new(
            0,
            &SuperEllipsoid::aligned([0.0; 3], [2.0; 3], 8.0),
            [1.0, 1.0],
            10.0,
        )
        .unwrap();
        let c = o
            .contact(&vec3([4.5, 0.0, 0.0]), PointKind::Joint, &[])
            .unwrap();
        assert!((c.distance_sq.sqrt() - 1.5).abs() < 1e-4, "{c:?}");
    }

    /// `Obstacle::contact` as it was written before its exponent patterns:
    /// one loop over the axes, each exponent dispatched on its own.
    fn contact_per_axis(o: &Obstacle, p: &Vec3, kind: PointKind) -> Option<Contact> {
        let k = kind as usize;
        let inflated = &o.inflated[k];
        let r = p - o.centre();
        if r.dot(&r) > inflated.reach_sq {
            return None;
        }
        let x = if o.aligned { r } else { o.rotation.tr_mul(&r) };
        let reach = &inflated.reach;
        if x.x.abs() > reach.x || x.y.abs() > reach.y || x.z.abs() > reach.z {
            return None;
        }
        let inv = &inflated.inv;
        let mut c = 0.0;
        let mut local_gradient = Vec3::zeros();
        let mut box_sq = 0.0;
        for axis in 0..3 {
            let u = x[axis].abs() * inv[axis];
            let (term, slope) = o.exponents[axis].power_and_slope(u);
            c += term;
            let sign = if x[axis] > 0.0 {
                1.0
            } else if x[axis] < 0.0 {
                -1.0
            } else {
                0.0
            };
            local_gradient[axis] = slope * inv[axis] * sign;
            let outside = max(x[axis].abs() - inflated.inner[axis], 0.0);
            box_sq += outside * outside;
        }
        if c > C_CUTOFF || c.is_nan() {
            return Some(Contact {
                clearance: f32::INFINITY,
                gradient: Vec3::zeros(),
                distance_sq: box_sq,
            });
        }
        let clearance = c - 1.0;
        let slope_sq = local_gradient.dot(&local_gradient);
        let convex_sq = if clearance <= 0.0 {
            0.0
        } else if slope_sq > 0.0 {
            clearance * clearance / slope_sq
        } else {
            box_sq
        };
        Some(Contact {
            clearance,
            gradient: if o.aligned {
                local_gradient
            } else {
                o.rotation * local_gradient
            },
            distance_sq: if clearance <= 0.0 {
                0.0
            } else {
                max(convex_sq, box_sq)
            },
        })
    }

    fn bits(c: Option<Contact>) -> Option<[u32; 5]> {
        c.map(|c| {
            [
                c.clearance.to_bits(),
                c.gradient.x.to_bits(),
                c.gradient.y.to_bits(),
                c.gradient.z.to_bits(),
                c.distance_sq.to_bits(),
            ]
        })
    }

    #[test]
    fn exponent_patterns_match_the_per_axis_loop_bit_for_bit() {
        let mut rng = 11u64;
        let patterns = [
            [2.0, 2.0, 2.0],
            [4.0, 4.0, 4.0],
            [8.0, 8.0, 8.0],
            [8.0, 2.0, 2.0],
            [2.0, 8.0, 2.0],
            [2.0, 2.0, 8.0],
            [1.0, 1.0, 1.0],
            [3.0, 3.0, 3.0],
            [2.5, 8.0, 3.0],
            [8.0, 4.0, 2.0],
            [32.0, 32.0, 32.0],
        ];
        for exponents in patterns {
            for euler_123 in [[0.0; 3], [0.3, -0.2, 0.9]] {
                let s = SuperEllipsoid {
                    centre: [1.0, -2.0, 0.0],
                    semi_axes: [3.0, 1.0, 2.0],
                    exponents,
                    euler_123,
                };
                let o = Obstacle::new(0, &s, [0.5, 0.25], 6.0).unwrap();
                let mut points = std::vec![
                    vec3([1.0, -2.0, 0.0]),
                    vec3([1.0, -2.0, -0.0]),
                    vec3([4.5, -2.0, 0.0]),
                    vec3([1.0, -3.5, 0.0]),
                ];
                for _ in 0..2000 {
                    let d = vec3([lcg(&mut rng), lcg(&mut rng), lcg(&mut rng)]) * 12.0;
                    points.push(o.centre() + d);
                }
                for p in points {
                    for kind in [PointKind::Joint, PointKind::Link] {
                        assert_eq!(
                            bits(o.contact(&p, kind, &[])),
                            bits(contact_per_axis(&o, &p, kind)),
                            "k={exponents:?} p={p:?}"
                        );
                    }
                }
            }
        }
    }

    #[test]
    fn sphere_bound_drops_only_points_outside_the_sphere() {
        let mut rng = 5u64;
        for reach_sq in [1.0f32, 2.0, 3.0, 1234.567, 3.0e8, 1.23e-4, 7.77e5] {
            let w = sphere_bound(reach_sq);
            assert!(w * w > reach_sq);
            let below = w.next_down();
            assert!(below * below <= reach_sq, "not the least: {reach_sq}");
            for _ in 0..2000 {
                // Just beyond the bound on one axis, anything within it on
                // the others: always beyond the sphere as computed.
                let beyond = w.next_up() * (1.0 + 1e-6 * lcg(&mut rng).abs());
                let (a, b) = (lcg(&mut rng) * w, lcg(&mut rng) * w);
                for r in [
                    vec3([beyond, a, b]),
                    vec3([a, -beyond, b]),
                    vec3([a, b, beyond]),
                ] {
                    assert!(r.dot(&r) > reach_sq, "{reach_sq} {r:?}");
                }
            }
        }
        assert_eq!(sphere_bound(f32::INFINITY), f32::INFINITY);
    }

    #[test]
    fn written_out_powers_match_the_loop_bit_for_bit() {
        for k in 0..=32u8 {
            for i in 0..200 {
                let u = i as f32 * 0.013_7 + 0.001;
                assert_eq!(
                    powi(u, k).to_bits(),
                    powi_loop(u, k).to_bits(),
                    "u = {u}, k = {k}"
                );
            }
        }
    }

    #[test]
    fn integer_fast_path_matches_powf() {
        for k in 1..=32u8 {
            for u in [0.0f32, 0.3, 1.0, 1.7] {
                let (fast, fast_slope) = Exponent::Integer(k).power_and_slope(u);
                let (slow, slow_slope) = Exponent::Real(k as f32).power_and_slope(u);
                let tol = 1e-5 * slow.abs().max(1.0);
                assert!((fast - slow).abs() <= tol, "k={k} u={u}");
                assert!((fast_slope - slow_slope).abs() <= 1e-5 * slow_slope.abs().max(1.0));
            }
        }
    }

    #[test]
    fn rejects_bad_obstacles() {
        let good = SuperEllipsoid::aligned([0.0; 3], [1.0; 3], 2.0);
        let check = |s: SuperEllipsoid| Obstacle::new(3, &s, [0.0, 0.0], 1.0).unwrap_err();
        let mut s = good;
        s.semi_axes[1] = 0.0;
        assert_eq!(check(s), ObstacleError::SemiAxisOutOfRange { obstacle: 3 });
        s.semi_axes[1] = -1.0;
        assert_eq!(check(s), ObstacleError::SemiAxisOutOfRange { obstacle: 3 });
        let mut s = good;
        s.centre[0] = f32::NAN;
        assert_eq!(
            check(s),
            ObstacleError::NotFinite {
                obstacle: 3,
                field: ObstacleParameter::Centre
            }
        );
        let mut s = good;
        s.exponents[2] = 0.5;
        assert_eq!(check(s), ObstacleError::ExponentOutOfRange { obstacle: 3 });
        let mut s = good;
        s.euler_123[0] = f32::INFINITY;
        assert!(matches!(check(s), ObstacleError::NotFinite { .. }));
    }

    /// One of each primitive, rotated, off the origin.
    fn primitives() -> [Solid; 4] {
        let place = |shape| Solid {
            centre: [1.0, -2.0, 0.5],
            euler_123: [0.3, -0.2, 0.9],
            shape,
        };
        [
            place(Shape::Sphere { radius: 1.5 }),
            place(Shape::Cuboid {
                half_extents: [2.0, 0.5, 1.0],
            }),
            place(Shape::Capsule {
                radius: 0.5,
                length: 3.0,
            }),
            place(Shape::Cylinder {
                radius: 0.75,
                length: 2.5,
            }),
        ]
    }

    #[test]
    fn margins_of_primitives_are_true_distances() {
        // Clearance is 0 exactly where the distance to the surface is the
        // point kind's margin, and `distance_sq` is the distance to that
        // inflated surface (for a sphere a lower bound on it).
        let mut rng = 17u64;
        let margins = [0.6, 0.3];
        for solid in primitives() {
            let o = Obstacle::new(0, &solid, margins, 5.0).unwrap();
            let (shape, rotation) = (Primitive::of(&solid.shape).unwrap(), *o.rotation());
            for _ in 0..400 {
                let p = o.centre() + vec3([lcg(&mut rng), lcg(&mut rng), lcg(&mut rng)]) * 5.0;
                let local = rotation.transpose() * (p - o.centre());
                let (d, _) = distance::signed_distance(&shape, &local);
                for kind in [PointKind::Joint, PointKind::Link] {
                    let m = margins[kind as usize];
                    let Some(c) = o.contact(&p, kind, &[]) else {
                        assert!(d - m > 5.0 - 1e-4, "{solid:?}: {p:?} dropped at {d}");
                        continue;
                    };
                    assert_eq!(c.clearance <= 0.0, d <= m, "{solid:?} {p:?} {d} {c:?}");
                    let expected = (d - m).max(0.0);
                    let bound = c.distance_sq.sqrt();
                    if matches!(shape, Primitive::Sphere { .. }) {
                        // The convex bound: never above the distance, at
                        // least half of it.
                        assert!(bound <= expected + 1e-5, "{bound} > {expected}");
                        assert!(bound >= 0.5 * expected - 1e-5, "{bound} << {expected}");
                    } else {
                        assert!((bound - expected).abs() < 1e-5, "{bound} != {expected}");
                    }
                    let uncut = o.clearance_uncut(&p, kind, &[]);
                    assert!((uncut - c.clearance).abs() <= 1e-6 * (1.0 + uncut.abs()));
                }
            }
        }
    }

    #[test]
    fn primitive_gradients_match_central_differences() {
        let mut rng = 23u64;
        let step = 1e-3;
        for solid in primitives() {
            let o = Obstacle::new(0, &solid, [0.6, 0.3], 5.0).unwrap();
            let mut checked = 0;
            while checked < 100 {
                let p = o.centre() + vec3([lcg(&mut rng), lcg(&mut rng), lcg(&mut rng)]) * 4.0;
                let Some(c) = o.contact(&p, PointKind::Link, &[]) else {
                    continue;
                };
                let f = |q: Vec3| o.clearance_uncut(&q, PointKind::Link, &[]);
                let central = Vec3::from_fn(|i, _| {
                    let (mut a, mut b) = (p, p);
                    a[i] += step;
                    b[i] -= step;
                    (f(a) - f(b)) / (2.0 * step)
                });
                let forward = Vec3::from_fn(|i, _| {
                    let mut a = p;
                    a[i] += step;
                    (f(a) - f(p)) / step
                });
                // Off the creases (edges, medial surfaces), where d is smooth.
                if (forward - central).norm() > 0.02 * (1.0 + central.norm()) {
                    continue;
                }
                checked += 1;
                assert!(
                    (c.gradient - central).norm() <= 1e-2 * (1.0 + central.norm()),
                    "{solid:?} at {p:?}: {:?} against {central:?}",
                    c.gradient
                );
            }
        }
    }

    #[test]
    fn a_sphere_is_the_exponent_2_super_ellipsoid_of_its_size() {
        // The potential treats a primitive as it treats the ellipsoid: for
        // a sphere the rebuilt C is the super-ellipsoid's own, and its pair
        // (C, gradient, influence and distance bound) is the ellipsoid's to
        // the bit, turned or not, near and far.
        let mut rng = 29u64;
        // Aligned, and turned: a sphere skips its rotation (it is the same
        // turned any way), so a turned sphere's pair is the aligned
        // ellipsoid's too.
        let sphere = |euler_123| {
            let solid = Solid {
                centre: [1.0, 2.0, 3.0],
                euler_123,
                shape: Shape::Sphere { radius: 2.0 },
            };
            Obstacle::new(0, &solid, [0.5, 0.25], 10.0).unwrap()
        };
        let spheres = [sphere([0.0; 3]), sphere([0.3, -0.5, 0.9])];
        let ellipsoid = Obstacle::new(
            0,
            &SuperEllipsoid::aligned([1.0, 2.0, 3.0], [2.0; 3], 2.0),
            [0.5, 0.25],
            10.0,
        )
        .unwrap();
        // Within 6 of the centre (near: inside, on and just off the
        // surface), then within 20 (far: beyond the influence too).
        for reach in [6.0, 20.0] {
            for _ in 0..200 {
                let p = ellipsoid.centre()
                    + vec3([lcg(&mut rng), lcg(&mut rng), lcg(&mut rng)]) * reach;
                for kind in [PointKind::Joint, PointKind::Link] {
                    let expected = ellipsoid.contact(&p, kind, &[]);
                    let b = ellipsoid.clearance_uncut(&p, kind, &[]);
                    for sphere in &spheres {
                        let a = sphere.clearance_uncut(&p, kind, &[]);
                        assert!((a - b).abs() <= 1e-5 * (1.0 + b.abs()), "{p:?}: {a} {b}");
                        assert_eq!(sphere.contact(&p, kind, &[]), expected, "{p:?}");
                    }
                }
            }
        }
    }

    /// A box given as its eight corners, as a hull.
    fn box_hull(half: [f32; 3]) -> Hull {
        let mut corners = [[0.0f32; 3]; 8];
        for (i, corner) in corners.iter_mut().enumerate() {
            for (axis, h) in half.into_iter().enumerate() {
                corner[axis] = if i >> axis & 1 == 1 { h } else { -h };
            }
        }
        Hull::new(&corners).unwrap()
    }

    #[test]
    fn a_box_hull_is_the_box() {
        // The same box as a primitive and as a hull of its corners: the
        // same `rho` (half its smallest width), so outside the box the same
        // `C`, gradient and distance bound, to rounding, turned or not.
        let mut rng = 31u64;
        let half = [1.5, 0.8, 2.0];
        let hulls = [box_hull(half)];
        let margins = [0.6, 0.3];
        for euler_123 in [[0.0; 3], [0.4, -0.7, 1.2]] {
            let place = |shape| Solid {
                centre: [1.0, -2.0, 0.5],
                euler_123,
                shape,
            };
            let cuboid = Obstacle::new(
                0,
                &place(Shape::Cuboid { half_extents: half }),
                margins,
                4.0,
            )
            .unwrap();
            let hull = Obstacle::new_in(0, &place(Shape::Convex { hull: 0 }), &hulls, margins, 4.0)
                .unwrap();
            assert_eq!(hull.bounding_radius(), cuboid.bounding_radius());
            let mut compared = 0;
            for _ in 0..600 {
                let p = cuboid.centre() + vec3([lcg(&mut rng), lcg(&mut rng), lcg(&mut rng)]) * 6.0;
                let local = cuboid.rotation().transpose() * (p - cuboid.centre());
                let (d, _) = distance::signed_distance(
                    &Primitive::Cuboid {
                        half_extents: vec3(half),
                    },
                    &local,
                );
                for kind in [PointKind::Joint, PointKind::Link] {
                    let (a, b) = (
                        cuboid.contact(&p, kind, &[]),
                        hull.contact(&p, kind, &hulls),
                    );
                    if d < 1e-3 {
                        // Inside the box the hull reports distance 0: C below 1.
                        if let Some(b) = b {
                            assert!(b.clearance < 0.0);
                        }
                        continue;
                    }
                    match (a, b) {
                        (None, None) => {}
                        (Some(a), Some(b)) => {
                            let scale = 1.0 + a.clearance.abs();
                            assert!(
                                (a.clearance - b.clearance).abs() <= 1e-4 * scale,
                                "{p:?}: {a:?} {b:?}"
                            );
                            assert!(
                                (a.gradient - b.gradient).norm()
                                    <= 1e-3 * (1.0 + a.gradient.norm()),
                                "{p:?}: {a:?} {b:?}"
                            );
                            assert!(
                                (a.distance_sq.sqrt() - b.distance_sq.sqrt()).abs()
                                    <= 1e-4 * (1.0 + d),
                                "{p:?}: {a:?} {b:?}"
                            );
                            compared += 1;
                        }
                        // At the influence boundary one may round out.
                        (a, b) => assert!(
                            (d - margins[kind as usize] - 4.0).abs() < 1e-3,
                            "{p:?} {d}: {a:?} {b:?}"
                        ),
                    }
                }
            }
            assert!(compared > 300, "only {compared}");
        }
    }

    #[test]
    fn hull_margins_are_true_distances_and_bounds_are_below_them() {
        let mut rng = 41u64;
        let margins = [0.5, 0.25];
        let mut points = [[0.0f32; 3]; 12];
        for p in points.iter_mut() {
            *p = [
                2.0 * lcg(&mut rng),
                1.2 * lcg(&mut rng),
                0.8 * lcg(&mut rng),
            ];
        }
        let hulls = [Hull::new(&points).unwrap()];
        let solid = Solid {
            centre: [0.0, 3.0, -1.0],
            euler_123: [0.2, 0.3, -0.4],
            shape: Shape::Convex { hull: 0 },
        };
        let o = Obstacle::new_in(0, &solid, &hulls, margins, 3.0).unwrap();
        for _ in 0..800 {
            let p = o.centre() + vec3([lcg(&mut rng), lcg(&mut rng), lcg(&mut rng)]) * 4.0;
            let local = o.rotation().transpose() * (p - o.centre());
            let d = hulls[0].distance(&local).distance;
            for kind in [PointKind::Joint, PointKind::Link] {
                let m = margins[kind as usize];
                let Some(c) = o.contact(&p, kind, &hulls) else {
                    assert!(d - m > 3.0 - 1e-4, "{p:?} dropped at {d}");
                    continue;
                };
                assert_eq!(c.clearance <= 0.0, d <= m, "{p:?} {d} {c:?}");
                let bound = c.distance_sq.sqrt();
                assert!(bound <= (d - m).max(0.0) + 1e-5);
                assert!(bound >= (d - m).max(0.0) - 1e-4 * (1.0 + d));
                let uncut = o.clearance_uncut(&p, kind, &hulls);
                assert!((uncut - c.clearance).abs() <= 1e-5 * (1.0 + uncut.abs()));
            }
        }
    }

    #[test]
    fn a_point_not_finite_is_out_of_a_hulls_influence() {
        let hulls = [box_hull([1.0; 3])];
        let o = Obstacle::new_in(
            0,
            &Solid::aligned([0.0; 3], Shape::Convex { hull: 0 }),
            &hulls,
            [0.1, 0.1],
            1.0,
        )
        .unwrap();
        for p in [[f32::NAN, 0.0, 0.0], [0.5, f32::NAN, 0.2]] {
            assert_eq!(o.contact(&vec3(p), PointKind::Joint, &hulls), None, "{p:?}");
        }
    }

    #[test]
    fn a_convex_obstacle_needs_its_hull() {
        let solid = Solid::aligned([0.0; 3], Shape::Convex { hull: 1 });
        let hulls = [box_hull([1.0; 3])];
        assert_eq!(
            Obstacle::new_in(3, &solid, &hulls, [0.1, 0.1], 1.0).err(),
            Some(ObstacleError::NoSuchHull { obstacle: 3 })
        );
        assert!(Obstacle::new(
            0,
            &Solid::aligned([0.0; 3], Shape::Convex { hull: 0 }),
            [0.1, 0.1],
            1.0
        )
        .is_err());
    }

    #[test]
    fn rejects_bad_primitives() {
        let check = |shape| Obstacle::new(2, &Solid::aligned([0.0; 3], shape), [0.0; 2], 1.0);
        for shape in [
            Shape::Sphere { radius: 0.0 },
            Shape::Sphere { radius: -1.0 },
            Shape::Cuboid {
                half_extents: [1.0, 2e4, 1.0],
            },
            Shape::Capsule {
                radius: 1.0,
                length: 0.0,
            },
            Shape::Cylinder {
                radius: 0.0,
                length: 1.0,
            },
        ] {
            assert_eq!(
                check(shape).unwrap_err(),
                ObstacleError::SizeOutOfRange { obstacle: 2 }
            );
        }
        assert_eq!(
            check(Shape::Cylinder {
                radius: f32::NAN,
                length: 1.0
            })
            .unwrap_err(),
            ObstacleError::NotFinite {
                obstacle: 2,
                field: ObstacleParameter::Size
            }
        );
    }
}
