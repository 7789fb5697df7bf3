//! The supervisor's logic as plain data and pure functions: what a run will
//! do, checked before anything starts ([`plan`]); which services run, in
//! which order ([`spec`]); their bookkeeping, restarts and the frozen
//! verdict ([`roster`], [`restart`]), and who starves whom ([`cpu`]); the
//! state files ([`state`]); the run report built from what flowed on the
//! channels ([`report`]); how services are started and recognised
//! ([`process`]); real-time scheduling as the services got it
//! ([`realtime`]); iceoryx2's node counter, checked and closed ([`shm`]). `main.rs` does the I/O: it
//! spawns, signals and reaps the processes, reads the channels, publishes
//! the health, writes the files, every 10 ms.

pub mod box_report;
pub mod camera_report;
pub mod collab_report;
pub mod cpu;
pub mod error;
pub mod mic_report;
pub mod owned;
pub mod plan;
pub mod process;
pub mod realtime;
pub mod report;
pub mod residual_model;
pub mod restart;
pub mod robot_pace;
pub mod roster;
pub mod shm;
pub mod spec;
pub mod standby_report;
pub mod state;
pub mod verdict;

pub use error::SupervisorError;
pub use plan::Plan;
pub use roster::{Frozen, Roster, Supervised};
pub use state::{StateJson, SupervisorState};
