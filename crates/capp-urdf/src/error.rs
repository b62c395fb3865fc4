//! What can go wrong, as one-line messages that name the file and the element.
//!
//! Every problem found in a URDF file (or in a mesh it names) is a
//! [`UrdfError::File`]: the file, the [`Element`] (a joint, a link, or the
//! robot as a whole) and the [`Problem`]. Its `Display` is one line,
//! `FILE: joint `NAME`: PROBLEM`, so a caller can print it as it is.

use std::fmt;
use std::path::PathBuf;

use thiserror::Error;

/// Why [`load`](crate::load) or [`Chain::forward`](crate::Chain::forward) failed.
#[derive(Debug, Clone, PartialEq, Error)]
pub enum UrdfError {
    /// Something in the URDF file, or in a mesh file it names, is refused.
    #[error("{}: {element}: {problem}", file.display())]
    File {
        /// The URDF file, as given to [`load`](crate::load).
        file: PathBuf,
        /// Where in it.
        element: Element,
        /// What is wrong.
        problem: Problem,
    },
    /// [`Chain::forward`](crate::Chain::forward) got a `q` of the wrong length.
    #[error("forward: {got} joint values for a chain of {expected} moving joints")]
    JointCount {
        /// The chain's number of moving joints.
        expected: usize,
        /// `q.len()`.
        got: usize,
    },
    /// [`Chain::forward`](crate::Chain::forward) got a NaN or infinite joint value.
    #[error("forward: joint value {index} is not finite")]
    NonFiniteJointValue {
        /// Its index in `q`.
        index: usize,
    },
}

/// The part of a URDF file a [`Problem`] is about.
#[derive(Debug, Clone, PartialEq, Eq)]
pub enum Element {
    /// The file as a whole (reading, XML syntax, the tree's roots).
    Robot,
    /// A `<link name=...>`.
    Link(String),
    /// A `<joint name=...>`.
    Joint(String),
}

impl fmt::Display for Element {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        match self {
            Element::Robot => f.write_str("robot"),
            Element::Link(name) => write!(f, "link `{name}`"),
            Element::Joint(name) => write!(f, "joint `{name}`"),
        }
    }
}

/// What is wrong with an [`Element`]. Each message is one line.
#[derive(Debug, Clone, PartialEq, Error)]
pub enum Problem {
    /// The file could not be read.
    #[error("cannot read the file: {0}")]
    Read(String),
    /// The XML is malformed or urdf-rs refused it (its message, on one line).
    #[error("not a valid URDF: {0}")]
    Parse(String),
    /// A joint type other than revolute, continuous, prismatic and fixed:
    /// planar, floating, spherical on the chain, or a type URDF does not know
    /// anywhere in the file.
    #[error("joint type `{0}` is not supported (only revolute, continuous, prismatic and fixed)")]
    UnsupportedJointType(String),
    /// A moving joint on the chain follows another joint (`<mimic>`).
    #[error("mimic joints are not supported on the chain (it mimics `{0}`)")]
    Mimic(String),
    /// A joint's `<parent>` or `<child>` names a link the file does not have.
    #[error("names link `{0}`, which is not in the file")]
    MissingLink(String),
    /// Two links or two joints share this name.
    #[error("the name is used twice")]
    DuplicateName,
    /// A link is the child of two joints.
    #[error("is the child of two joints, `{0}` and `{1}`")]
    TwoParents(String, String),
    /// Following the parents from this link comes back to it.
    #[error("the joints form a loop through this link")]
    Loop,
    /// The file has no `<link>`.
    #[error("has no links")]
    NoLinks,
    /// No `base_link` was given and the tree has several roots.
    #[error("several root links ({0}); choose one with `base_link`")]
    SeveralRoots(String),
    /// The given `base_link` is not in the file.
    #[error("base link not found in the file")]
    BaseNotFound,
    /// The given `tip_link` is not in the file.
    #[error("tip link not found in the file")]
    TipNotFound,
    /// The base link is not an ancestor of the tip link (the element is the tip).
    #[error("base link `{0}` is not an ancestor of this tip link")]
    NotAncestor(String),
    /// No `tip_link` was given and the tree below the base branches.
    #[error("the chain branches below it; choose a tip with `tip_link` among the leaves {0}")]
    AmbiguousTip(String),
    /// The chain from base to tip has no moving joint.
    #[error("no moving joint between base link `{0}` and this tip link")]
    NoMovingJoint(String),
    /// A revolute or prismatic joint without `<limit>`.
    #[error("a {0} joint needs a <limit lower upper velocity>")]
    MissingLimit(&'static str),
    /// `<axis xyz>` of length zero.
    #[error("axis ({0}) has zero length")]
    ZeroAxis(String),
    /// A NaN or infinite number where a finite one is needed.
    #[error("{0} is not finite")]
    NonFinite(&'static str),
    /// `<limit lower>` above `<limit upper>`.
    #[error("lower limit {lower} is above upper limit {upper}")]
    LimitsReversed {
        /// `<limit lower>`.
        lower: f64,
        /// `<limit upper>`.
        upper: f64,
    },
    /// A negative `<limit velocity>`.
    #[error("velocity limit {0} is negative")]
    NegativeVelocity(f64),
    /// A negative size of a `<collision>` shape.
    #[error("{0} is negative")]
    NegativeSize(&'static str),
    /// A `<mesh filename>` that resolves to no existing file.
    #[error("mesh `{filename}` not found ({looked})")]
    MeshNotFound {
        /// The filename as written.
        filename: String,
        /// Where it was looked for.
        looked: String,
    },
    /// A mesh whose extension is not .stl, .obj or .dae.
    #[error("mesh `{0}`: unsupported format (only .stl, .obj and .dae)")]
    UnsupportedMeshFormat(String),
    /// mesh-loader could not read the mesh, or it has no vertices or a
    /// non-finite one.
    #[error("mesh `{filename}`: {reason}")]
    BadMesh {
        /// The filename as written.
        filename: String,
        /// Why, on one line.
        reason: String,
    },
}

/// Replaces line breaks so that a message from a dependency stays one line.
pub(crate) fn one_line(message: &str) -> String {
    message.split_whitespace().collect::<Vec<_>>().join(" ")
}
