//! The case families, each generated from a seed: the same seed gives the
//! same cases (the same TOML text) on any machine.
//!
//! | family | robot | scene | target |
//! |---|---|---|---|
//! | [`pips_bay`] | PIPS (inches) | payload bay: floor, bulkheads, side walls, cylindrical payloads, equipment, boxes in the way | pose; both tolerance sets |
//! | [`pips_free`] | PIPS | none | pose over the reachable workspace |
//! | [`iiwa_shelves`] | KUKA LBR iiwa 7 (metres) | table, shelf unit, boxes in the way | pose |
//! | [`panda_shelves`] | Franka Emika Panda from its URDF (metres) | table, shelf unit, boxes in the way | pose |
//! | [`ur5_table`] | Universal Robots UR5 from its URDF (metres), joints within +-pi | table, low shelf unit, boxes on the table and in the way | pose |
//! | [`planar_posts`] | the planar 3-link arm (metres) | round posts | position |
//! | [`snake_folds`] | a 12- to 24-joint snake (metres), its links kept apart | floor, pedestal, a ring of posts, boxes in the way | pose or position near its own base, behind it, inside the ring |
//! | [`cad_cell`] | Franka Emika Panda from its URDF (metres), its links kept apart | CAD primitives only (true distances): table and shelf unit as true boxes, vertical and horizontal cylindrical pipes, boxes turned about z, capsules and balls on the table and in the way | pose |
//!
//! Every case is built the same way ([`scene`]): a scene, a start (home or a
//! random configuration), a goal configuration, both within limits and clear
//! of every inflated obstacle by `C - 1 >= CLEAR_MARGIN` by the independent
//! `f64` model ([`capp_sim::geometry::Geometry`]); then obstacles placed in the way
//! (at arm points of the joint-space midpoint of start and goal, and on the
//! straight end-effector path), each kept only if start and goal stay clear;
//! finally the file is read back by the loader and the start must be accepted
//! by `Planner::new`. Every draw has a bounded number of retries.

pub mod cad_cell;
pub mod iiwa_shelves;
pub mod panda_shelves;
pub mod pips_bay;
pub mod pips_free;
pub mod planar_posts;
pub mod scene;
pub mod snake_folds;
pub mod ur5_table;

use anyhow::{bail, Result};

use crate::case::Case;
use crate::rng::Rng;

/// One family: its name, what it is, how many cases a full run has, and its generator.
#[derive(Clone, Copy)]
pub struct Family {
    /// Name (`--family`).
    pub name: &'static str,
    /// One line for the report.
    pub description: &'static str,
    /// Cases in a full run.
    pub count: usize,
    /// Case `index` from its own random stream; `None` when the retries ran out.
    pub generate: fn(&mut Rng, usize) -> Option<Case>,
}

/// Every family, in report order.
pub fn families() -> Vec<Family> {
    vec![
        pips_bay::FAMILY,
        pips_free::FAMILY,
        iiwa_shelves::FAMILY,
        panda_shelves::FAMILY,
        ur5_table::FAMILY,
        planar_posts::FAMILY,
        snake_folds::FAMILY,
        cad_cell::FAMILY,
    ]
}

/// Draws per case before the generator gives up on it (each draw is a whole
/// new scene, start and goal from the case's stream).
const DRAWS: usize = 40;

/// Case `index` of `family` under `seed`. Each case has its own stream, so a
/// case does not depend on how many others are generated.
pub fn case(family: &Family, seed: u64, index: usize) -> Result<Case> {
    let mut rng = Rng::derive(seed, family.name, index as u64);
    for _ in 0..DRAWS {
        if let Some(case) = (family.generate)(&mut rng, index) {
            return Ok(case);
        }
    }
    bail!(
        "{} case {index}: no valid scene, start and goal in {DRAWS} draws (seed {seed})",
        family.name
    )
}

/// The first `count` cases of `family`.
pub fn cases(family: &Family, seed: u64, count: usize) -> Result<Vec<Case>> {
    (0..count).map(|i| case(family, seed, i)).collect()
}
