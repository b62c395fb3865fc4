//! The rendered files exist, are valid SVG / PNG / GIF / HTML, are not
//! blank, and the PNGs carry their text.

use std::path::Path;

use capp_sim::render::{self, plots, views, Canvas, Shape};
use capp_sim::trajectory::Trajectory;
use capp_sim::{trajectory, Problem};
mod common;

fn payload_bay() -> (Problem, Trajectory) {
    common::planned(&Path::new(env!("CARGO_MANIFEST_DIR")).join("scenarios/pips_payload_bay.toml"))
}

/// Width, height and RGB pixels of a PNG file.
fn decode_png(path: &Path) -> (u32, u32, Vec<u8>) {
    decode_png_bytes(&std::fs::read(path).unwrap())
}

/// Width, height and RGB pixels of PNG bytes.
fn decode_png_bytes(bytes: &[u8]) -> (u32, u32, Vec<u8>) {
    let mut reader = png::Decoder::new(std::io::Cursor::new(bytes))
        .read_info()
        .unwrap();
    let mut buf = vec![0; reader.output_buffer_size()];
    let info = reader.next_frame(&mut buf).unwrap();
    assert_eq!(info.color_type, png::ColorType::Rgb);
    buf.truncate(info.buffer_size());
    (info.width, info.height, buf)
}

/// Pixels darker than the page in rows `y0..y1`.
fn inked_rows(width: u32, pixels: &[u8], y0: usize, y1: usize) -> usize {
    let w = width as usize * 3;
    pixels[y0 * w..y1 * w]
        .chunks(3)
        .filter(|p| p.iter().any(|&c| c < 160))
        .count()
}

#[test]
fn rendered_files_are_valid_and_not_blank() {
    let (problem, t) = payload_bay();
    let dir = tempfile::tempdir().unwrap();
    let files = render::render(&problem, &t, dir.path()).unwrap();
    let names: Vec<String> = files
        .iter()
        .map(|f| f.file_name().unwrap().to_string_lossy().into_owned())
        .collect();
    assert_eq!(names, render::FILES);

    for name in ["arm.svg", "plots.svg"] {
        let svg = std::fs::read_to_string(dir.path().join(name)).unwrap();
        assert!(
            svg.starts_with("<svg xmlns=\"http://www.w3.org/2000/svg\""),
            "{name}"
        );
        assert!(svg.trim_end().ends_with("</svg>"), "{name}");
        assert!(svg.matches("<polyline").count() >= 3, "{name}");
        assert!(!svg.contains("NaN"), "{name}");
        assert!(svg.contains("<text"), "{name} carries text");
    }
    let arm = std::fs::read_to_string(dir.path().join("arm.svg")).unwrap();
    assert!(arm.contains("<polygon"));
    for label in ["payload", "bay floor", "aft bulkhead", "x [in]", "z [in]"] {
        assert!(
            arm.contains(&format!(">{label}</text>")),
            "arm.svg: {label}"
        );
    }
    // The payload bay is reached without an escape: nothing drawn for one.
    for colour in [views::DETOUR, views::WALK, views::RETURN] {
        let stroke = format!(
            "stroke=\"#{:02x}{:02x}{:02x}\"",
            colour[0], colour[1], colour[2]
        );
        assert!(!arm.contains(&stroke), "arm.svg: {stroke}");
    }
    assert!(!arm.contains("escape started"));
    let plots = std::fs::read_to_string(dir.path().join("plots.svg")).unwrap();
    assert!(!plots.contains("(shaded)"));
    for label in ["V [in²]", "step", "orientation", "C − 1"] {
        assert!(
            plots.contains(&format!(">{label}</text>")),
            "plots.svg: {label}"
        );
    }

    for name in ["arm.png", "plots.png"] {
        let (width, height, pixels) = decode_png(&dir.path().join(name));
        assert!(width >= 400 && height >= 300, "{name}");
        let inked = pixels
            .chunks(3)
            .filter(|p| p.iter().any(|&c| c < 200))
            .count();
        let total = (width * height) as usize;
        assert!(
            inked * 500 > total,
            "{name}: only {inked} of {total} pixels drawn"
        );
        // More than two colours: arm, obstacles, path, page.
        let mut colours: Vec<&[u8]> = pixels.chunks(3).collect();
        colours.sort();
        colours.dedup();
        assert!(colours.len() > 4, "{name}");
        // The title band (above every panel) holds only text: it is inked.
        let title = inked_rows(width, &pixels, 8, 32);
        assert!(title > 300, "{name}: {title} pixels of title");
    }

    let html = std::fs::read_to_string(dir.path().join("animation.html")).unwrap();
    assert!(html.starts_with("<!DOCTYPE html>"));
    assert!(html.contains("const frames = [[\""));
    assert!(html.contains("id=\"arm2\""));

    let viewer = std::fs::read_to_string(dir.path().join("viewer.html")).unwrap();
    assert!(viewer.starts_with("<!DOCTYPE html>"));
    assert!(viewer.contains("var THREE="), "three.js inlined");
    assert!(viewer.contains("const RUN = {"));
    assert!(viewer.contains("\"name\": \"payload\""));
    // Self-contained: nothing is loaded from elsewhere.
    assert!(!viewer.contains("<script src") && !viewer.contains("<link"));
    let run = viewer.split("const RUN = ").nth(1).unwrap();
    let run = run.split("</script>").next().unwrap();
    assert!(!run.contains("NaN") && !run.contains("inf"));
    assert!(
        run.contains("\"escapes\": [],"),
        "no escapes in the payload bay"
    );

    let file = std::fs::File::open(dir.path().join("motion.gif")).unwrap();
    let mut options = gif::DecodeOptions::new();
    options.set_color_output(gif::ColorOutput::RGBA);
    let mut decoder = options.read_info(std::io::BufReader::new(file)).unwrap();
    let (w, h) = (decoder.width(), decoder.height());
    assert!(w >= 400 && h >= 300);
    let mut frames = 0;
    let mut first_inked = 0;
    while let Some(frame) = decoder.read_next_frame().unwrap() {
        if frames == 0 {
            assert_eq!((frame.width, frame.height), (w, h), "first frame is whole");
            first_inked = frame
                .buffer
                .chunks(4)
                .filter(|p| p[..3].iter().any(|&c| c < 160))
                .count();
        }
        frames += 1;
    }
    assert!(frames >= 20, "{frames} frames");
    assert!(
        first_inked * 100 > (w as usize * h as usize),
        "{first_inked}"
    );
}

