//! What urdf-rs does not tell: the joint types as written, and which joints
//! wrote a `<limit>`.
//!
//! urdf-rs refuses an unknown joint `type` with a serde message that names no
//! joint, and fills a missing `<limit>` with zeros (URDF 1.0), which would
//! read as a joint locked at 0. This pass reads the `<joint>` children of
//! `<robot>` (not the `<joint>` inside `<transmission>`) with roxmltree.

use std::collections::HashSet;

use crate::error::{one_line, Element, Problem};

/// Joint types URDF defines; urdf-rs parses all of them.
const KNOWN_TYPES: [&str; 7] = [
    "revolute",
    "continuous",
    "prismatic",
    "fixed",
    "floating",
    "planar",
    "spherical",
];

/// Facts about the file's joints that urdf-rs loses.
#[derive(Debug, Default)]
pub(crate) struct Scan {
    /// Names of the joints that have a `<limit>` child.
    pub with_limit: HashSet<String>,
}

/// Reads the joint elements of `text`.
pub(crate) fn scan(text: &str) -> Result<Scan, (Element, Problem)> {
    let document = roxmltree::Document::parse(text)
        .map_err(|e| (Element::Robot, Problem::Parse(one_line(&e.to_string()))))?;
    let mut scan = Scan::default();
    let joints = document
        .root_element()
        .children()
        .filter(|node| node.has_tag_name("joint"));
    for joint in joints {
        let name = joint.attribute("name").unwrap_or_default();
        let kind = joint.attribute("type").unwrap_or_default();
        if !KNOWN_TYPES.contains(&kind) {
            return Err((
                Element::Joint(name.to_owned()),
                Problem::UnsupportedJointType(kind.to_owned()),
            ));
        }
        if joint.children().any(|child| child.has_tag_name("limit")) {
            scan.with_limit.insert(name.to_owned());
        }
    }
    Ok(scan)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn unknown_type_names_the_joint() {
        let text = r#"<robot name="r"><link name="a"/><link name="b"/>
            <joint name="j" type="hinge"><parent link="a"/><child link="b"/></joint></robot>"#;
        let (element, problem) = scan(text).unwrap_err();
        assert_eq!(element, Element::Joint("j".into()));
        assert_eq!(problem, Problem::UnsupportedJointType("hinge".into()));
    }

    #[test]
    fn limits_are_seen_only_on_robot_joints() {
        let text = r#"<robot name="r">
            <joint name="j" type="revolute"><limit lower="0" upper="1" velocity="1" effort="1"/></joint>
            <joint name="k" type="fixed"/>
            <transmission name="t"><joint name="k"><limit/></joint></transmission></robot>"#;
        let scan = scan(text).unwrap();
        assert!(scan.with_limit.contains("j"));
        assert!(!scan.with_limit.contains("k"));
    }
}
