//! Robots from URDF files, end to end: the vendored Panda and UR5 scenarios
//! load through `[robot] urdf`, the core's f32 kinematics and the checker's
//! f64 chain agree with Pinocchio's golden values, both scenarios plan to
//! their targets and the independent checker accepts the trajectories, and
//! malformed URDFs stop `capp run` with one line naming the file and the
//! element, exit status 2 and no output folder.

mod common;

use std::path::{Path, PathBuf};
use std::process::Command;

use capp_core::kinematics::{forward_kinematics, Frames};
use capp_sim::check::check;
use capp_sim::geometry::forward_chain;
use capp_sim::problem::MAX_JOINTS;
use capp_sim::Problem;

fn repo() -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR")).join("..")
}

fn scenario(name: &str) -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR"))
        .join("scenarios")
        .join(name)
}

/// Golden rows of `robots/golden/CSV`: joint values, then per joint its
/// world origin and axis, then the tip position and rotation (row-major).
fn golden(csv: &str) -> Vec<Vec<f64>> {
    let text = std::fs::read_to_string(repo().join("robots/golden").join(csv)).unwrap();
    text.lines()
        .skip(1)
        .map(|l| l.split(',').map(|x| x.parse().unwrap()).collect())
        .collect()
}

/// The scenario's robot against Pinocchio: the core in f32 to 1e-5 m and
/// 1e-5 rad (the issue's target), the checker's f64 chain (of the same
/// f32-rounded origins) to 1e-6.
fn matches_pinocchio(file: &str, csv: &str) {
    let problem = Problem::load(&scenario(file)).unwrap();
    let robot = problem.robot().unwrap();
    assert!(robot.is_general());
    let n = problem.joints.len();
    let mut frames = Frames::<MAX_JOINTS>::default();
    let (mut worst_m, mut worst_rad) = (0.0f64, 0.0f64);
    let rows = golden(csv);
    assert_eq!(rows.len(), 100);
    let urdf = problem.urdf.as_ref().unwrap();
    let (slides, per_metre) = (&urdf.pivot_slide, urdf.per_metre);
    assert!(slides.iter().any(|s| s.abs() > 1e-3), "{file}: {slides:?}");
    for row in &rows {
        let q64 = &row[..n];
        let q: Vec<f32> = q64.iter().map(|&x| x as f32).collect();
        forward_kinematics(&robot, &q, &mut frames);
        let (points, end) = forward_chain(&problem.joints, &problem.tool, q64);
        for (k, point) in points.iter().enumerate().take(n) {
            let at = n + 6 * k;
            let pivot = frames.pivot(k);
            let axis = frames.axis(k);
            // Pinocchio's joint origin, slid along its axis as the loader
            // slid it (`input::pivots`).
            let slide = slides[k] * per_metre;
            for i in 0..3 {
                let expect = row[at + i] + slide * row[at + 3 + i];
                worst_m = worst_m.max((pivot[i] as f64 - expect).abs());
                worst_rad = worst_rad.max((axis[i] as f64 - row[at + 3 + i]).abs());
                assert!((point[i] - expect).abs() < 1e-6, "{file} f64 pivot {k}");
            }
        }
        let at = 7 * n;
        let tip = frames.end_position();
        let r = frames.end_rotation();
        for i in 0..3 {
            worst_m = worst_m.max((tip[i] as f64 - row[at + i]).abs());
            assert!((end[i][3] - row[at + i]).abs() < 1e-6, "{file} f64 tip");
            for j in 0..3 {
                let expect = row[at + 3 + 3 * i + j];
                worst_rad = worst_rad.max((r[(i, j)] as f64 - expect).abs());
                assert!((end[i][j] - expect).abs() < 1e-6, "{file} f64 tip rotation");
            }
        }
    }
    assert!(worst_m <= 1e-5, "{file}: f32 positions off by {worst_m} m");
    assert!(
        worst_rad <= 1e-5,
        "{file}: f32 axes/rotation off by {worst_rad}"
    );
    println!("{file}: core f32 against Pinocchio: {worst_m:.2e} m, {worst_rad:.2e} rad");
}

