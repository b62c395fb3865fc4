//! Self-collision end to end: plans of folding arms keep every checked pair
//! of link capsules apart (checked independently in f64 at every step and
//! densely between steps, by `run_checked`), where the same plans without
//! capsules pass links through one another; a start in self-collision is
//! refused with the two links named.

mod common;

use capp_core::self_collision::pairs::{PairTable, SAMPLES};
use capp_core::{Joint, Mission, Outcome, Planner, Robot, Settings, StartError, Waypoint};
use common::{min_link_gap64, Sc};

/// A planar snake of `n` links of 5 in turning about z (all in the plane
/// z = 0, so folding it puts links on one another), limits +-2.8 rad.
fn snake(n: usize) -> Vec<Joint> {
    vec![Joint::revolute(0.0, 5.0, 0.0, -2.8, 2.8, 0.5); n]
}

const RADIUS: f32 = 0.5;

fn scenario(joints: &[Joint], target: [f32; 3], capsules: bool) -> Sc {
    let robot = Robot::new(joints).unwrap();
    let settings = Settings::for_robot(&robot);
    let mut sc = Sc::new(
        robot,
        &[] as &[capp_core::Solid],
        &Mission::new(&[Waypoint::at(target)], settings).unwrap(),
    )
    .unwrap();
    if capsules {
        let n = joints.len();
        let radius = vec![RADIUS; n];
        let home = vec![0.0; n];
        let table = PairTable::<18>::new(sc.robot(), &radius, &[], &home, SAMPLES, 1).unwrap();
        sc.set_link_capsules(&radius, table.checked_rows()).unwrap();
    }
    sc
}

/// The smallest checked-pair gap along a plan (every step, 8 samples
/// between steps), f64, with capsules of `RADIUS` on every pair but the
/// adjacent ones.
fn closest_along(
    joints: &[Joint],
    target: [f32; 3],
    start: &[f32],
    capsules: bool,
) -> (Outcome, f64) {
    let sc = scenario(joints, target, capsules);
    let judge = scenario(joints, target, true);
    let mut planner = Planner::new(&sc, start).unwrap();
    let mut previous: Vec<f32> = start.to_vec();
    let mut worst = f64::INFINITY;
    let outcome = planner
        .run(&sc, |p, _| {
            for i in 1..=8 {
                let f = i as f64 / 8.0;
                let q: Vec<f64> = previous
                    .iter()
                    .zip(p.joints())
                    .map(|(&a, &b)| a as f64 + (b as f64 - a as f64) * f)
                    .collect();
                worst = worst.min(min_link_gap64(&judge, &q).0);
            }
            previous.copy_from_slice(p.joints());
        })
        .unwrap();
    (outcome, worst)
}

/// Folding a planar snake onto itself: without capsules the plan passes
/// links through one another (the scenario exercises what it tests); with
/// them the same missions are reached with every checked pair apart.
#[test]
fn a_folding_snake_reaches_its_targets_without_passing_through_itself() {
    let joints = snake(8);
    for (curl, target) in [
        (0.5f32, [1.0f32, 1.0, 0.0]),
        (0.5, [2.0, 0.5, 0.0]),
        (0.5, [3.0, -3.0, 0.0]),
        (0.7, [1.0, 1.0, 0.0]),
        (0.7, [2.0, 0.5, 0.0]),
    ] {
        let start = vec![curl; 8];
        let (off, gap_off) = closest_along(&joints, target, &start, false);
        assert_eq!(off, Outcome::Reached);
        assert!(
            gap_off < -0.2,
            "{curl} {target:?}: without capsules the links should cross (gap {gap_off})"
        );
        let (on, gap_on) = closest_along(&joints, target, &start, true);
        assert_eq!(on, Outcome::Reached, "{curl} {target:?}");
        assert!(
            gap_on > 0.0,
            "{curl} {target:?}: links touch (gap {gap_on})"
        );
        // And every other invariant, step by step (limits, rates, f64 gaps).
        let run = common::run_checked(&scenario(&joints, target, true), &start);
        assert_eq!(run.outcome, Outcome::Reached);
    }
}

