//! `viewer.html` in a real browser: headless Chromium loads the page, which
//! sets its title to `ok <frames> frames` once WebGL (SwiftShader, on the CPU)
//! has drawn the first frame; then a screenshot shows the arm.
//!
//! Skipped with a message when no Chromium is installed, unless
//! `CAPP_REQUIRE_CHROMIUM` is set (`scripts/test.sh` installs Debian's
//! `chromium` and sets it): there a skip is a failure. `CAPP_CHROMIUM`
//! names the browser to use.

mod common;

use std::path::{Path, PathBuf};
use std::process::{Command, Stdio};
use std::time::{Duration, Instant};

use capp_sim::output::rows_csv;
use capp_sim::render::viewer::viewer;
use capp_sim::{plan, trajectory, Problem};

const NAMES: [&str; 4] = [
    "chromium",
    "chromium-browser",
    "google-chrome",
    "google-chrome-stable",
];

fn chromium() -> Option<PathBuf> {
    if let Some(p) = std::env::var_os("CAPP_CHROMIUM") {
        return Some(PathBuf::from(p));
    }
    let path = std::env::var_os("PATH")?;
    std::env::split_paths(&path)
        .flat_map(|dir| NAMES.iter().map(move |n| dir.join(n)))
        .find(|p| p.is_file())
}

/// The browser, or `None` after saying that `test` is skipped; with
/// `CAPP_REQUIRE_CHROMIUM` set (the test script sets it, having installed
/// Chromium) a missing browser fails the test instead.
fn chromium_or_skip(test: &str) -> Option<PathBuf> {
    let required = std::env::var_os("CAPP_REQUIRE_CHROMIUM").is_some();
    let exe = chromium();
    if exe.is_none() {
        assert!(
            !required,
            "CAPP_REQUIRE_CHROMIUM is set but no chromium is installed"
        );
        eprintln!(
            "SKIPPED {test}: no Chromium found \
             (apt-get install chromium, or set CAPP_CHROMIUM; scripts/test.sh installs it)"
        );
    }
    exe
}

/// Headless, no GPU: WebGL runs on SwiftShader. The networking flags keep
/// the browser from reaching out (there is no network to reach).
const FLAGS: [&str; 11] = [
    "--headless",
    "--no-sandbox",
    "--disable-gpu",
    "--use-angle=swiftshader",
    "--enable-unsafe-swiftshader",
    "--disable-quic",
    "--no-first-run",
    "--disable-background-networking",
    "--disable-component-update",
    "--disable-sync",
    // Let the page's scripts run before the DOM is dumped or the shot taken.
    "--virtual-time-budget=1500",
];

/// What the browser printed.
struct Output {
    stdout: String,
    stderr: String,
}

/// Runs the browser on `page` with `extra` flags; a hung browser is killed
/// after ten minutes (a guard against hanging the suite, not a speed test).
/// Its output goes to files, so a chatty browser cannot fill a pipe and stall.
fn browse(exe: &Path, page: &Path, extra: &[String]) -> Output {
    browse_url(exe, &format!("file://{}", page.display()), extra)
}

/// [`browse`] on a URL (e.g. with a `#frame=N`).
fn browse_url(exe: &Path, url: &str, extra: &[String]) -> Output {
    let scratch = tempfile::tempdir().unwrap();
    let (out, err) = (scratch.path().join("stdout"), scratch.path().join("stderr"));
    let mut child = Command::new(exe)
        .args(FLAGS)
        .arg(format!(
            "--user-data-dir={}",
            scratch.path().join("profile").display()
        ))
        .args(extra)
        .arg(url)
        .stdin(Stdio::null())
        .stdout(std::fs::File::create(&out).unwrap())
        .stderr(std::fs::File::create(&err).unwrap())
        .spawn()
        .unwrap_or_else(|e| panic!("cannot start {}: {e}", exe.display()));
    let start = Instant::now();
    while child.try_wait().unwrap().is_none() {
        if start.elapsed() > Duration::from_secs(600) {
            let _ = child.kill();
            let _ = child.wait();
            panic!("{} still running after ten minutes", exe.display());
        }
        std::thread::sleep(Duration::from_millis(100));
    }
    let read =
        |p: &Path| String::from_utf8_lossy(&std::fs::read(p).unwrap_or_default()).into_owned();
    Output {
        stdout: read(&out),
        stderr: read(&err),
    }
}

