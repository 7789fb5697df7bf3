//! Typed errors of model construction and of the algorithms' input checks.

use std::path::PathBuf;

/// Everything that can go wrong building a [`crate::Model`] or calling an algorithm.
#[derive(Debug, thiserror::Error)]
pub enum ModelError {
    #[error("{path}: cannot read: {source}")]
    Io {
        path: PathBuf,
        source: std::io::Error,
    },
    #[error("{origin}: malformed URDF: {message}")]
    Parse { origin: String, message: String },
    #[error("joint '{joint}': {kind} joints are not supported (only revolute, continuous, prismatic and fixed)")]
    UnsupportedJoint { joint: String, kind: String },
    #[error("joint '{joint}' mimics '{leader}', which the URDF does not define")]
    MimicUnknownLeader { joint: String, leader: String },
    #[error("joint '{joint}' mimics '{leader}', a fixed joint (a leader must move)")]
    MimicLeaderFixed { joint: String, leader: String },
    #[error("joint '{joint}' mimics '{leader}', which is a mimic joint itself (a leader must have its own degree of freedom)")]
    MimicChain { joint: String, leader: String },
    #[error("joint '{joint}': axis has zero length")]
    ZeroAxis { joint: String },
    #[error("joint '{joint}' names link '{link}', which the URDF does not define")]
    MissingLink { joint: String, link: String },
    #[error("link '{link}' is the child of more than one joint")]
    SeveralParents { link: String },
    #[error("the URDF has no root link (every link is a child: the joints form a cycle)")]
    NoRoot,
    #[error("the URDF has several root links: {roots:?} (a robot must be one tree)")]
    SeveralRoots { roots: Vec<String> },
    #[error("the URDF has no actuated (revolute, continuous or prismatic) joint")]
    NoActuatedJoint,
    #[error("{element}: {field} is not a finite number")]
    NotFinite { element: String, field: String },
    #[error("link '{link}': invalid inertial data: {reason}")]
    Inertia { link: String, reason: String },
    #[error("joint '{joint}': lower limit {lower} is above upper limit {upper}")]
    Limits {
        joint: String,
        lower: f64,
        upper: f64,
    },
    #[error("joint '{joint}': {field} is {value}; it must be positive (only a continuous joint may go without <limit>, and is then unlimited)")]
    LimitNotPositive {
        joint: String,
        field: &'static str,
        value: f64,
    },
    #[error("two {element}s are named '{name}'")]
    DuplicateName { element: &'static str, name: String },
    #[error("joint '{joint}' moves no mass (no mass or inertia in the links it carries): the joint-space inertia matrix would be singular")]
    MovesNoMass { joint: String },
    #[error("{origin}: XML nested deeper than {max} elements")]
    TooDeep { origin: String, max: usize },
    #[error("{}: larger than {max} bytes; not a robot description", path.display())]
    TooLarge { path: PathBuf, max: u64 },
    #[error("unknown link '{0}'")]
    UnknownLink(String),
    #[error("joint '{0}' to lock: the URDF has no moving joint of that name")]
    UnknownLockedJoint(String),
    #[error(transparent)]
    Dimension(#[from] LengthError),
    #[error("the joint-space inertia matrix is not positive definite")]
    NotPositiveDefinite,
}

/// An array of the wrong length: the one length check of phri's numerics
/// ([`check_len`]), wrapped by every library's own error.
#[derive(Clone, Copy, Debug, PartialEq, Eq, thiserror::Error)]
#[error("{what}: expected length {expected}, got {got}")]
pub struct LengthError {
    pub what: &'static str,
    pub expected: usize,
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