#[test]
fn panda_scenario_kinematics_match_pinocchio() {
    matches_pinocchio("panda_table.toml", "panda_fk.csv");
}

#[test]
fn ur5_scenario_kinematics_match_pinocchio() {
    matches_pinocchio("ur5_table.toml", "ur5_fk.csv");
}

#[test]
fn urdf_scenarios_plan_to_their_targets_and_the_checker_accepts() {
    for file in ["panda_table.toml", "ur5_table.toml"] {
        let (problem, trajectory) = common::planned(&scenario(file));
        // Radii from the collision geometry: every link of both robots has some.
        assert!(
            problem.links.radius.iter().all(|&r| r > 0.0 && r < 0.5),
            "{file}"
        );
        let report = check(&problem, &trajectory);
        assert!(report.accepted(), "{file}: {report:?}");
        assert!(
            report.to_string().contains("target reached"),
            "{file}: {report}"
        );
    }
}

/// `panda_table.toml` with its URDF path made absolute, to be written
/// into a scratch directory.
fn panda_table_anywhere() -> String {
    std::fs::read_to_string(scenario("panda_table.toml"))
        .unwrap()
        .replace("../../robots", &repo().join("robots").display().to_string())
}

/// `slide_pivots = false` keeps the URDF's joint origins (the pivots are
/// Pinocchio's); by default the Panda's column between joints 1 and 2, a
/// chord of no length at the URDF's origins, gets a chord through it and a
/// capsule of the column's own radius, and more link pairs are checked
/// because fewer touch at home. The key goes with `urdf` only.
#[test]
fn pivots_slide_along_their_axes_unless_told_not_to() {
    let dir = tempfile::tempdir().unwrap();
    let text = panda_table_anywhere();
    let kept = text.replace(
        "tip_link = \"panda_link8\"",
        "tip_link = \"panda_link8\"\nslide_pivots = false",
    );
    assert_ne!(kept, text);
    let (slid_path, kept_path) = (dir.path().join("slid.toml"), dir.path().join("kept.toml"));
    std::fs::write(&slid_path, &text).unwrap();
    std::fs::write(&kept_path, &kept).unwrap();
    let slid = Problem::load(&slid_path).unwrap();
    let kept = Problem::load(&kept_path).unwrap();
    assert!(kept
        .urdf
        .as_ref()
        .unwrap()
        .pivot_slide
        .iter()
        .all(|&s| s == 0.0));
    let rows = golden("panda_fk.csv");
    let mut frames = Frames::<MAX_JOINTS>::default();
    let robot = kept.robot().unwrap();
    let q: Vec<f32> = rows[0][..7].iter().map(|&x| x as f32).collect();
    forward_kinematics(&robot, &q, &mut frames);
    for k in 0..7 {
        for i in 0..3 {
            assert!((frames.pivot(k)[i] as f64 - rows[0][7 + 6 * k + i]).abs() < 1e-5);
        }
    }
    // The column between joints 1 and 2: round its slid chord, 0.09 m; the
    // URDF's chord has no length there (both frames 0.333 m up), so
    // unslid it takes a segment of its own along the column, as thin.
    let (r_slid, r_kept) = (slid.links.radius[0], kept.links.radius[0]);
    assert!((r_slid - 0.09).abs() < 1e-4, "{r_slid}");
    assert!((r_kept - 0.09).abs() < 1e-3, "{r_kept}");
    assert!(!kept.links.segments.is_empty());
    let pairs = |p: &Problem| p.scenario().unwrap().capsules().checked_count();
    assert!(
        pairs(&slid) > pairs(&kept),
        "{} vs {}",
        pairs(&slid),
        pairs(&kept)
    );

    let dh = std::fs::read_to_string(scenario("planar_arm.toml"))
        .unwrap()
        .replacen(
            "[[robot.joints]]",
            "[robot]\nslide_pivots = true\n\n[[robot.joints]]",
            1,
        );
    let path = dir.path().join("dh.toml");
    std::fs::write(&path, dh).unwrap();
    let e = Problem::load(&path).unwrap_err().to_string();
    assert!(e.contains("`slide_pivots` go with `urdf`"), "{e}");
}