/// A shipped scenario planned and its `viewer.html` written in a temporary
/// folder: the folder, the page's path and its text.
fn planned_page(scenario: &str) -> (tempfile::TempDir, PathBuf, String) {
    let path = Path::new(env!("CARGO_MANIFEST_DIR"))
        .join("scenarios")
        .join(scenario);
    let problem = Problem::load(&path).unwrap();
    let scenario = problem.validate().unwrap();
    let result = plan::run(&problem, &scenario, |_| {}).unwrap();
    let text = rows_csv(problem.joints.len(), &result.rows).unwrap();
    let t = trajectory::parse(&text, Path::new("trajectory.csv")).unwrap();
    let dir = tempfile::tempdir().unwrap();
    let page = dir.path().join("viewer.html");
    let html = viewer(&problem, &t);
    std::fs::write(&page, &html).unwrap();
    (dir, page, html)
}

/// The page's `<title>`: its self-check (`ok N frames`, or the error).
fn page_title(dom: &str) -> &str {
    dom.split("<title>")
        .nth(1)
        .and_then(|s| s.split("</title>").next())
        .unwrap_or("(no title)")
}

#[test]
fn viewer_draws_in_a_real_browser() {
    let Some(exe) = chromium_or_skip("viewer_draws_in_a_real_browser") else {
        return;
    };

    let (dir, page, html) = planned_page("planar_arm.toml");
    let frames: usize = html
        .split("\"frames\": ")
        .nth(1)
        .and_then(|s| s.split(',').next())
        .and_then(|s| s.parse().ok())
        .unwrap();
    assert!(frames > 10);

    // The page's self-check, in its title.
    let out = browse(&exe, &page, &["--dump-dom".to_string()]);
    let title = page_title(&out.stdout);
    assert_eq!(
        title,
        format!("ok {frames} frames"),
        "the page did not report success; browser stderr:\n{}",
        out.stderr
    );

    // A screenshot: the 3-D view right of the panel is drawn, and the arm's
    // orange links are in it.
    let shot = dir.path().join("shot.png");
    let out = browse(
        &exe,
        &page,
        &[
            "--window-size=1000,700".to_string(),
            format!("--screenshot={}", shot.display()),
        ],
    );
    assert!(
        shot.is_file(),
        "no screenshot; browser stderr:\n{}",
        out.stderr
    );
    let (w, pixels) = common::png_rgb(&shot);
    let h = pixels.len() / w;
    let px = |x: usize, y: usize| pixels[y * w + x];
    let background = [0xf4, 0xf6, 0xf9];
    let (mut drawn, mut orange, mut colours) = (0, 0, std::collections::HashSet::new());
    for y in 0..h {
        for x in 360..w {
            let c = px(x, y);
            colours.insert(c);
            if c.iter().zip(background).any(|(a, b)| a.abs_diff(b) > 12) {
                drawn += 1;
            }
            let [r, g, b] = c.map(i32::from);
            if r > 120 && r > g + 40 && g > b {
                orange += 1;
            }
        }
    }
    let area = (w - 360) * h;
    assert!(drawn * 50 > area, "only {drawn} of {area} pixels drawn");
    assert!(colours.len() > 50, "{} colours", colours.len());
    assert!(orange > 200, "{orange} pixels of links");
}