/// `viewer.html` carries every link's capsule (its radius; the chord is the
/// link the page already draws between frame origins), whether the scenario
/// keeps them apart, the closest checked pair of every frame, and the
/// checkbox that shows them.
#[test]
fn viewer_has_every_links_capsule_and_the_toggle() {
    let (problem, t) = payload_bay();
    let html = render::viewer::viewer(&problem, &t);
    let run = html.split("const RUN = ").nth(1).unwrap();
    let run = run.split("</script>").next().unwrap();
    let field = |name: &str| {
        run.split(&format!("\n\"{name}\": "))
            .nth(1)
            .unwrap_or_else(|| panic!("no {name}"))
            .split(",\n")
            .next()
            .unwrap()
            .to_string()
    };
    let frames: usize = field("frames").parse().unwrap();
    let radii: Vec<f64> = field("capsules")
        .trim_matches(['[', ']'])
        .split(',')
        .map(|v| v.parse().unwrap())
        .collect();
    assert_eq!(radii.len(), problem.joints.len(), "one capsule per link");
    for (r, &want) in radii.iter().zip(&problem.links.radius) {
        assert!((r - want as f64).abs() <= 1e-4 * want as f64, "{r} {want}");
    }
    assert_eq!(field("self_collision"), "true");
    // Per frame, [a, b, gap] of the closest checked pair: PIPS's nearest
    // pairs are never adjacent (the acm skips those) and never overlap.
    let closest = field("closest_links");
    let pairs: Vec<&str> = closest
        .trim_start_matches("[[")
        .trim_end_matches("]]")
        .split("],[")
        .collect();
    assert_eq!(pairs.len(), frames, "{closest}");
    for p in pairs {
        let v: Vec<f64> = p.split(',').map(|x| x.parse().unwrap()).collect();
        let (a, b, gap) = (v[0] as usize, v[1] as usize, v[2]);
        assert!(1 <= a && a + 1 < b && b <= problem.joints.len(), "{p}");
        assert!(gap > 0.0, "{p}");
    }
    // The toggle: a checkbox, its handler, the key and the URL option.
    assert!(html.contains("<input type=\"checkbox\" id=\"capsules\">"));
    assert!(html.contains("capsuleBox.onchange"));
    assert!(html.contains("e.key === 'c'"));
    assert!(html.contains("#capsules with the capsules shown"));

    // Self-collision off: the capsules are still drawn, no pair is named.
    let mut off = problem.clone();
    off.links.enabled = false;
    let html = render::viewer::viewer(&off, &t);
    assert!(html.contains("\n\"self_collision\": false,\n"));
    let nulls = vec!["null"; frames].join(",");
    assert!(html.contains(&format!("\n\"closest_links\": [{nulls}],\n")));
}

