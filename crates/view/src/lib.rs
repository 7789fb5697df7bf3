//! phri-view: the cell as its viewers show it, shared by the Foxglove
//! viewer (`phri-viz`) and the ROS 2 bridge (`phri-ros2`), with no viewer's
//! wire format in it.
//!
//! - [`depth`]: a depth frame (`perception/depth`) back-projected through its
//!   header's intrinsics into packed points in the camera's optical frame
//!   (+x right, +y down, +z along the optical axis, \[m\]), the camera's pose in
//!   the robot's base frame and the frame's time on phri's clock.
//! - [`robot`]: [`RobotView`], the robot's collision capsules and link frames
//!   posed by forward kinematics from a joint state (base frame, \[m\]).
//! - [`status`]: [`Status`], the controller's mode, the collaboration
//!   phase, the momentum residual and the thresholds it is judged against
//!   (\[Nm\]), the obstacle distance (\[m\]), as one serialisable sample.
//!
//! Frames: the robot's base frame is the cell's world (z up, SI units); the
//! camera's optical frame is the one its depth frames are taken in.

#![deny(missing_docs)]

pub mod depth;
pub mod robot;
pub mod status;

pub use robot::{Capsule, RobotView};
pub use status::{Status, Thresholds};
