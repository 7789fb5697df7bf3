//! `phri-franka`: a Franka arm (FR3 over FCI v10, Panda/FER over v5) behind
//! phri's robot channels, as `phri-sim` serves them for the simulated arm.
//! The control box compensates gravity itself and expects joint torques
//! without it; it also refuses a torque that changes faster than
//! 1000 Nm/s. [`FciCycle`] turns phri's command (the whole torque, gravity
//! included) into what the box accepts, with the protocol rules of
//! [`phri_robot::RobotLink`] (fresh, reused, missed; brakes after 20).

#![deny(missing_docs)]

pub mod box_status;
pub mod cycle;
pub mod fci_error;
pub mod model_check;
pub mod state;
pub mod state_guard;

pub use box_status::{BoxError, BoxLog, BoxTorques, Refused};
pub use cycle::{CycleError, FciCycle, FciTorque, JOINTS, MAX_TORQUE_RATE_NM_PER_S};
pub use fci_error::FciError;
pub use model_check::first_difference;
pub use state::fill_state;
pub use state_guard::{StateGuard, StateRefusal};
