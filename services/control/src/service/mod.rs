//! The controller as a service of the cell, around the pure step: its
//! channels ([`channels`]), one period's inputs gathered from them
//! ([`intake`]), the period itself ([`period`]: the hot standby's adoption,
//! the step, the role's duty), the messages it publishes ([`publish`]) and
//! what the loop logs ([`notes`]). `main.rs` only opens the service and
//! runs the loop; the lock-step cell drives [`crate::Controller`] directly.

pub mod channels;
pub mod intake;
pub mod notes;
pub mod period;
pub mod publish;

pub use channels::{open, InputChannels, OutputChannels};
pub use notes::Note;
pub use period::ControlService;
