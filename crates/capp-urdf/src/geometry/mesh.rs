//! Reading a mesh file's vertices and triangles with mesh-loader.
//!
//! Formats by extension (any case): `.stl` (binary or ASCII), `.obj`,
//! `.dae` (Collada; mesh-loader applies its `<unit>` and node transforms but
//! not `<up_axis>`). All meshes of a file are merged. Vertices are f32 in the
//! file, f64 here, in the mesh's own units and frame: the caller applies
//! `<mesh scale>` and the `<collision><origin>`.

use std::path::Path;

use nalgebra::Point3;

use crate::error::{one_line, Problem};

/// A mesh's vertices and its triangles as indices into them.
#[derive(Debug, Default)]
pub(crate) struct Mesh {
    pub vertices: Vec<Point3<f64>>,
    pub faces: Vec<[usize; 3]>,
}

/// Reads `path`; `filename` (as the URDF wrote it) names it in errors.
pub(crate) fn read(path: &Path, filename: &str) -> Result<Mesh, Problem> {
    let bad = |reason: String| Problem::BadMesh {
        filename: filename.to_owned(),
        reason,
    };
    let extension = path
        .extension()
        .and_then(|e| e.to_str())
        .map(str::to_ascii_lowercase);
    let loader = mesh_loader::Loader::default().merge_meshes(true);
    let scene = match extension.as_deref() {
        Some("stl") => loader.load_stl(path),
        Some("obj") => loader.load_obj(path),
        Some("dae") => loader.load_collada(path),
        _ => return Err(Problem::UnsupportedMeshFormat(filename.to_owned())),
    }
    .map_err(|e| bad(one_line(&e.to_string())))?;
    let mut mesh = Mesh::default();
    for part in &scene.meshes {
        let offset = mesh.vertices.len();
        for v in &part.vertices {
            if !v.iter().all(|x| x.is_finite()) {
                return Err(bad("a vertex is not finite".into()));
            }
            mesh.vertices
                .push(Point3::new(v[0].into(), v[1].into(), v[2].into()));
        }
        let count = part.vertices.len();
        mesh.faces.extend(
            part.faces
                .iter()
                .map(|f| f.map(|i| i as usize))
                .filter(|f| f.iter().all(|&i| i < count))
                .map(|f| f.map(|i| i + offset)),
        );
    }
    if mesh.vertices.is_empty() {
        return Err(bad("it has no vertices".into()));
    }
    Ok(mesh)
}
