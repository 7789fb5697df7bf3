//! phri-viz: the cell as Foxglove sees it.
//!
//! A pure scene builder ([`Pipeline`]) turns the latest messages of the cell's
//! channels into Foxglove's built-in schemas (protobuf): the robot's link
//! capsules posed by forward kinematics, the person's capsules, the repulsion
//! vectors and minimum-distance lines, the collaborative hand and the
//! estimated contact forces (`foxglove.SceneUpdate`), the frames
//! (`foxglove.FrameTransforms`), the filtered depth as a point cloud and an
//! image (`foxglove.PointCloud`, `foxglove.RawImage`), the joint states
//! (`foxglove.JointStates`), and a JSON status with the controller's mode, the
//! collaboration phase, the residual and its thresholds ([`status::Status`]).
//!
//! `phri-viz` (this crate's binary, feature `server`) serves them live over
//! Foxglove's WebSocket protocol, to its owner only ([`peer`], `server`); `phri-record` writes the same messages on
//! the same topics ([`topics::ALL`]) into its MCAP files, so a recording shows
//! the same 3-D scene. Frames: `base` is the robot's base frame (the cell's
//! world, z up, \[m\]); the camera's optical frame is `camera`.

pub mod depth;
pub mod geometry;
pub mod peer;
pub mod pipeline;
pub mod scene;
#[cfg(feature = "server")]
pub mod server;
pub mod status;
pub mod topics;

/// The Foxglove SDK this crate builds on (its message types, `Encode`, `Decode`).
pub use foxglove;
pub use phri_view::RobotView;
pub use pipeline::{Output, Pipeline, Rates, VizMessage};
pub use topics::{Topic, ALL as TOPICS};

/// The robot's base frame: every scene entity is posed in it [m, z up].
pub const BASE_FRAME: &str = "base";
/// The depth camera's optical frame (+x right, +y down, +z along the optical axis).
pub const CAMERA_FRAME: &str = "camera";

/// What stops the scene builder from starting.
#[derive(Debug, thiserror::Error)]
pub enum VizError {
    /// the configuration or the robot model it names
    #[error(transparent)]
    Config(#[from] phri_config::ConfigError),
    /// a per-joint setting that does not fit the robot
    #[error("{0}")]
    Invalid(#[from] phri_config::Invalid),
}
