//! Each malformed URDF is refused with a one-line message that names the
//! file and the element (joint or link) at fault.

mod common;

use capp_urdf::{load, Element, LoadOptions, Problem, UrdfError};
use common::{joint, link, origin, robot, write, LIMIT};

struct Case {
    label: &'static str,
    urdf: String,
    options: LoadOptions,
    /// Extra files beside the URDF.
    files: Vec<(&'static str, &'static [u8])>,
    /// The element the message must name.
    element: Element,
    problem: fn(&Problem) -> bool,
}

fn case(
    label: &'static str,
    urdf: String,
    element: Element,
    problem: fn(&Problem) -> bool,
) -> Case {
    Case {
        label,
        urdf,
        options: LoadOptions::default(),
        files: Vec::new(),
        element,
        problem,
    }
}

fn j(name: &str) -> Element {
    Element::Joint(name.into())
}

fn l(name: &str) -> Element {
    Element::Link(name.into())
}

/// Two links a, b joined by joint `j` of `kind` with `extra`.
fn pair(kind: &str, extra: &str) -> String {
    robot(&[link("a"), link("b"), joint("j", kind, "a", "b", extra)].join("\n"))
}

/// a -j-> b, with a collision `geometry` (XML) on b.
fn with_geometry(geometry: &str) -> String {
    let b =
        format!("<link name=\"b\"><collision><geometry>{geometry}</geometry></collision></link>");
    robot(&[link("a"), b, joint("j", "revolute", "a", "b", LIMIT)].join("\n"))
}

fn options(base: Option<&str>, tip: Option<&str>) -> LoadOptions {
    LoadOptions {
        base_link: base.map(Into::into),
        tip_link: tip.map(Into::into),
        ..LoadOptions::default()
    }
}

