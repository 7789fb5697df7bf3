//! `phri-freenect`'s library: a Kinect v1 depth camera through libfreenect.
//!
//! - [`ffi`]: the libfreenect binding (the crate's only `unsafe`) and
//!   [`Device`], a safe 640×480 11-bit disparity stream;
//! - [`disparity`]: raw disparity ↔ millimetres (OpenKinect's formula, a
//!   2048-entry table; `phri_depth::kinect`, which a replay of a fakenect
//!   recording shares);
//! - [`timestamps`]: the device's 32-bit 60 MHz timestamps mapped onto
//!   CLOCK_MONOTONIC;
//! - [`recording`]: fakenect recordings written from millimetre frames (for
//!   tests without a Kinect).

#![deny(missing_docs)]

pub use phri_depth::kinect as disparity;
pub mod ffi;
pub mod recording;
pub mod timestamps;

pub use disparity::{Disparity, FrameError};
pub use ffi::{Device, Frame};
pub use recording::{write_recording, RecordingError};
pub use timestamps::{Capture, TimestampMapper};

use phri_depth::Intrinsics;

/// Depth image width \[px\] (`FREENECT_RESOLUTION_MEDIUM`).
pub const WIDTH: u32 = 640;
/// Depth image height \[px\].
pub const HEIGHT: u32 = 480;
/// Pixels in a depth frame.
pub const PIXELS: usize = phri_depth::kinect::PIXELS;
/// The Kinect v1 depth camera's nominal focal length along x \[px\] at 640×480.
pub const FX: f64 = 580.0;
/// Its nominal focal length along y \[px\].
pub const FY: f64 = 580.0;
/// Its nominal principal point, column \[px\].
pub const CX: f64 = 320.0;
/// Its nominal principal point, row \[px\].
pub const CY: f64 = 240.0;

/// The Kinect v1 depth camera's nominal intrinsics at 640×480 (the values
/// published with every frame: libfreenect reports no calibration of its
/// own in 11-bit mode).
pub const KINECT_DEPTH: Intrinsics = Intrinsics {
    width: WIDTH,
    height: HEIGHT,
    fx: FX,
    fy: FY,
    cx: CX,
    cy: CY,
};

/// How long the service waits for the first frame before it gives up \[s\].
pub const FIRST_FRAME_TIMEOUT_S: u64 = 5;

/// A libfreenect failure; every message is one line naming the device.
#[derive(Debug, thiserror::Error, Clone, PartialEq, Eq)]
pub enum FreenectError {
    /// no device at that index
    #[error("freenect device {index}: no Kinect found (libfreenect sees {count} devices)")]
    NoDevice {
        /// the device's index among libfreenect's devices
        index: u32,
        /// devices libfreenect sees
        count: u32,
    },
    /// a libfreenect call failed
    #[error("freenect device {index}: {call} failed (code {code})")]
    Call {
        /// the device's index among libfreenect's devices
        index: u32,
        /// the libfreenect function
        call: &'static str,
        /// its return code
        code: i32,
    },
    /// libfreenect has no 640×480 11-bit depth mode of 614400 bytes
    #[error("freenect device {index}: no 640x480 11-bit depth mode (libfreenect offers {width}x{height}, {bytes} bytes)")]
    Mode {
        /// the device's index among libfreenect's devices
        index: u32,
        /// width of the mode libfreenect offers \[px\]
        width: i16,
        /// its height \[px\]
        height: i16,
        /// its frame size \[bytes\]
        bytes: i32,
    },
    /// event processing failed (USB error, or fakenect past its recording)
    #[error("freenect device {index}: processing events failed (code {code})")]
    Events {
        /// the device's index among libfreenect's devices
        index: u32,
        /// the return code of `freenect_process_events_timeout`
        code: i32,
    },
    /// no frame within the wait
    #[error("freenect device {index}: no depth frame within {waited_ms} ms")]
    Timeout {
        /// the device's index among libfreenect's devices
        index: u32,
        /// how long it waited \[ms\]
        waited_ms: u64,
    },
    /// no frame at all since the start
    #[error("freenect device {index}: no depth frame within {seconds} s")]
    NeverAnswered {
        /// the device's index among libfreenect's devices
        index: u32,
        /// how long it waited for the first frame \[s\]
        seconds: u64,
    },
}
