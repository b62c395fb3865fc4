//! Where a run escaped dead ends shows in its summary and its pictures: a
//! three-link planar arm whose straight path is blocked, run through the
//! command line as a user runs it (`capp run --render`, so the pictures are
//! drawn from `trajectory.csv` read back).

mod common;

use std::path::{Path, PathBuf};

use capp_sim::escapes::{self, Kind};
use capp_sim::output::summary::Summary;
use capp_sim::render::plots::band_color;
use capp_sim::render::views::{DETOUR, RETURN, WALK};
use capp_sim::{plan, Problem};

/// `capp run FILE --out DIR --render -q`; returns the output folder.
fn run(dir: &Path, name: &str, text: &str) -> PathBuf {
    let file = dir.join(format!("{name}.toml"));
    std::fs::write(&file, text).unwrap();
    let out = dir.join(name);
    let code = capp_sim::cli::main([
        "capp".as_ref(),
        "run".as_ref(),
        file.as_os_str(),
        "--out".as_ref(),
        out.as_os_str(),
        "--render".as_ref(),
        "-q".as_ref(),
    ]);
    assert_eq!(code, std::process::ExitCode::SUCCESS, "{name}");
    out
}

fn hex(c: [u8; 3]) -> String {
    format!("#{:02x}{:02x}{:02x}", c[0], c[1], c[2])
}

/// Polylines drawn in `colour` (path stretches and legend swatches).
fn strokes(svg: &str, colour: [u8; 3]) -> usize {
    svg.matches(&format!("stroke=\"{}\"", hex(colour))).count()
}

/// Polygons filled with `colour`.
fn fills(svg: &str, colour: [u8; 3]) -> usize {
    let fill = format!("fill=\"{}\"", hex(colour));
    svg.split("<polygon ")
        .skip(1)
        .filter(|p| p.split("/>").next().is_some_and(|p| p.contains(&fill)))
        .count()
}

#[test]
fn a_detour_and_a_walk_show_in_the_summary_and_every_picture() {
    let dir = tempfile::tempdir().unwrap();
    for (name, half_height, kind, colour, phrase) in [
        (
            "detour",
            5.0,
            Kind::Detour,
            DETOUR,
            "detour at step {step} round \"post\" on its {side} side",
        ),
        (
            "walk",
            20.0,
            Kind::Walk,
            WALK,
            "walk at step {step} to the {side} side of \"post\"",
        ),
    ] {
        // Walks and detours alone (a search would come first: its own test
        // is in tests/scenarios.rs).
        let text = format!(
            "{}escape_searches = 0\n",
            common::planar_trap(name, half_height)
        );
        let out = run(dir.path(), name, &text);
        let summary = std::fs::read_to_string(out.join("summary.txt")).unwrap();
        eprintln!("{summary}");
        assert!(summary.contains("outcome:           reached"), "{summary}");
        assert!(
            summary.contains("escapes:           1 attempt ("),
            "{summary}"
        );
        assert!(!summary.contains("stalled after"), "{summary}");

        // The stretches, from the CSV the pictures are drawn from; the
        // summary names the step the CSV says the escape started at, which
        // comes after at least one progress window of the normal law.
        let t = capp_sim::trajectory::read(&out.join("trajectory.csv")).unwrap();
        let stretches = t.escapes();
        assert_eq!(stretches.len(), 1, "{name}: {stretches:?}");
        assert_eq!(stretches[0].kind, kind);
        let step = stretches[0].step;
        let window = capp_core::Settings::default().escape.window as u32;
        assert!(step > window, "{name}: escape at step {step}");
        // Round the post (its only obstacle), on the side the CSV names.
        let side = stretches[0].side.expect("an escape round the post");
        assert_eq!(side.obstacle, 0, "{name}: {side:?}");
        let side = escapes::side_name(side);
        let phrase = phrase
            .replace("{step}", &step.to_string())
            .replace("{side}", &side);
        assert!(summary.contains(&phrase), "{phrase}\n{summary}");

        // arm.svg: the stretch in its colour in each of the three views, a
        // legend line, a diamond where it started (and one in the legend).
        let other = if kind == Kind::Detour { WALK } else { DETOUR };
        let arm = std::fs::read_to_string(out.join("arm.svg")).unwrap();
        assert_eq!(strokes(&arm, colour), 3 + 1, "{name}: arm.svg");
        assert_eq!(strokes(&arm, other), 0, "{name}: arm.svg");
        assert_eq!(strokes(&arm, RETURN), 0, "{name}: arm.svg");
        assert_eq!(fills(&arm, colour), 3 + 1, "{name}: arm.svg diamonds");
        assert!(arm.contains(">escape started (1)</text>"), "{name}");
        let legend = if kind == Kind::Detour {
            ">detour round an obstacle</text>"
        } else {
            ">walk from a dead end</text>"
        };
        assert!(arm.contains(legend), "{name}");

        // plots.svg: a band per panel (five: V, errors, clearance, velocity,
        // acceleration) and the legend's swatch.
        let plots = std::fs::read_to_string(out.join("plots.svg")).unwrap();
        assert_eq!(fills(&plots, band_color(&stretches[0])), 5 + 1, "{name}");
        assert!(plots.contains(" (shaded)</text>"), "{name}");

        // viewer.html: the states per frame and the stretch with its colour.
        let viewer = std::fs::read_to_string(out.join("viewer.html")).unwrap();
        let run = viewer.split("const RUN = ").nth(1).unwrap();
        let run = run.split("</script>").next().unwrap();
        let states = run.split("\"escape\": [").nth(1).unwrap();
        let states = states.split("],").next().unwrap();
        let escaping = states.split(',').filter(|s| *s != "null").count();
        assert!(escaping >= 5, "{name}: {escaping} frames escaping");
        let side = side.replace('-', "−");
        let expected = if kind == Kind::Detour {
            format!("\"detour 1 round \\\"post\\\", its {side} side\"")
        } else {
            format!("\"walk 1 to the {side} side of \\\"post\\\"\"")
        };
        assert!(states.contains(&expected), "{name}: {states}");
        assert!(
            run.contains(&format!(
                "{{\"kind\": \"{}\", \"colour\": \"{}\", \"step\": {step},",
                kind.name(),
                hex(colour)
            )),
            "{name}"
        );
    }
}