fn cases() -> Vec<Case> {
    let chain3 = robot(
        &[
            link("a"),
            link("b"),
            link("c"),
            joint("j1", "revolute", "a", "b", LIMIT),
            joint("j2", "revolute", "b", "c", LIMIT),
        ]
        .join("\n"),
    );
    vec![
        case(
            "unknown_type",
            pair("hinge", LIMIT),
            j("j"),
            |p| matches!(p, Problem::UnsupportedJointType(t) if t == "hinge"),
        ),
        case(
            "planar",
            pair("planar", LIMIT),
            j("j"),
            |p| matches!(p, Problem::UnsupportedJointType(t) if t == "planar"),
        ),
        case(
            "floating",
            pair("floating", ""),
            j("j"),
            |p| matches!(p, Problem::UnsupportedJointType(t) if t == "floating"),
        ),
        case(
            "mimic",
            robot(
                &[
                    link("a"),
                    link("b"),
                    link("c"),
                    joint("lead", "revolute", "a", "b", LIMIT),
                    joint(
                        "follow",
                        "revolute",
                        "b",
                        "c",
                        &format!("{LIMIT}<mimic joint=\"lead\" multiplier=\"2\"/>"),
                    ),
                ]
                .join("\n"),
            ),
            j("follow"),
            |p| matches!(p, Problem::Mimic(lead) if lead == "lead"),
        ),
        case(
            "missing_link",
            robot(&[link("a"), joint("j", "revolute", "a", "ghost", LIMIT)].join("\n")),
            j("j"),
            |p| matches!(p, Problem::MissingLink(name) if name == "ghost"),
        ),
        case(
            "two_parents",
            robot(
                &[
                    link("a"),
                    link("b"),
                    link("c"),
                    joint("j1", "revolute", "a", "c", LIMIT),
                    joint("j2", "revolute", "b", "c", LIMIT),
                ]
                .join("\n"),
            ),
            l("c"),
            |p| matches!(p, Problem::TwoParents(x, y) if x == "j1" && y == "j2"),
        ),
        case(
            "loop",
            robot(
                &[
                    link("a"),
                    link("b"),
                    joint("there", "revolute", "a", "b", LIMIT),
                    joint("back", "revolute", "b", "a", LIMIT),
                ]
                .join("\n"),
            ),
            l("b"),
            |p| matches!(p, Problem::Loop),
        ),
        case(
            "duplicate_link",
            robot(
                &[
                    link("a"),
                    link("b"),
                    link("a"),
                    joint("j", "revolute", "a", "b", LIMIT),
                ]
                .join("\n"),
            ),
            l("a"),
            |p| matches!(p, Problem::DuplicateName),
        ),
        case(
            "several_roots",
            robot(
                &[
                    link("a"),
                    link("b"),
                    link("island"),
                    joint("j", "revolute", "a", "b", LIMIT),
                ]
                .join("\n"),
            ),
            Element::Robot,
            |p| matches!(p, Problem::SeveralRoots(list) if list.contains("`a`") && list.contains("`island`")),
        ),
        Case {
            options: options(Some("nowhere"), None),
            ..case("missing_base", chain3.clone(), l("nowhere"), |p| {
                matches!(p, Problem::BaseNotFound)
            })
        },
        Case {
            options: options(None, Some("nowhere")),
            ..case("missing_tip", chain3.clone(), l("nowhere"), |p| {
                matches!(p, Problem::TipNotFound)
            })
        },
        Case {
            options: options(Some("c"), Some("a")),
            ..case(
                "not_ancestor",
                chain3.clone(),
                l("a"),
                |p| matches!(p, Problem::NotAncestor(base) if base == "c"),
            )
        },
        case(
            "branches",
            robot(
                &[
                    link("a"),
                    link("b"),
                    link("left"),
                    link("right"),
                    joint("j", "revolute", "a", "b", LIMIT),
                    joint("jl", "prismatic", "b", "left", LIMIT),
                    joint("jr", "prismatic", "b", "right", LIMIT),
                ]
                .join("\n"),
            ),
            l("b"),
            |p| matches!(p, Problem::AmbiguousTip(leaves) if leaves.contains("`left`") && leaves.contains("`right`")),
        ),
        case(
            "no_moving_joint",
            pair("fixed", ""),
            l("b"),
            |p| matches!(p, Problem::NoMovingJoint(base) if base == "a"),
        ),
        case(
            "missing_limit",
            pair("revolute", "<axis xyz=\"0 0 1\"/>"),
            j("j"),
            |p| matches!(p, Problem::MissingLimit("revolute")),
        ),
        case(
            "zero_axis",
            pair("revolute", &format!("<axis xyz=\"0 0 0\"/>{LIMIT}")),
            j("j"),
            |p| matches!(p, Problem::ZeroAxis(_)),
        ),
        case(
            "infinite_axis",
            pair("prismatic", &format!("<axis xyz=\"inf 0 0\"/>{LIMIT}")),
            j("j"),
            |p| matches!(p, Problem::NonFinite("axis xyz")),
        ),
        case(
            "nan_origin",
            pair("revolute", &format!("<origin xyz=\"0 nan 0\"/>{LIMIT}")),
            j("j"),
            |p| matches!(p, Problem::NonFinite("origin xyz")),
        ),
        case(
            "nan_fixed_origin",
            robot(
                &[
                    link("a"),
                    link("b"),
                    link("c"),
                    joint(
                        "bolt",
                        "fixed",
                        "a",
                        "b",
                        &origin([0.0; 3], [f64::NAN, 0.0, 0.0]),
                    ),
                    joint("j", "revolute", "b", "c", LIMIT),
                ]
                .join("\n"),
            ),
            j("bolt"),
            |p| matches!(p, Problem::NonFinite("origin rpy")),
        ),
        case(
            "reversed_limits",
            pair(
                "revolute",
                "<limit lower=\"1\" upper=\"-1\" effort=\"1\" velocity=\"1\"/>",
            ),
            j("j"),
            |p| matches!(p, Problem::LimitsReversed { lower, upper } if *lower == 1.0 && *upper == -1.0),
        ),
        case(
            "nan_limit",
            pair(
                "prismatic",
                "<limit lower=\"NaN\" upper=\"1\" effort=\"1\" velocity=\"1\"/>",
            ),
            j("j"),
            |p| matches!(p, Problem::NonFinite("limit lower")),
        ),
        case(
            "negative_velocity",
            pair(
                "revolute",
                "<limit lower=\"-1\" upper=\"1\" effort=\"1\" velocity=\"-3\"/>",
            ),
            j("j"),
            |p| matches!(p, Problem::NegativeVelocity(v) if *v == -3.0),
        ),
        case(
            "negative_box",
            with_geometry("<box size=\"0.1 -0.2 0.3\"/>"),
            l("b"),
            |p| matches!(p, Problem::NegativeSize("box size")),
        ),
        case(
            "infinite_cylinder",
            with_geometry("<cylinder radius=\"0.1\" length=\"inf\"/>"),
            l("b"),
            |p| matches!(p, Problem::NonFinite("cylinder length")),
        ),
        case(
            "mesh_not_found",
            with_geometry("<mesh filename=\"meshes/gone.stl\"/>"),
            l("b"),
            |p| matches!(p, Problem::MeshNotFound { filename, .. } if filename == "meshes/gone.stl"),
        ),
        case(
            "package_not_found",
            with_geometry("<mesh filename=\"package://robot/meshes/b.stl\"/>"),
            l("b"),
            |p| matches!(p, Problem::MeshNotFound { filename, .. } if filename.starts_with("package://robot/")),
        ),
        Case {
            files: vec![("b.ply", b"ply\nformat ascii 1.0\nend_header\n")],
            ..case(
                "mesh_format",
                with_geometry("<mesh filename=\"b.ply\"/>"),
                l("b"),
                |p| matches!(p, Problem::UnsupportedMeshFormat(f) if f == "b.ply"),
            )
        },
        Case {
            files: vec![("b.stl", b"")],
            ..case(
                "empty_mesh",
                with_geometry("<mesh filename=\"b.stl\"/>"),
                l("b"),
                |p| matches!(p, Problem::BadMesh { filename, .. } if filename == "b.stl"),
            )
        },
        Case {
            files: vec![("b.stl", b"solid b\nendsolid b\n")],
            ..case(
                "mesh_without_vertices",
                with_geometry("<mesh filename=\"b.stl\" scale=\"1 1 1\"/>"),
                l("b"),
                |p| matches!(p, Problem::BadMesh { reason, .. } if reason.contains("no vertices")),
            )
        },
        case(
            "nan_mesh_scale",
            with_geometry("<mesh filename=\"b.stl\" scale=\"1 nan 1\"/>"),
            l("b"),
            |p| matches!(p, Problem::NonFinite("mesh scale")),
        ),
    ]
}