/// The text is painted: removing it changes the title band, which is
/// otherwise empty.
#[test]
fn pngs_have_text() {
    let (problem, t) = payload_bay();
    let without_text = |c: &Canvas| Canvas {
        shapes: c
            .shapes
            .iter()
            .filter(|s| !matches!(s, Shape::Text { .. }))
            .cloned()
            .collect(),
        ..c.clone()
    };
    for (name, canvas) in [
        ("arm", views::arm_scene(&problem, &t, 360.0, 6).canvas),
        ("plots", plots::plots(&problem, &t)),
    ] {
        let with = canvas.raster();
        let without = without_text(&canvas).raster();
        let band = inked_rows(canvas.width, &with, 8, 32);
        assert!(band > 300, "{name}: {band}");
        assert_eq!(inked_rows(canvas.width, &without, 8, 32), 0, "{name}");
        let changed = with
            .chunks(3)
            .zip(without.chunks(3))
            .filter(|(a, b)| a != b)
            .count();
        assert!(changed > 3000, "{name}: text changed {changed} pixels");
        // The PNG carries those pixels, text and all, at the canvas's size.
        let (width, height, decoded) = decode_png_bytes(&canvas.png().unwrap());
        assert_eq!((width, height), (canvas.width, canvas.height), "{name}");
        assert!(decoded == with, "{name}: the PNG is not the painted page");
    }
}

/// The arm picture against the geometry, not against itself: in the front
/// view (x right, z up) the payload's grey (the obstacle colour at 35 %
/// over the white page, the only shape there) where a point inside the
/// payload projects, clear of its label at the centre and of the arm, which
/// stays below it; and the page's white above it, between the grid lines.
#[test]
fn the_arm_png_draws_the_payload_where_it_projects() {
    let (problem, t) = payload_bay();
    let scene = views::arm_scene(&problem, &t, 360.0, 6);
    let (width, height, pixels) = decode_png_bytes(&scene.canvas.png().unwrap());
    // Three 360 px panels side by side, with room for the axes and titles.
    assert!(width > 3 * 360 && height > 360, "{width} x {height}");
    assert_eq!(width as usize * height as usize * 3, pixels.len());
    let front = scene.panels[1];
    assert_eq!(front.axes, (0, 2), "the front view");
    let pixel = |q: [f64; 3]| -> [u8; 3] {
        let (x, y) = front.map(&q);
        let i = (y.round() as usize * width as usize + x.round() as usize) * 3;
        [pixels[i], pixels[i + 1], pixels[i + 2]]
    };
    let o = problem
        .obstacle_names
        .iter()
        .position(|n| n == "payload")
        .unwrap();
    let (c, a) = (
        problem.obstacles[o].centre.map(f64::from),
        match problem.obstacles[o].shape {
            capp_core::Shape::SuperEllipsoid { semi_axes, .. } => semi_axes.map(f64::from),
            other => panic!("the bay's payload is a super-ellipsoid, not {other:?}"),
        },
    );
    // (2/3)^8 + (5/9)^2 < 1: inside the payload (exponents 8, 2, 2).
    let inside = [c[0] + a[0] * 2.0 / 3.0, c[1], c[2] + a[2] * 5.0 / 9.0];
    let grey = views::OBSTACLE.map(|k| (255.0 - 0.35 * (255.0 - k as f64)).round() as u8);
    assert_eq!(pixel(inside), grey, "the payload at {inside:?}");
    // Above the payload's top (z = 50), between the grid lines (x = 40 and
    // 60, z = 60 and 80): nothing drawn.
    let above = [c[0] - a[0] * 2.0 / 3.0, c[1], c[2] + 2.0 * a[2]];
    assert_eq!(pixel(above), [255; 3], "the page at {above:?}");
}

