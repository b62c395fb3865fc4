//! `capp acm SCENARIO`: the allowed-collision matrix of a scenario's robot,
//! the link capsules and every pair of links, checked or skipped and why
//! ([`capp_core::self_collision::pairs`]).

use std::fmt::Write;

use capp_core::self_collision::pairs::{PairStatus, SAMPLES};

use crate::problem::{LoadError, Problem, PAIR_SEED};

/// The report `capp acm` prints.
pub fn report(problem: &Problem) -> Result<String, LoadError> {
    let mut out = String::new();
    let unit = &problem.length_unit;
    let _ = writeln!(out, "{}: {} links", problem.name, problem.joints.len());
    if !problem.links.enabled {
        let _ = writeln!(
            out,
            "self-collision is off for this scenario ([robot] self_collision = false): no pair is checked"
        );
    }
    let _ = match problem.links.segments.is_empty() {
        true => writeln!(
            out,
            "\ncapsules (the chord from each joint's pivot to the next, DH link k after joint k):"
        ),
        false => writeln!(
            out,
            "\ncapsules (each link's segment, fixed in the body joint k moves, link k after joint k):"
        ),
    };
    for (k, r) in problem.links.radius.iter().enumerate() {
        let _ = writeln!(out, "  {:<28} radius {r} {unit}", problem.link_label(k));
    }
    let table = problem.pair_table()?;
    let (mut checked, mut skipped) = (Vec::new(), Vec::new());
    for (a, b, status) in table.pairs() {
        if status == PairStatus::Checked {
            checked.push((a, b));
        } else {
            skipped.push((a, b, status));
        }
    }
    let _ = writeln!(
        out,
        "\nchecked: {} pairs (home: the file's home configuration; {SAMPLES} sampled configurations, seed {PAIR_SEED})",
        checked.len()
    );
    for (a, b) in &checked {
        let _ = writeln!(out, "  {:>2} - {:<2}", a + 1, b + 1);
    }
    let _ = writeln!(out, "\nskipped: {} pairs", skipped.len());
    for (a, b, status) in &skipped {
        let _ = writeln!(out, "  {:>2} - {:<2} {}", a + 1, b + 1, status.reason());
    }
    Ok(out)
}
