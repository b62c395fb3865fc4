//! `<collision>` elements as capsules in their body's frame.
//!
//! Only `<collision>` is read, never `<visual>`. An element's shape is
//! placed by its own `<origin>` (relative to its link's frame) and by the
//! link's frame in the body (`fold.rs`). Primitives become one capsule each
//! (`primitives.rs`); a mesh is read (`mesh.rs`), scaled by `<mesh scale>`,
//! placed, and fitted with one or more capsules (`fit.rs`).

mod fit;
mod mesh;
mod primitives;

use std::path::{Path, PathBuf};

use nalgebra::{Isometry3, Point3, Vector3};

use crate::chain::Capsule;
use crate::error::Problem;
use crate::pose;
use crate::resolve::resolve;

/// How many capsules a `<mesh>` becomes.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default)]
pub enum CapsuleCount {
    /// One to four: each more capsule is taken only when it brings the
    /// total volume below 0.8 of the best so far. A straight prism stays
    /// one; a bent or tapered link is split.
    #[default]
    Auto,
    /// Always one.
    One,
    /// Two along the mesh's principal axis (fewer if a slice is empty).
    Two,
    /// Three along the principal axis.
    Three,
    /// Four along the principal axis.
    Four,
}

/// Where meshes are found and how they are fitted.
#[derive(Debug, Clone, Copy)]
pub(crate) struct MeshSettings<'a> {
    /// The URDF file's directory, for relative mesh paths.
    pub urdf_dir: &'a Path,
    /// Directories that hold ROS packages, for `package://`.
    pub packages: &'a [(String, PathBuf)],
    pub package_dirs: &'a [PathBuf],
    /// Capsules per mesh.
    pub count: CapsuleCount,
}

/// The capsules of one `<collision>` of a link placed at `link` in its body.
pub(crate) fn capsules(
    collision: &urdf_rs::Collision,
    link: &Isometry3<f64>,
    settings: &MeshSettings<'_>,
) -> Result<Vec<Capsule>, Problem> {
    pose::finite(*collision.origin.xyz, "collision origin xyz")?;
    pose::finite(*collision.origin.rpy, "collision origin rpy")?;
    let frame = link * pose::isometry(&collision.origin)?;
    use urdf_rs::Geometry as G;
    let local = match &collision.geometry {
        G::Sphere { radius } => primitives::sphere(*radius)?,
        G::Cylinder { radius, length } => {
            primitives::along_z(*radius, *length, primitives::Shape::Cylinder)?
        }
        G::Capsule { radius, length } => {
            primitives::along_z(*radius, *length, primitives::Shape::Capsule)?
        }
        G::Box { size } => primitives::cuboid(**size)?,
        G::Mesh { filename, scale } => {
            let scale = match scale {
                Some(s) => pose::vector(**s, "mesh scale")?,
                None => Vector3::repeat(1.0),
            };
            let path = resolve(
                filename,
                settings.urdf_dir,
                settings.packages,
                settings.package_dirs,
            )?;
            let mesh = mesh::read(&path, filename)?;
            let placed: Vec<Point3<f64>> = mesh
                .vertices
                .iter()
                .map(|v| frame * Point3::from(v.coords.component_mul(&scale)))
                .collect();
            return Ok(fit::fit_mesh(&placed, &mesh.faces, settings.count));
        }
    };
    Ok(vec![local.transformed(&frame)])
}
