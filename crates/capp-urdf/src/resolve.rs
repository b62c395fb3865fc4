//! Where a `<mesh filename>` points on disk.
//!
//! - `package://NAME/rest`: `ROOT/rest` if `packages` names `NAME`'s
//!   `ROOT`, else `DIR/NAME/rest` for the first `DIR` of `package_dirs`
//!   where that file exists (as ROS and Pinocchio do);
//! - `file:///abs/path`: that absolute path (a relative `file://` path is
//!   taken relative to the URDF file's directory);
//! - anything else: a path, relative to the URDF file's directory unless
//!   absolute.

use std::path::{Path, PathBuf};

use crate::error::Problem;

/// The existing file `filename` names, or [`Problem::MeshNotFound`].
pub(crate) fn resolve(
    filename: &str,
    urdf_dir: &Path,
    packages: &[(String, PathBuf)],
    package_dirs: &[PathBuf],
) -> Result<PathBuf, Problem> {
    let not_found = |looked: String| Problem::MeshNotFound {
        filename: filename.to_owned(),
        looked,
    };
    if let Some(rest) = filename.strip_prefix("package://") {
        let (name, inside) = rest.split_once('/').unwrap_or((rest, ""));
        let named = packages.iter().filter(|(n, _)| n == name);
        let mut candidates: Vec<PathBuf> = named.map(|(_, root)| root.join(inside)).collect();
        candidates.extend(package_dirs.iter().map(|dir| dir.join(rest)));
        if candidates.is_empty() {
            return Err(not_found(format!(
                "no package \"{name}\" or package_dirs given"
            )));
        }
        return match candidates.iter().find(|path| path.is_file()) {
            Some(path) => Ok(path.clone()),
            None => Err(not_found(format!("looked at {}", list(&candidates)))),
        };
    }
    let path = filename.strip_prefix("file://").unwrap_or(filename);
    let path = urdf_dir.join(path);
    if path.is_file() {
        Ok(path)
    } else {
        Err(not_found(format!("looked at {}", path.display())))
    }
}

fn list(paths: &[PathBuf]) -> String {
    let shown: Vec<String> = paths.iter().map(|p| p.display().to_string()).collect();
    shown.join(", ")
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn package_file_and_relative_paths() {
        let dir = tempfile::tempdir().unwrap();
        let (first, second) = (dir.path().join("a"), dir.path().join("b"));
        std::fs::create_dir_all(second.join("pkg/meshes")).unwrap();
        std::fs::create_dir_all(&first).unwrap();
        let mesh = second.join("pkg/meshes/m.stl");
        std::fs::write(&mesh, b"solid x\nendsolid x\n").unwrap();
        let dirs = [first.clone(), second.clone()];

        let found = resolve("package://pkg/meshes/m.stl", &first, &[], &dirs).unwrap();
        assert_eq!(found, mesh);
        let named = [("pkg".to_string(), second.join("pkg"))];
        let found = resolve("package://pkg/meshes/m.stl", &first, &named, &[]).unwrap();
        assert_eq!(found, mesh);
        let other = [("other".to_string(), second.join("pkg"))];
        assert!(resolve("package://pkg/meshes/m.stl", &first, &other, &[]).is_err());
        let uri = format!("file://{}", mesh.display());
        assert_eq!(resolve(&uri, &first, &[], &[]).unwrap(), mesh);
        assert_eq!(
            resolve("pkg/meshes/m.stl", &second, &[], &[]).unwrap(),
            mesh
        );

        let missing = resolve("package://pkg/meshes/n.stl", &first, &[], &dirs).unwrap_err();
        let message = missing.to_string();
        assert!(
            message.contains("n.stl") && message.contains(", "),
            "{message}"
        );
        let none = resolve("package://pkg/meshes/m.stl", &first, &[], &[]).unwrap_err();
        assert!(none.to_string().contains("no package \"pkg\""), "{none}");
    }
}
