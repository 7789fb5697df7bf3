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
    Head = 0,
    Neck = 1,
    Torso = 2,
    LeftShoulder = 3,
    RightShoulder = 4,
    LeftElbow = 5,
    RightElbow = 6,
    LeftHand = 7,
    RightHand = 8,
    LeftHip = 9,
    RightHip = 10,
    LeftKnee = 11,
    RightKnee = 12,
    LeftFoot = 13,
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
