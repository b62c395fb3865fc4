//! Test support shared by the host-sim tests: a planar dead end by
//! construction, as scenario text; the shipped planar arm planned tracked.
#![allow(dead_code)]

use std::path::Path;
use std::process::Command;

use capp_sim::output::rows_csv;
use capp_sim::trajectory::Trajectory;
use capp_sim::{plan, trajectory, Problem};

/// xorshift64*: the tests' own seeded numbers.
pub struct Rng(pub u64);

impl Rng {
    /// Uniform in [0, 1).
    pub fn next(&mut self) -> f64 {
        self.0 ^= self.0 >> 12;
        self.0 ^= self.0 << 25;
        self.0 ^= self.0 >> 27;
        (self.0.wrapping_mul(0x2545_F491_4F6C_DD1D) >> 11) as f64 / (1u64 << 53) as f64
    }

    /// Uniform in [lo, hi).
    pub fn range(&mut self, lo: f64, hi: f64) -> f64 {
        lo + (hi - lo) * self.next()
    }
}

/// A configuration drawn uniformly within `problem`'s joint limits.
pub fn random_q(problem: &Problem, rng: &mut Rng) -> Vec<f64> {
    problem
        .joints
        .iter()
        .map(|j| rng.range(j.min as f64, j.max as f64))
        .collect()
}

/// The planar arm of `capp-core`'s tests (links of 10 in, reach 30 in),
/// starting at `START`, its hand at (28.96, 2.90); the target is the hand's
/// mirror image across y = 0, 5.80 in away. A wall along y = 0, from
/// x = 23 to x = 37, 1 in thick, of half-height `half_height`, stands
/// between them. A dead end by construction, not by tuning: the disk of
/// radius 5.80 round the target meets y = 0 in x within 28.96 -+ 5.02 (half
/// chord sqrt(5.80^2 - 2.90^2)), inside the wall, so the wall cuts the disk
/// in two with the hand and the target on either side. Every collision-free
/// path of the hand (which moves in the plane z = 0 only) leaves the disk:
/// V must first rise above its start value, which no descent of V does,
/// however good the law. A path exists round the wall's inner end (its outer
/// end is beyond the reach). A low wall (half-height 5) is small enough to
/// be detoured round; a tall one (20: its inflated box more than half the
/// reach) is not, and is escaped by a walk.
/// Two revolute joints in a plane, metres and degrees (links of 0.5 and
/// 0.4 m), as scenario text: the `[units]` and the `[[robot.joints]]`,
/// starting on a line of its own.
pub const PLANAR_ARM: &str = r#"[units]
angle = "degrees"
length = "metres"

[[robot.joints]]
type = "revolute"
alpha = 0.0
a = 0.5
theta = 0.0
min = -170.0
max = 170.0
max_rate = 30.0

[[robot.joints]]
type = "revolute"
alpha = 0.0
a = 0.4
theta = 0.0
min = -150.0
max = 150.0
max_rate = 30.0
"#;

const START: [f64; 3] = [0.4, -0.3, -0.3];
const WALL_CENTRE_X: f64 = 30.0;
const WALL_HALF_LENGTH: f64 = 7.0;

/// The hand at `START`, (x, y).
fn start_hand() -> (f64, f64) {
    let (mut x, mut y, mut angle) = (0.0, 0.0, 0.0);
    for q in START {
        angle += q;
        x += 10.0 * f64::cos(angle);
        y += 10.0 * f64::sin(angle);
    }
    (x, y)
}

/// The trap as a scenario file's text, named `name`.
pub fn planar_trap(name: &str, half_height: f64) -> String {
    let (x, y) = start_hand();
    // The construction holds: the chord of the start error's disk round the
    // target, along y = 0, lies within the wall's length.
    let half_chord = ((2.0 * y).powi(2) - y * y).sqrt();
    assert!(y > 0.0 && (x - WALL_CENTRE_X).abs() + half_chord < WALL_HALF_LENGTH);
    let joint = "[[robot.joints]]\ntype = \"revolute\"\nalpha = 0.0\na = 10.0\nmin = -2.8\nmax = 2.8\nmax_rate = 0.5\n";
    format!(
        "name = \"{name}\"\nstart = {START:?}\n\
         [units]\nangle = \"radians\"\nlength = \"inches\"\n\
         {joint}{joint}{joint}\
         [target]\nposition = [{x}, {}, 0.0]\n\
         [[obstacles]]\nname = \"post\"\ncentre = [{WALL_CENTRE_X}, 0.0, 0.0]\nsemi_axes = [{WALL_HALF_LENGTH}, 0.5, {half_height}]\nexponent = 8.0\n\
         [settings]\njoint_margin = 1.0\nlink_margin = 0.5\npoints_per_link = 3\ninfluence_distance = 5.0\n",
        -y
    )
}

