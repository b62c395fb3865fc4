//! Conversions to and from capp-core's types (feature `core`). Values are
//! copied bit for bit (a joint's origin and the tool too); validation stays with capp-core's constructors.

use capp_core::avoidance::AvoidanceSettings;
use capp_core::control::{LawKind as CoreLaw, LawSettings};
use capp_core::escape::EscapeSettings;
use capp_core::planner::Outcome as CoreOutcome;
use capp_core::{JointKind as CoreKind, Shape, Solid, SuperEllipsoid};

use capp_core::robot::{JointOrigin, Placement as CorePlacement};

use crate::{
    EscapeMode, Joint, JointKind, LawKind, Obstacle, Origin, Outcome, Placement, Primitive,
    Settings, Waypoint,
};

impl From<CorePlacement> for Placement {
    fn from(p: CorePlacement) -> Self {
        Placement {
            rotation: p.rotation,
            translation: p.translation,
        }
    }
}

impl From<Placement> for CorePlacement {
    fn from(p: Placement) -> Self {
        CorePlacement {
            rotation: p.rotation,
            translation: p.translation,
        }
    }
}

impl From<JointOrigin> for Origin {
    fn from(o: JointOrigin) -> Self {
        Origin {
            placement: o.placement.into(),
            axis: o.axis,
        }
    }
}

impl From<Origin> for JointOrigin {
    fn from(o: Origin) -> Self {
        JointOrigin {
            placement: o.placement.into(),
            axis: o.axis,
        }
    }
}

impl From<CoreKind> for JointKind {
    fn from(k: CoreKind) -> Self {
        match k {
            CoreKind::Revolute => JointKind::Revolute,
            CoreKind::Prismatic => JointKind::Prismatic,
        }
    }
}

impl From<JointKind> for CoreKind {
    fn from(k: JointKind) -> Self {
        match k {
            JointKind::Revolute => CoreKind::Revolute,
            JointKind::Prismatic => CoreKind::Prismatic,
        }
    }
}

impl From<capp_core::Joint> for Joint {
    fn from(j: capp_core::Joint) -> Self {
        Joint {
            kind: j.kind.into(),
            alpha: j.alpha,
            a: j.a,
            theta: j.theta,
            d: j.d,
            min: j.min,
            max: j.max,
            max_rate: j.max_rate,
            weight: j.weight,
            origin: j.origin.map(Origin::from),
        }
    }
}

impl From<Joint> for capp_core::Joint {
    fn from(j: Joint) -> Self {
        capp_core::Joint {
            kind: j.kind.into(),
            alpha: j.alpha,
            a: j.a,
            theta: j.theta,
            d: j.d,
            min: j.min,
            max: j.max,
            max_rate: j.max_rate,
            weight: j.weight,
            origin: j.origin.map(JointOrigin::from),
        }
    }
}

// The wire's hull limits are the core's.
const _: () = assert!(crate::MAX_HULLS == capp_core::obstacle::MAX_HULLS);
const _: () = assert!(crate::MAX_HULL_VERTICES == capp_core::obstacle::MAX_HULL_VERTICES);

impl From<Solid> for Obstacle {
    fn from(s: Solid) -> Self {
        let (semi_axes, exponents, primitive) = match s.shape {
            Shape::SuperEllipsoid {
                semi_axes,
                exponents,
            } => (semi_axes, exponents, None),
            Shape::Sphere { radius } => ([0.0; 3], [0.0; 3], Some(Primitive::Sphere { radius })),
            Shape::Cuboid { half_extents } => {
                ([0.0; 3], [0.0; 3], Some(Primitive::Cuboid { half_extents }))
            }
            Shape::Capsule { radius, length } => (
                [0.0; 3],
                [0.0; 3],
                Some(Primitive::Capsule { radius, length }),
            ),
            Shape::Cylinder { radius, length } => (
                [0.0; 3],
                [0.0; 3],
                Some(Primitive::Cylinder { radius, length }),
            ),
            Shape::Convex { hull } => ([0.0; 3], [0.0; 3], Some(Primitive::Convex { hull })),
        };
        Obstacle {
            centre: s.centre,
            semi_axes,
            exponents,
            euler_123: s.euler_123,
            primitive,
        }
    }
}

impl From<SuperEllipsoid> for Obstacle {
    fn from(s: SuperEllipsoid) -> Self {
        Solid::from(s).into()
    }
}

impl From<Obstacle> for Solid {
    fn from(o: Obstacle) -> Self {
        let shape = match o.primitive {
            None => Shape::SuperEllipsoid {
                semi_axes: o.semi_axes,
                exponents: o.exponents,
            },
            Some(Primitive::Sphere { radius }) => Shape::Sphere { radius },
            Some(Primitive::Cuboid { half_extents }) => Shape::Cuboid { half_extents },
            Some(Primitive::Capsule { radius, length }) => Shape::Capsule { radius, length },
            Some(Primitive::Cylinder { radius, length }) => Shape::Cylinder { radius, length },
            Some(Primitive::Convex { hull }) => Shape::Convex { hull },
        };
        Solid {
            centre: o.centre,
            euler_123: o.euler_123,
            shape,
        }
    }
}

impl From<capp_core::Waypoint> for Waypoint {
    fn from(w: capp_core::Waypoint) -> Self {
        Waypoint {
            position: w.position,
            orientation: w.orientation,
        }
    }
}