/// A convex hull (the bracket of `pips_payload_bay_mesh.toml`, from an STL)
/// is drawn by the page's own code in a real browser: the page's self-check
/// passes with the hull's faces in it, and the legend names the bracket.
#[test]
fn viewer_draws_a_mesh_hull_in_a_real_browser() {
    let Some(exe) = chromium_or_skip("viewer_draws_a_mesh_hull_in_a_real_browser") else {
        return;
    };
    let (_dir, page, html) = planned_page("pips_payload_bay_mesh.toml");
    assert!(html.contains("bracket"), "the bracket is not in the page");
    let out = browse(&exe, &page, &["--dump-dom".to_string()]);
    let dom = &out.stdout;
    let title = page_title(dom);
    assert!(
        title.starts_with("ok "),
        "the page did not report success ({title}); browser stderr:\n{}",
        out.stderr
    );
    assert!(
        dom.contains("bracket"),
        "the legend does not name the bracket"
    );
}

/// The side panel says which escape the step is in: the planar arm of
/// `tests/escapes.rs` detours round a low wall it is trapped behind
/// (`common::planar_trap`), and the page opened at a frame of the detour
/// shows it.
#[test]
fn viewer_shows_the_escape_under_way() {
    let Some(exe) = chromium_or_skip("viewer_shows_the_escape_under_way") else {
        return;
    };
    let text = common::planar_trap("detour", 5.0);
    let dir = tempfile::tempdir().unwrap();
    let file = dir.path().join("detour.toml");
    std::fs::write(&file, text).unwrap();
    let problem = Problem::load(&file).unwrap();
    let scenario = problem.validate().unwrap();
    let result = plan::run(&problem, &scenario, |_| {}).unwrap();
    let csv = rows_csv(problem.joints.len(), &result.rows).unwrap();
    let t = trajectory::parse(&csv, Path::new("trajectory.csv")).unwrap();
    let html = viewer(&problem, &t);
    let page = dir.path().join("viewer.html");
    std::fs::write(&page, &html).unwrap();
    // The first frame of the detour, from the page's own data.
    let states = html.split("\"escape\": [").nth(1).unwrap();
    let states = states.split("],").next().unwrap();
    let frame = states
        .split(',')
        .position(|s| s.starts_with("\"detour 1"))
        .expect("a frame of the detour");
    let dom = |at: usize| {
        let url = format!("file://{}#frame={at}", page.display());
        browse_url(&exe, &url, &["--dump-dom".to_string()]).stdout
    };
    let during = dom(frame);
    assert!(during.contains("<title>ok "), "{during}");
    assert!(
        during.contains("escape: detour 1 round \"post\", its −x side"),
        "the panel does not show the detour:\n{during}"
    );
    let before = dom(0);
    assert!(before.contains("escape: none (the law drives)"), "{before}");
}

/// The link capsules' checkbox works in a real browser: the page opens with
/// them hidden; `#capsules` shows them through the checkbox (as a click
/// would), the page says so (`data-capsules` on its body), and the
/// screenshot gains their see-through blue.
#[test]
fn viewer_shows_and_hides_the_link_capsules() {
    let Some(exe) = chromium_or_skip("viewer_shows_and_hides_the_link_capsules") else {
        return;
    };
    let path = Path::new(env!("CARGO_MANIFEST_DIR")).join("scenarios/planar_arm.toml");
    let problem = Problem::load(&path).unwrap();
    let scenario = problem.validate().unwrap();
    let result = plan::run(&problem, &scenario, |_| {}).unwrap();
    let text = rows_csv(problem.joints.len(), &result.rows).unwrap();
    let t = trajectory::parse(&text, Path::new("trajectory.csv")).unwrap();
    let dir = tempfile::tempdir().unwrap();
    let page = dir.path().join("viewer.html");
    std::fs::write(&page, viewer(&problem, &t)).unwrap();
    let url = |hash: &str| format!("file://{}{hash}", page.display());

    let state = |hash: &str| {
        let dom = browse_url(&exe, &url(hash), &["--dump-dom".to_string()]).stdout;
        assert!(dom.contains("<title>ok "), "{dom}");
        let body = dom.split("<body").nth(1).unwrap_or("");
        let body = body.split('>').next().unwrap_or("").to_string();
        (body, dom)
    };
    let (hidden, _) = state("#frame=0");
    assert!(hidden.contains("data-capsules=\"hidden\""), "{hidden}");
    let (shown, dom) = state("#frame=0&capsules");
    assert!(shown.contains("data-capsules=\"shown\""), "{shown}");
    // The planar arm's one checked pair, links 1 and 3, is named in the panel.
    assert!(dom.contains("1 – 3: "), "{dom}");

    // The same frame with the capsules hidden and shown: the see-through
    // tubes (blue, the checked pair red) change the scene right of the panel.
    let shot = |hash: &str, name: &str| {
        let shot = dir.path().join(name);
        let out = browse_url(
            &exe,
            &url(hash),
            &[
                "--window-size=1000,700".to_string(),
                format!("--screenshot={}", shot.display()),
            ],
        );
        assert!(
            shot.is_file(),
            "no screenshot; browser stderr:\n{}",
            out.stderr
        );
        right_of_panel(&shot)
    };
    let (off, on) = (
        shot("#frame=0", "hidden.png"),
        shot("#frame=0&capsules", "shown.png"),
    );
    assert_eq!(off.len(), on.len());
    let changed = off
        .iter()
        .zip(&on)
        .filter(|(a, b)| a.iter().zip(b.iter()).any(|(x, y)| x.abs_diff(*y) > 12))
        .count();
    eprintln!("{changed} pixels change when the capsules are shown");
    assert!(changed > 2000, "{changed} pixels changed");
}