#[test]
fn overrides_by_name_and_missing_velocity_limits() {
    let dir = tempfile::tempdir().unwrap();
    let text = panda_table_anywhere();
    let path = dir.path().join("p.toml");
    std::fs::write(&path, &text).unwrap();
    let problem = Problem::load(&path).unwrap();
    assert_eq!(problem.joint_names[6], "panda_joint7");
    assert_eq!(problem.joints[6].max_rate, 1.5, "the override by name");
    assert_eq!(problem.joints[0].max_rate, 2.175_f32, "the URDF's velocity");

    let unknown = text.replace("joint = \"panda_joint7\"", "joint = \"panda_joint9\"");
    std::fs::write(&path, unknown).unwrap();
    let err = Problem::load(&path).unwrap_err().to_string();
    assert!(err.contains("no joint is named \"panda_joint9\""), "{err}");

    // A URDF without velocity limits needs them from the scenario.
    let urdf =
        std::fs::read_to_string(repo().join("robots/panda_description/urdf/panda_collision.urdf"))
            .unwrap();
    let slow = urdf.replace("velocity=\"2.61\"", "velocity=\"0\"");
    assert_ne!(slow, urdf);
    let urdf_path = dir.path().join("panda.urdf");
    std::fs::write(&urdf_path, slow).unwrap();
    let text = text.replace(
        &repo()
            .join("robots/panda_description/urdf/panda_collision.urdf")
            .display()
            .to_string(),
        "panda.urdf",
    );
    std::fs::write(&path, &text).unwrap();
    let err = Problem::load(&path).unwrap_err().to_string();
    assert!(
        err.contains("(\"panda_joint5\"): the URDF gives no max_rate"),
        "{err}"
    );
}

/// A URDF robot for the malformed cases: base, two revolute joints, a tip.
fn urdf(joints: &str) -> String {
    format!(
        r#"<?xml version="1.0"?>
<robot name="two">
  <link name="base"/>
  <link name="upper"/>
  <link name="tip"/>
{joints}
</robot>
"#
    )
}

const GOOD_JOINTS: &str = r#"  <joint name="shoulder" type="revolute">
    <parent link="base"/><child link="upper"/>
    <origin xyz="0 0 0.1" rpy="0 0 0"/><axis xyz="0 0 1"/>
    <limit lower="-2" upper="2" velocity="1" effort="1"/>
  </joint>
  <joint name="elbow" type="revolute">
    <parent link="upper"/><child link="tip"/>
    <origin xyz="0.5 0 0" rpy="0 0 0"/><axis xyz="0 1 0"/>
    <limit lower="-2" upper="2" velocity="1" effort="1"/>
  </joint>"#;

const SCENARIO: &str = r#"name = "two"
[units]
angle = "radians"
length = "metres"
[robot]
urdf = "robot.urdf"
base_link = "base"
tip_link = "tip"
[target]
position = [0.3, 0.4, 0.1]
"#;

