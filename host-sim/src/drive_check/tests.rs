//! The drive figures on hand-made trajectories whose answers are known.

use std::path::Path;

use super::*;
use crate::input::scenario_file;
use crate::trajectory::TrajectoryRow;

const DT: f64 = 0.05;

/// A planar arm of two 1 m links turning about z, in radians and metres:
/// rates 1 rad/s, so (the defaults) 2 rad/s^2 and 20 rad/s^3; both margins
/// `margin`; one ball of radius `radius` at `ball` (or none).
fn arm(ball: Option<[f64; 2]>, radius: f64, margin: f64) -> Problem {
    let joint = "[[robot.joints]]\ntype = \"revolute\"\nalpha = 0.0\na = 1.0\nmin = -6.0\nmax = 6.0\nmax_rate = 1.0\n";
    let obstacle = match ball {
        Some([x, y]) => format!(
            "[[obstacles]]\ncentre = [{x}, {y}, 0.0]\nsemi_axes = [{radius}, {radius}, {radius}]\nexponent = 2.0\n"
        ),
        None => String::new(),
    };
    let text = format!(
        "[units]\nangle = \"radians\"\nlength = \"metres\"\n[robot]\nself_collision = false\n\
         {joint}{joint}[target]\nposition = [0.0, 2.0, 0.0]\n{obstacle}\
         [settings]\njoint_margin = {margin}\nlink_margin = {margin}\n"
    );
    scenario_file::parse(&text, Path::new("arm.toml")).unwrap_or_else(|e| panic!("{e}"))
}

/// Rows at the fixed period (row 0: `h = 0`), joint 1 at `q1(k)`, joint 2
/// at 0 (the arm straight), positions rounded to `f32` as a trajectory file stores them.
fn rows(count: usize, q1: impl Fn(usize) -> f64) -> Trajectory {
    Trajectory {
        joints: 2,
        rows: (0..count)
            .map(|k| TrajectoryRow {
                line: k + 2,
                step: k as u64,
                h: if k == 0 { 0.0 } else { DT as f32 as f64 },
                q: vec![q1(k) as f32 as f64, 0.0],
                velocity: None,
                acceleration: None,
                position: None,
                v: None,
                position_error: None,
                orientation_error: None,
                clearance: None,
                escape: None,
            })
            .collect(),
    }
}

fn measure_of(problem: &Problem, t: &Trajectory, reached: bool) -> DriveReport {
    measure(problem, &Geometry::new(problem), t, reached, 1e-5, 3.0)
}

/// Position at `t` of piecewise-constant jerk `(duration, jerk)` from rest
/// at `q0`, starting at `t = 0` (at rest before): each piece a cubic.
fn profile(pieces: &[(f64, f64)], q0: f64, t: f64) -> f64 {
    let (mut q, mut v, mut a, mut start) = (q0, 0.0, 0.0, 0.0);
    for &(d, j) in pieces {
        let s = (t - start).clamp(0.0, d);
        let at = q + v * s + a * s * s / 2.0 + j * s * s * s / 6.0;
        if t <= start + d {
            return at;
        }
        q = at;
        v += a * d + j * d * d / 2.0;
        a += j * d;
        start += d;
    }
    let s = t - start;
    q + v * s + a * s * s / 2.0
}

/// Rest to rest at the limits (A = 2, J = 20, R = 1): jerk 0.1 s, constant
/// acceleration 0.4 s, jerk 0.1 s, cruise `cruise` s, and the mirror image.
fn s_curve(cruise: f64) -> Vec<(f64, f64)> {
    vec![
        (0.1, 20.0),
        (0.4, 0.0),
        (0.1, -20.0),
        (cruise, 0.0),
        (0.1, -20.0),
        (0.4, 0.0),
        (0.1, 20.0),
    ]
}