fn check(message: &str, file: &str, element: &str) {
    assert!(!message.contains('\n'), "one line: {message}");
    assert!(message.contains(file), "names the file {file}: {message}");
    assert!(message.contains(element), "names {element}: {message}");
}

#[test]
fn each_malformed_urdf_names_file_and_element() {
    let cases = cases();
    assert!(cases.len() >= 12);
    for case in cases {
        let dir = tempfile::tempdir().unwrap();
        for (name, bytes) in &case.files {
            write(dir.path(), name, bytes);
        }
        let file = format!("case_{}.urdf", case.label);
        let path = write(dir.path(), &file, &case.urdf);
        let error = match load(&path, &case.options) {
            Ok(chain) => panic!("{}: loaded {chain:?}", case.label),
            Err(error) => error,
        };
        let UrdfError::File {
            element, problem, ..
        } = &error
        else {
            panic!("{}: {error:?}", case.label);
        };
        assert_eq!(*element, case.element, "{}: {error}", case.label);
        assert!((case.problem)(problem), "{}: {error}", case.label);
        let named = match &case.element {
            Element::Joint(name) | Element::Link(name) => format!("`{name}`"),
            Element::Robot => "robot".into(),
        };
        check(&error.to_string(), &file, &named);
    }
}

#[test]
fn unreadable_and_malformed_files_name_the_file() {
    let dir = tempfile::tempdir().unwrap();
    let missing = dir.path().join("absent.urdf");
    let error = load(&missing, &LoadOptions::default()).unwrap_err();
    assert!(matches!(
        &error,
        UrdfError::File {
            problem: Problem::Read(_),
            ..
        }
    ));
    check(&error.to_string(), "absent.urdf", "robot");

    let broken = write(
        dir.path(),
        "broken.urdf",
        "<robot name=\"r\"><link name=\"a\">\n</robot>",
    );
    let error = load(&broken, &LoadOptions::default()).unwrap_err();
    assert!(matches!(
        &error,
        UrdfError::File {
            problem: Problem::Parse(_),
            ..
        }
    ));
    check(&error.to_string(), "broken.urdf", "robot");

    let no_name = write(
        dir.path(),
        "no_name.urdf",
        "<robot name=\"r\"><link/></robot>",
    );
    let error = load(&no_name, &LoadOptions::default()).unwrap_err();
    check(&error.to_string(), "no_name.urdf", "robot");
}

#[test]
fn off_chain_oddities_do_not_stop_the_load() {
    // A floating joint and a mimic joint on branches the chain does not use.
    let urdf = robot(
        &[
            link("a"),
            link("b"),
            link("c"),
            link("float"),
            link("follower"),
            joint("j1", "revolute", "a", "b", LIMIT),
            joint("j2", "revolute", "b", "c", LIMIT),
            joint("drift", "floating", "a", "float", ""),
            joint(
                "copy",
                "revolute",
                "b",
                "follower",
                &format!("{LIMIT}<mimic joint=\"j1\"/>"),
            ),
        ]
        .join("\n"),
    );
    let dir = tempfile::tempdir().unwrap();
    let path = write(dir.path(), "ok.urdf", urdf);
    let chain = load(&path, &options(None, Some("c"))).unwrap();
    assert_eq!(chain.joints.len(), 2);
}