#[test]
fn malformed_urdfs_stop_capp_run_with_one_line_and_no_output() {
    let good = GOOD_JOINTS;
    let cases: Vec<(&str, String, &str)> = vec![
        ("the good robot", urdf(good), ""),
        ("not XML", "<robot name=\"x\"><link".into(), "robot"),
        (
            "a missing link",
            urdf(&good.replace("<child link=\"tip\"/>", "<child link=\"hand\"/>")),
            "joint `elbow`",
        ),
        (
            "an unknown joint type",
            urdf(&good.replace("\"elbow\" type=\"revolute\"", "\"elbow\" type=\"hinge\"")),
            "joint `elbow`",
        ),
        (
            "a floating joint on the chain",
            urdf(&good.replace("\"elbow\" type=\"revolute\"", "\"elbow\" type=\"floating\"")),
            "joint `elbow`",
        ),
        (
            "a planar joint on the chain",
            urdf(&good.replace("\"shoulder\" type=\"revolute\"", "\"shoulder\" type=\"planar\"")),
            "joint `shoulder`",
        ),
        (
            "a mimic joint on the chain",
            urdf(&good.replace(
                "<axis xyz=\"0 1 0\"/>",
                "<axis xyz=\"0 1 0\"/><mimic joint=\"shoulder\"/>",
            )),
            "joint `elbow`",
        ),
        (
            "a loop",
            urdf(&format!(
                "{good}\n  <joint name=\"back\" type=\"fixed\"><parent link=\"tip\"/><child link=\"base\"/></joint>"
            )),
            "",
        ),
        (
            "a revolute joint without limit",
            urdf(&good.replace(
                "<limit lower=\"-2\" upper=\"2\" velocity=\"1\" effort=\"1\"/>\n  </joint>\n  <joint name=\"elbow\"",
                "</joint>\n  <joint name=\"elbow\"",
            )),
            "joint `shoulder`",
        ),
        (
            "a zero axis",
            urdf(&good.replace("<axis xyz=\"0 1 0\"/>", "<axis xyz=\"0 0 0\"/>")),
            "joint `elbow`",
        ),
        (
            "a NaN origin",
            urdf(&good.replace("xyz=\"0.5 0 0\"", "xyz=\"NaN 0 0\"")),
            "joint `elbow`",
        ),
        (
            "lower above upper",
            urdf(good).replace(
                "<limit lower=\"-2\" upper=\"2\" velocity=\"1\" effort=\"1\"/>\n  </joint>\n</robot>",
                "<limit lower=\"2\" upper=\"-2\" velocity=\"1\" effort=\"1\"/>\n  </joint>\n</robot>",
            ),
            "joint `elbow`",
        ),
        (
            "a duplicate joint name",
            urdf(&good.replace("\"elbow\"", "\"shoulder\"")),
            "joint `shoulder`",
        ),
        (
            "a mesh that is not there",
            urdf(good).replace(
                "<link name=\"upper\"/>",
                "<link name=\"upper\"><collision><geometry><mesh filename=\"package://arm/upper.stl\"/></geometry></collision></link>",
            ),
            "link `upper`",
        ),
        (
            "a negative box size",
            urdf(good).replace(
                "<link name=\"upper\"/>",
                "<link name=\"upper\"><collision><geometry><box size=\"0.1 -0.1 0.1\"/></geometry></collision></link>",
            ),
            "link `upper`",
        ),
    ];
    let mut refused = 0;
    for (label, text, element) in &cases {
        let dir = tempfile::tempdir().unwrap();
        let urdf_path = dir.path().join("robot.urdf");
        std::fs::write(&urdf_path, text).unwrap();
        let path = dir.path().join("two.toml");
        std::fs::write(&path, SCENARIO).unwrap();
        let out = dir.path().join("out");
        let o = Command::new(env!("CARGO_BIN_EXE_capp"))
            .args(["run", path.to_str().unwrap(), "-o", out.to_str().unwrap()])
            .output()
            .unwrap();
        let stderr = String::from_utf8(o.stderr).unwrap();
        if element.is_empty() && *label == "the good robot" {
            assert!(o.status.success(), "{label}: {stderr}");
            continue;
        }
        assert_eq!(o.status.code(), Some(2), "{label}: {stderr}");
        assert_eq!(stderr.lines().count(), 1, "{label}: one line: {stderr}");
        assert!(!stderr.contains("panicked"), "{label}: {stderr}");
        assert!(
            stderr.contains("robot.urdf"),
            "{label}: names the URDF: {stderr}"
        );
        assert!(
            stderr.contains(element),
            "{label}: names {element}: {stderr}"
        );
        assert!(!out.exists(), "{label}: no output folder");
        refused += 1;
    }
    assert!(refused >= 12, "{refused} malformed URDFs tried");
}