/// `planar_arm.toml` with `motion = "tracked"`, planned, as its
/// trajectory file reads back.
pub fn tracked_planar() -> (Problem, Trajectory) {
    let text = std::fs::read_to_string(
        Path::new(env!("CARGO_MANIFEST_DIR")).join("scenarios/planar_arm.toml"),
    )
    .unwrap();
    let dir = tempfile::tempdir().unwrap();
    let file = dir.path().join("planar_tracked.toml");
    std::fs::write(&file, format!("{text}\nmotion = \"tracked\"\n")).unwrap();
    planned(&file)
}

/// The scenario file at `path` planned: the problem and its trajectory as
/// the trajectory file reads back.
pub fn planned(path: &Path) -> (Problem, Trajectory) {
    let problem = Problem::load(path).unwrap();
    let scenario = problem.validate().unwrap();
    let result = plan::run(&problem, &scenario, |_| {}).unwrap();
    let csv = rows_csv(problem.joints.len(), &result.rows).unwrap();
    let t = trajectory::parse(&csv, Path::new("trajectory.csv")).unwrap();
    (problem, t)
}

/// A PNG file's width and its pixels as RGB, row by row (RGB or RGBA files:
/// alpha, if any, dropped).
/// The `capp` binary.
pub fn capp() -> Command {
    Command::new(env!("CARGO_BIN_EXE_capp"))
}

/// `capp run SCENARIO -o OUT` with `extra` arguments: its output.
pub fn run(scenario: &Path, out: &Path, extra: &[&str]) -> std::process::Output {
    capp()
        .args([
            "run",
            scenario.to_str().unwrap(),
            "-o",
            out.to_str().unwrap(),
        ])
        .args(extra)
        .output()
        .unwrap()
}

/// `capp run SCENARIO -o OUT`, which must end without reaching the target.
pub fn stops_short(scenario: &Path, out: &Path) {
    let o = run(scenario, out, &[]);
    let stdout = String::from_utf8_lossy(&o.stdout);
    assert!(
        stdout.contains("outcome:") && !stdout.contains("outcome:           reached"),
        "{stdout}"
    );
}

/// `capp run SCENARIO -o OUT --render`, which must succeed and reach its
/// target: its standard output.
pub fn run_rendered(scenario: &Path, out: &Path) -> String {
    let o = run(scenario, out, &["--render"]);
    let stdout = String::from_utf8_lossy(&o.stdout).into_owned();
    assert_eq!(
        o.status.code(),
        Some(0),
        "{stdout}{}",
        String::from_utf8_lossy(&o.stderr)
    );
    assert!(stdout.contains("outcome:           reached"), "{stdout}");
    stdout
}

/// `capp check OUT`, which must exit 0 and accept the run: its report.
pub fn check_accepts(out: &Path) -> String {
    let o = capp()
        .args(["check", out.to_str().unwrap()])
        .output()
        .unwrap();
    let report = String::from_utf8_lossy(&o.stdout).into_owned();
    assert_eq!(
        o.status.code(),
        Some(0),
        "{report}{}",
        String::from_utf8_lossy(&o.stderr)
    );
    assert!(report.contains("ACCEPTED"), "{report}");
    report
}

pub fn png_rgb(path: &Path) -> (usize, Vec<[u8; 3]>) {
    let file = std::fs::File::open(path).unwrap_or_else(|e| panic!("{}: {e}", path.display()));
    let mut reader = png::Decoder::new(std::io::BufReader::new(file))
        .read_info()
        .unwrap();
    let mut buf = vec![0; reader.output_buffer_size()];
    let info = reader.next_frame(&mut buf).unwrap();
    let channels = info.color_type.samples();
    assert!(channels >= 3, "{}: not RGB", path.display());
    let pixels = buf[..info.buffer_size()]
        .chunks(channels)
        .map(|p| [p[0], p[1], p[2]])
        .collect();
    (info.width as usize, pixels)
}