/// A screenshot's pixels right of the side panel (x >= 360), row by row:
/// the 3-D view.
fn right_of_panel(shot: &Path) -> Vec<[u8; 3]> {
    let (w, pixels) = common::png_rgb(shot);
    pixels
        .chunks(w)
        .flat_map(|row| row[360..].iter().copied())
        .collect()
}

/// A JSON list of numbers (or `null`s) named `key` in the page's `RUN`.
fn run_list(html: &str, key: &str) -> Option<Vec<Option<f64>>> {
    let rest = html.split(&format!("\n\"{key}\": ")).nth(1)?;
    if rest.starts_with("null") {
        return None;
    }
    let body = rest.strip_prefix('[')?.split(']').next()?;
    Some(
        body.split(',')
            .map(|s| match s.trim() {
                "null" => None,
                s => Some(s.parse().unwrap_or_else(|_| panic!("{key}: {s}"))),
            })
            .collect(),
    )
}

/// The opening tag of the element with `id` in a dumped DOM.
fn tag<'a>(dom: &'a str, id: &str) -> &'a str {
    let at = dom
        .find(&format!("id=\"{id}\""))
        .unwrap_or_else(|| panic!("no #{id} in the page"));
    let start = dom[..at].rfind('<').unwrap();
    let end = at + dom[at..].find('>').unwrap();
    &dom[start..=end]
}

/// An attribute's value in a tag.
fn attribute<'a>(tag: &'a str, name: &str) -> Option<&'a str> {
    let rest = tag.split(&format!(" {name}=\"")).nth(1)?;
    rest.split('"').next()
}

/// The text of the table cell after the one reading `label`.
fn cell_after<'a>(dom: &'a str, label: &str) -> &'a str {
    let rest = dom
        .split(&format!("<td>{label}</td>"))
        .nth(1)
        .unwrap_or_else(|| panic!("no row {label:?}"));
    let rest = &rest[rest.find('>').unwrap() + 1..];
    rest.split("</td>").next().unwrap()
}

