//! A model-free person tracker on depth images (REFERENCE §15): no learned
//! model, only the body's surface.
//!
//! Per frame ([`Tracker::step`]):
//! 1. [`grid`]: the depth image downsampled to one sample per `grid_step_px`
//!    cells, back-projected to the camera frame; readings out of range, in an
//!    ignore mask (the robot's own pixels) or not clearly nearer than a learned
//!    [`background`] are dropped; optionally the [`floor`] plane (given or by
//!    RANSAC) is removed.
//! 2. [`segment`]: connected components by depth continuity (thresholds grow
//!    with the cell size and the depth noise σ_z(z) ∝ z²); a component of
//!    plausible size, extent and shape is a person (up to [`MAX_PEOPLE`], largest first).
//! 3. [`geodesic`]: per person a graph over its surface and its accumulative
//!    geodesic extrema (Plagemann et al. ICRA 2010).
//! 4. [`skeleton`]: head, hands and feet among the extrema, neck, shoulders,
//!    elbows, torso, hips and knees by the body's geometry; the person's own
//!    left and right (facing the camera: the person's left is the image's right).
//! 5. [`track`]: ids stable across frames (a person hidden up to a second keeps
//!    its id), joints smoothed by a one-euro [`filter`].
//!
//! Frames and units: the camera's optical frame (x right, y down, z forward),
//! metres, seconds. Pure and deterministic: no I/O, no allocation per frame
//! after [`Tracker::new`]. Every tunable is in [`TrackerConfig`].

#![deny(missing_docs)]

pub mod background;
pub mod config;
pub mod error;
pub mod filter;
pub mod floor;
pub mod geodesic;
pub mod grid;
pub mod segment;
pub mod skeleton;
pub mod track;
pub mod tracker;

pub use config::TrackerConfig;
pub use error::TrackError;
pub use floor::{FloorMode, Plane};
pub use phri_depth::Intrinsics;
pub use skeleton::RawSkeleton;
pub use tracker::{Person, Tracker};

/// People per frame, as `perception/skeleton` carries (`MAX_PEOPLE` of phri-ipc-schema).
pub const MAX_PEOPLE: usize = 4;
/// Joints per person (`SKELETON_JOINTS` of phri-ipc-schema).
pub const JOINTS: usize = 15;

/// The 15 joints, in the order of phri-ipc-schema's `SkeletonJoint` (OpenNI/NiTE's).
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash)]
#[repr(u8)]
pub enum Joint {
    /// centre of the head
    Head = 0,
    /// neck, on the surface path from the head toward the body's centre
    Neck = 1,
    /// centre of the torso, below the neck
    Torso = 2,
    /// the person's left shoulder
    LeftShoulder = 3,
    /// the person's right shoulder
    RightShoulder = 4,
    /// the person's left elbow
    LeftElbow = 5,
    /// the person's right elbow
    RightElbow = 6,
    /// the person's left hand
    LeftHand = 7,
    /// the person's right hand
    RightHand = 8,
    /// the person's left hip
    LeftHip = 9,
    /// the person's right hip
    RightHip = 10,
    /// the person's left knee
    LeftKnee = 11,
    /// the person's right knee
    RightKnee = 12,
    /// the person's left foot
    LeftFoot = 13,
    /// the person's right foot
    RightFoot = 14,
}

/// The joints' snake-case names in [`Joint`] order (as phri-ipc-schema spells them).
pub const JOINT_NAMES: [&str; JOINTS] = [
    "head",
    "neck",
    "torso",
    "left_shoulder",
    "right_shoulder",
    "left_elbow",
    "right_elbow",
    "left_hand",
    "right_hand",
    "left_hip",
    "right_hip",
    "left_knee",
    "right_knee",
    "left_foot",
    "right_foot",
];