impl From<Waypoint> for capp_core::Waypoint {
    fn from(w: Waypoint) -> Self {
        capp_core::Waypoint {
            position: w.position,
            orientation: w.orientation,
        }
    }
}

impl From<capp_core::Settings> for Settings {
    fn from(s: capp_core::Settings) -> Self {
        Settings {
            time_step_s: s.time_step_s,
            fine_radius: s.fine_radius,
            fine_step_fraction: s.fine_step_fraction,
            position_tolerance: s.position_tolerance,
            orientation_tolerance: s.orientation_tolerance,
            law: match s.law.kind {
                CoreLaw::Gradient => LawKind::Gradient,
                CoreLaw::Paper => LawKind::Paper,
                CoreLaw::DampedLeastSquares => LawKind::DampedLeastSquares,
            },
            orientation_scale: s.law.orientation_scale,
            approach_radius: s.law.approach_radius,
            joint_margin: s.avoidance.joint_margin,
            link_margin: s.avoidance.link_margin,
            points_per_link: s.avoidance.points_per_link,
            influence_distance: s.avoidance.influence_distance,
            engage_clearance: s.avoidance.engage_clearance,
            advance_fraction: s.avoidance.advance_fraction,
            damping: s.law.damping,
            max_steps: s.max_steps,
            stall_window: s.stall_window,
            stall_progress: s.stall_progress,
            max_halvings: s.max_halvings,
            escape_attempts: s.escape.attempts,
            escape_window: s.escape.window as u32,
            escape_walk_steps: s.escape.walk_steps as u32,
            escape_reach: s.escape.reach,
            escape_seed: s.escape.seed,
            escape_searches: s.escape.searches,
            saturation: s.law.saturation,
            tracked: s.motion == capp_core::Motion::Tracked,
        }
    }
}

impl From<Settings> for capp_core::Settings {
    fn from(s: Settings) -> Self {
        capp_core::Settings {
            time_step_s: s.time_step_s,
            fine_radius: s.fine_radius,
            fine_step_fraction: s.fine_step_fraction,
            position_tolerance: s.position_tolerance,
            orientation_tolerance: s.orientation_tolerance,
            law: LawSettings {
                kind: match s.law {
                    LawKind::Gradient => CoreLaw::Gradient,
                    LawKind::Paper => CoreLaw::Paper,
                    LawKind::DampedLeastSquares => CoreLaw::DampedLeastSquares,
                },
                orientation_scale: s.orientation_scale,
                approach_radius: s.approach_radius,
                damping: s.damping,
                saturation: s.saturation,
            },
            avoidance: AvoidanceSettings {
                joint_margin: s.joint_margin,
                link_margin: s.link_margin,
                points_per_link: s.points_per_link,
                influence_distance: s.influence_distance,
                engage_clearance: s.engage_clearance,
                advance_fraction: s.advance_fraction,
            },
            max_steps: s.max_steps,
            stall_window: s.stall_window,
            stall_progress: s.stall_progress,
            max_halvings: s.max_halvings,
            // Beyond u16 is refused by validation (0 is refused too).
            escape: EscapeSettings {
                attempts: s.escape_attempts,
                window: u16::try_from(s.escape_window).unwrap_or(0),
                walk_steps: u16::try_from(s.escape_walk_steps).unwrap_or(0),
                reach: s.escape_reach,
                seed: s.escape_seed,
                searches: s.escape_searches,
            },
            motion: if s.tracked {
                capp_core::Motion::Tracked
            } else {
                capp_core::Motion::Stepped
            },
        }
    }
}

impl From<CoreOutcome> for Outcome {
    fn from(o: CoreOutcome) -> Self {
        match o {
            CoreOutcome::Reached => Outcome::Reached,
            CoreOutcome::Stalled => Outcome::Stalled,
            CoreOutcome::Capped => Outcome::Capped,
        }
    }
}

/// `Run`'s decimation fields for a capp-core setpoint filter.
pub fn run_command(filter: capp_core::SetpointFilter) -> crate::Command {
    match filter {
        capp_core::SetpointFilter::Every(every) => crate::Command::Run {
            every,
            error_change: None,
        },
        capp_core::SetpointFilter::ErrorChange {
            position,
            orientation,
        } => crate::Command::Run {
            every: 1,
            error_change: Some(crate::ErrorChange {
                position,
                orientation,
            }),
        },
    }
}

/// The capp-core setpoint filter `Run`'s fields ask for.
pub fn setpoint_filter(
    every: u32,
    error_change: Option<crate::ErrorChange>,
) -> capp_core::SetpointFilter {
    match error_change {
        Some(c) => capp_core::SetpointFilter::ErrorChange {
            position: c.position,
            orientation: c.orientation,
        },
        None => capp_core::SetpointFilter::Every(every.max(1)),
    }
}

/// The escape's state as the board reports it: the mode and the attempt.
pub fn escape_status(e: capp_core::escape::EscapeState) -> (EscapeMode, u8) {
    use capp_core::escape::EscapeState as E;
    {
        match e {
            E::Descending { attempts } => (EscapeMode::Descending, attempts),
            E::Walking { attempt, .. } => (EscapeMode::Walking, attempt),
            E::Detouring { attempt, .. } => (EscapeMode::Detouring, attempt),
            E::Returning => (EscapeMode::Returning, 0),
            E::Searching { attempt, .. } => (EscapeMode::Searching, attempt),
            E::Following { attempt, .. } => (EscapeMode::Following, attempt),
        }
    }
}
