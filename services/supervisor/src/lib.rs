//! The supervisor's logic as plain data and pure functions: what a run will
//! do, checked before anything starts ([`plan`]); which services run, in
//! which order ([`spec`]); their bookkeeping, restarts and the frozen
//! verdict ([`roster`], [`restart`], [`verdict`]), and who starves whom
//! ([`cpu`]); the supervision itself as a state machine, events in and
//! actions out, tested without processes ([`supervision`]); the state files
//! ([`state`]); the run report built from what flowed on the channels
//! ([`report`], [`evaluation`]); how services are started and recognised
//! ([`process`]); real-time scheduling as the services got it
//! ([`realtime`]); iceoryx2's node counter, checked and closed ([`shm`]);
//! the picture of the cell's processes and channels ([`drawing`]).
//! [`run`] does the I/O around the state machine: it spawns, signals and
//! reaps the processes, reads the channels, publishes the health, writes
//! the files, every 10 ms; `main.rs` only reads the command line.

#![deny(missing_docs)]

pub mod barrier_report;
pub mod box_report;
pub mod camera_report;
pub mod collab_report;
pub mod cpu;
pub mod drawing;
pub mod error;
pub mod evaluation;
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
pub mod run;
pub mod shm;
pub mod spec;
pub mod standby_report;
pub mod state;
pub mod supervision;
pub mod verdict;

pub use error::SupervisorError;
pub use plan::Plan;
pub use roster::{Frozen, Roster, Supervised};
pub use state::{StateJson, SupervisorState};
