//! Errors of the configuration, each naming the file and the key at fault.

use std::path::PathBuf;

/// A value that is well-typed but out of range: `key` is dotted (`control.kp`).
#[derive(Clone, Debug, PartialEq, thiserror::Error)]
#[error("{key}: {reason}")]
pub struct Invalid {
    /// the key at fault, dotted (`control.kp`, `robot.capsules[2].radius`)
    pub key: String,
    /// what is wrong with its value
    pub reason: String,
}

impl Invalid {
    /// The value of `key` is refused for `reason`.
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
    /// a file could not be read
    #[error("{}: cannot read: {source}", path.display())]
    Io {
        /// the file
        path: PathBuf,
        /// the system's error
        source: std::io::Error,
    },
    /// TOML syntax error
    #[error("{origin}: {message}")]
    Parse {
        /// the file (or `<defaults>`, `<default robot>`)
        origin: String,
        /// the parser's message, with the line
        message: String,
    },
    /// a `--set` without `=`, as given
    #[error("--set '{0}': expected section.key=value")]
    Override(String),
    /// a `--set` whose key or value cannot be applied, and why
    #[error("--set '{set}': {reason}")]
    SetValue {
        /// the `--set`, as given
        set: String,
        /// why it cannot be applied
        reason: String,
    },
    /// a section or key the configuration does not have
    #[error("{origin}: unknown section [{section}] (known: {known})")]
    UnknownSection {
        /// what gave the section
        origin: String,
        /// the section's name
        section: String,
        /// the sections there are, comma-separated
        known: String,
    },
    /// a key of a known section with a wrong type or an unknown name
    #[error("{origin}: {key}: {message}")]
    Key {
        /// what gave the key
        origin: String,
        /// the key, dotted (`<top>` when none can be named)
        key: String,
        /// what is wrong with it
        message: String,
    },
    /// a well-typed value out of range
    #[error("{origin}: {invalid}")]
    Invalid {
        /// what gave the value
        origin: String,
        /// the key and what is wrong with its value
        #[source]
        invalid: Invalid,
    },
    /// the scenario could not be loaded
    #[error(transparent)]
    Scenario(#[from] crate::scenario::ScenarioError),
    /// a file another user could have written, or not a regular file
    #[error(transparent)]
    Untrusted(crate::trust::TrustError),
    /// `--scenario` names neither a file nor a known scenario
    #[error("--scenario: '{name}' is neither a file nor a scenario in {dir} (known: {known})")]
    NoScenario {
        /// the name, as given
        name: String,
        /// the `scenarios/` directory beside the configuration file
        dir: String,
        /// the scenarios there, by name
        known: String,
    },
    /// `robot.name` names an arm without a robot file
    #[error("{by}: robot.name: no arm '{name}': no robots/{name}/robot.toml in {dir} or the built-in deploy/robots (known: {known})")]
    NoRobot {
        /// the arm's name, as given
        name: String,
        /// what named it: a `--set`, or the configuration file
        by: String,
        /// the `robots/` directory beside the configuration file
        dir: String,
        /// the arms with a robot file there, by name
        known: String,
    },
    /// the robot model could not be built from the URDF
    #[error("{}", model_message(path, source))]
    Model {
        /// the URDF
        path: PathBuf,
        /// the model's error
        source: phri_model::ModelError,
    },
    /// a URDF no arm has (too many links or joints), named by what gave `robot.urdf`
    #[error("{origin}: robot.urdf: {}: {invalid}", path.display())]
    Urdf {
        /// what gave `robot.urdf`
        origin: String,
        /// the URDF
        path: PathBuf,
        /// how many links or joints it has, and the limit
        invalid: String,
    },
    /// the robot model has more joints than the messages carry
    #[error("{}: {joints} joints, the messages carry at most {max}", path.display())]
    TooManyJoints {
        /// the URDF
        path: PathBuf,
        /// the model's joints (velocity coordinates)
        joints: usize,
        /// the most joints a message carries (`phri_ipc::MAX_DOF`)
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
