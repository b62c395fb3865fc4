//! Folding fixed joints: the chain's moving joints, its tool, and which links
//! ride on which rigid body.
//!
//! Walking the path from base to tip, `acc` is the current link's frame in
//! the current body's frame. A fixed joint multiplies its origin into `acc`;
//! a moving joint takes `acc * origin` as its own origin, starts a new body,
//! and resets `acc` to the identity. What is left in `acc` at the tip is the
//! tool. Links hanging off the path by fixed joints (a camera mount, a flange
//! frame past the tip) join the body they are bolted to; links behind a
//! moving joint off the path (a gripper's fingers) are left out.

use std::collections::HashSet;

use nalgebra::Isometry3;

use crate::chain::ChainJoint;
use crate::error::{Element, Problem};
use crate::joint;
use crate::pose;
use crate::scan::Scan;
use crate::tree::{Located, Tree};

/// A link of a body and its frame in the body's frame.
pub(crate) type Placed = (usize, Isometry3<f64>);

/// The chain's kinematics, and its bodies as placed links.
#[derive(Debug)]
pub(crate) struct Folded {
    pub joints: Vec<ChainJoint>,
    pub tool: Isometry3<f64>,
    /// `bodies[0]` rides on the base, `bodies[i + 1]` on `joints[i]`.
    pub bodies: Vec<Vec<Placed>>,
}

/// Folds the joints of `path` (from `tree.path`) below `base`.
pub(crate) fn fold(
    robot: &urdf_rs::Robot,
    tree: &Tree<'_>,
    base: usize,
    path: &[usize],
    scan: &Scan,
) -> Result<Folded, Located> {
    let on_path: HashSet<usize> = path.iter().copied().collect();
    let mut folded = Folded {
        joints: Vec::new(),
        tool: Isometry3::identity(),
        bodies: Vec::new(),
    };
    let mut body = Vec::new();
    attach(
        robot,
        tree,
        &on_path,
        base,
        Isometry3::identity(),
        &mut body,
    )?;
    let mut acc = Isometry3::identity();
    for &j in path {
        let urdf = &robot.joints[j];
        let at = |problem| (Element::Joint(urdf.name.clone()), problem);
        match joint::kind(urdf).map_err(at)? {
            None => acc *= pose::isometry(&urdf.origin).map_err(at)?,
            Some(kind) => {
                let has_limit = scan.with_limit.contains(&urdf.name);
                let chain_joint = joint::chain_joint(urdf, kind, &acc, has_limit).map_err(at)?;
                folded.joints.push(chain_joint);
                folded.bodies.push(std::mem::take(&mut body));
                acc = Isometry3::identity();
            }
        }
        attach(robot, tree, &on_path, tree.child(j), acc, &mut body)?;
    }
    folded.bodies.push(body);
    folded.tool = acc;
    Ok(folded)
}

/// Adds `link` at `frame`, then whatever hangs off it by fixed joints that
/// are not on the path.
fn attach(
    robot: &urdf_rs::Robot,
    tree: &Tree<'_>,
    on_path: &HashSet<usize>,
    link: usize,
    frame: Isometry3<f64>,
    body: &mut Vec<Placed>,
) -> Result<(), Located> {
    body.push((link, frame));
    for &k in tree.children(link) {
        let urdf = &robot.joints[k];
        if on_path.contains(&k) || urdf.joint_type != urdf_rs::JointType::Fixed {
            continue;
        }
        let origin = pose::isometry(&urdf.origin)
            .map_err(|problem: Problem| (Element::Joint(urdf.name.clone()), problem))?;
        attach(robot, tree, on_path, tree.child(k), frame * origin, body)?;
    }
    Ok(())
}
