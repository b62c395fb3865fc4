//! The planner variants the report puts side by side.
//!
//! A variant is a few `[settings]` lines of the scenario format, inserted into
//! each case's file before the loader reads it. So a variant is applied by
//! the same code as any user's file (no second path into `Settings`), and any
//! case can be re-planned with a variant by `capp run` on the file the suite
//! writes. To compare a new law or setting, add one entry to [`variants`]
//! (a new `LawKind` needs its `law = "..."` name in the scenario format,
//! which `capp run` needs anyway).

/// One planner configuration.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct Variant {
    /// Short name (`--variant`, report rows).
    pub name: &'static str,
    /// What it is, one line.
    pub description: &'static str,
    /// `[settings]` lines (`key = value`, TOML), empty for the defaults.
    pub settings: &'static str,
}

/// Every variant, the default first.
pub fn variants() -> Vec<Variant> {
    vec![
        Variant {
            name: "damped",
            description: "the defaults: damped least squares (`LawKind::DampedLeastSquares`) with saturation in the null space, projection engaged near contact (C - 1 < 1)",
            settings: "",
        },
        Variant {
            name: "tracked",
            description: "the defaults under the tracker (`motion = \"tracked\"`, issue 22): a fixed control period, each joint within its rate, acceleration and jerk limits, every tick's stop cleared, arrival at rest",
            settings: "motion = \"tracked\"",
        },
        Variant {
            name: "uniform",
            description: "the default law with each rate-limited step scaled uniformly into the rate limits, only its most loaded joint at its limit (`saturation = false`)",
            settings: "saturation = false",
        },
        Variant {
            name: "gradient",
            description: "the first-order gradient law (`LawKind::Gradient`, the default before issue 12), otherwise the defaults",
            settings: "law = \"gradient\"",
        },
        Variant {
            name: "paper",
            description: "eq. 15 as printed (`LawKind::Paper`), otherwise the defaults",
            settings: "law = \"paper\"",
        },
        Variant {
            name: "always-on",
            description: "the default law with the paper's always-on projection (`engage_clearance = 0`)",
            settings: "engage_clearance = 0.0",
        },
    ]
}

/// `text` (a scenario file) with `settings` lines added to its `[settings]`
/// table (created at the end when the file has none).
pub fn with_settings(text: &str, settings: &str) -> String {
    if settings.trim().is_empty() {
        return text.to_string();
    }
    let lines: Vec<&str> = text.lines().collect();
    match lines.iter().position(|l| l.trim() == "[settings]") {
        Some(i) => {
            let mut out: Vec<&str> = lines[..=i].to_vec();
            out.extend(settings.lines());
            out.extend(&lines[i + 1..]);
            out.join("\n") + "\n"
        }
        None => format!("{}\n\n[settings]\n{}\n", text.trim_end(), settings.trim()),
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn settings_go_into_the_settings_table() {
        let t = "name = \"x\"\n\n[settings]\nmax_steps = 5\n\n[output]\nsetpoints = 1\n";
        let out = with_settings(t, "law = \"paper\"");
        assert_eq!(
            out,
            "name = \"x\"\n\n[settings]\nlaw = \"paper\"\nmax_steps = 5\n\n[output]\nsetpoints = 1\n"
        );
        let out = with_settings("name = \"x\"\n", "law = \"paper\"");
        assert_eq!(out, "name = \"x\"\n\n[settings]\nlaw = \"paper\"\n");
        assert_eq!(with_settings(t, ""), t);
    }
}
