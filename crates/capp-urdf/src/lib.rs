//! # capp-urdf: a serial chain and its collision capsules from a URDF file
//!
//! [`load`] reads a URDF file and returns the [`Chain`] between a base link
//! and a tip link: its moving joints in order ([`ChainJoint`]: kind, origin,
//! axis, limits, velocity), the tool (tip frame after the last moving joint),
//! and one [`Body`] per rigid part with its `<collision>` geometry as
//! [`Capsule`]s. [`Chain::forward`] gives every joint's frame and the tip's
//! at a joint vector. Host only (std, f64); capp-core is not involved.
//!
//! ## What is read
//!
//! - `<robot name>`; `<link name>` and its `<collision>` elements (origin and
//!   geometry: box, cylinder, sphere, capsule, mesh with scale); never
//!   `<visual>` or `<inertial>`.
//! - `<joint name type>` with `<origin xyz rpy>`, `<parent>`, `<child>`,
//!   `<axis xyz>` (default 1 0 0), `<limit lower upper velocity>`, `<mimic>`
//!   (refused on the chain). Joints inside `<transmission>` are ignored.
//! - Mesh files: STL (binary and ASCII), OBJ, Collada; `package://NAME/...`
//!   looked up in [`LoadOptions::packages`] and
//!   [`LoadOptions::package_dirs`], `file://` and paths relative
//!   to the URDF file's directory.
//!
//! ## Frames and units
//!
//! Metres and radians, as URDF. The world frame is the base link's frame.
//! A joint's frame is its child link's frame; `<origin rpy>` means
//! R = Rz(yaw) Ry(pitch) Rx(roll). Fixed joints are folded: into the next
//! moving joint's [`ChainJoint::origin`], or into [`Chain::tool`] after the
//! last one. `bodies[0]` is in the base frame, `bodies[i + 1]` in
//! `joints[i]`'s frame; [`Chain::forward`] gives the equations.
//!
//! ## What is refused
//!
//! Each as a one-line [`UrdfError`] naming the file and the joint or link:
//! unreadable or malformed XML; a joint type URDF does not define; planar,
//! floating and spherical joints and `<mimic>` on the chain; duplicate names;
//! a joint naming a missing link; a link with two parents; a loop; several
//! roots without `base_link`; a missing base or tip link; a base that is not
//! an ancestor of the tip; a branching tree without `tip_link`; a chain
//! without moving joints; a revolute or prismatic joint without `<limit>`;
//! a zero axis; NaN or infinite numbers (origins, axes, sizes, scales,
//! velocities; an infinite lower or upper limit in its own direction is
//! URDF 1.2's "unlimited" and kept); lower > upper; a negative velocity or
//! size; a mesh that is not found, not .stl/.obj/.dae, unreadable, empty.
//!
//! Only what the chain uses is checked beyond the tree's shape: a floating
//! joint or a bad origin on a branch off the chain does not stop the load.
#![forbid(unsafe_code)]
#![warn(missing_docs)]

mod chain;
mod error;
mod fold;
mod geometry;
mod joint;
mod pose;
mod resolve;
mod scan;
mod tree;

use std::path::{Path, PathBuf};

pub use chain::{Body, Capsule, Chain, ChainJoint, JointKind};
pub use error::{Element, Problem, UrdfError};
pub use geometry::CapsuleCount;

/// What [`load`] takes besides the file.
#[derive(Debug, Clone, Default)]
pub struct LoadOptions {
    /// The chain's base link; `None`: the tree's root (an error if there are
    /// several).
    pub base_link: Option<String>,
    /// The chain's tip link; `None`: follow the tree down from the base,
    /// at each branch into the only child subtree that has a moving joint
    /// (or the only child); an error naming the leaves when that is
    /// ambiguous (e.g. a gripper with two fingers).
    pub tip_link: Option<String>,
    /// Where named ROS packages are (`NAME`, its root directory):
    /// `package://NAME/rest` is `ROOT/rest`. Looked at before
    /// [`LoadOptions::package_dirs`]; what `ros2 pkg prefix` would answer.
    pub packages: Vec<(String, PathBuf)>,
    /// Directories holding ROS packages: `package://NAME/rest` is
    /// `DIR/NAME/rest` for the first `DIR` where that file exists.
    pub package_dirs: Vec<PathBuf>,
    /// How many capsules each `<mesh>` becomes.
    pub capsules_per_mesh: CapsuleCount,
}

/// Reads the URDF file at `path` and returns the chain `options` select.
///
/// Errors are [`UrdfError::File`], naming `path` and the element at fault.
pub fn load(path: &Path, options: &LoadOptions) -> Result<Chain, UrdfError> {
    let at = |(element, problem)| UrdfError::File {
        file: path.to_path_buf(),
        element,
        problem,
    };
    let text = std::fs::read_to_string(path).map_err(|e| {
        at((
            Element::Robot,
            Problem::Read(error::one_line(&e.to_string())),
        ))
    })?;
    let scan = scan::scan(&text).map_err(at)?;
    let robot = urdf_rs::read_from_string(&text).map_err(|e| {
        at((
            Element::Robot,
            Problem::Parse(error::one_line(&e.to_string())),
        ))
    })?;
    let tree = tree::Tree::new(&robot).map_err(at)?;
    let base = tree.base(options.base_link.as_deref()).map_err(at)?;
    let tip = tree.tip(base, options.tip_link.as_deref()).map_err(at)?;
    let path_joints = tree.path(base, tip).map_err(at)?;
    let folded = fold::fold(&robot, &tree, base, &path_joints, &scan).map_err(at)?;
    if folded.joints.is_empty() {
        let base_name = robot.links[base].name.clone();
        return Err(at((
            tree.link_element(tip),
            Problem::NoMovingJoint(base_name),
        )));
    }
    let settings = geometry::MeshSettings {
        urdf_dir: path.parent().unwrap_or(Path::new(".")),
        packages: &options.packages,
        package_dirs: &options.package_dirs,
        count: options.capsules_per_mesh,
    };
    let mut bodies = Vec::with_capacity(folded.bodies.len());
    for placed in &folded.bodies {
        let mut body = Body::default();
        for (link, frame) in placed {
            let urdf = &robot.links[*link];
            for collision in &urdf.collision {
                let capsules = geometry::capsules(collision, frame, &settings)
                    .map_err(|problem| at((Element::Link(urdf.name.clone()), problem)))?;
                body.capsules.extend(capsules);
            }
            body.links.push(urdf.name.clone());
        }
        bodies.push(body);
    }
    Ok(Chain {
        robot_name: robot.name.clone(),
        base_link: robot.links[base].name.clone(),
        tip_link: robot.links[tip].name.clone(),
        joints: folded.joints,
        tool: folded.tool,
        bodies,
    })
}