/// A jerk-limited move (an independent closed form, sampled at `k dt`)
/// keeps every figure: differences of a curve average its derivatives, so
/// they never exceed their bounds, and the acceleration's plateau (longer
/// than two periods) is met exactly.
#[test]
fn a_jerk_limited_move_passes() {
    let problem = arm(None, 0.0, 0.01);
    let pieces = s_curve(0.5);
    // Rest for 0.2 s, the 2.2 s move, rest for 0.3 s.
    let t = rows(55, |k| profile(&pieces, 0.5, k as f64 * DT - 0.2));
    let r = measure_of(&problem, &t, true);
    assert!(r.clean(), "{r}");
    assert_eq!(
        (r.off_period, r.rate.rows, r.accel.rows, r.jerk.rows),
        (0, 0, 0, 0)
    );
    let peak = |e: &Excess| e.peak.as_ref().unwrap().ratio;
    assert!(peak(&r.rate) > 0.99 && peak(&r.rate) <= 1.0 + 1e-4, "{r}");
    assert!(peak(&r.accel) > 0.99 && peak(&r.accel) <= 1.0 + 1e-4, "{r}");
    assert!(peak(&r.jerk) > 0.5 && peak(&r.jerk) <= 1.0 + 1e-4, "{r}");
    assert!(!r.arrives_moving && r.final_speed.as_ref().unwrap().ratio < 1e-5);
    // The same move in half the time breaks the limits.
    let fast = rows(55, |k| profile(&pieces, 0.5, 2.0 * (k as f64 * DT - 0.2)));
    let r = measure_of(&problem, &fast, true);
    assert!(
        r.rate.rows > 0 && r.accel.rows > 0 && r.jerk.rows > 0,
        "{r}"
    );
}

/// At rest until row 9, then half the rate at once from row 10: a jump of
/// 0.5 rad/s in one period is 10 rad/s^2 (5x the limit) at row 10, and the
/// jerk 200 rad/s^3 (10x) at rows 10 and 11.
#[test]
fn a_velocity_jump_is_found_at_its_row() {
    let problem = arm(None, 0.0, 0.01);
    let t = rows(20, |k| 0.3 + 0.5 * (k.max(9) - 9) as f64 * DT);
    let r = measure_of(&problem, &t, true);
    assert_eq!(r.off_period, 0, "{r}");
    assert_eq!((r.rate.rows, r.accel.rows, r.jerk.rows), (0, 1, 2), "{r}");
    let accel = r.accel.peak.as_ref().unwrap();
    assert_eq!((accel.step, accel.joint), (10, 0));
    assert!((accel.ratio - 5.0).abs() < 1e-4, "{r}");
    let jerk = r.jerk.peak.as_ref().unwrap();
    assert_eq!(jerk.step, 10);
    assert!((jerk.ratio - 10.0).abs() < 1e-3, "{r}");
    assert!((r.rate.peak.as_ref().unwrap().ratio - 0.5).abs() < 1e-4);
    // It ends moving at half the rate.
    assert!(r.arrives_moving);
    assert!((r.final_speed.as_ref().unwrap().ratio - 0.5).abs() < 1e-4);
    // Not reached: moving, but not "arrives moving".
    assert!(!measure_of(&problem, &t, false).arrives_moving);
    assert!(
        r.to_string()
            .contains("acceleration: 1 rows over, worst 5.000x its limit (joint 1, step 10)"),
        "{r}"
    );
}

/// The arm at rest before the first row: a trajectory already moving at
/// row 0 starts from rest, so row 1 is the jump.
#[test]
fn rest_before_the_first_row() {
    let problem = arm(None, 0.0, 0.01);
    let t = rows(10, |k| 0.3 + 0.5 * k as f64 * DT);
    let d = differences(&t, DT);
    assert_eq!(d.values[0][0], [0.0, 0.0, 0.0]);
    let r = measure_of(&problem, &t, false);
    assert_eq!((r.accel.rows, r.jerk.rows), (1, 2), "{r}");
    let accel = r.accel.peak.as_ref().unwrap();
    assert_eq!(accel.step, 1);
    assert!((accel.ratio - 5.0).abs() < 1e-4, "{r}");
}

