//! What every phri process needs: a monotonic clock and absolute-deadline
//! sleep, real-time scheduling, shutdown on signals, and configuration.

pub mod args;
pub mod clock;
pub mod config;
pub mod rt;
pub mod service;
pub mod shutdown;

pub use args::Args;
pub use clock::{now_ns, sleep_until_ns};
pub use config::{load_config, section, ConfigError};
pub use service::ServiceContext;
pub use shutdown::Shutdown;
