//! An obstacle as a user describes it: a shape, a centre and an orientation.

use super::SuperEllipsoid;

/// The shape of an obstacle in its own frame (centred on the frame's
/// origin; capsules and cylinders along its z axis). Sizes in length units.
#[derive(Clone, Copy, Debug, PartialEq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub enum Shape {
    /// The paper's super-ellipsoid (eq. 25).
    SuperEllipsoid {
        /// Semi-axes `(a, b, c)`, > 0.
        semi_axes: [f32; 3],
        /// Exponents `(k_x, k_y, k_z)`, each in `[1, 64]`.
        exponents: [f32; 3],
    },
    /// A ball.
    Sphere {
        /// Radius, > 0.
        radius: f32,
    },
    /// A box `|x_i| <= half_extents_i`.
    Cuboid {
        /// Half-extents along the shape's x, y, z, each > 0.
        half_extents: [f32; 3],
    },
    /// The points within `radius` of a segment of `length` along z.
    Capsule {
        /// Radius, > 0.
        radius: f32,
        /// The segment's full length, > 0.
        length: f32,
    },
    /// A round cylinder with flat ends, along z.
    Cylinder {
        /// Radius, > 0.
        radius: f32,
        /// Full length, > 0.
        length: f32,
    },
    /// The convex hull of a vertex set in the shape's frame: the scenario's
    /// hull number `hull` (0-based; [`super::hull`]).
    Convex {
        /// Index into the scenario's hull list.
        hull: u8,
    },
}

/// An obstacle as given: a [`Shape`] placed at `centre` with orientation
/// `R = Rz(rz) Ry(ry) Rx(rx)` (1-2-3 Euler angles, radians), the shape's
/// axes as `R`'s columns.
#[derive(Clone, Copy, Debug, PartialEq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub struct Solid {
    /// Centre `(x, y, z)`, length units.
    pub centre: [f32; 3],
    /// `(rx, ry, rz)`, radians.
    pub euler_123: [f32; 3],
    /// The shape.
    pub shape: Shape,
}

impl Solid {
    /// An axis-aligned solid.
    pub fn aligned(centre: [f32; 3], shape: Shape) -> Self {
        Solid {
            centre,
            euler_123: [0.0; 3],
            shape,
        }
    }

    /// The super-ellipsoid this is, if it is one.
    pub fn super_ellipsoid(&self) -> Option<SuperEllipsoid> {
        match self.shape {
            Shape::SuperEllipsoid {
                semi_axes,
                exponents,
            } => Some(SuperEllipsoid {
                centre: self.centre,
                semi_axes,
                exponents,
                euler_123: self.euler_123,
            }),
            _ => None,
        }
    }

    /// The shape's size parameters, every one of which must be a finite
    /// length in `[MIN_SEMI_AXIS, MAX_EXTENT]`, and how many there are.
    pub(crate) fn sizes(&self) -> ([f32; 3], usize) {
        match self.shape {
            Shape::SuperEllipsoid { semi_axes, .. } => (semi_axes, 3),
            Shape::Sphere { radius } => ([radius, 0.0, 0.0], 1),
            Shape::Cuboid { half_extents } => (half_extents, 3),
            Shape::Capsule { radius, length } | Shape::Cylinder { radius, length } => {
                ([radius, length, 0.0], 2)
            }
            // A hull's size is its vertices', checked with them.
            Shape::Convex { .. } => ([0.0; 3], 0),
        }
    }
}

impl From<SuperEllipsoid> for Solid {
    fn from(s: SuperEllipsoid) -> Self {
        Solid {
            centre: s.centre,
            euler_123: s.euler_123,
            shape: Shape::SuperEllipsoid {
                semi_axes: s.semi_axes,
                exponents: s.exponents,
            },
        }
    }
}