#[test]
fn a_urdf_start_in_self_collision_points_to_capp_robot() {
    // The UR5 with its elbow folded to 3.0 rad: the forearm's capsule
    // touches the shoulder's. The error says which, on one line, and where to
    // see the capsules (round chords that can miss the bodies).
    let dir = tempfile::tempdir().unwrap();
    let text = std::fs::read_to_string(scenario("ur5_table.toml"))
        .unwrap()
        .replace("../../robots", &repo().join("robots").display().to_string())
        .replace(
            "example-robot-data = \"../..\"",
            &format!("example-robot-data = \"{}\"", repo().display()),
        )
        .replace(
            "start = [0.0, -1.571, 1.571, -1.571, -1.571, 0.0]",
            "start = [0.0, -1.571, 3.0, -1.571, -1.571, 0.0]",
        );
    let path = dir.path().join("folded.toml");
    std::fs::write(&path, text).unwrap();
    let o = Command::new(env!("CARGO_BIN_EXE_capp"))
        .args(["run", path.to_str().unwrap(), "-o"])
        .arg(dir.path().join("out"))
        .output()
        .unwrap();
    assert_eq!(o.status.code(), Some(2));
    let err = String::from_utf8_lossy(&o.stderr);
    assert_eq!(err.trim().lines().count(), 1, "{err}");
    assert!(
        err.contains("start configuration puts link 1 (after joint \"shoulder_pan_joint\") into link 3 (after joint \"elbow_joint\") (self-collision: their capsules touch; `capp robot` shows each link's capsule against its body)"),
        "{err}"
    );
    assert!(!dir.path().join("out").exists());
}

#[test]
fn capp_robot_prints_the_chain_limits_and_capsules() {
    let o = Command::new(env!("CARGO_BIN_EXE_capp"))
        .args(["robot", scenario("ur5_table.toml").to_str().unwrap()])
        .output()
        .unwrap();
    assert!(o.status.success());
    let text = String::from_utf8(o.stdout).unwrap();
    // The URDF's numbers, read back: shoulder_lift's origin and elbow's limits.
    assert!(text.contains("robot \"ur5\""), "{text}");
    assert!(
        text.contains("base_link -> tool0: 6 moving joints"),
        "{text}"
    );
    // Its pivot slid along its axis (y) so that the upper arm's chord runs
    // through the upper arm: the URDF's xyz 0 0.1358 0 plus the slide.
    assert!(
        text.contains("origin xyz 0.0000 0.2828 0.0090  rpy 0.0000 1.5708"),
        "{text}"
    );
    assert!(
        text.contains("(pivot slid +0.1470 m along the axis from the URDF's origin)"),
        "{text}"
    );
    assert!(
        text.contains(
            "elbow_joint            revolute   limits [-3.1416, 3.1416]  max_rate 3.15 rad/s"
        ),
        "{text}"
    );
    assert!(
        // The URDF's 0.0823 less wrist_3's slide of 0.0074 along y.
        text.contains("tool (the tip's frame in the last joint's): xyz 0.0000 0.0749 0.0000"),
        "{text}"
    );
    assert!(text.contains("URDF links forearm_link:"), "{text}");
    assert!(text.contains("base (base_link, base):"), "{text}");
    // The upper arm lies off its chord (0.2121 m round it would hold the
    // body): its capsule is a segment of its own along the body, as thin
    // as the body's fitted capsule (0.1006 m).
    let upper = text
        .split("link 2 (after joint \"shoulder_lift_joint\")")
        .nth(1)
        .and_then(|rest| rest.split("  link 3 ").next())
        .unwrap_or_else(|| panic!("{text}"));
    assert!(upper.contains("radius 0.1006 m"), "{upper}");
    assert!(!upper.contains("misses this body"), "{upper}");
    // A DH robot prints its table.
    let o = Command::new(env!("CARGO_BIN_EXE_capp"))
        .args(["robot", scenario("planar_arm.toml").to_str().unwrap()])
        .output()
        .unwrap();
    let text = String::from_utf8(o.stdout).unwrap();
    assert!(text.contains("3 joints (DH rows"), "{text}");
    assert!(text.contains("DH alpha 0.0000  a 0.5000"), "{text}");
}

