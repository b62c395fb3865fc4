//! Helpers shared by the integration tests: URDF text into temp files.

#![allow(dead_code)]

use std::path::{Path, PathBuf};

use capp_urdf::{load, Chain, LoadOptions, UrdfError};
use nalgebra::Isometry3;

/// Writes `text` to `dir/name` and returns the path.
pub fn write(dir: &Path, name: &str, text: impl AsRef<[u8]>) -> PathBuf {
    let path = dir.join(name);
    if let Some(parent) = path.parent() {
        std::fs::create_dir_all(parent).unwrap();
    }
    std::fs::write(&path, text).unwrap();
    path
}

/// `<robot name="test">` around `body`.
pub fn robot(body: &str) -> String {
    format!("<?xml version=\"1.0\"?>\n<robot name=\"test\">\n{body}\n</robot>\n")
}

/// A `<link>` without geometry.
pub fn link(name: &str) -> String {
    format!("<link name=\"{name}\"/>")
}

/// A `<joint>`: `extra` holds origin, axis, limit, ... as XML.
pub fn joint(name: &str, kind: &str, parent: &str, child: &str, extra: &str) -> String {
    format!(
        "<joint name=\"{name}\" type=\"{kind}\"><parent link=\"{parent}\"/><child link=\"{child}\"/>{extra}</joint>"
    )
}

/// `<origin>` with full precision.
pub fn origin(xyz: [f64; 3], rpy: [f64; 3]) -> String {
    format!(
        "<origin xyz=\"{:?} {:?} {:?}\" rpy=\"{:?} {:?} {:?}\"/>",
        xyz[0], xyz[1], xyz[2], rpy[0], rpy[1], rpy[2]
    )
}

/// A `<limit>` of -2..2 at 1.5 per second.
pub const LIMIT: &str = "<limit lower=\"-2\" upper=\"2\" effort=\"10\" velocity=\"1.5\"/>";

/// Writes `urdf` as `name` in a fresh temp dir and loads it.
pub fn load_text(
    urdf: &str,
    name: &str,
    options: &LoadOptions,
) -> (tempfile::TempDir, Result<Chain, UrdfError>) {
    let dir = tempfile::tempdir().unwrap();
    let path = write(dir.path(), name, urdf);
    let chain = load(&path, options);
    (dir, chain)
}

/// The largest difference between two poses' homogeneous matrices.
pub fn pose_gap(a: &Isometry3<f64>, b: &Isometry3<f64>) -> f64 {
    (a.to_homogeneous() - b.to_homogeneous()).abs().max()
}