/// The texts of a canvas.
fn texts(c: &Canvas) -> Vec<&str> {
    c.shapes
        .iter()
        .filter_map(|s| match s {
            Shape::Text { text, .. } => Some(text.as_str()),
            _ => None,
        })
        .collect()
}

/// `plots.png`'s drive panels: each joint's velocity over its rate limit
/// and acceleration over its acceleration limit, the limits `±1` dashed,
/// the largest `|fraction|` named and marked where the data puts it
/// between the `±1` lines; a note instead for a trajectory written before
/// the columns.
#[test]
fn plots_show_velocity_and_acceleration_against_their_limits() {
    let (problem, t) = common::tracked_planar();
    let canvas = plots::plots(&problem, &t);
    let all = texts(&canvas);
    for label in [
        "velocity / rate limit [1]",
        "acceleration / acceleration limit [1]",
        "its rate limit, ±1",
        "its acceleration limit, ±1",
        "joint 3 (wrist)",
        "step (tracked: t = step × 0.05 s)",
    ] {
        assert!(all.contains(&label), "no {label:?} in {all:?}");
    }
    // The largest fractions, from the rows and the limits.
    let peak = |value: fn(&trajectory::TrajectoryRow) -> &Vec<f64>,
                limit: &dyn Fn(usize) -> f64| {
        // The first row, then the first joint, at the largest.
        let mut best = (0.0f64, 0u64, 0usize);
        for r in &t.rows {
            for (j, v) in value(r).iter().enumerate() {
                if (v / limit(j)).abs() > best.0.abs() {
                    best = (v / limit(j), r.step, j);
                }
            }
        }
        best
    };
    let drive = &problem.drive.joints;
    let v = peak(|r| r.velocity.as_ref().unwrap(), &|j| drive[j].max_rate);
    let a = peak(|r| r.acceleration.as_ref().unwrap(), &|j| {
        drive[j].max_accel
    });
    assert!(v.0.abs() > 0.5 && a.0.abs() > 0.9, "{v:?} {a:?}");
    let largest: Vec<&str> = all
        .iter()
        .copied()
        .filter(|s| s.starts_with("largest: "))
        .collect();
    assert_eq!(largest.len(), 2, "{largest:?}");
    for (text, (value, step, joint)) in largest.iter().zip([v, a]) {
        let want = format!(
            "largest: {value:.3} at step {step}, joint {} ({})",
            joint + 1,
            problem.joint_names[joint]
        );
        assert_eq!(*text, want);
    }
    // Each panel: its two dashed limit lines (at +1 above -1) and the
    // peak's dot, where the fraction puts it between them.
    let limit_lines: Vec<f64> = canvas
        .shapes
        .iter()
        .filter_map(|s| match s {
            Shape::Line {
                points,
                color,
                dashed: true,
                ..
            // Across the panel (not the legend's 18 px sample).
            } if *color == plots::LIMIT && points[1].0 - points[0].0 > 100.0 => Some(points[0].1),
            _ => None,
        })
        .collect();
    assert_eq!(limit_lines.len(), 4, "{limit_lines:?}");
    let dots: Vec<f64> = canvas
        .shapes
        .iter()
        .filter_map(|s| match s {
            // The marks (the legend's samples are 4 px).
            Shape::Disc { centre, radius, .. } if *radius < 4.0 => Some(centre.1),
            _ => None,
        })
        .collect();
    assert_eq!(dots.len(), 2);
    for (panel, value) in [v.0, a.0].into_iter().enumerate() {
        let (minus, plus) = (limit_lines[2 * panel], limit_lines[2 * panel + 1]);
        assert!(plus < minus, "+1 above -1");
        let y = plus + (1.0 - value) / 2.0 * (minus - plus);
        assert!(
            (dots[panel] - y).abs() < 0.01,
            "dot at {}, {value} is at {y}",
            dots[panel]
        );
    }

    // A trajectory from before the columns: the panels say so.
    let mut old = t.clone();
    for r in &mut old.rows {
        r.velocity = None;
        r.acceleration = None;
    }
    let canvas = plots::plots(&problem, &old);
    let all = texts(&canvas);
    let note = "not recorded: the trajectory has no such columns (written before them)";
    assert_eq!(all.iter().filter(|s| **s == note).count(), 2);
    assert!(!all.iter().any(|s| s.starts_with("largest: ")));
}
