//! The Universal Robots UR5 (metres) from its URDF, on a work table among
//! boxes, with a low shelf unit on the table.
//!
//! Robot: the vendored `robots/ur_description/urdf/ur5_robot.urdf`, base
//! `base_link`, tip `tool0` (six joints, the URDF's rates); link capsules
//! enclose its collision meshes (`package://example-robot-data/...`, mapped
//! to the repository root by `[robot] packages`), and the pairs checked for
//! self-collision are the loader's (`capp acm`). The file names the URDF
//! and the package root by absolute paths ([`crate::case::UrdfRobot`]).
//! Joint limits are the URDF's (+-2 pi, the elbow +-pi, as the real arm);
//! random starts and goals are drawn within 80 % of +-pi about each joint's
//! middle ([`Draft::sample_within`]), so they use the first turn of each
//! joint and the planner and the oracle may turn further. (Limiting the
//! joints to +-pi by `[[robot.overrides]]`, as the package's
//! `ur5_joint_limited_robot.urdf` does, made targets that a wrist reaches
//! only the long way round: in a first run of seed 1 the planner reached
//! 79 % of the certified cases, and each of the eight unreached ones looked
//! at ended with a joint at its limit.)
//!
//! Scene: the table top just under the base; a low shelf unit standing on
//! it (two side panels, one or two boards, a top, sometimes a back panel;
//! 0.45 to 0.7 m high) at a random azimuth 0.35 to 0.55 m out; one to three
//! boxes on the table 0.3 to 0.7 m out; then boxes in the way (arm points of
//! the joint-space midpoint, the straight end-effector path). Even cases
//! start at a ready pose (upper arm up, forearm forward, tool down) when it
//! is clear, the others at a random clear configuration; every start and
//! goal keeps the checked link pairs [`LINK_MARGIN`] radius sums apart.
//! Target: position and orientation of the goal configuration, tolerances
//! 0.005 m and 0.05. Margins as `iiwa_shelves` (0.08 m at joints, 0.06 m
//! inside links, three points per link). Other settings: defaults.

use super::scene::{box_on_table, shelf_unit, table_top_spec, Draft, ShelfSizes};
use super::Family;
use crate::case::{repo_path, round, Case, Obstacle, RobotSpec, UrdfRobot};
use crate::rng::Rng;

/// The family.
pub const FAMILY: Family = Family {
    name: "ur5_table",
    description: "Universal Robots UR5 (URDF) on a table among boxes and a low shelf, boxes in the way; tolerances 0.005 m / 0.05",
    count: 80,
    generate,
};

/// Smallest `gap / (r_a + r_b)` of any checked link pair at a start or goal.
pub const LINK_MARGIN: f64 = 0.1;

/// A ready pose, radians: upper arm up, forearm forward, tool down.
pub const READY: [f64; 6] = [0.0, -1.571, 1.571, -1.571, -1.571, 0.0];

/// The robot: the vendored URDF, base to tool flange.
pub fn robot() -> UrdfRobot {
    UrdfRobot {
        urdf: repo_path("robots/ur_description/urdf/ur5_robot.urdf"),
        base_link: "base_link",
        tip_link: "tool0",
        packages: vec![("example-robot-data", repo_path(""))],
        overrides: Vec::new(),
    }
}

fn generate(rng: &mut Rng, index: usize) -> Option<Case> {
    let from_ready = index.is_multiple_of(2);
    let ready: Vec<f64> = READY.iter().map(|&x| round(x)).collect();
    let name = format!("ur5_table-{index:03}");
    let mut draft = Draft::new(table_top_spec(
        &name,
        "Universal Robots UR5 (URDF) on a table among boxes and a low shelf",
        RobotSpec::Urdf(robot()),
        ready.clone(),
    ))?;
    draft.keep_links_apart(LINK_MARGIN)?;
    draft.sample_within(std::f64::consts::PI);

    let top = -0.01 - rng.range(0.0, 0.04);
    draft.push(Obstacle::cuboid(
        "table",
        [0.15, 0.0, top - 0.05],
        [0.85, 0.85, 0.05],
    ));
    let (shelf, boards) = shelf_unit(
        rng,
        top,
        &ShelfSizes {
            azimuth: (-1.6, 1.6),
            near: (0.35, 0.55),
            half_depth: (0.12, 0.18),
            half_width: (0.2, 0.35),
            height: (0.45, 0.7),
            boards: 2,
            board_jitter: 0.04,
        },
    );
    for o in shelf {
        draft.push(o);
    }
    let boxes = 1 + rng.below(3);
    for k in 0..boxes {
        let o = box_on_table(
            rng,
            format!("box on the table {}", k + 1),
            top,
            (0.3, 0.7),
            (-3.1, 3.1),
            (0.04, 0.12),
            (0.04, 0.15),
        );
        draft.push(o);
    }

    let (start, at_ready) = draft.ready_or_random(rng, ready, from_ready)?;
    let goal = draft.random_goal(rng, &start, 0.8, 0.2, 1500)?;

    let placed = draft.boxes_in_the_way(rng, &start, &goal, 1, (0.04, 0.08));
    let tags = format!(
        "start {}; {boards} boards, {boxes} boxes; {} obstacles ({placed} in the way)",
        if at_ready { "ready" } else { "random" },
        draft.spec.obstacles.len()
    );
    draft.finish(FAMILY.name, index, tags, &start, &goal, true)
}
