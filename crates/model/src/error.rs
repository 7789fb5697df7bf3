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
    #[error("joint '{joint}': mimic joints are not supported")]
    Mimic { joint: String },
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
    #[error("unknown link '{0}'")]
    UnknownLink(String),
    #[error("{what}: expected length {expected}, got {got}")]
    Dimension {
        what: &'static str,
        expected: usize,
        got: usize,
    },
    #[error("the joint-space inertia matrix is not positive definite")]
    NotPositiveDefinite,
}

/// `Ok(())` if `got == expected`, a [`ModelError::Dimension`] naming `what` otherwise.
#[inline]
pub fn check_len(what: &'static str, expected: usize, got: usize) -> Result<(), ModelError> {
    if expected == got {
        Ok(())
    } else {
        Err(ModelError::Dimension {
            what,
            expected,
            got,
        })
    }
}