/// The fitted collision capsules ride on their bodies: at Pinocchio's 100
/// configurations (the golden file, not our kinematics) every capsule end of
/// the body joint `k` moves keeps its distance to joint `k`'s pivot and to
/// the next joint's pivot (or the tip), and its offsets along joint `k`'s
/// axis and along the next joint's (or the tip frame's x); the base's stay
/// where they are. A capsule hung on the wrong body,
/// or placed with the frame before its joint's motion, moves relative to
/// those points. `joint_frames` itself puts each joint's pivot and axis
/// where Pinocchio does.
#[test]
fn collision_capsules_ride_on_their_bodies_as_pinocchio_moves_them() {
    use capp_sim::geometry::{collision_capsules, joint_frames};
    for (file, csv) in [
        ("panda_table.toml", "panda_fk.csv"),
        ("ur5_table.toml", "ur5_fk.csv"),
    ] {
        let problem = Problem::load(&scenario(file)).unwrap();
        let n = problem.joints.len();
        let urdf = problem.urdf.as_ref().unwrap();
        // Which body each capsule is on (0: the base).
        let owner: Vec<usize> = urdf
            .bodies
            .iter()
            .enumerate()
            .flat_map(|(b, body)| std::iter::repeat_n(b, body.capsules.len()))
            .collect();
        assert!(owner.iter().filter(|&&b| b > 0).count() >= n, "{file}");
        let rows = golden(csv);
        let sub = |a: &[f64], b: &[f64]| [a[0] - b[0], a[1] - b[1], a[2] - b[2]];
        let dot = |a: [f64; 3], b: &[f64]| a[0] * b[0] + a[1] * b[1] + a[2] * b[2];
        let norm = |a: [f64; 3]| dot(a, &a).sqrt();
        // Per capsule end: (distance to pivot k, to pivot k + 1, along axis k),
        // or its world position for the base.
        let mut first: Vec<[f64; 4]> = Vec::new();
        let mut worst = 0.0f64;
        for row in &rows {
            let q = &row[..n];
            let pivot = |k: usize| -> &[f64] {
                match k < n {
                    true => &row[n + 6 * k..n + 6 * k + 3],
                    false => &row[7 * n..7 * n + 3],
                }
            };
            let axis = |k: usize| &row[n + 6 * k + 3..n + 6 * k + 6];
            // A direction fixed in body `b` other than its joint's axis: the
            // next joint's axis, or the tip frame's x for the last body.
            let across = |b: usize| -> [f64; 3] {
                match b < n {
                    true => [axis(b)[0], axis(b)[1], axis(b)[2]],
                    false => [0, 1, 2].map(|i| row[7 * n + 3 + 3 * i]),
                }
            };
            let frames = joint_frames(&problem.joints, q);
            assert_eq!(frames.len(), n);
            for (k, f) in frames.iter().enumerate() {
                let local = problem.joints[k].origin.unwrap().axis.map(f64::from);
                let world = [0, 1, 2].map(|i| (0..3).map(|j| f[i][j] * local[j]).sum::<f64>());
                let unit = world.map(|x| x / norm(world));
                // The loader slid each pivot along its axis (`input::pivots`).
                let slide = urdf.pivot_slide[k] * urdf.per_metre;
                for i in 0..3 {
                    let expect = pivot(k)[i] + slide * axis(k)[i];
                    assert!((f[i][3] - expect).abs() < 1e-6, "{file} pivot {k}");
                    assert!((unit[i] - axis(k)[i]).abs() < 1e-6, "{file} axis {k}");
                }
            }
            let capsules = collision_capsules(&problem, q);
            assert_eq!(capsules.len(), owner.len(), "{file}");
            let mut now = Vec::new();
            for (c, &b) in capsules.iter().zip(&owner) {
                for end in [&c[0..3], &c[3..6]] {
                    now.push(match b {
                        0 => [end[0], end[1], end[2], 0.0],
                        _ => [
                            norm(sub(end, pivot(b - 1))),
                            norm(sub(end, pivot(b))),
                            dot(sub(end, pivot(b - 1)), axis(b - 1)),
                            dot(sub(end, pivot(b - 1)), &across(b)),
                        ],
                    });
                }
            }
            if first.is_empty() {
                first = now;
            } else {
                for (a, b) in first.iter().zip(&now) {
                    for i in 0..4 {
                        worst = worst.max((a[i] - b[i]).abs());
                    }
                }
            }
        }
        assert!(
            worst < 1e-5,
            "{file}: capsules drift {worst} m off their bodies"
        );
    }
}

