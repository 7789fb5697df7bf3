//! phri's shared-memory contract: one `#[repr(C)]` message type per concept,
//! each with a stable `#[type_name]`; every channel one typed constant that
//! carries its name, message type, QoS and whether it wakes its readers
//! ([`channels`]); modes and kinds as `#[repr(u32)]` enums ([`enums`]).
//!
//! Timestamps are `CLOCK_MONOTONIC` nanoseconds (system-wide, comparable
//! across processes); every message carries a sequence number. Joint arrays
//! hold `dof` valid entries in the order `phri-model` prints.

#![deny(missing_docs)]

pub mod channel;
pub mod channels;
pub mod cleanup;
pub mod enums;
pub mod error;
pub mod json;
pub mod liveness;
pub mod messages;
pub mod owners;
pub mod ports;
#[cfg(test)]
mod ports_in_code;
pub mod qos;
pub mod views;

pub use channel::*;
pub use channels::*;
pub use cleanup::*;
pub use enums::*;
pub use error::IpcError;
pub use messages::*;
pub use owners::{Owned, OwnerTable, Refusal, Sender, ServiceRole};
pub use qos::*;
pub use views::{best_hand, merge_newest, merge_views};
