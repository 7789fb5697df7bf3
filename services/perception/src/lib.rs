//! Perception for collision avoidance (paper Sect. V) as pure steps:
//! the simulated camera renders the world ([`camera`]), ingestion validates
//! frames and removes the robot's own pixels ([`ingest`]), repulsion workers
//! compute depth-space distances and repulsive vectors for their control
//! points ([`repulsion`]). The binaries in `src/bin` wire them to channels.

pub mod camera;
pub mod config;
pub mod ingest;
pub mod repulsion;
pub mod robot;

pub use config::{CameraConfig, IngestConfig, PointConfig, RepulsionConfig};
