//! The KUKA LBR iiwa 7 R800 (metres) on a table, in front of a shelf unit.
//!
//! Standard DH (all `a = 0`): `d = 0.34, 0, 0.4, 0, 0.4, 0, 0.126`,
//! `alpha = -90, 90, -90, 90, -90, 90, 0` degrees; limits +-170, +-120,
//! +-170, +-120, +-170, +-120, +-175 degrees; rate limits 98, 98, 100, 130,
//! 140, 180, 180 degrees per second (the R800's data sheet).
//!
//! Scene: the table top just under the base; a shelf unit (two side panels,
//! two to four boards, sometimes a back panel) at a random azimuth 0.5 to
//! 0.8 m out; sometimes a box on the table; then boxes in the way (arm points
//! of the joint-space midpoint, the straight end-effector path). Target:
//! position and orientation of the goal configuration, tolerances 0.005 m
//! and 0.05. The loader's PIPS-sized margins (6 and 3 in) would make the
//! iiwa 0.3 m thick, so this family sets its own: 0.08 m at joints, 0.06 m
//! inside links, three points per link (0.1 m apart on the long links, so a
//! 3 cm board cannot pass between two of them). Other settings: defaults.

use super::scene::{shelf_unit, table_top_spec, Draft, ShelfSizes};
use super::Family;
use crate::case::{Case, DhJoint, Obstacle, RobotSpec};
use crate::rng::Rng;

/// The family.
pub const FAMILY: Family = Family {
    name: "iiwa_shelves",
    description: "KUKA LBR iiwa 7 on a table before a shelf unit, boxes in the way; tolerances 0.005 m / 0.05",
    count: 80,
    generate,
};

const DEG: f64 = std::f64::consts::PI / 180.0;

/// The iiwa 7 R800's DH table.
pub fn joints() -> Vec<DhJoint> {
    let d = [0.34, 0.0, 0.4, 0.0, 0.4, 0.0, 0.126];
    let alpha = [-90.0, 90.0, -90.0, 90.0, -90.0, 90.0, 0.0];
    let limit = [170.0, 120.0, 170.0, 120.0, 170.0, 120.0, 175.0];
    let rate = [98.0, 98.0, 100.0, 130.0, 140.0, 180.0, 180.0];
    let names = ["a1", "a2", "a3", "a4", "a5", "a6", "a7"];
    (0..7)
        .map(|i| DhJoint {
            name: names[i],
            alpha: alpha[i] * DEG,
            a: 0.0,
            d: d[i],
            theta: 0.0,
            min: -limit[i] * DEG,
            max: limit[i] * DEG,
            max_rate: rate[i] * DEG,
        })
        .collect()
}

/// A ready pose: elbow bent, tool down and out in front.
const READY: [f64; 7] = [0.0, 0.5, 0.0, -1.4, 0.0, 1.2, 0.0];

fn generate(rng: &mut Rng, index: usize) -> Option<Case> {
    let from_ready = index.is_multiple_of(2);
    let ready: Vec<f64> = READY.iter().map(|&x| crate::case::round(x)).collect();
    let name = format!("iiwa_shelves-{index:03}");
    let mut draft = Draft::new(table_top_spec(
        &name,
        "KUKA LBR iiwa 7 on a table before a shelf",
        RobotSpec::Table(joints()),
        vec![0.0; 7],
    ))?;

    let top = -0.01 - rng.range(0.0, 0.05);
    draft.push(Obstacle::cuboid(
        "table",
        [0.2, 0.0, top - 0.05],
        [0.9, 0.9, 0.05],
    ));
    let (shelf, boards) = shelf_unit(
        rng,
        top,
        &ShelfSizes {
            azimuth: (-1.3, 1.3),
            near: (0.5, 0.8),
            half_depth: (0.12, 0.2),
            half_width: (0.3, 0.5),
            height: (0.9, 1.3),
            boards: 3,
            board_jitter: 0.05,
        },
    );
    for o in shelf {
        draft.push(o);
    }
    if rng.chance(0.5) {
        let s = [
            rng.range(0.05, 0.12),
            rng.range(0.05, 0.12),
            rng.range(0.05, 0.15),
        ];
        let r = rng.range(0.35, 0.6);
        let o = Obstacle::cuboid("box on the table", [r, 0.0, top + s[2]], s)
            .turned(rng.range(-3.1, 3.1));
        draft.push(o);
    }

    let (start, at_ready) = draft.ready_or_random(rng, ready, from_ready)?;
    let goal = draft.random_goal(rng, &start, 0.8, 0.25, 1500)?;

    let placed = draft.boxes_in_the_way(rng, &start, &goal, 2, (0.04, 0.1));
    let tags = format!(
        "start {}; {boards} boards; {} obstacles ({placed} in the way)",
        if at_ready { "ready" } else { "random" },
        draft.spec.obstacles.len()
    );
    draft.finish(FAMILY.name, index, tags, &start, &goal, true)
}
