//! The link tree: who is whose parent, the base and the tip, the path between.
//!
//! Links and joints are referred to by their index in `urdf_rs::Robot`'s
//! `links` and `joints`. Checked here, for the whole file: unique names, every
//! joint naming existing links, one parent per link, no loop.

use std::collections::HashMap;

use crate::error::{Element, Problem};

/// A checked tree over a parsed robot.
#[derive(Debug)]
pub(crate) struct Tree<'r> {
    robot: &'r urdf_rs::Robot,
    index: HashMap<&'r str, usize>,
    /// Per link, the joint whose child it is.
    parent: Vec<Option<usize>>,
    /// Per link, the joints whose parent it is, in file order.
    children: Vec<Vec<usize>>,
}

/// A problem and where it is.
pub(crate) type Located = (Element, Problem);

impl<'r> Tree<'r> {
    /// Builds and checks the tree.
    pub(crate) fn new(robot: &'r urdf_rs::Robot) -> Result<Self, Located> {
        if robot.links.is_empty() {
            return Err((Element::Robot, Problem::NoLinks));
        }
        let mut index = HashMap::new();
        for (i, link) in robot.links.iter().enumerate() {
            if index.insert(link.name.as_str(), i).is_some() {
                return Err((Element::Link(link.name.clone()), Problem::DuplicateName));
            }
        }
        let mut joint_names = HashMap::new();
        let mut parent = vec![None; robot.links.len()];
        let mut children = vec![Vec::new(); robot.links.len()];
        for (j, joint) in robot.joints.iter().enumerate() {
            let at = || Element::Joint(joint.name.clone());
            if joint_names.insert(joint.name.as_str(), j).is_some() {
                return Err((at(), Problem::DuplicateName));
            }
            let find = |name: &str| {
                index
                    .get(name)
                    .copied()
                    .ok_or_else(|| (at(), Problem::MissingLink(name.to_owned())))
            };
            let p = find(&joint.parent.link)?;
            let c = find(&joint.child.link)?;
            if let Some(first) = parent[c] {
                let first: &urdf_rs::Joint = &robot.joints[first];
                return Err((
                    Element::Link(joint.child.link.clone()),
                    Problem::TwoParents(first.name.clone(), joint.name.clone()),
                ));
            }
            parent[c] = Some(j);
            children[p].push(j);
        }
        let tree = Tree {
            robot,
            index,
            parent,
            children,
        };
        for link in 0..robot.links.len() {
            tree.check_no_loop(link)?;
        }
        Ok(tree)
    }

    /// Walks up from `link`; more steps than links means a loop.
    fn check_no_loop(&self, link: usize) -> Result<(), Located> {
        let mut at = link;
        for _ in 0..=self.robot.links.len() {
            match self.parent_link(at) {
                Some(up) => at = up,
                None => return Ok(()),
            }
        }
        Err((self.link_element(at), Problem::Loop))
    }

    fn parent_link(&self, link: usize) -> Option<usize> {
        self.parent[link].map(|j| self.link_of(&self.robot.joints[j].parent.link))
    }

    /// The index of a link named by a joint (checked in [`Tree::new`]).
    fn link_of(&self, name: &str) -> usize {
        self.index[name]
    }

    /// The child link of joint `j`.
    pub(crate) fn child(&self, j: usize) -> usize {
        self.link_of(&self.robot.joints[j].child.link)
    }

    /// The joints whose parent is `link`.
    pub(crate) fn children(&self, link: usize) -> &[usize] {
        &self.children[link]
    }

    /// `link`'s name as an error location.
    pub(crate) fn link_element(&self, link: usize) -> Element {
        Element::Link(self.robot.links[link].name.clone())
    }

    /// The named base link, or the tree's only root.
    pub(crate) fn base(&self, name: Option<&str>) -> Result<usize, Located> {
        if let Some(name) = name {
            return self
                .index
                .get(name)
                .copied()
                .ok_or_else(|| (Element::Link(name.to_owned()), Problem::BaseNotFound));
        }
        let roots: Vec<usize> = (0..self.robot.links.len())
            .filter(|&l| self.parent[l].is_none())
            .collect();
        match roots.as_slice() {
            [root] => Ok(*root),
            _ => Err((Element::Robot, Problem::SeveralRoots(self.names(&roots)))),
        }
    }

    /// The named tip link, or the leaf found by following the chain down
    /// from `base`: at a branch, the only child subtree with a moving joint;
    /// with none, the only child. Anything else is ambiguous.
    pub(crate) fn tip(&self, base: usize, name: Option<&str>) -> Result<usize, Located> {
        if let Some(name) = name {
            return self
                .index
                .get(name)
                .copied()
                .ok_or_else(|| (Element::Link(name.to_owned()), Problem::TipNotFound));
        }
        let mut at = base;
        loop {
            let kids = self.children(at);
            let moving: Vec<usize> = kids
                .iter()
                .copied()
                .filter(|&j| self.subtree_moves(j))
                .collect();
            at = match (moving.as_slice(), kids) {
                (_, []) => return Ok(at),
                ([j], _) | ([], [j]) => self.child(*j),
                _ => {
                    let mut leaves = Vec::new();
                    self.leaves(at, &mut leaves);
                    return Err((
                        self.link_element(at),
                        Problem::AmbiguousTip(self.names(&leaves)),
                    ));
                }
            };
        }
    }

    /// Whether joint `j` or any joint below it moves.
    fn subtree_moves(&self, j: usize) -> bool {
        is_moving(&self.robot.joints[j])
            || self
                .children(self.child(j))
                .iter()
                .any(|&k| self.subtree_moves(k))
    }

    fn leaves(&self, link: usize, out: &mut Vec<usize>) {
        match self.children(link) {
            [] => out.push(link),
            kids => kids.iter().for_each(|&j| self.leaves(self.child(j), out)),
        }
    }

    /// The joints from `base` down to `tip`, in order.
    pub(crate) fn path(&self, base: usize, tip: usize) -> Result<Vec<usize>, Located> {
        let mut path = Vec::new();
        let mut at = tip;
        while at != base {
            let Some(j) = self.parent[at] else {
                let base_name = self.robot.links[base].name.clone();
                return Err((self.link_element(tip), Problem::NotAncestor(base_name)));
            };
            path.push(j);
            at = self.link_of(&self.robot.joints[j].parent.link);
        }
        path.reverse();
        Ok(path)
    }

    fn names(&self, links: &[usize]) -> String {
        let quoted: Vec<String> = links
            .iter()
            .map(|&l| format!("`{}`", self.robot.links[l].name))
            .collect();
        quoted.join(", ")
    }
}

/// Whether a joint moves (anything but fixed; the unsupported moving kinds
/// count as moving so that they are reported when they are on the chain).
pub(crate) fn is_moving(joint: &urdf_rs::Joint) -> bool {
    joint.joint_type != urdf_rs::JointType::Fixed
}
