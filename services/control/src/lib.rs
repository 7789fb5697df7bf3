//! The torque loop as a pure, deterministic step: joint positions, the
//! newest residual and the newest repulsion results in, a limited joint
//! torque and a mode out. [`Controller::step`] applies the paper's hierarchy
//! in order:
//!
//! 1. safety inputs ([`safety`]): without a fresh, valid residual the arm
//!    holds a protective stop; blind perception slows the task, or stops it
//!    with a person last seen near;
//! 2. reaction to a detected collision ([`modes::next_mode`]): at once, the
//!    configured strategy (reflex eq. 9, admittance eq. 13, stop, float,
//!    time-scaled retreat along the past path), then recover and resume;
//! 3. the active behaviour ([`modes`]): sync after a (re)start (no jump to an
//!    old command), the Cartesian task (waypoints on minimum-jerk segments),
//!    the reaction, protective stop, recover;
//! 4. avoidance ([`resolve`], [`avoidance`], [`sns`]): the end effector's
//!    repulsion adds to the task (eq. 19), the other control points shape the
//!    joint velocity bounds (eq. 20), SNS solves within them, and below the
//!    end effector's task the body points move away ([`body_task`]); CLIK
//!    ([`clik`]) without perception;
//! 5. the computed-torque law `τ = M a + C q̇ + g` with gravity compensated;
//! 6. torque, velocity and position limits of the model ([`limits`]).
//!
//! [`inputs`] and [`outputs`] are the one conversion between the cell's
//! messages and the step, for `main.rs` and the lock-step cell.
//! [`service`] is the controller in the cell: its channels, one period's
//! inputs gathered from them, the step and the messages published.
//! [`snapshot`] carries the behaviour state from one controller to another
//! (a hot standby adopting the primary's every period).

#![deny(missing_docs)]

pub mod avoidance;
pub mod body_task;
pub mod cbf;
pub mod clik;
pub mod collab;
pub mod controller;
pub mod cut;
pub mod drives;
pub mod error;
pub mod history;
pub mod inputs;
pub mod limits;
pub mod modes;
pub mod outputs;
pub mod path;
pub mod reference;
pub mod requests;
pub mod resolve;
pub mod safety;
pub mod service;
pub mod slew;
pub mod snapshot;
pub mod sns;
pub mod ssm;
pub mod standby;
pub mod terms;

pub use controller::{ControlCounters, ControlOutput, Controller, ControllerParams};
pub use error::{ControlError, InputError};
pub use inputs::{
    CollabInput, ControlInput, InputGate, PerceptionView, RepulsionInputs, ResidualView,
};
pub use outputs::{
    write_barrier_status, write_collab_state, write_messages, write_ssm_status, Stamps,
};
pub use phri_config::{AvoidanceParams, ControlConfig};
pub use phri_ipc::{ControlMode, Reaction};
pub use snapshot::{SnapshotError, BEHAVIOUR_BYTES};
