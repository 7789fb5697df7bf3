//! Estimators over the robot model, as preallocated state with an
//! allocation-free `step`: joint velocity from encoder positions
//! ([`velocity`]), the momentum residual of paper eqs. 4-8 ([`observer`])
//! and its two-level contact/collision detector with isolation of the
//! colliding link ([`detect`]).

#![deny(missing_docs)]

pub mod contact_force;
pub mod detect;
pub mod observer;
pub mod velocity;

pub use contact_force::{
    ContactPoint, ForceError, ForceEstimate, ForceEstimator, MAX_FORCE_CONTACTS, MAX_JOINTS,
};
pub use detect::{Detection, Detector};
pub use observer::{ResidualError, ResidualObserver, ResidualOutput};
pub use velocity::VelocityEstimator;
