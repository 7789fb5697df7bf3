//! phri's shared-memory contract: one `#[repr(C)]` message type per concept,
//! each with a stable `#[type_name]`, every service name as a constant, and
//! every service's quality of service in one place ([`qos`]).
//!
//! Timestamps are `CLOCK_MONOTONIC` nanoseconds (system-wide, comparable
//! across processes); every message carries a sequence number. Joint arrays
//! hold `dof` valid entries in the order `phri-model` prints.

pub mod cleanup;
pub mod messages;
pub mod names;
pub mod qos;

pub use cleanup::*;
pub use messages::*;
pub use names::*;
pub use qos::*;