/// Pixels of `png` close to `colour` (within 40 per channel).
fn pixels_like(png: &Path, colour: [u8; 3]) -> usize {
    common::png_rgb(png)
        .1
        .iter()
        .filter(|p| (0..3).all(|i| p[i].abs_diff(colour[i]) <= 40))
        .count()
}

/// `capp robot SCENARIO --render DIR`: the pictures and the viewer of the
/// robot at its start configuration. The Panda's picture has the fitted
/// collision capsules in orange and the link capsules in teal (a rim round
/// them), and its
/// viewer carries one frame with every fitted capsule and opens with the
/// capsules shown; PIPS (a DH table) has link capsules only. A folder that
/// is not capp's is refused and left alone.
#[test]
fn capp_robot_render_draws_the_capsules() {
    use capp_sim::render::robot::{COLLISION_CAPSULE, FILES, LINK_CAPSULE};
    let scratch = tempfile::tempdir().unwrap();
    let render = |file: &str, dir: &Path| {
        Command::new(env!("CARGO_BIN_EXE_capp"))
            .args(["robot", scenario(file).to_str().unwrap(), "--render"])
            .arg(dir)
            .output()
            .unwrap()
    };
    let panda = scratch.path().join("panda");
    let o = render("panda_table.toml", &panda);
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    let text = String::from_utf8(o.stdout).unwrap();
    assert!(text.contains("pictures:"), "{text}");
    for name in FILES.iter().chain(&["COMPLETE"]) {
        assert!(panda.join(name).is_file(), "{name} missing");
    }
    let svg = std::fs::read_to_string(panda.join("robot.svg")).unwrap();
    assert!(svg.contains("URDF collision capsules"), "legend");
    let orange = pixels_like(&panda.join("robot.png"), COLLISION_CAPSULE);
    let teal = pixels_like(&panda.join("robot.png"), LINK_CAPSULE);
    // The link capsules hug the fitted ones (segments of their own where a
    // chord would miss the body), so little teal shows round the orange.
    assert!(orange > 5000 && teal > 300, "orange {orange}, teal {teal}");

    let problem = Problem::load(&scenario("panda_table.toml")).unwrap();
    let fitted: usize = problem
        .urdf
        .as_ref()
        .unwrap()
        .bodies
        .iter()
        .map(|b| b.capsules.len())
        .sum();
    let html = std::fs::read_to_string(panda.join("viewer.html")).unwrap();
    assert!(html.contains("\n\"capsules_shown\": true,"));
    let list = html
        .split("\n\"collision_capsules\": [[[")
        .nth(1)
        .expect("collision_capsules in the page")
        .split("]],")
        .next()
        .unwrap();
    // One frame: `[[c, c, ...]]`, each `c` seven numbers in brackets.
    assert_eq!(list.matches("],[").count() + 1, fitted, "{list}");
    assert!(
        list.split("],[").all(|c| c.split(',').count() == 7),
        "{list}"
    );
    assert!(html.contains("\n\"frames\": 1,"), "one frame");

    let pips = scratch.path().join("pips");
    let o = render("pips_payload_bay.toml", &pips);
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    assert_eq!(pixels_like(&pips.join("robot.png"), COLLISION_CAPSULE), 0);
    assert!(pixels_like(&pips.join("robot.png"), LINK_CAPSULE) > 500);
    let html = std::fs::read_to_string(pips.join("viewer.html")).unwrap();
    assert!(html.contains("\n\"collision_capsules\": null,"));

    // Rendering again replaces a finished folder; a foreign one is refused.
    assert!(render("panda_table.toml", &panda).status.success());
    let mine = scratch.path().join("mine");
    std::fs::create_dir(&mine).unwrap();
    std::fs::write(mine.join("notes.txt"), "keep").unwrap();
    let o = render("panda_table.toml", &mine);
    assert_eq!(o.status.code(), Some(2));
    let stderr = String::from_utf8_lossy(&o.stderr);
    assert_eq!(stderr.trim().lines().count(), 1, "{stderr}");
    assert_eq!(
        std::fs::read_to_string(mine.join("notes.txt")).unwrap(),
        "keep"
    );
    assert!(!mine.join("robot.png").exists());
}
