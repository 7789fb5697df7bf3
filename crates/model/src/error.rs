//! Typed errors of model construction and of the algorithms' input checks.

use std::path::PathBuf;

/// Everything that can go wrong building a [`crate::Model`] or calling an algorithm.
#[derive(Debug, thiserror::Error)]
pub enum ModelError {
    /// the URDF file could not be opened or read
    #[error("{path}: cannot read: {source}")]
    Io {
        /// the URDF file
        path: PathBuf,
        /// the operating system's error
        source: std::io::Error,
    },
    /// the XML parser refused the URDF text (or failed on it)
    #[error("{origin}: malformed URDF: {message}")]
    Parse {
        /// the file's path, or `<urdf>` for URDF text
        origin: String,
        /// the parser's message
        message: String,
    },
    /// a floating, planar or spherical joint
    #[error("joint '{joint}': {kind} joints are not supported (only revolute, continuous, prismatic and fixed)")]
    UnsupportedJoint {
        /// joint name
        joint: String,
        /// its URDF type, lower case (`floating`, `planar`, …)
        kind: String,
    },
    /// a `<mimic>` names a joint the URDF does not have
    #[error("joint '{joint}' mimics '{leader}', which the URDF does not define")]
    MimicUnknownLeader {
        /// the mimic joint
        joint: String,
        /// the leader it names
        leader: String,
    },
    /// a `<mimic>` names a fixed joint as its leader
    #[error("joint '{joint}' mimics '{leader}', a fixed joint (a leader must move)")]
    MimicLeaderFixed {
        /// the mimic joint
        joint: String,
        /// the fixed leader it names
        leader: String,
    },
    /// a `<mimic>` names a mimic joint (or itself) as its leader
    #[error("joint '{joint}' mimics '{leader}', which is a mimic joint itself (a leader must have its own degree of freedom)")]
    MimicChain {
        /// the mimic joint
        joint: String,
        /// the leader it names, itself a mimic joint
        leader: String,
    },
    /// a moving joint's axis is the zero vector
    #[error("joint '{joint}': axis has zero length")]
    ZeroAxis {
        /// joint name
        joint: String,
    },
    /// a joint's parent or child link is not in the URDF
    #[error("joint '{joint}' names link '{link}', which the URDF does not define")]
    MissingLink {
        /// joint name
        joint: String,
        /// the undefined link it names
        link: String,
    },
    /// a link is the child of two or more joints (the links are not a tree)
    #[error("link '{link}' is the child of more than one joint")]
    SeveralParents {
        /// link name
        link: String,
    },
    /// every link is some joint's child: the joints form a cycle
    #[error("the URDF has no root link (every link is a child: the joints form a cycle)")]
    NoRoot,
    /// more than one link is no joint's child: the URDF is several trees
    #[error("the URDF has several root links: {roots:?} (a robot must be one tree)")]
    SeveralRoots {
        /// names of the root links
        roots: Vec<String>,
    },
    /// no revolute, continuous or prismatic joint: nothing to control
    #[error("the URDF has no actuated (revolute, continuous or prismatic) joint")]
    NoActuatedJoint,
    /// a number read (or given) is NaN or infinite, or out of its range
    #[error("{element}: {field} is not a finite number")]
    NotFinite {
        /// where the number is, e.g. `joint 'j1'` or `link 'l1' inertial`
        element: String,
        /// which number, e.g. `mass` or `limit lower`
        field: String,
    },
    /// a link's inertial data is physically impossible
    #[error("link '{link}': invalid inertial data: {reason}")]
    Inertia {
        /// link name
        link: String,
        /// what is wrong (negative mass, inertia not positive semidefinite)
        reason: String,
    },
    /// a joint's lower position limit is above its upper one
    #[error("joint '{joint}': lower limit {lower} is above upper limit {upper}")]
    Limits {
        /// joint name
        joint: String,
        /// lower position limit \[rad or m\]
        lower: f64,
        /// upper position limit \[rad or m\]
        upper: f64,
    },
    /// a velocity or effort limit is zero or negative
    #[error("joint '{joint}': {field} is {value}; it must be positive (only a continuous joint may go without <limit>, and is then unlimited)")]
    LimitNotPositive {
        /// joint name
        joint: String,
        /// which limit: `velocity` or `effort`
        field: &'static str,
        /// its value in the URDF
        value: f64,
    },
    /// two links or two joints share a name
    #[error("two {element}s are named '{name}'")]
    DuplicateName {
        /// `link` or `joint`
        element: &'static str,
        /// the shared name
        name: String,
    },
    /// a moving joint carries neither mass nor inertia: `M` would be singular
    #[error("joint '{joint}' moves no mass (no mass or inertia in the links it carries): the joint-space inertia matrix would be singular")]
    MovesNoMass {
        /// joint name
        joint: String,
    },
    /// the XML nests deeper than [`crate::MAX_XML_DEPTH`] (checked before parsing)
    #[error("{origin}: XML nested deeper than {max} elements")]
    TooDeep {
        /// the file's path, or `<urdf>` for URDF text
        origin: String,
        /// the depth allowed, [`crate::MAX_XML_DEPTH`]
        max: usize,
    },
    /// the file is larger than [`crate::MAX_URDF_BYTES`]
    #[error("{}: larger than {max} bytes; not a robot description", path.display())]
    TooLarge {
        /// the file
        path: PathBuf,
        /// the size allowed \[bytes\], [`crate::MAX_URDF_BYTES`]
        max: u64,
    },
    /// a link name the model does not have (or `#i`, a frame index out of range)
    #[error("unknown link '{0}'")]
    UnknownLink(String),
    /// a joint to lock that the URDF does not have, or that is fixed
    #[error("joint '{0}' to lock: the URDF has no moving joint of that name")]
    UnknownLockedJoint(String),
    /// an input array of the wrong length
    #[error(transparent)]
    Dimension(#[from] LengthError),
    /// the joint-space inertia matrix failed its Cholesky factorization
    #[error("the joint-space inertia matrix is not positive definite")]
    NotPositiveDefinite,
}

/// An array of the wrong length: the one length check of phri's numerics
/// ([`check_len`]), wrapped by every library's own error.
#[derive(Clone, Copy, Debug, PartialEq, Eq, thiserror::Error)]
#[error("{what}: expected length {expected}, got {got}")]
pub struct LengthError {
    /// the array, e.g. `q` or `qd`
    pub what: &'static str,
    /// the length it must have
    pub expected: usize,
    /// the length it had
    pub got: usize,
}

/// `Ok(())` if `got == expected`, a [`LengthError`] naming `what` otherwise.
#[inline]
pub fn check_len(what: &'static str, expected: usize, got: usize) -> Result<(), LengthError> {
    if expected == got {
        Ok(())
    } else {
        Err(LengthError {
            what,
            expected,
            got,
        })
    }
}
