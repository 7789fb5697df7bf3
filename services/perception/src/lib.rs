//! Perception for collision avoidance (paper Sect. V) as pure steps: the
//! simulated camera renders and stamps the world ([`camera`]) and injects the
//! faults it is asked for ([`fault`]); ingestion validates frames and removes
//! the robot's own pixels ([`ingest`]), from the camera channel, whatever
//! its source (the simulated camera, a replay of recorded frames
//! ([`replay`]), a Kinect's or a ROS 2 camera's process, all through
//! [`live`]); repulsion workers compute depth-space distances
//! and repulsive vectors for their control points and fill their message
//! ([`repulsion`]). The binaries in `src/bin` only wire them to channels;
//! the lock-step cell calls the same steps. Configuration sections come from
//! `phri-config` (`[camera]`, `[perception]`, `[repulsion]`).

#![deny(missing_docs)]

pub mod camera;
pub mod fault;
pub mod flag;
pub mod ingest;
pub mod live;
pub mod mask;
pub mod pipeline;
pub mod replay;
pub mod repulsion;
pub mod robot;
pub mod skeleton;
pub mod source;
pub mod surfaces;
pub mod tracker;
pub mod turns;

pub use camera::{CameraError, CameraSim, HeaderError};
pub use fault::{FaultAccepted, FaultRefused, FaultState};
pub use flag::CameraFlag;
pub use ingest::{FrameError, Ingest, IngestOutcome, StateHistory};
pub use live::{CameraOut, CameraStamps, DropCause, RobotClock};
pub use pipeline::{Perception, PipelineError};
pub use repulsion::{RepulsionError, Worker};
pub use source::{RateLimited, Ticks};
pub use surfaces::SeenSurfaces;
pub use tracker::{DepthTracker, TrackerError};
