//! The Cortex-M4F counts: how QEMU is run, and the counter's output parsed.

use std::collections::BTreeMap;
use std::path::Path;

use anyhow::{bail, Result};

/// `qemu-system-arm` arguments that boot `elf` on the mps2-an386 with one
/// instruction per nanosecond of virtual time (`sleep=off`: do not wait for
/// the host's clock; the counts do not depend on it), semihosting on stdout.
pub fn qemu_args(elf: &Path) -> Vec<String> {
    [
        "-machine",
        "mps2-an386",
        "-icount",
        "shift=0,sleep=off",
        "-nographic",
        "-monitor",
        "none",
        "-semihosting-config",
        "enable=on,target=native",
        "-kernel",
    ]
    .iter()
    .map(|s| s.to_string())
    .chain([elf.display().to_string()])
    .collect()
}

/// Key of one figure: scene (`pips`, `chain`, `memory`, `clock`,
/// `calibration`), joints, obstacles, what.
pub type Key = (String, usize, usize, String);

/// Every `M4F <scene> <joints> <obstacles> <what> <value>` line.
#[derive(Debug, Default)]
pub struct Counts {
    values: BTreeMap<Key, f64>,
}

impl Counts {
    /// Parses the counter's output; fails on an `error` line or a missing `done`.
    pub fn parse(text: &str) -> Result<Self> {
        let mut values = BTreeMap::new();
        for line in text.lines() {
            let fields: Vec<&str> = line.split_whitespace().collect();
            if fields.first() != Some(&"M4F") {
                continue;
            }
            if fields.get(4) == Some(&"error") {
                bail!("the M4F counter reported: {line}");
            }
            if let [_, scene, joints, obstacles, what, value] = fields[..] {
                values.insert(
                    (
                        scene.to_string(),
                        joints.parse()?,
                        obstacles.parse()?,
                        what.to_string(),
                    ),
                    value.parse()?,
                );
            }
        }
        if !text.contains("step_count: done") {
            bail!("the M4F counter did not finish:\n{text}");
        }
        Ok(Counts { values })
    }

    /// One figure, if it was printed.
    pub fn get(&self, scene: &str, joints: usize, obstacles: usize, what: &str) -> Option<f64> {
        self.values
            .get(&(scene.into(), joints, obstacles, what.into()))
            .copied()
    }
}
