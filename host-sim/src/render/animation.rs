//! `animation.html`: the three orthographic views (with their ticks and
//! names) as SVG, the arm moving over them; play, pause, scrub. No WebGL
//! needed: the fallback when `viewer.html` cannot run.

use std::fmt::Write as _;

use super::canvas::escape;
use super::views::ArmScene;
use crate::problem::Problem;

/// The page.
pub fn animation(problem: &Problem, scene: &ArmScene) -> String {
    let n = scene.origins.len();
    let frames = n.min(300);
    let mut data = String::from("[");
    for f in 0..frames {
        let k = if frames > 1 {
            f * (n - 1) / (frames - 1)
        } else {
            0
        };
        data.push('[');
        for p in &scene.panels {
            let pts: Vec<String> = scene.origins[k]
                .iter()
                .map(|q| {
                    let (x, y) = p.map(q);
                    format!("{x:.1},{y:.1}")
                })
                .collect();
            let _ = write!(data, "\"{}\",", pts.join(" "));
        }
        data.push_str("],");
    }
    data.push(']');
    let mut arms = String::new();
    for i in 0..3 {
        let _ = writeln!(
            arms,
            "<polyline id=\"arm{i}\" fill=\"none\" stroke=\"#d03020\" stroke-width=\"3\" stroke-linejoin=\"round\"/>"
        );
    }
    let svg = scene.canvas.svg_with(&arms);
    format!(
        r#"<!DOCTYPE html>
<html><head><meta charset="utf-8"><title>{name}: CAPP motion</title></head>
<body style="font-family:sans-serif">
<h3>{name}</h3>
<div>{svg}</div>
<button id="play">pause</button>
<input id="seek" type="range" min="0" max="{last}" value="0" style="width:600px">
<span id="label"></span>
<script>
const frames = {data};
const rows = {n};
let i = 0, playing = true;
const seek = document.getElementById('seek');
function show(k) {{
  for (let p = 0; p < 3; p++) document.getElementById('arm' + p).setAttribute('points', frames[k][p]);
  seek.value = k;
  document.getElementById('label').textContent = 'frame ' + (k + 1) + ' / ' + frames.length + ' (of ' + rows + ' rows)';
}}
document.getElementById('play').onclick = function () {{ playing = !playing; this.textContent = playing ? 'pause' : 'play'; }};
seek.oninput = function () {{ i = +this.value; show(i); }};
setInterval(function () {{ if (playing) {{ i = (i + 1) % frames.length; show(i); }} }}, 40);
show(0);
</script>
</body></html>
"#,
        name = escape(&problem.name),
        last = frames.saturating_sub(1),
    )
}
