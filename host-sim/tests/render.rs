//! The rendered files exist, are valid SVG / PNG / HTML, and are not blank.

use std::path::Path;

use capp_sim::output::rows_csv;
use capp_sim::{plan, render, trajectory, Problem};

#[test]
fn rendered_files_are_valid_and_not_blank() {
    let path = Path::new(env!("CARGO_MANIFEST_DIR")).join("scenarios/pips_payload_bay.toml");
    let problem = Problem::load(&path).unwrap();
    let scenario = problem.validate().unwrap();
    let result = plan::run(&problem, &scenario, |_| {}).unwrap();
    let text = rows_csv(problem.joints.len(), &result.rows).unwrap();
    let t = trajectory::parse(&text, Path::new("trajectory.csv")).unwrap();
    let dir = tempfile::tempdir().unwrap();
    let files = render::render(&problem, &t, dir.path()).unwrap();
    assert_eq!(files.len(), 5);

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
    assert!(std::fs::read_to_string(dir.path().join("arm.svg"))
        .unwrap()
        .contains("<polygon"));

    for name in ["arm.png", "plots.png"] {
        let file = std::fs::File::open(dir.path().join(name)).unwrap();
        let mut reader = png::Decoder::new(std::io::BufReader::new(file))
            .read_info()
            .unwrap();
        let mut buf = vec![0; reader.output_buffer_size()];
        let info = reader.next_frame(&mut buf).unwrap();
        assert!(info.width >= 400 && info.height >= 300, "{name}");
        let pixels = &buf[..info.buffer_size()];
        let inked = pixels
            .chunks(3)
            .filter(|p| p.iter().any(|&c| c < 200))
            .count();
        let total = (info.width * info.height) as usize;
        assert!(
            inked * 500 > total,
            "{name}: only {inked} of {total} pixels drawn"
        );
        // More than two colours: arm, obstacles, path, page.
        let mut colours: Vec<&[u8]> = pixels.chunks(3).collect();
        colours.sort();
        colours.dedup();
        assert!(colours.len() > 4, "{name}");
    }

    let html = std::fs::read_to_string(dir.path().join("animation.html")).unwrap();
    assert!(html.starts_with("<!DOCTYPE html>"));
    assert!(html.contains("const frames = [[\""));
    assert!(html.contains("id=\"arm2\""));
}
