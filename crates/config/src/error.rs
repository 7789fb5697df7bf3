//! Errors of the configuration, each naming the file and the key at fault.

use std::path::PathBuf;

/// A value that is well-typed but out of range: `key` is dotted (`control.kp`).
#[derive(Clone, Debug, PartialEq, thiserror::Error)]
#[error("{key}: {reason}")]
pub struct Invalid {
    pub key: String,
    pub reason: String,
}

impl Invalid {
    pub fn new(key: impl Into<String>, reason: impl Into<String>) -> Invalid {
        Invalid {
            key: key.into(),
            reason: reason.into(),
        }
    }
}

/// Why a configuration could not be loaded. `origin` is the file (or
/// `<defaults>`, `--set`), so that every message names where to look.
#[derive(Debug, thiserror::Error)]
pub enum ConfigError {
    #[error("{}: cannot read: {source}", path.display())]
    Io {
        path: PathBuf,
        source: std::io::Error,
    },
    /// TOML syntax error
    #[error("{origin}: {message}")]
    Parse { origin: String, message: String },
    #[error("--set '{0}': expected section.key=value")]
    Override(String),
    /// a `--set` whose key or value cannot be applied, and why
    #[error("--set '{set}': {reason}")]
    SetValue { set: String, reason: String },
    /// a section or key the configuration does not have
    #[error("{origin}: unknown section [{section}] (known: {known})")]
    UnknownSection {
        origin: String,
        section: String,
        known: String,
    },
    /// a key of a known section with a wrong type or an unknown name
    #[error("{origin}: {key}: {message}")]
    Key {
        origin: String,
        key: String,
        message: String,
    },
    /// a well-typed value out of range
    #[error("{origin}: {invalid}")]
    Invalid {
        origin: String,
        #[source]
        invalid: Invalid,
    },
    #[error(transparent)]
    Scenario(#[from] crate::scenario::ScenarioError),
    /// a file another user could have written, or not a regular file
    #[error(transparent)]
    Untrusted(crate::trust::TrustError),
    #[error("--scenario: '{name}' is neither a file nor a scenario in {dir} (known: {known})")]
    NoScenario {
        name: String,
        dir: String,
        /// the scenarios there, by name
        known: String,
    },
    #[error("{by}: robot.name: no arm '{name}': no robots/{name}/robot.toml in {dir} or the built-in deploy/robots (known: {known})")]
    NoRobot {
        name: String,
        /// what named it: a `--set`, or the configuration file
        by: String,
        dir: String,
        /// the arms with a robot file there, by name
        known: String,
    },
    #[error("{}", model_message(path, source))]
    Model {
        path: PathBuf,
        source: phri_model::ModelError,
    },
    /// a URDF no arm has (too many links or joints), named by what gave `robot.urdf`
    #[error("{origin}: robot.urdf: {}: {invalid}", path.display())]
    Urdf {
        origin: String,
        path: PathBuf,
        invalid: String,
    },
    #[error("{}: {joints} joints, the messages carry at most {max}", path.display())]
    TooManyJoints {
        path: PathBuf,
        joints: usize,
        max: usize,
    },
}

impl From<crate::trust::TrustError> for ConfigError {
    fn from(e: crate::trust::TrustError) -> ConfigError {
        match e {
            crate::trust::TrustError::Io { path, source } => ConfigError::Io { path, source },
            e => ConfigError::Untrusted(e),
        }
    }
}

/// The model's error, prefixed with the file unless it names it already.
fn model_message(path: &std::path::Path, e: &phri_model::ModelError) -> String {
    let m = e.to_string();
    let p = path.display().to_string();
    if m.starts_with(&p) {
        m
    } else {
        format!("{p}: {m}")
    }
}
