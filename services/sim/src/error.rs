//! Typed errors of the simulator.

use phri_config::Invalid;
use phri_model::LengthError;

/// Why a [`crate::Simulator`] could not be built or set to a state. Each
/// variant names the key (`sim.q0`) or the argument (`q`, `qd`) at fault.
#[derive(Debug, thiserror::Error)]
pub enum SimError {
    #[error("the model has {n} joints; the simulator supports at most {max}")]
    TooManyJoints { n: usize, max: usize },
    /// a `[sim]` key out of range or not fitting the model (`sim.dt_s`, `sim.viscous_friction`)
    #[error(transparent)]
    Config(#[from] Invalid),
    /// an array of the wrong length (`sim.q0`, `q`, `qd`)
    #[error(transparent)]
    Length(#[from] LengthError),
    #[error("{what}: joint {joint}: not a finite number")]
    NotFinite { what: &'static str, joint: usize },
    #[error(
        "{what}: joint {joint} ('{name}'): {value} rad is outside the limits [{lower}, {upper}]"
    )]
    OutsideLimits {
        what: &'static str,
        joint: usize,
        name: String,
        value: f64,
        lower: f64,
        upper: f64,
    },
    /// a scripted push names a link the robot model does not have, or one
    /// without a collision capsule on its body (`index`: the keyframe)
    #[error("keyframe[{index}].push.link: '{link}' {reason}")]
    PushLink {
        index: usize,
        link: String,
        reason: String,
    },
}
