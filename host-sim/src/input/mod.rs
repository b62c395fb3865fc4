//! Reading a planning problem from a file: the two readers and the choice
//! between them.
//!
//! | module | reads |
//! |---|---|
//! | [`scenario_file`] | the TOML scenario format (documented in `docs/scenario.md`) |
//! | [`legacy`] | CAPP.c's `input.dat` (and writes its `joints.dat` records) |
//! | `mesh_obstacle` | a scenario's `convex` and `mesh` obstacles: hulls, mesh parts as primitives, shared hulls, convex pieces |
//! | [`urdf`] | a scenario's `[robot] urdf = "..."`: a URDF robot as general joints |
//! | [`pivots`] | where a URDF joint's pivot sits on its axis, so each link's chord runs through its body |
//! | [`link_capsule`] | the one capsule checked per URDF link: round its chord, or round a segment of its own along its body |
//!
//! [`Problem::load`] picks the reader by the file's extension ([`is_toml`])
//! and validates what it read. The types both readers produce ([`Problem`],
//! [`LoadError`], [`crate::problem::Lines`], ...) live in [`crate::problem`],
//! which knows nothing of either format.

pub mod legacy;
pub mod link_capsule;
mod mesh_obstacle;
pub mod pivots;
pub mod scenario_file;
pub mod urdf;

use std::path::Path;

use crate::problem::{LoadError, Problem};

impl Problem {
    /// Reads `path`: a `.toml` file as a scenario, anything else as `input.dat`,
    /// and validates the result ([`Problem::validate`]).
    pub fn load(path: &Path) -> Result<Problem, LoadError> {
        let text = std::fs::read_to_string(path)
            .map_err(|e| LoadError::new(path, None, format!("cannot read the file: {e}")))?;
        let problem = if is_toml(path) {
            scenario_file::parse(&text, path)?
        } else {
            legacy::parse(&text, path)?
        };
        problem.validate()?;
        Ok(problem)
    }
}

/// Whether `path` is read as a TOML scenario (by its extension).
pub fn is_toml(path: &Path) -> bool {
    path.extension()
        .is_some_and(|e| e.eq_ignore_ascii_case("toml"))
}