#[test]
fn a_run_that_spends_its_attempts_says_so_in_a_few_lines() {
    let path = Path::new(env!("CARGO_MANIFEST_DIR")).join("scenarios/pips_dead_end.toml");
    let problem = Problem::load(&path).unwrap();
    let scenario = problem.validate().unwrap();
    let result = plan::run(&problem, &scenario, |_| {}).unwrap();
    let attempts = problem.settings.escape.attempts as usize;
    let stretches = escapes::of_rows(&result.rows);
    // Every attempt walks or detours, some after a search.
    assert_eq!(
        stretches
            .iter()
            .filter(|s| s.kind != Kind::Return && s.kind != Kind::Search)
            .count(),
        attempts
    );
    assert_eq!(
        stretches.iter().filter(|s| s.kind == Kind::Search).count(),
        problem.settings.escape.searches as usize
    );
    assert_eq!(stretches.last().map(|s| s.kind), Some(Kind::Return));
    let text = Summary::new(&problem, &result).to_string();
    let lines: Vec<&str> = text
        .lines()
        .skip_while(|l| !l.starts_with("escapes:"))
        .take_while(|l| !l.starts_with("setpoints:"))
        .collect();
    assert!((2..=5).contains(&lines.len()), "{text}");
    assert!(
        lines[0].starts_with(&format!("escapes:           {attempts} attempts (")),
        "{text}"
    );
    assert!(lines[0].contains(", ..., "), "{text}");
    assert!(lines.iter().any(|l| l.contains("\"wall\" ")), "{text}");
    assert!(
        lines.iter().any(|l| l
            .trim_start()
            .starts_with(&format!("stalled after {attempts} escape attempts; "))),
        "{text}"
    );
}

#[test]
fn rows_from_a_board_say_nothing_about_escapes() {
    let path = Path::new(env!("CARGO_MANIFEST_DIR")).join("scenarios/planar_arm.toml");
    let problem = Problem::load(&path).unwrap();
    let scenario = problem.validate().unwrap();
    let mut result = plan::run(&problem, &scenario, |_| {}).unwrap();
    let here = Summary::new(&problem, &result).to_string();
    assert!(here.contains("escapes:           none\n"), "{here}");
    for r in &mut result.rows {
        r.escape = None;
    }
    let board = Summary::new(&problem, &result).to_string();
    assert!(!board.contains("escape"), "{board}");
}
