//! What every phri process needs: a monotonic clock and absolute-deadline
//! sleep, real-time scheduling (and, for the processes off the torque loop,
//! the CPUs and scheduler that keep them off it: [`placement`]), shutdown on
//! signals, and the service context (arguments, configuration through
//! `phri-config`, the node).

#![deny(missing_docs)]

pub mod cli;
pub mod clock;
pub mod cputime;
pub mod log;
pub mod placement;
pub mod rt;
pub mod rundir;
pub mod service;
pub mod shutdown;

pub use clock::{now_ns, sleep_until_ns};
pub use service::{
    attach_hint, prefix_or_default, ServiceContext, ServiceError, DEFAULT_PREFIX, PREFIX_ENV,
};
pub use shutdown::Shutdown;
