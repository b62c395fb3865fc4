//! PIPS in free space (inches): targets (position and orientation) from
//! goal configurations spread over 90 % of every joint's range, so over the
//! reachable workspace; even cases start at home, odd ones from a random
//! configuration. Shipped tolerances (0.1 in, 0.05); other settings the
//! loader's defaults.

use super::pips_bay::{home, spec};
use super::scene::Draft;
use super::Family;
use crate::case::Case;
use crate::rng::Rng;

/// The family.
pub const FAMILY: Family = Family {
    name: "pips_free",
    description: "PIPS in free space, poses over the reachable workspace; tolerances 0.1 in / 0.05",
    count: 60,
    generate,
};

fn generate(rng: &mut Rng, index: usize) -> Option<Case> {
    let from_home = index.is_multiple_of(2);
    let home = home();
    let name = format!("pips_free-{index:03}");
    let draft = Draft::new(spec(&name, "PIPS in free space", &home, 0.1, 0.05))?;
    let start = if from_home {
        home
    } else {
        draft.random_clear(rng, 0.7, 10)?
    };
    let goal = draft.random_goal(rng, &start, 0.9, 20.0, 100)?;
    let tags = format!("start {}", if from_home { "home" } else { "random" });
    draft.finish(FAMILY.name, index, tags, &start, &goal, true)
}
