//! Momentum-residual collision detection (paper Sect. III, eqs. 4-8) as a pure,
//! deterministic step: joint positions and applied torques in, residual,
//! detection flags and the isolated link out. `main.rs` wires it to channels.

pub mod config;
pub mod detect;
pub mod observer;
pub mod velocity;

pub use config::ResidualConfig;
pub use detect::{Detection, Detector};
pub use observer::{ResidualError, ResidualObserver};
pub use velocity::VelocityEstimator;
