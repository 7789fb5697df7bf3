//! Depth camera side of phri: a Kinect-class camera watching the robot and the
//! human, and the depth-space collision-avoidance distances of the paper's
//! Sect. V (Flacco et al. ICRA 2012; REFERENCE §3, §6).
//!
//! - [`camera`]: pinhole [`Intrinsics`] (Kinect 640×480 default), the camera's
//!   [`CameraPose`] in the robot base frame, projection and back-projection.
//! - [`shapes`]: [`Capsule`] and [`Aabb`] primitives, base frame.
//! - [`render`]: [`Renderer`], an exact ray-cast z-buffer of capsules, boxes and
//!   a floor into `u16` millimetre frames, with Kinect-like noise and drop-outs.
//! - [`flying`]: [`FlyingPixels`] removes isolated flying pixels (sensor noise).
//! - [`selffilter`]: [`SelfFilter`] removes the robot's own pixels.
//! - [`distance`]: [`DepthSpaceDistance`], distances and repulsive vectors
//!   (eqs. 15-18) for points of interest on the robot.
//! - [`fusion`]: [`CameraView`] and [`fuse`], distances fused across several
//!   cameras, each a lower bound of the truth, capped by the nearest surface
//!   any camera saw.
//! - [`png`](mod@png): 16-bit grayscale depth PNGs.
//! - [`kinect`]: the Kinect v1's 11-bit disparity and millimetres.
//!
//! Frames: base frame of the robot (SI units); camera frame z forward, x right,
//! y down. Depth frames are `width × height` row-major `u16` millimetres, 0 = no
//! reading. The per-frame paths allocate nothing: buffers are preallocated by
//! the constructors and outputs are caller-owned slices.

#![deny(missing_docs)]

pub mod camera;
pub mod distance;
pub mod error;
pub mod flying;
pub mod fusion;
pub mod kinect;
mod lanes;
pub mod noise;
pub mod png;
pub mod render;
pub mod ros_image;
pub mod selffilter;
pub mod shapes;

pub use camera::{CameraPose, Intrinsics, PixelDepth};
pub use distance::{DepthSpaceDistance, PixelWindow, PointOfInterest, Repulsion, RepulsionParams};
pub use error::{DepthError, DepthPngError};
pub use flying::{Filtered, FlyingPixels};
pub use fusion::{capped_by_surface, fuse, CameraView, Fused, SeenSurface};
pub use noise::sigma_z;
pub use png::{decode_depth_png, encode_depth_png, read_depth_png, write_depth_png};
pub use render::{RenderOptions, Renderer, LABEL_NONE};
pub use selffilter::{SelfFilter, SelfFilterParams};
pub use shapes::{Aabb, Capsule};