/// A short step puts its row and every later one off the period; a hold
/// (`h = 0`) counts as a period at rest, so stopping dead shows.
#[test]
fn off_period_rows_and_holds() {
    let problem = arm(None, 0.0, 0.01);
    let mut t = rows(10, |k| 0.3 + 0.0 * k as f64);
    t.rows[4].h = 0.025;
    let r = measure_of(&problem, &t, true);
    assert_eq!(r.off_period, 6, "{r}");
    assert_eq!(r.first_off_period.unwrap().step, 4);
    // Moving at 0.5 rad/s, then held in zero time for a row, then on.
    let mut t = rows(10, |k| {
        0.3 + 0.5 * k.min(5) as f64 * DT + 0.5 * k.saturating_sub(6) as f64 * DT
    });
    t.rows[6].h = 0.0;
    let d = differences(&t, DT);
    assert_eq!(d.interval[6], DT);
    assert_eq!(d.values[6][0][0], 0.0);
    assert!(
        (d.values[6][0][1] + 10.0).abs() < 1e-3,
        "{:?}",
        d.values[6][0]
    );
    let r = measure_of(&problem, &t, true);
    assert_eq!(r.off_period, 4, "{r}");
}

/// The joint 1 trajectory that comes up to full rate (1 rad/s) and then
/// cruises until the last row: `(trajectory, angle of the last row)`.
fn cruising() -> (Trajectory, f64) {
    let pieces = s_curve(10.0);
    let count = 40;
    let t = rows(count, |k| profile(&pieces, 0.0, k as f64 * DT - 0.1));
    let last = t.rows[count - 1].q[0];
    (t, last)
}

/// The tip (radius 2) at `angle`.
fn tip(angle: f64) -> [f64; 2] {
    [2.0 * angle.cos(), 2.0 * angle.sin()]
}

/// From full rate the stop takes 0.25 rad (the braking tests' trapezoid
/// with p = 2, k = 8): a ball 0.15 rad ahead of the last row is hit by the
/// stops of the last rows, one 0.3 rad ahead (and off the path) by none.
#[test]
fn a_stop_into_an_obstacle_is_counted() {
    let (t, last) = cruising();
    let clear = arm(Some(tip(last + 0.3)), 0.02, 0.01);
    let r = measure_of(&clear, &t, false);
    assert_eq!(r.braking_collisions, 0, "{r}");
    assert_eq!((r.rate.rows, r.accel.rows, r.jerk.rows), (0, 0, 0), "{r}");
    // 12 ticks from exactly full rate; the f32 positions' rounding in the
    // state can add a tick or two of tiny corrections.
    assert!(r.stops > 30 && (12..=14).contains(&r.longest_stop), "{r}");
    let hit = arm(Some(tip(last + 0.15)), 0.02, 0.01);
    let r = measure_of(&hit, &t, false);
    assert!((2..=4).contains(&r.braking_collisions), "{r}");
    let first = r.first_braking_collision.as_ref().unwrap();
    assert!(first.step >= 35, "{r}");
    assert!(
        first.what.contains("far end of link 2 inside obstacle 1"),
        "{r}"
    );
}

/// A small ball between the ticks of every stop that passes it (its angle
/// 0.02 rad, modulo the rows' 0.05, from every tick) is found between ticks.
#[test]
fn a_stop_is_checked_between_ticks() {
    let (t, last) = cruising();
    let problem = arm(Some(tip(last + 0.07)), 0.003, 0.001);
    let r = measure_of(&problem, &t, false);
    assert!(r.braking_collisions >= 1, "{r}");
    let first = r.first_braking_collision.as_ref().unwrap();
    assert!(first.what.contains("between ticks"), "{r}");
}
