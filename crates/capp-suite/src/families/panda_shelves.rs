//! The Franka Emika Panda (metres) from its URDF, on a table, in front of a
//! shelf unit: the first family whose robot is read from a URDF file
//! (general joints and a tool frame in the planner, issue 23).
//!
//! Robot: the vendored `robots/panda_description/urdf/panda_collision.urdf`,
//! base `panda_link0`, tip the flange `panda_link8` (seven joints, the
//! URDF's limits and rates; no hand); link capsules and the pairs checked
//! for self-collision as the loader makes them (`capp acm`). The file names
//! the URDF by its absolute path ([`crate::case::UrdfRobot`]).
//!
//! Scene (as [`super::iiwa_shelves`], sized for the Panda's 0.85 m reach):
//! the table top just under the base; a shelf unit (two side panels, one to
//! three boards, a top, sometimes a back panel) at a random azimuth 0.4 to
//! 0.6 m out; sometimes a box on the table; then boxes in the way (arm
//! points of the joint-space midpoint, the straight end-effector path).
//! Even cases start at the usual ready pose when it is clear, the others
//! (and even ones where it is not) at a random clear configuration; every
//! start and goal keeps the checked link pairs [`LINK_MARGIN`] radius sums
//! apart. Target: position and orientation of the goal configuration,
//! tolerances 0.005 m and 0.05. Margins as `iiwa_shelves` (0.08 m at
//! joints, 0.06 m inside links, three points per link: the Panda's links
//! are about as thick as the iiwa's). Other settings: defaults.

use super::scene::{box_on_table, shelf_unit, table_top_spec, Draft, ShelfSizes};
use super::Family;
use crate::case::{repo_path, round, Case, RobotSpec, UrdfRobot};
use crate::rng::Rng;

/// The family.
pub const FAMILY: Family = Family {
    name: "panda_shelves",
    description: "Franka Emika Panda (URDF) on a table before a shelf unit, boxes in the way; tolerances 0.005 m / 0.05",
    count: 80,
    generate,
};

/// Smallest `gap / (r_a + r_b)` of any checked link pair at a start or goal.
pub const LINK_MARGIN: f64 = 0.1;

/// The Panda's usual ready pose (franka_ros), radians.
pub const READY: [f64; 7] = [0.0, -0.785, 0.0, -2.356, 0.0, 1.571, 0.785];

/// The robot: the vendored URDF, base to flange.
pub fn robot() -> UrdfRobot {
    UrdfRobot {
        urdf: repo_path("robots/panda_description/urdf/panda_collision.urdf"),
        base_link: "panda_link0",
        tip_link: "panda_link8",
        packages: Vec::new(),
        overrides: Vec::new(),
    }
}

fn generate(rng: &mut Rng, index: usize) -> Option<Case> {
    let from_ready = index.is_multiple_of(2);
    let ready: Vec<f64> = READY.iter().map(|&x| round(x)).collect();
    let name = format!("panda_shelves-{index:03}");
    let mut draft = Draft::new(table_top_spec(
        &name,
        "Franka Emika Panda (URDF) on a table before a shelf",
        RobotSpec::Urdf(robot()),
        ready.clone(),
    ))?;
    draft.keep_links_apart(LINK_MARGIN)?;

    let top = -0.01 - rng.range(0.0, 0.04);
    draft.push(crate::case::Obstacle::cuboid(
        "table",
        [0.15, 0.0, top - 0.05],
        [0.8, 0.8, 0.05],
    ));
    let (shelf, boards) = shelf_unit(
        rng,
        top,
        &ShelfSizes {
            azimuth: (-1.3, 1.3),
            near: (0.4, 0.6),
            half_depth: (0.12, 0.18),
            half_width: (0.25, 0.4),
            height: (0.8, 1.1),
            boards: 3,
            board_jitter: 0.04,
        },
    );
    for o in shelf {
        draft.push(o);
    }
    if rng.chance(0.5) {
        draft.push(box_on_table(
            rng,
            "box on the table",
            top,
            (0.3, 0.5),
            (-3.1, 3.1),
            (0.04, 0.1),
            (0.04, 0.12),
        ));
    }

    let (start, at_ready) = draft.ready_or_random(rng, ready, from_ready)?;
    let goal = draft.random_goal(rng, &start, 0.8, 0.2, 1500)?;

    let placed = draft.boxes_in_the_way(rng, &start, &goal, 1, (0.04, 0.08));
    let tags = format!(
        "start {}; {boards} boards; {} obstacles ({placed} in the way)",
        if at_ready { "ready" } else { "random" },
        draft.spec.obstacles.len()
    );
    draft.finish(FAMILY.name, index, tags, &start, &goal, true)
}