/// The drive panel: per frame, each joint's velocity and acceleration as
/// fractions of their limits. The page's data (`velocity_fraction`,
/// `acceleration_fraction`) against the trajectory and the limits; then
/// the page, opened at the frame with the largest acceleration, against its
/// data: every bar's value and height, the red of a bar over its limit, the
/// largest of each named in the table; at rest the bars are empty. A
/// trajectory written before the columns gets a note, not bars.
#[test]
fn viewer_shows_each_joints_velocity_and_acceleration() {
    let Some(exe) = chromium_or_skip("viewer_shows_each_joints_velocity_and_acceleration") else {
        return;
    };
    let (problem, t) = common::tracked_planar();
    let dir = tempfile::tempdir().unwrap();
    let html = viewer(&problem, &t);
    let page = dir.path().join("viewer.html");
    std::fs::write(&page, &html).unwrap();

    // The data against the trajectory and the limits.
    let n = problem.joints.len();
    let steps = run_list(&html, "step").unwrap();
    let velocity = run_list(&html, "velocity_fraction").expect("velocity_fraction");
    let acceleration = run_list(&html, "acceleration_fraction").expect("acceleration_fraction");
    assert_eq!(velocity.len(), steps.len() * n);
    assert_eq!(acceleration.len(), steps.len() * n);
    assert!(html.contains("\n\"joint_names\": [\"shoulder\",\"elbow\",\"wrist\"],\n"));
    let limits = &problem.drive.joints;
    for (f, step) in steps.iter().enumerate() {
        let row = t
            .rows
            .iter()
            .find(|r| Some(r.step as f64) == *step)
            .unwrap();
        for j in 0..n {
            let want_v = row.velocity.as_ref().unwrap()[j] / limits[j].max_rate;
            let want_a = row.acceleration.as_ref().unwrap()[j] / limits[j].max_accel;
            for (got, want) in [
                (velocity[f * n + j], want_v),
                (acceleration[f * n + j], want_a),
            ] {
                let got = got.unwrap();
                // The page's 4 decimals (5 significant digits below 1e-3).
                assert!(
                    (got - want).abs() <= 6e-5 + 1e-4 * want.abs(),
                    "frame {f} joint {}: {got} in the page, {want} in the trajectory",
                    j + 1
                );
            }
        }
    }

    // The frame with the largest |acceleration| / limit: the page's bars
    // and table there.
    let at = |list: &[Option<f64>], f: usize, j: usize| list[f * n + j].unwrap();
    let frame = (0..steps.len())
        .max_by(|&a, &b| {
            let m = |f| {
                (0..n)
                    .map(|j| at(&acceleration, f, j).abs())
                    .fold(0.0, f64::max)
            };
            m(a).total_cmp(&m(b))
        })
        .unwrap();
    let url = format!("file://{}#frame={frame}", page.display());
    let dom = browse_url(&exe, &url, &["--dump-dom".to_string()]).stdout;
    assert!(dom.contains("<title>ok "), "{dom}");
    let names = ["shoulder", "elbow", "wrist"];
    let mut over = 0;
    for (kind, list) in [("velocity", &velocity), ("acceleration", &acceleration)] {
        for (j, name) in names.iter().enumerate() {
            let x = at(list, frame, j);
            let bar = tag(&dom, &format!("drive-{kind}-{}", j + 1));
            let shown: f64 = attribute(bar, "data-value")
                .and_then(|s| s.parse().ok())
                .unwrap_or_else(|| panic!("no value in {bar}"));
            assert!((shown - x).abs() <= 1e-12, "{bar}: the data says {x}");
            let style = attribute(bar, "style").unwrap();
            let height: f64 = style
                .trim_start_matches("height: ")
                .trim_end_matches("%;")
                .parse()
                .unwrap_or_else(|_| panic!("{style}"));
            let want = 100.0 * x.abs().min(1.25) / 1.25;
            assert!(
                (height - want).abs() < 1e-6,
                "{bar}: height {want} % for {x}"
            );
            let red = attribute(bar, "class").unwrap().contains("over");
            assert_eq!(red, x.abs() > 1.001, "{bar}");
            over += red as usize;
            assert!(attribute(bar, "title").unwrap().starts_with(name), "{bar}");
        }
        let label = match kind {
            "velocity" => "largest |velocity| / rate limit",
            _ => "largest |acceleration| / its limit",
        };
        let j = (0..n).fold(0, |b, j| {
            if at(list, frame, j).abs() > at(list, frame, b).abs() {
                j
            } else {
                b
            }
        });
        let want = format!("{:.3} ({})", at(list, frame, j).abs(), names[j]);
        assert_eq!(cell_after(&dom, label), want, "frame {frame}");
    }
    let peak = (0..n)
        .map(|j| at(&acceleration, frame, j).abs())
        .fold(0.0, f64::max);
    eprintln!("frame {frame}: largest |acceleration| / limit {peak}, {over} bars over");
    assert!(peak > 0.9, "{peak}");

    // At rest (frame 0 of a tracked run): empty bars, zeros in the table.
    let dom = browse_url(
        &exe,
        &format!("file://{}#frame=0", page.display()),
        &["--dump-dom".to_string()],
    )
    .stdout;
    for kind in ["velocity", "acceleration"] {
        for j in 1..=n {
            let bar = tag(&dom, &format!("drive-{kind}-{j}"));
            assert_eq!(attribute(bar, "style"), Some("height: 0%;"), "{bar}");
        }
    }
    assert_eq!(
        cell_after(&dom, "largest |velocity| / rate limit"),
        "0.000 (shoulder)"
    );

    // A trajectory from before the columns: no data, a note, no bars.
    let mut old = t.clone();
    for r in &mut old.rows {
        r.velocity = None;
        r.acceleration = None;
    }
    let html = viewer(&problem, &old);
    assert!(html.contains("\n\"velocity_fraction\": null,\n"));
    std::fs::write(&page, &html).unwrap();
    let dom = browse(&exe, &page, &["--dump-dom".to_string()]).stdout;
    assert!(dom.contains("<title>ok "), "{dom}");
    assert!(
        dom.contains("velocities and accelerations not recorded in this trajectory"),
        "{dom}"
    );
    assert!(!dom.contains("<div class=\"bar velocity\""));
    assert!(!dom.contains("<td>largest |velocity| / rate limit</td>"));
}

