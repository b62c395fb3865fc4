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
    for row in &rows {
        let q64 = &row[..n];
        let q: Vec<f32> = q64.iter().map(|&x| x as f32).collect();
        forward_kinematics(&robot, &q, &mut frames);
        let (points, end) = forward_chain(&problem.joints, &problem.tool, q64);
        for (k, point) in points.iter().enumerate().take(n) {
            let at = n + 6 * k;
            let pivot = frames.pivot(k);
            let axis = frames.axis(k);
            for i in 0..3 {
                worst_m = worst_m.max((pivot[i] as f64 - row[at + i]).abs());
                worst_rad = worst_rad.max((axis[i] as f64 - row[at + 3 + i]).abs());
                assert!(
                    (point[i] - row[at + i]).abs() < 1e-6,
                    "{file} f64 pivot {k}"
                );
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

#[test]
fn overrides_by_name_and_missing_velocity_limits() {
    let dir = tempfile::tempdir().unwrap();
    let text = std::fs::read_to_string(scenario("panda_table.toml"))
        .unwrap()
        .replace("../../robots", &repo().join("robots").display().to_string());
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
    assert!(
        text.contains("origin xyz 0.0000 0.1358 0.0000  rpy 0.0000 1.5708"),
        "{text}"
    );
    assert!(
        text.contains(
            "elbow_joint            revolute   limits [-3.1416, 3.1416]  max_rate 3.15 rad/s"
        ),
        "{text}"
    );
    assert!(
        text.contains("tool (the tip's frame in the last joint's): xyz 0.0000 0.0823 0.0000"),
        "{text}"
    );
    assert!(text.contains("URDF links forearm_link:"), "{text}");
    assert!(text.contains("base (base_link, base):"), "{text}");
    // A DH robot prints its table.
    let o = Command::new(env!("CARGO_BIN_EXE_capp"))
        .args(["robot", scenario("planar_arm.toml").to_str().unwrap()])
        .output()
        .unwrap();
    let text = String::from_utf8(o.stdout).unwrap();
    assert!(text.contains("3 joints (DH rows"), "{text}");
    assert!(text.contains("DH alpha 0.0000  a 0.5000"), "{text}");
}
