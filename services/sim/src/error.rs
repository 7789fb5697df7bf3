//! Typed errors of the simulator.

use phri_model::ModelError;

/// Why a [`crate::Simulator`] could not be built or set to a state.
#[derive(Debug, thiserror::Error)]
pub enum SimError {
    #[error("the model has {n} joints; the simulator supports at most {max}")]
    TooManyJoints { n: usize, max: usize },
    #[error("sim config: {field}: {reason}")]
    Config { field: &'static str, reason: String },
    #[error("sim config: {0}")]
    Toml(String),
    #[error("{what}: {reason}")]
    State { what: &'static str, reason: String },
    #[error(transparent)]
    Model(#[from] ModelError),
}