/// `capp robot --render`'s viewer: the Panda at its start, one frame, the
/// capsules shown without asking, the URDF's fitted collision capsules in
/// the legend and drawn: against the same page without them, the 3-D view
/// changes.
#[test]
fn robot_viewer_shows_the_fitted_collision_capsules() {
    use capp_sim::render::robot::{render_robot, start};
    use capp_sim::render::viewer::{viewer_with, ViewerOptions};
    use capp_sim::trajectory::Trajectory;
    let Some(exe) = chromium_or_skip("robot_viewer_shows_the_fitted_collision_capsules") else {
        return;
    };
    let path = Path::new(env!("CARGO_MANIFEST_DIR")).join("scenarios/panda_table.toml");
    let problem = Problem::load(&path).unwrap();
    let dir = tempfile::tempdir().unwrap();
    render_robot(&problem, dir.path()).unwrap();
    let page = dir.path().join("viewer.html");
    let out = browse(&exe, &page, &["--dump-dom".to_string()]);
    let dom = &out.stdout;
    assert!(dom.contains("<title>ok 1 frames</title>"), "{}", out.stderr);
    let body = dom.split("<body").nth(1).unwrap_or("");
    let body = body.split('>').next().unwrap_or("");
    assert!(body.contains("data-capsules=\"shown\""), "{body}");
    assert!(dom.contains("URDF collision capsules"), "legend");

    let plain = dir.path().join("plain.html");
    let options = ViewerOptions {
        capsules_shown: true,
        collision_capsules: false,
    };
    let still = Trajectory::still(&start(&problem));
    std::fs::write(&plain, viewer_with(&problem, &still, options)).unwrap();
    let shot = |page: &Path, name: &str| {
        let shot = dir.path().join(name);
        browse(
            &exe,
            page,
            &[
                "--window-size=1000,700".to_string(),
                format!("--screenshot={}", shot.display()),
            ],
        );
        right_of_panel(&shot)
    };
    let (with, without) = (shot(&page, "with.png"), shot(&plain, "without.png"));
    assert_eq!(with.len(), without.len());
    let changed = with
        .iter()
        .zip(&without)
        .filter(|(a, b)| a.iter().zip(b.iter()).any(|(x, y)| x.abs_diff(*y) > 12))
        .count();
    eprintln!("{changed} pixels change with the fitted capsules");
    assert!(changed > 2000, "{changed} pixels changed");
}