/// A start with two links through each other is refused, naming them.
#[test]
fn a_start_in_self_collision_is_refused_with_the_two_links() {
    let joints = snake(8);
    let sc = scenario(&joints, [1.0, 1.0, 0.0], true);
    let start = vec![0.9f32; 8];
    let q: Vec<f64> = start.iter().map(|&x| x as f64).collect();
    let (gap, a, b) = min_link_gap64(&sc, &q);
    assert!(gap < 0.0);
    match Planner::new(&sc, &start) {
        Err(StartError::SelfCollision { links: [x, y] }) => {
            // The links named overlap (they need not be the deepest pair).
            let chain = common::fk64(&joints, &q);
            let o = &chain.origins;
            let (x, y) = (x as usize, y as usize);
            let named =
                common::segment_distance64(o[x], o[x + 1], o[y], o[y + 1]) - 2.0 * RADIUS as f64;
            assert!(
                named < 0.0,
                "links {x} {y} named, gap {named}; deepest {a} {b}"
            );
            assert!(x < y && sc.capsules().is_checked(x, y));
        }
        other => panic!("expected a self-collision refusal, got {other:?}"),
    }
    // Without capsules the same start is accepted.
    assert!(Planner::new(&scenario(&joints, [1.0, 1.0, 0.0], false), &start).is_ok());
}

/// Capsules that do not fit the robot get an error value, and the scenario
/// keeps none.
#[test]
fn bad_capsules_are_refused() {
    use capp_core::self_collision::CapsuleError as E;
    use capp_core::ScenarioError::Capsules as C;
    let joints = snake(4);
    let mut sc = scenario(&joints, [10.0, 1.0, 0.0], false);
    let rows = [0b1100u64, 0b1000, 0, 0];
    assert_eq!(
        sc.set_link_capsules(&[0.5, 0.0, 0.5, 0.5], &rows),
        Err(C(E::BadRadius { link: 1 }))
    );
    assert_eq!(
        sc.set_link_capsules(&[0.5, 0.5, f32::NAN, 0.5], &rows),
        Err(C(E::BadRadius { link: 2 }))
    );
    assert_eq!(
        sc.set_link_capsules(&[0.5; 3], &rows),
        Err(C(E::WrongLength { given: 3, links: 4 }))
    );
    // A link paired with itself, or with a link the robot does not have.
    assert_eq!(
        sc.set_link_capsules(&[0.5; 4], &[0b1101, 0, 0, 0]),
        Err(C(E::BadPair { link: 0 }))
    );
    assert_eq!(
        sc.set_link_capsules(&[0.5; 4], &[0, 0, 0b1_0000, 0]),
        Err(C(E::BadPair { link: 2 }))
    );
    assert!(!sc.capsules().is_on());
    assert!(sc.set_link_capsules(&[0.5; 4], &rows).is_ok());
    assert_eq!(sc.capsules().checked_count(), 3);
}

/// PIPS between random configurations, with its capsules and pedestal
/// group: every run keeps every checked pair apart at every step and between
/// steps (`run_checked`, f64), whatever its outcome.
#[test]
fn pips_between_random_configurations_keeps_its_links_apart() {
    use capp_core::pips;
    let joints = pips::joints();
    let mut rng = common::Rng(11);
    let (mut runs, mut folded) = (0, 0);
    while runs < 10 {
        let start = common::random_config(&mut rng, &joints);
        let goal = common::random_config(&mut rng, &joints);
        let (p, r) = common::pose_of(&joints, &goal);
        let robot = Robot::new(&joints).unwrap();
        let mut settings = Settings::for_robot(&robot);
        settings.max_steps = 1500;
        let mut sc = Sc::new(
            robot,
            &[] as &[capp_core::Solid],
            &Mission::new(&[Waypoint::pose(p, r)], settings).unwrap(),
        )
        .unwrap();
        common::pips_capsules(&mut sc);
        if Planner::new(&sc, &start).is_err() {
            continue; // a random start in self-collision: refused, not planned
        }
        runs += 1;
        let run = common::run_checked(&sc, &start);
        if run.min_link_gap < 6.0 {
            folded += 1;
        }
    }
    // Some runs bring links within two radius sums of each other (where
    // the projection engages): the checks had something to check.
    assert!(folded >= 1, "no run came near itself");
}
