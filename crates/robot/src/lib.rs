//! What every robot adapter of phri shares, the simulator's and a real
//! arm's alike: the robot side of the 1 kHz protocol ([`link`]), so that an
//! adapter for a real arm never links the simulator.

#![deny(missing_docs)]

pub mod link;

pub use link::{
    CommandGate, CycleTiming, LinkError, LinkOutput, MissRun, RobotLink, Wake, GRACE_POLL_NS,
    LATE_CYCLE_GRACE_NS, MAX_MISSED, SLOTS, SLOT_SERVICES, STATS_EVERY,
};
