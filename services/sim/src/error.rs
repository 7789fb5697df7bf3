//! Typed errors of the simulator.

use phri_config::Invalid;
use phri_model::LengthError;

/// Why a [`crate::Simulator`] could not be built or set to a state. Each
/// variant names the key (`sim.q0`) or the argument (`q`, `qd`) at fault.
#[derive(Debug, thiserror::Error)]
pub enum SimError {
    /// the model has more joints than the messages carry
    #[error("the model has {n} joints; the simulator supports at most {max}")]
    TooManyJoints {
        /// joints of the model
        n: usize,
        /// most joints supported ([`crate::MAX_JOINTS`])
        max: usize,
    },
    /// a `[sim]` key out of range or not fitting the model (`sim.dt_s`, `sim.viscous_friction`)
    #[error(transparent)]
    Config(#[from] Invalid),
    /// an array of the wrong length (`sim.q0`, `q`, `qd`)
    #[error(transparent)]
    Length(#[from] LengthError),
    /// a NaN or infinite entry in a joint array
    #[error("{what}: joint {joint}: not a finite number")]
    NotFinite {
        /// the argument (`q`, `qd`)
        what: &'static str,
        /// index of the first joint at fault
        joint: usize,
    },
    /// a joint position outside the model's position limits (or not finite)
    #[error(
        "{what}: joint {joint} ('{name}'): {value} rad is outside the limits [{lower}, {upper}]"
    )]
    OutsideLimits {
        /// the key or argument (`sim.q0`, `q`)
        what: &'static str,
        /// index of the first joint at fault
        joint: usize,
        /// the joint's name in the model
        name: String,
        /// the position \[rad\]
        value: f64,
        /// the joint's lower limit \[rad\]
        lower: f64,
        /// the joint's upper limit \[rad\]
        upper: f64,
    },
    /// a scripted push names a link the robot model does not have, or one
    /// without a collision capsule on its body (`index`: the keyframe)
    #[error("keyframe[{index}].push.link: '{link}' {reason}")]
    PushLink {
        /// index of the keyframe whose push it is
        index: usize,
        /// the link name as scripted
        link: String,
        /// what is wrong with it
        reason: String,
    },
}
