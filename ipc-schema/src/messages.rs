//! Message types. All are plain data: `#[repr(C)]`, no pointers, fixed size.

use iceoryx2::prelude::*;
use serde::{Deserialize, Serialize};

/// Largest number of joints a message carries.
pub const MAX_DOF: usize = 12;
/// Largest number of simultaneous contacts in [`Truth`].
pub const MAX_CONTACTS: usize = 8;
/// Latency histogram bins of [`RobotStats`]: 1 µs each, the last one collects everything above.
pub const LATENCY_BINS: usize = 2000;
/// Services tracked in [`Health`].
pub const MAX_SERVICES: usize = 16;
/// People in a [`Skeleton`].
pub const MAX_PEOPLE: usize = 4;
/// Joints of a [`TrackedPerson`] (OpenNI/NiTE's 15, [`crate::SkeletonJoint`]).
pub const SKELETON_JOINTS: usize = 15;
/// Estimated contact forces in a [`CollabState`].
pub const MAX_COLLAB_FORCES: usize = 2;
/// Samples in one [`AudioChunk`]: 20 ms at [`AUDIO_RATE_HZ`].
pub const AUDIO_CHUNK_SAMPLES: usize = 320;
/// Sample rate of `audio/mic` \[Hz\] (mono, 16 bit).
pub const AUDIO_RATE_HZ: u32 = 16_000;
/// Bytes of the text of an [`HriRequest`] (UTF-8, zero padded).
pub const REQUEST_TEXT: usize = 64;
/// Human capsules in [`WorldState`].
pub const MAX_HUMAN_CAPSULES: usize = 16;
/// Control points one repulsion worker may own.
pub const MAX_POINTS_PER_WORKER: usize = 8;

/// Bits of [`JointState::status`].
pub mod robot_status {
    /// the robot's brakes are engaged (too many missing commands)
    pub const BRAKING: u32 = 1;
    /// `wrench` holds a wrist force/torque reading
    pub const FT_VALID: u32 = 2;
    /// the command applied in the last period was fresh (answered the previous state)
    pub const COMMAND_FRESH: u32 = 4;
    /// the torque applied is not known: the arm's own control box holds it
    /// (a real robot's adapter under the protocol's brakes), so `tau` is not
    /// what acted and a momentum residual over this state means nothing
    pub const TORQUE_UNKNOWN: u32 = 8;
    /// the controller on `robot/command/standby` is in charge (its fresh
    /// command is applied first); clear: the one on `robot/command`
    pub const STANDBY_IN_CHARGE: u32 = 16;
}

/// Measured joint state, published by the robot every control period.
#[derive(Debug, Clone, Copy, ZeroCopySend, Serialize, Deserialize)]
#[repr(C)]
#[type_name("phri::JointState")]
pub struct JointState {
    /// sequence number, one per state
    pub seq: u64,
    /// measurement time \[ns\]: the robot's cycle clock (CLOCK_MONOTONIC at
    /// start, then exactly one period per state)
    pub stamp_ns: u64,
    /// when the robot published it [ns, CLOCK_MONOTONIC]
    pub published_ns: u64,
    /// joints: valid entries of `q` and `tau`
    pub dof: u32,
    /// [`robot_status`] bits
    pub status: u32,
    /// measured joint positions [rad or m] (encoders; no velocities)
    #[serde(with = "crate::json::finite_array")]
    pub q: [f64; MAX_DOF],
    /// joint torque applied in the last period \[Nm\] (command after limits, or brake torque)
    #[serde(with = "crate::json::finite_array")]
    pub tau: [f64; MAX_DOF],
    /// wrist force/torque [N, Nm]: force then moment, base frame, at the last link's origin
    #[serde(with = "crate::json::finite_array")]
    pub wrench: [f64; 6],
    /// `seq` of the command applied in the last period (0: none yet)
    pub command_seq: u64,
    /// consecutive periods without a fresh command
    pub missed_commands: u32,
    /// padding, not in the JSON view
    #[serde(skip)]
    pub _pad: u32,
}

/// Joint torque command, answering one [`JointState`].
#[derive(Debug, Clone, Copy, ZeroCopySend, Serialize, Deserialize)]
#[repr(C)]
#[type_name("phri::TorqueCommand")]
pub struct TorqueCommand {
    /// sequence number
    pub seq: u64,
    /// publish time \[ns\]
    pub stamp_ns: u64,
    /// the state this command answers
    pub state_seq: u64,
    /// measurement time of the state answered \[ns, robot clock\]
    pub state_stamp_ns: u64,
    /// joints: valid entries of `tau`
    pub dof: u32,
    /// [`crate::ControlMode`]
    #[serde(with = "crate::json::control_mode")]
    pub mode: u32,
    /// motor torque \[Nm\], limits already enforced
    #[serde(with = "crate::json::finite_array")]
    pub tau: [f64; MAX_DOF],
}

/// Bits of [`Residual::flags`].
pub mod residual_flags {
    /// some joint's residual passed its contact threshold
    pub const CONTACT: u32 = 1;
    /// some joint's residual, or the norm, passed the collision threshold
    pub const COLLISION: u32 = 2;
    /// the wrist F/T reading was used (modified residual, eq. 8)
    pub const FT_USED: u32 = 4;
    /// the observer is initialised and the value is meaningful
    pub const VALID: u32 = 8;
}

/// Momentum residual (paper eq. 5) for one joint state.
#[derive(Debug, Clone, Copy, ZeroCopySend, Serialize, Deserialize)]
#[repr(C)]
#[type_name("phri::Residual")]
pub struct Residual {
    /// sequence number
    pub seq: u64,
    /// publish time \[ns\]
    pub stamp_ns: u64,
    /// `seq` of the joint state it was computed from
    pub state_seq: u64,
    /// measurement time of that state \[ns, robot clock\]
    pub state_stamp_ns: u64,
    /// joints: valid entries of `r` and `qd`
    pub dof: u32,
    /// [`residual_flags`]
    pub flags: u32,
    /// last joint whose residual passed its contact threshold (−1: none): the
    /// colliding link is this joint's link or one after it (paper Sect. III)
    pub isolated_joint: i32,
    /// padding, not in the JSON view
    #[serde(skip)]
    pub _pad: u32,
    /// residual r ≈ τ_ext \[Nm\]
    #[serde(with = "crate::json::finite_array")]
    pub r: [f64; MAX_DOF],
    /// joint velocity estimated from positions [rad/s]
    #[serde(with = "crate::json::finite_array")]
    pub qd: [f64; MAX_DOF],
    /// ‖r‖ \[Nm\]
    #[serde(with = "crate::json::finite")]
    pub norm: f64,
    /// time spent computing \[ns\]
    pub compute_ns: u64,
}

/// Controller status, one per command.
#[derive(Debug, Clone, Copy, ZeroCopySend, Serialize, Deserialize)]
#[repr(C)]
#[type_name("phri::ControlStatus")]
pub struct ControlStatus {
    /// sequence number
    pub seq: u64,
    /// publish time [ns, CLOCK_MONOTONIC]
    pub stamp_ns: u64,
    /// `seq` of the state answered
    pub state_seq: u64,
    /// measurement time of the state answered [ns, robot clock]
    pub state_stamp_ns: u64,
    /// [`crate::ControlMode`]
    #[serde(with = "crate::json::control_mode")]
    pub mode: u32,
    /// configured reaction strategy ([`crate::Reaction`])
    pub reaction: u32,
    /// task waypoints reached since start
    pub waypoints_reached: u64,
    /// collisions detected (reactions entered) since start
    pub detections: u64,
    /// protective stops entered since start
    pub protective_stops: u64,
    /// returns to the task after a reaction's recovery since start
    pub resumes: u64,
    /// age of the residual used \[ns\] (u64::MAX: none)
    #[serde(with = "crate::json::opt_ns")]
    pub residual_age_ns: u64,
    /// joint reference \[rad\]
    #[serde(with = "crate::json::finite_array")]
    pub q_ref: [f64; MAX_DOF],
    /// end-effector position \[m\], base frame
    #[serde(with = "crate::json::finite_array")]
    pub ee: [f64; 3],
    /// time spent computing \[ns\]
    pub compute_ns: u64,
    /// state published → this controller woke \[ns\]
    pub wake_latency_ns: u64,
    /// age of the perception results used \[ns\] (u64::MAX: none)
    #[serde(with = "crate::json::opt_ns")]
    pub perception_age_ns: u64,
    /// smallest obstacle distance of the control points last seen \[m\]
    #[serde(with = "crate::json::distance")]
    pub min_distance: f64,
    /// largest repulsion risk ‖V_Call‖/V_max over the control points [0, 1]
    #[serde(with = "crate::json::finite")]
    pub risk: f64,
    /// SNS task scale [0, 1]
    #[serde(with = "crate::json::finite")]
    pub task_scale: f64,
    /// model evaluations that failed since the controller started (each one
    /// made that period hold fail-safe; never silently dropped)
    pub model_errors: u64,
}

/// One contact in [`Truth`].
#[derive(Debug, Clone, Copy, Default, ZeroCopySend, Serialize, Deserialize)]
#[repr(C)]
#[type_name("phri::ContactTruth")]
pub struct ContactTruth {
    /// index into the robot model's collision objects
    pub robot_object: i32,
    /// human body part ([`crate::BodyPart`] as i32; −1: unknown)
    pub human_part: i32,
    /// 1 when the part is designated collaborative
    #[serde(with = "crate::json::flag")]
    pub intended: u32,
    /// padding, not in the JSON view
    #[serde(skip)]
    pub _pad: u32,
    /// force on the robot \[N\], base frame
    #[serde(with = "crate::json::finite_array")]
    pub force: [f64; 3],
    /// contact point \[m\], base frame
    #[serde(with = "crate::json::finite_array")]
    pub point: [f64; 3],
    /// penetration \[m\]
    #[serde(with = "crate::json::finite")]
    pub depth: f64,
}

/// Simulator ground truth. For evaluation only.
#[derive(Debug, Clone, Copy, ZeroCopySend, Serialize, Deserialize)]
#[repr(C)]
#[type_name("phri::Truth")]
pub struct Truth {
    /// sequence number: the joint state's, as `state_seq`
    pub seq: u64,
    /// measurement time of that joint state \[ns, robot clock\]
    pub stamp_ns: u64,
    /// the [`JointState`] published with this truth
    pub state_seq: u64,
    /// valid entries of `contacts`
    pub n_contacts: u32,
    /// joints: valid entries of `tau_ext`, `q` and `qd`
    pub dof: u32,
    /// true external joint torque \[Nm\]
    #[serde(with = "crate::json::finite_array")]
    pub tau_ext: [f64; MAX_DOF],
    /// true joint positions \[rad\] (not quantised as the encoders' are)
    #[serde(with = "crate::json::finite_array")]
    pub q: [f64; MAX_DOF],
    /// true joint velocities \[rad/s\]
    #[serde(with = "crate::json::finite_array")]
    pub qd: [f64; MAX_DOF],
    /// human-robot surface distance \[m\] (negative: penetration; +inf: no human)
    #[serde(with = "crate::json::distance")]
    pub min_distance: f64,
    /// the deepest contacts, base frame (the first `n_contacts`)
    pub contacts: [ContactTruth; MAX_CONTACTS],
}

/// Robot loop statistics, cumulative since the robot process started.
#[derive(Debug, Clone, Copy, ZeroCopySend, Serialize, Deserialize)]
#[repr(C)]
#[type_name("phri::RobotStats")]
pub struct RobotStats {
    /// sequence number
    pub seq: u64,
    /// publish time \[ns, CLOCK_MONOTONIC\]
    pub stamp_ns: u64,
    /// control periods run
    pub cycles: u64,
    /// periods whose command did not arrive before the next period began
    pub missed_deadlines: u64,
    /// periods run with brakes engaged
    pub braked_cycles: u64,
    /// times the brakes engaged
    pub brake_events: u64,
    /// periods where the robot's own loop woke late by more than half a period
    pub overruns: u64,
    /// largest state-published → command-received latency \[ns\]
    pub latency_max_ns: u64,
    /// latency histogram, 1 µs bins; the last bin holds everything above
    #[serde(with = "crate::json::latency_hist")]
    pub latency_hist: [u32; LATENCY_BINS],
}

/// One supervised service in [`Health`].
#[derive(Debug, Clone, Copy, ZeroCopySend, Serialize, Deserialize)]
#[repr(C)]
#[type_name("phri::ServiceHealth")]
pub struct ServiceHealth {
    /// service name, UTF-8, zero padded
    #[serde(with = "crate::json::c_string")]
    pub name: [u8; 32],
    /// process id (0: not running)
    pub pid: i32,
    /// 1 while the process runs
    #[serde(with = "crate::json::flag")]
    pub alive: u32,
    /// times the supervisor restarted it
    pub restarts: u32,
    /// padding, not in the JSON view
    #[serde(skip)]
    pub _pad: u32,
    /// last start \[ns\]
    pub started_ns: u64,
}

impl ServiceHealth {
    /// The service's name as text (`?` when not UTF-8).
    pub fn name_str(&self) -> &str {
        crate::json::c_str_ref(&self.name)
    }
}

/// Supervisor's view of the services.
#[derive(Debug, Clone, Copy, ZeroCopySend, Serialize, Deserialize)]
#[repr(C)]
#[type_name("phri::Health")]
pub struct Health {
    /// sequence number
    pub seq: u64,
    /// publish time \[ns, CLOCK_MONOTONIC\]
    pub stamp_ns: u64,
    /// services supervised; `services` lists the first [`MAX_SERVICES`] of
    /// them in start order (read `count.min(MAX_SERVICES)` entries)
    pub count: u32,
    /// padding, not in the JSON view
    #[serde(skip)]
    pub _pad: u32,
    /// the services in start order: from the first (`supervisor/health`) or from
    /// number [`MAX_SERVICES`] on (`supervisor/health/more`); the entries past
    /// the last service are zeroed
    pub services: [ServiceHealth; MAX_SERVICES],
}

/// Owned channels an [`InputAudit`] holds (at least `owners::PUBLISHERS`).
pub const AUDIT_CHANNELS: usize = 8;

/// What one reader refused on the owned channels it reads, 2 Hz
/// ([`crate::INPUT_AUDIT`]): counts since the reader started, per owned
/// channel (in `owners::PUBLISHERS` order) and per kind of refusal
/// (stranger, future, stale, not its point: `owners::Refusal`).
#[derive(Debug, Clone, Copy, ZeroCopySend, Serialize, Deserialize)]
#[repr(C)]
#[type_name("phri::InputAudit")]
pub struct InputAudit {
    /// sequence number (per reader)
    pub seq: u64,
    /// publish time [ns, CLOCK_MONOTONIC]
    pub stamp_ns: u64,
    /// the reader's service name, UTF-8, zero padded
    #[serde(with = "crate::json::c_string")]
    pub service: [u8; 32],
    /// refusals per owned channel and kind
    pub refused: [[u64; 4]; AUDIT_CHANNELS],
    /// per owned channel: the newest stranger's process id (0: none)
    pub stranger_pid: [i32; AUDIT_CHANNELS],
}

impl InputAudit {
    /// The reader's service name as text (`?` when not UTF-8).
    pub fn service_str(&self) -> &str {
        crate::json::c_str_ref(&self.service)
    }
}

/// What the ROS 2 bridge (`phri-ros2`) did with the requests it read on
/// `/phri/request`, 2 Hz ([`crate::ROS2_REQUESTS`]): counts cumulative since
/// that bridge process started (a restarted bridge starts again at 0).
#[derive(Debug, Clone, Copy, Default, ZeroCopySend, Serialize, Deserialize)]
#[repr(C)]
#[type_name("phri::BridgeRequests")]
pub struct BridgeRequests {
    /// sequence number
    pub seq: u64,
    /// publish time [ns, CLOCK_MONOTONIC]
    pub stamp_ns: u64,
    /// requests passed on to `hri/request`
    pub passed: u64,
    /// of them, stops (never rate-limited)
    pub stops: u64,
    /// refused by rule: requests not accepted (`accept_requests = false`),
    /// not a request phri knows
    pub refused: u64,
    /// dropped: over a peer's rate limit, or not delivered to `hri/request`
    pub dropped: u64,
    /// samples that could not be decoded
    pub malformed: u64,
}

impl Zeroed for BridgeRequests {}

/// A camera's own figures, 2 Hz and at exit ([`crate::CAMERA_STATUS`], one
/// channel for every camera): what it published and why it dropped what it
/// did not. Counts cumulative since that camera process started.
#[derive(Debug, Clone, Copy, Default, ZeroCopySend, Serialize, Deserialize)]
#[repr(C)]
#[type_name("phri::CameraStatus")]
pub struct CameraStatus {
    /// sequence number (per camera)
    pub seq: u64,
    /// publish time [ns, CLOCK_MONOTONIC]
    pub stamp_ns: u64,
    /// the camera's index in `[[camera]]`
    pub camera: u32,
    /// where its frames come from: 0 simulated, 1 freenect (Kinect v1),
    /// 2 ROS 2, 3 replay (`phri_config::CameraSource` in that order)
    pub source: u32,
    /// frames published on its `camera/depth` channel
    pub frames: u64,
    /// dropped: captured longer ago than `[camera] max_age_s` when they arrived
    pub dropped_old: u64,
    /// dropped: stamped in the future
    pub dropped_future: u64,
    /// dropped: malformed (wrong size or step, an encoding refused, values
    /// that are not depths, a truncated file)
    pub dropped_malformed: u64,
    /// dropped: no usable intrinsics yet (a ROS 2 image before its
    /// CameraInfo, or a CameraInfo refused)
    pub dropped_no_info: u64,
    /// dropped: the source ran behind its rate (a replay's tick overrun, a
    /// frame the driver replaced before it was published)
    pub dropped_behind: u64,
}

impl Zeroed for CameraStatus {}

/// The microphone's own figures, 2 Hz and at exit ([`crate::AUDIO_MIC_STATUS`]).
#[derive(Debug, Clone, Copy, Default, ZeroCopySend, Serialize, Deserialize)]
#[repr(C)]
#[type_name("phri::MicStatus")]
pub struct MicStatus {
    /// sequence number
    pub seq: u64,
    /// publish time [ns, CLOCK_MONOTONIC]
    pub stamp_ns: u64,
    /// where the sound comes from: 0 the stand-in (`[audio]`), 1 ALSA
    pub source: u32,
    /// the capture device's own rate \[Hz\] (16 000 for the stand-in)
    pub device_rate_hz: u32,
    /// `audio/mic` chunks published
    pub chunks: u64,
    /// capture overruns (the device's buffer overflowed: sound lost)
    pub overruns: u64,
}

impl Zeroed for MicStatus {}

/// Bytes of [`BoxStatus::last_error`].
pub const BOX_ERROR_TEXT: usize = 128;

/// The control box behind a robot adapter (`phri-franka`: FCI), 10 Hz and at
/// every error ([`crate::ROBOT_BOX`]): the box's own figures, cumulative
/// since the adapter started.
#[derive(Debug, Clone, Copy, ZeroCopySend, Serialize, Deserialize)]
#[repr(C)]
#[type_name("phri::BoxStatus")]
pub struct BoxStatus {
    /// sequence number
    pub seq: u64,
    /// publish time [ns, CLOCK_MONOTONIC]
    pub stamp_ns: u64,
    /// states read from the box
    pub states: u64,
    /// states read while phri controlled the arm (torque control running)
    pub controlled: u64,
    /// sum over those states of FCI's `control_command_success_rate` (the
    /// share of the box's last 100 periods that got a command): mean = sum / controlled
    #[serde(with = "crate::json::finite")]
    pub success_sum: f64,
    /// the lowest `control_command_success_rate` of those states (1 before any)
    #[serde(with = "crate::json::finite")]
    pub success_min: f64,
    /// errors of the box (motions it aborted: reflexes, limits, lost commands)
    pub errors: u64,
    /// automatic error recoveries the adapter ran
    pub recoveries: u64,
    /// when the newest error came [ns, CLOCK_MONOTONIC] (0: none)
    pub last_error_ns: u64,
    /// the newest error: the box's error names (libfranka's), UTF-8, zero padded
    #[serde(with = "crate::json::c_string")]
    pub last_error: [u8; BOX_ERROR_TEXT],
    /// joints in the arrays below
    pub dof: u32,
    /// padding, not in the JSON view
    #[serde(skip)]
    pub _pad: u32,
    /// the box's own joint torques of its newest state \[Nm\] (FCI's `tau_J`,
    /// its torque sensors), for comparison with phri's applied torque
    #[serde(with = "crate::json::finite_array")]
    pub tau_j: [f64; MAX_DOF],
    /// the box's own external torque estimate of its newest state \[Nm\]
    /// (FCI's `tau_ext_hat_filtered`), for comparison with phri's residual
    #[serde(with = "crate::json::finite_array")]
    pub tau_ext_hat: [f64; MAX_DOF],
    /// state datagrams refused, by why: from another address or port than
    /// the box's, of the wrong size, a message id not above the newest, one
    /// too far ahead; states whose joint positions are not finite, or moved
    /// faster than the joints' velocity limits allow (never published)
    pub refused_foreign: u64,
    /// state datagrams refused: of the wrong size
    pub refused_malformed: u64,
    /// state datagrams refused: a message id not above the newest
    pub refused_stale_id: u64,
    /// state datagrams refused: a message id too far ahead
    pub refused_id_ahead: u64,
    /// states refused: joint positions that are not finite
    pub refused_non_finite: u64,
    /// states refused: joints that moved faster than their velocity limits allow
    pub refused_too_fast: u64,
}

impl BoxStatus {
    /// The newest error's text (`?` when not UTF-8).
    pub fn last_error_str(&self) -> &str {
        crate::json::c_str_ref(&self.last_error)
    }
}

/// A zeroed value of a plain-data message (all fields are numbers).
pub trait Zeroed: Sized + Copy {
    /// All bytes zero: every number 0, every text empty.
    fn zeroed() -> Self {
        // SAFETY: every message type is #[repr(C)] of integers and floats, for
        // which all-zero bytes are a valid value.
        unsafe { std::mem::zeroed() }
    }
}

impl Zeroed for JointState {}
impl Zeroed for TorqueCommand {}
impl Zeroed for ServiceHealth {}
impl Zeroed for Residual {}
impl Zeroed for ControlStatus {}
impl Zeroed for Truth {}
impl Zeroed for RobotStats {}
impl Zeroed for Health {}
impl Zeroed for InputAudit {}
impl Zeroed for BoxStatus {}

/// One capsule of the simulated world: segment `a`–`b` swept by `radius` \[m\], base frame.
#[derive(Debug, Clone, Copy, Default, ZeroCopySend, Serialize, Deserialize)]
#[repr(C)]
#[type_name("phri::WorldCapsule")]
pub struct WorldCapsule {
    /// one end of the segment \[m\], base frame
    #[serde(with = "crate::json::finite_array")]
    pub a: [f64; 3],
    /// the other end of the segment \[m\], base frame
    #[serde(with = "crate::json::finite_array")]
    pub b: [f64; 3],
    /// the capsule's radius \[m\]
    #[serde(with = "crate::json::finite")]
    pub radius: f64,
    /// human body part ([`crate::BodyPart`] as i32)
    pub part: i32,
    /// padding, not in the JSON view
    #[serde(skip)]
    pub _pad: u32,
}

/// The simulated world a simulated camera sees: the arm's true joints and the
/// human's capsules, on the robot's clock. Simulation only.
#[derive(Debug, Clone, Copy, ZeroCopySend, Serialize, Deserialize)]
#[repr(C)]
#[type_name("phri::WorldState")]
pub struct WorldState {
    /// sequence number: the joint state's
    pub seq: u64,
    /// [ns, robot clock]
    pub stamp_ns: u64,
    /// joints: valid entries of `q`
    pub dof: u32,
    /// valid entries of `human`
    pub n_human: u32,
    /// true joint positions \[rad\]
    #[serde(with = "crate::json::finite_array")]
    pub q: [f64; MAX_DOF],
    /// the human's capsules (the first `n_human`)
    pub human: [WorldCapsule; MAX_HUMAN_CAPSULES],
}

/// Header of a depth frame (`camera/depth`, `perception/depth`): the payload
/// is `width × height` `u16` depths in millimetres, row-major, 0 = no reading.
#[derive(Debug, Clone, Copy, Default, ZeroCopySend, Serialize, Deserialize)]
#[repr(C)]
#[type_name("phri::FrameHeader")]
pub struct FrameHeader {
    /// camera frame number
    pub seq: u64,
    /// capture time [ns, robot clock]
    pub capture_ns: u64,
    /// capture time [ns, CLOCK_MONOTONIC]
    pub capture_wall_ns: u64,
    /// when this sample was published [ns, CLOCK_MONOTONIC]
    pub published_ns: u64,
    /// image width \[px\]
    pub width: u32,
    /// image height \[px\]
    pub height: u32,
    /// pinhole intrinsics \[px\]
    #[serde(with = "crate::json::finite")]
    pub fx: f64,
    /// focal length along y \[px\] (`fx`: along x)
    #[serde(with = "crate::json::finite")]
    pub fy: f64,
    /// principal point, x \[px\]
    #[serde(with = "crate::json::finite")]
    pub cx: f64,
    /// principal point, y \[px\]
    #[serde(with = "crate::json::finite")]
    pub cy: f64,
    /// metres per depth unit (0.001: millimetres)
    #[serde(with = "crate::json::finite")]
    pub depth_scale: f64,
    /// camera pose in the base frame: rotation (row-major 3×3, camera axes:
    /// x right, y down, z forward) then translation \[m\]
    #[serde(with = "crate::json::finite_array")]
    pub pose_r: [f64; 9],
    /// the camera's position in the base frame \[m\] (the pose's translation)
    #[serde(with = "crate::json::finite_array")]
    pub pose_t: [f64; 3],
    /// joint state used to remove the robot's own pixels (perception/depth only)
    #[serde(with = "crate::json::finite_array")]
    pub q: [f64; MAX_DOF],
    /// stamp of that joint state [ns, robot clock] (0: none)
    pub q_stamp_ns: u64,
    /// joints: valid entries of `q`
    pub dof: u32,
    /// pixels removed as the robot's own
    pub removed_pixels: u32,
    /// valid pixels left
    pub valid_pixels: u32,
    /// the frame's arrival at ingestion → this publication \[ns\], saturating
    /// (perception/depth only; 0 on camera/depth). Was padding: the layout
    /// and size are unchanged.
    pub ingest_ns: u32,
}

/// Result for one control point.
#[derive(Debug, Clone, Copy, Default, ZeroCopySend, Serialize, Deserialize)]
#[repr(C)]
#[type_name("phri::PointRepulsion")]
pub struct PointRepulsion {
    /// control point index (in the configured list)
    pub point: u32,
    /// 1 when something was within the surveillance region
    #[serde(with = "crate::json::flag")]
    pub active: u32,
    /// repulsive velocity V_Call [m/s], base frame (eqs. 16-18)
    #[serde(with = "crate::json::finite_array")]
    pub v_call: [f64; 3],
    /// minimum distance to an obstacle pixel \[m\] (ρ when none)
    #[serde(with = "crate::json::distance")]
    pub min_distance: f64,
    /// the closest obstacle point \[m\], base frame
    #[serde(with = "crate::json::finite_array")]
    pub obstacle: [f64; 3],
    /// the control point at the frame's joint state \[m\], base frame
    #[serde(with = "crate::json::finite_array")]
    pub position: [f64; 3],
}

/// One repulsion worker's result for one frame (`perception/repulsion`).
#[derive(Debug, Clone, Copy, ZeroCopySend, Serialize, Deserialize)]
#[repr(C)]
#[type_name("phri::RepulsionResult")]
pub struct RepulsionResult {
    /// sequence number (per worker)
    pub seq: u64,
    /// the frame this answers
    pub frame_seq: u64,
    /// the frame's capture time [ns, robot clock]
    pub capture_ns: u64,
    /// publish time [ns, CLOCK_MONOTONIC]
    pub published_ns: u64,
    /// the frame's capture time [ns, CLOCK_MONOTONIC]
    pub frame_capture_wall_ns: u64,
    /// this worker's number, below `workers`: it owns the control points `i`
    /// with `i mod workers = worker`
    pub worker: u32,
    /// workers in the configuration
    pub workers: u32,
    /// valid entries of `points`
    pub n_points: u32,
    /// the frame's arrival at ingestion → this result's publication \[ns\],
    /// saturating (0: unknown). Was padding: the layout and size are unchanged.
    pub since_arrival_ns: u32,
    /// processing time \[ns\]
    pub compute_ns: u64,
    /// one result per control point the worker owns (the first `n_points`)
    pub points: [PointRepulsion; MAX_POINTS_PER_WORKER],
}

impl Zeroed for WorldState {}
impl Zeroed for FrameHeader {}
impl Zeroed for RepulsionResult {}

/// A fault for the simulated camera to inject into its depth frames
/// (`phri-fault camera corrupt|delay`), for testing what perception faults
/// cost. A real camera driver ignores this channel.
#[derive(Debug, Clone, Copy, ZeroCopySend, Serialize, Deserialize)]
#[repr(C)]
#[type_name("phri::DepthFault")]
pub struct DepthFault {
    /// sequence number
    pub seq: u64,
    /// when it was sent [ns, CLOCK_MONOTONIC]
    pub stamp_ns: u64,
    /// [`crate::DepthFaultKind`]
    #[serde(with = "crate::json::depth_fault_kind")]
    pub kind: u32,
    /// corruptions: how many consecutive frames
    pub frames: u32,
    /// [`crate::DepthFaultKind::Delay`]: extra capture → publish delay \[ms\]
    #[serde(with = "crate::json::finite")]
    pub delay_ms: f64,
    /// [`crate::DepthFaultKind::Delay`]: how long \[s\]
    #[serde(with = "crate::json::finite")]
    pub duration_s: f64,
}

impl Zeroed for DepthFault {}

/// One event of a contact episode between the person and the robot, from the
/// simulator's ground truth (`sim/contacts`): its beginning, every 100 ms
/// while it lasts, and its end. Few and deeply queued, so that no episode is
/// lost to a reader that was stalled (`sim/truth` at 1 kHz may overflow).
/// For evaluation only.
#[derive(Debug, Clone, Copy, ZeroCopySend, Serialize, Deserialize)]
#[repr(C)]
#[type_name("phri::ContactEvent")]
pub struct ContactEvent {
    /// sequence number
    pub seq: u64,
    /// [ns, robot clock]: the state this event was seen with
    pub stamp_ns: u64,
    /// when the episode began [ns, robot clock]
    pub start_ns: u64,
    /// the episode's number (counted from 1 by the simulator)
    pub episode: u64,
    /// [`crate::ContactPhase`]
    #[serde(with = "crate::json::contact_phase")]
    pub phase: u32,
    /// index into the robot model's collision objects
    pub robot_object: i32,
    /// human body part ([`crate::BodyPart`] as i32)
    pub human_part: i32,
    /// 1 when the part is designated collaborative (an intended contact)
    #[serde(with = "crate::json::flag")]
    pub intended: u32,
    /// force on the robot now \[N\], base frame (zero at the end)
    #[serde(with = "crate::json::finite_array")]
    pub force: [f64; 3],
    /// largest force magnitude so far \[N\]
    #[serde(with = "crate::json::finite")]
    pub peak_force_n: f64,
    /// contact point \[m\], base frame
    #[serde(with = "crate::json::finite_array")]
    pub point: [f64; 3],
}

impl Zeroed for ContactEvent {}

/// One person as a body tracker sees them.
#[derive(Debug, Clone, Copy, ZeroCopySend, Serialize, Deserialize)]
#[repr(C)]
#[type_name("phri::TrackedPerson")]
pub struct TrackedPerson {
    /// the tracker's id of this person, stable while tracked
    pub id: u32,
    /// 1 while the person is tracked
    #[serde(with = "crate::json::flag")]
    pub tracked: u32,
    /// joint positions \[m\], robot base frame, in [`crate::SkeletonJoint`] order
    pub joints: [[f64; 3]; SKELETON_JOINTS],
    /// confidence of each joint [0, 1]; 0: occluded or not found (its position is then the last guess)
    pub confidence: [f64; SKELETON_JOINTS],
}

/// The people a body tracker sees in one depth frame (`perception/skeleton`):
/// the same sequence number and capture times as the frame. A real tracker
/// (OpenNI/NiTE-class) publishes the same message; the simulated camera
/// stands in for one.
#[derive(Debug, Clone, Copy, ZeroCopySend, Serialize, Deserialize)]
#[repr(C)]
#[type_name("phri::Skeleton")]
pub struct Skeleton {
    /// the depth frame's number
    pub seq: u64,
    /// the frame's capture time [ns, robot clock]
    pub capture_ns: u64,
    /// the frame's capture time [ns, CLOCK_MONOTONIC]
    pub capture_wall_ns: u64,
    /// when this was published [ns, CLOCK_MONOTONIC]
    pub published_ns: u64,
    /// valid entries of `people`
    pub n_people: u32,
    /// padding, not in the JSON view
    #[serde(skip)]
    pub _pad: u32,
    /// the people seen (the first `n_people`)
    pub people: [TrackedPerson; MAX_PEOPLE],
}

impl Zeroed for Skeleton {}

/// A request to the robot from a person (`hri/request`; several publishers:
/// the gesture recogniser, the voice recogniser, `phri-hri`).
#[derive(Debug, Clone, Copy, ZeroCopySend, Serialize, Deserialize)]
#[repr(C)]
#[type_name("phri::HriRequest")]
pub struct HriRequest {
    /// sequence number (per source)
    pub seq: u64,
    /// when it was made [ns, CLOCK_MONOTONIC]
    pub stamp_ns: u64,
    /// voice: when the utterance ended [ns, CLOCK_MONOTONIC] (0: not voice)
    pub utterance_end_ns: u64,
    /// [`crate::RequestSource`]
    #[serde(with = "crate::json::request_source")]
    pub source: u32,
    /// [`crate::RequestKind`]
    #[serde(with = "crate::json::request_kind")]
    pub kind: u32,
    /// [`crate::CollabPart`] named (`none`: none)
    #[serde(with = "crate::json::collab_part")]
    pub part: u32,
    /// the tracker's id of the person asking (u32::MAX: whoever shows the part)
    pub person: u32,
    /// how sure the recogniser is [0, 1]
    #[serde(with = "crate::json::finite")]
    pub confidence: f64,
    /// the recogniser's own score (voice: the decoder's; 0 otherwise)
    #[serde(with = "crate::json::finite")]
    pub score: f64,
    /// what was recognised (voice: the words; gesture: the gesture), UTF-8, zero padded
    #[serde(with = "crate::json::c_string")]
    pub text: [u8; REQUEST_TEXT],
}

impl Zeroed for HriRequest {}

/// A chunk of microphone audio (`audio/mic`), as a capture driver publishes
/// it: mono 16-bit PCM at [`AUDIO_RATE_HZ`], [`AUDIO_CHUNK_SAMPLES`] samples
/// (20 ms) with the capture time of the first one. Chunks follow each other
/// without gaps; a gap in `seq` is audio lost.
#[derive(Debug, Clone, Copy, ZeroCopySend, Serialize, Deserialize)]
#[repr(C)]
#[type_name("phri::AudioChunk")]
pub struct AudioChunk {
    /// chunk number: a gap is audio lost
    pub seq: u64,
    /// capture time of the first sample [ns, CLOCK_MONOTONIC]
    pub capture_ns: u64,
    /// when this was published [ns, CLOCK_MONOTONIC]
    pub published_ns: u64,
    /// sample rate \[Hz\]
    pub rate_hz: u32,
    /// valid samples in `pcm` (≤ [`AUDIO_CHUNK_SAMPLES`])
    pub samples: u32,
    /// mono 16-bit PCM [full scale ±32768]
    #[serde(with = "crate::json::i16_array")]
    pub pcm: [i16; AUDIO_CHUNK_SAMPLES],
}

impl Zeroed for AudioChunk {}

/// One utterance the voice recogniser heard (`voice/utterance`), whatever
/// became of it: the words, the score, and the verdict (a request published,
/// or why not).
#[derive(Debug, Clone, Copy, ZeroCopySend, Serialize, Deserialize)]
#[repr(C)]
#[type_name("phri::Utterance")]
pub struct Utterance {
    /// sequence number
    pub seq: u64,
    /// speech began / ended [ns, CLOCK_MONOTONIC: `audio/mic`'s capture clock]
    pub start_ns: u64,
    /// speech ended \[ns, CLOCK_MONOTONIC\] (`audio/mic`'s capture clock)
    pub end_ns: u64,
    /// when the verdict was reached [ns, CLOCK_MONOTONIC]
    pub decoded_ns: u64,
    /// decoding time \[ms\]
    #[serde(with = "crate::json::finite")]
    pub decode_ms: f64,
    /// the recogniser's score: acoustic log-likelihood per 10 ms frame of the
    /// command against a free phone loop (higher: surer; 0 when nothing decoded)
    #[serde(with = "crate::json::finite")]
    pub score: f64,
    /// [`crate::VoiceIntent`] recognised (`none`: no command)
    #[serde(with = "crate::json::voice_intent")]
    pub intent: u32,
    /// [`crate::VoiceVerdict`]
    #[serde(with = "crate::json::voice_verdict")]
    pub verdict: u32,
    /// `seq` of the `hri/request` published for it (0: none)
    pub request_seq: u64,
    /// the words recognised (empty: none), UTF-8, zero padded
    #[serde(with = "crate::json::c_string")]
    pub text: [u8; REQUEST_TEXT],
}

impl Zeroed for Utterance {}

/// The collaborative hand as depth ingestion sees it (`perception/hand`),
/// per frame while a collaboration is on: the tracker's hand refined from
/// the depth pixels around it; those pixels were removed from the frame the
/// repulsion workers see.
#[derive(Debug, Clone, Copy, ZeroCopySend, Serialize, Deserialize)]
#[repr(C)]
#[type_name("phri::HandObservation")]
pub struct HandObservation {
    /// the depth frame's number
    pub seq: u64,
    /// the frame's capture time [ns, robot clock]
    pub capture_ns: u64,
    /// when this was published [ns, CLOCK_MONOTONIC]
    pub published_ns: u64,
    /// the tracker's id of the person
    pub person: u32,
    /// [`crate::CollabPart`]
    #[serde(with = "crate::json::collab_part")]
    pub part: u32,
    /// 1 when the position was refined from depth pixels (0: the tracker's alone)
    #[serde(with = "crate::json::flag")]
    pub refined: u32,
    /// depth pixels removed around the hand (the mask)
    pub masked_pixels: u32,
    /// the hand's position \[m\], base frame: the centre of the depth points around the tracked hand
    #[serde(with = "crate::json::finite_array")]
    pub position: [f64; 3],
    /// the tracker's hand position \[m\], base frame
    #[serde(with = "crate::json::finite_array")]
    pub tracked: [f64; 3],
    /// the tracker's confidence of the hand [0, 1]
    #[serde(with = "crate::json::finite")]
    pub confidence: f64,
}

impl Zeroed for HandObservation {}

/// One estimated contact force in a [`CollabState`] (paper eqs. 22-23).
#[derive(Debug, Clone, Copy, Default, ZeroCopySend, Serialize, Deserialize)]
#[repr(C)]
#[type_name("phri::ContactForce")]
pub struct ContactForce {
    /// the contact point \[m\], base frame
    #[serde(with = "crate::json::finite_array")]
    pub point: [f64; 3],
    /// force applied by the human on the robot \[N\], base frame
    #[serde(with = "crate::json::finite_array")]
    pub force: [f64; 3],
    /// the robot link it acts on (index of the model's frames; −1: none)
    pub frame: i32,
    /// 0 when the force is not observable from the residual (a contact on
    /// links 1-2, or the stacked Jacobian lost rank): then `force` holds only
    /// what the damped pseudoinverse recovers, not the whole force
    #[serde(with = "crate::json::flag")]
    pub observable: u32,
}

/// The collaboration, as the controller runs it (`collab/state`, 1 kHz).
#[derive(Debug, Clone, Copy, ZeroCopySend, Serialize, Deserialize)]
#[repr(C)]
#[type_name("phri::CollabState")]
pub struct CollabState {
    /// sequence number
    pub seq: u64,
    /// publish time [ns, CLOCK_MONOTONIC]
    pub stamp_ns: u64,
    /// measurement time of the state answered [ns, robot clock]
    pub state_stamp_ns: u64,
    /// [`crate::CollabPhase`]
    #[serde(with = "crate::json::collab_phase")]
    pub phase: u32,
    /// [`crate::CollabReason`] of the last change of phase
    #[serde(with = "crate::json::collab_reason")]
    pub reason: u32,
    /// the tracker's id of the collaborating person
    pub person: u32,
    /// [`crate::CollabPart`]: the collaborative human part
    #[serde(with = "crate::json::collab_part")]
    pub human_part: u32,
    /// the collaborative robot part: the model frame that may touch (−1: none)
    pub robot_frame: i32,
    /// the last request answered: its source ([`crate::RequestSource`], 0: none yet),
    /// kind, part, whether it was accepted and why ([`crate::CollabReason`])
    pub request_source: u32,
    /// the last request answered: its kind ([`crate::RequestKind`])
    pub request_kind: u32,
    /// the last request answered: its part ([`crate::CollabPart`])
    pub request_part: u32,
    /// the last request answered: 1 when it was accepted
    #[serde(with = "crate::json::flag")]
    pub request_accepted: u32,
    /// the last request answered: why ([`crate::CollabReason`])
    #[serde(with = "crate::json::collab_reason")]
    pub request_reason: u32,
    /// the last request answered: its sequence number (per source) and when it was made [ns, CLOCK_MONOTONIC]
    pub request_seq: u64,
    /// the last request answered: when it was made \[ns, CLOCK_MONOTONIC\]
    pub request_stamp_ns: u64,
    /// the collaborative hand the controller uses \[m\], base frame
    #[serde(with = "crate::json::finite_array")]
    pub hand: [f64; 3],
    /// age of that hand observation \[ns\] (u64::MAX: none)
    #[serde(with = "crate::json::opt_ns")]
    pub hand_age_ns: u64,
    /// ‖r − Σ J_kᵀ F̂_k‖: the residual the intended contacts do not explain \[Nm\]
    #[serde(with = "crate::json::finite")]
    pub unexplained_norm: f64,
    /// valid entries of `forces`
    pub n_forces: u32,
    /// requests this controller may have lost since it started: each time
    /// it found its `hri/request` queue full after not reading it for
    /// `phri_ipc::DELIVERY_WAIT` (a publisher may have left it out), once
    /// (what was the padding: same size)
    pub requests_dropped: u32,
    /// the estimated contact forces (the first `n_forces`)
    pub forces: [ContactForce; MAX_COLLAB_FORCES],
}

impl Zeroed for CollabState {}

/// Speed and separation monitoring (ISO/TS 15066 clause 5.5.4) from the
/// controller, one per command: what the monitor did this period and in
/// total since the controller started (a restarted controller counts anew).
#[derive(Debug, Clone, Copy, ZeroCopySend, Serialize, Deserialize)]
#[repr(C)]
#[type_name("phri::SsmStatus")]
pub struct SsmStatus {
    /// sequence number
    pub seq: u64,
    /// publish time [ns, CLOCK_MONOTONIC]
    pub stamp_ns: u64,
    /// measurement time of the state answered [ns, robot clock]
    pub state_stamp_ns: u64,
    /// 1: configured (`[ssm] enabled`)
    #[serde(with = "crate::json::flag")]
    pub enabled: u32,
    /// 1: monitoring this period (configured, outside the collaboration, perception fresh)
    #[serde(with = "crate::json::flag")]
    pub monitoring: u32,
    /// 1: it bounded some control point's approach this period
    #[serde(with = "crate::json::flag")]
    pub limiting: u32,
    /// 1: a violation this period: a control point had been moving toward its
    /// obstacle inside the protective separation distance for longer than
    /// the stop time T_s
    #[serde(with = "crate::json::flag")]
    pub violating: u32,
    /// periods it bounded some approach
    pub limited_periods: u64,
    /// periods of violation
    pub violation_periods: u64,
    /// violations: runs of such periods
    pub violations: u64,
    /// the smallest clearance less the protective separation distance over the control points \[m\] (null: none monitored)
    #[serde(with = "crate::json::distance")]
    pub min_margin_m: f64,
    /// the largest person's speed toward a control point used [m/s]
    #[serde(with = "crate::json::finite")]
    pub human_speed_m_s: f64,
    /// T_r: the age of the perception acted on \[s\] (null: not monitoring)
    #[serde(with = "crate::json::finite")]
    pub reaction_s: f64,
    /// violations of the standard's own protective separation distance:
    /// ISO 13855's human speed in place of the configured one, the same
    /// other terms (8 bytes added)
    pub violations_standard: u64,
}

impl Zeroed for SsmStatus {}

/// The control-barrier safety filter (`[avoidance] law = "cbf"`) from the
/// controller in charge, one per command while that law runs (none under
/// the paper's law): what the filter did this period and in total since the
/// controller started (a restarted controller counts anew).
#[derive(Debug, Clone, Copy, ZeroCopySend, Serialize, Deserialize)]
#[repr(C)]
#[type_name("phri::BarrierStatus")]
pub struct BarrierStatus {
    /// sequence number
    pub seq: u64,
    /// publish time [ns, CLOCK_MONOTONIC]
    pub stamp_ns: u64,
    /// measurement time of the state answered [ns, robot clock]
    pub state_stamp_ns: u64,
    /// 1: a barrier changed the motion this period (some control point's
    /// approach was braked)
    #[serde(with = "crate::json::flag")]
    pub braking: u32,
    /// 1: no motion within the joints' bounds kept every barrier this
    /// period: the slack moved the points away as well as it could
    #[serde(with = "crate::json::flag")]
    pub slack: u32,
    /// 1: the solver failed this period: the reference braked to rest
    #[serde(with = "crate::json::flag")]
    pub failed: u32,
    /// padding, not in the JSON view
    #[serde(skip)]
    pub _pad: u32,
    /// periods the filter ran
    pub periods: u64,
    /// periods a barrier changed the motion
    pub braking_periods: u64,
    /// periods that needed the slack
    pub slack_periods: u64,
    /// periods the solver failed
    pub failed_periods: u64,
    /// the most active-set changes of one solve
    pub max_iterations: u64,
}

impl Zeroed for BarrierStatus {}

/// Bytes of a controller's behaviour state in [`ControlBehaviour`].
pub const BEHAVIOUR_BYTES: usize = 8192;

/// A controller's behaviour state after its step (mode, path time, the
/// collaboration's phase, reaction and integrator states): published by
/// the controller in charge every period, adopted by the other one (the
/// hot standby) before its next step. The bytes are the controller's own
/// layout (`phri_control::snapshot`): only a controller of the same
/// configuration reads them.
#[derive(Debug, Clone, Copy, ZeroCopySend, Serialize, Deserialize)]
#[repr(C)]
#[type_name("phri::ControlBehaviour")]
pub struct ControlBehaviour {
    /// sequence number
    pub seq: u64,
    /// publish time [ns, CLOCK_MONOTONIC]
    pub stamp_ns: u64,
    /// the state whose step left this behaviour
    pub state_seq: u64,
    /// measurement time of that state \[ns, robot clock\]
    pub state_stamp_ns: u64,
    /// bytes used in `bytes`
    pub len: u32,
    /// padding, not in the JSON view
    #[serde(skip)]
    pub _pad: u32,
    /// the behaviour state: `len` bytes in the controller's own layout (not in
    /// the JSON view); past `len` unspecified (a publisher sends the bytes in
    /// use only, [`ControlBehaviour::used_bytes`])
    #[serde(skip, default = "crate::json::zero_bytes")]
    pub bytes: [u8; BEHAVIOUR_BYTES],
}

impl Zeroed for ControlBehaviour {}

impl ControlBehaviour {
    /// The behaviour state's bytes: the first `len` of `bytes` (all of them
    /// when `len` says more).
    pub fn snapshot(&self) -> &[u8] {
        &self.bytes[..(self.len as usize).min(self.bytes.len())]
    }

    /// The message's bytes in use: its header and the snapshot's (what a
    /// publisher sends, [`crate::Publisher::publish_head`]; the rest of
    /// `bytes` is left unspecified on the channel).
    pub fn used_bytes(&self) -> usize {
        std::mem::offset_of!(ControlBehaviour, bytes) + self.snapshot().len()
    }
}

/// Which controller commanded the robot, from the robot adapter (the
/// simulator or a real arm's): 10 Hz and at every takeover, cumulative
/// since the adapter started. Slot 0 is the controller on `robot/command`,
/// slot 1 the one on `robot/command/standby`.
#[derive(Debug, Clone, Copy, ZeroCopySend, Serialize, Deserialize)]
#[repr(C)]
#[type_name("phri::CommanderStats")]
pub struct CommanderStats {
    /// sequence number
    pub seq: u64,
    /// publish time [ns, CLOCK_MONOTONIC]
    pub stamp_ns: u64,
    /// the slot in charge now (0 or 1)
    pub in_charge: u32,
    /// padding, not in the JSON view
    #[serde(skip)]
    pub _pad: u32,
    /// periods whose applied command was each slot's fresh answer
    pub periods: [u64; 2],
    /// periods both slots answered the same state
    pub both_answered: u64,
    /// takeovers: the slot not in charge answered for the one in charge
    pub takeovers: u64,
    /// the last takeover: the state answered [ns, robot clock] and its number (0: none yet)
    pub last_takeover_state_stamp_ns: u64,
    /// the last takeover: the `seq` of the state answered (0: none yet)
    pub last_takeover_state_seq: u64,
    /// the slot that took over
    pub last_takeover_to: u32,
    /// the yardstick of a takeover's difference: the largest joint change
    /// of the applied command from one period to the next without a
    /// takeover, both periods fresh and the brakes off \[Nm\]. Was padding:
    /// the layout and size are unchanged.
    pub max_step_nm: f32,
    /// largest joint difference between the command taking over and the
    /// last command applied before \[Nm\]
    #[serde(with = "crate::json::finite")]
    pub last_takeover_diff_nm: f64,
    /// the largest such difference so far \[Nm\]
    #[serde(with = "crate::json::finite")]
    pub max_takeover_diff_nm: f64,
    /// the largest joint difference between the two slots' answers to the
    /// same state, while both answered and the brakes were off \[Nm\]
    #[serde(with = "crate::json::finite")]
    pub max_answer_diff_nm: f64,
    /// commands refused per slot because their sender is not the controller
    /// the supervisor started for that slot (never applied)
    pub refused_stranger: [u64; 2],
    /// commands refused per slot as malformed (wrong joint count, a
    /// non-finite torque)
    pub refused_malformed: [u64; 2],
    /// the newest refused stranger's pid (0: none)
    pub stranger_pid: i32,
    /// padding, not in the JSON view
    #[serde(skip)]
    pub _pad2: u32,
}

impl Zeroed for CommanderStats {}

/// `impl Message`: the publish time (and stream) of a message type, and the
/// arrays cut to a count in its JSON view (`counted: [dof => q, tau; n => xs]`;
/// the fields must exist: checked at compile time).
macro_rules! message {
    (
        $t:ty, published: |$m:ident| $published:expr
        $(, stream: |$s:ident| $stream:expr)?
        $(, counted: [$($count:ident => $($array:ident),+);+])?
    ) => {
        impl crate::channel::Message for $t {
            $(const COUNTED: &'static [crate::json::Counted] =
                &[$((stringify!($count), &[$(stringify!($array)),+])),+];)?
            fn seq(&self) -> u64 {
                self.seq
            }
            fn published_ns(&self) -> Option<u64> {
                let $m = self;
                $published
            }
            $(fn stream(&self) -> u64 {
                let $s = self;
                $stream
            })?
        }
        $(const _: () = {
            // every counted name is a field: a count and arrays
            #[allow(dead_code)]
            fn counted_fields_exist(m: &$t) {
                $(let _: u32 = m.$count; $(let _ = m.$array.len();)+)+
            }
        };)?
    };
}

message!(JointState, published: |m| Some(m.published_ns), counted: [dof => q, tau]);
message!(TorqueCommand, published: |m| Some(m.stamp_ns), counted: [dof => tau]);
message!(Residual, published: |m| Some(m.stamp_ns), counted: [dof => r, qd]);
message!(ControlStatus, published: |m| Some(m.stamp_ns));
message!(Truth, published: |_m| None, counted: [dof => tau_ext, q, qd; n_contacts => contacts]);
message!(RobotStats, published: |_m| None);
message!(Health, published: |m| Some(m.stamp_ns), counted: [count => services]);
message!(WorldState, published: |_m| None, counted: [dof => q; n_human => human]);
message!(
    RepulsionResult,
    published: |m| Some(m.published_ns),
    stream: |m| m.worker as u64,
    counted: [n_points => points]
);
message!(DepthFault, published: |m| Some(m.stamp_ns));
message!(ContactEvent, published: |_m| None);
message!(Skeleton, published: |m| Some(m.published_ns), counted: [n_people => people]);
message!(HriRequest, published: |m| Some(m.stamp_ns), stream: |m| m.source as u64);
message!(HandObservation, published: |m| Some(m.published_ns));
message!(AudioChunk, published: |m| Some(m.published_ns), counted: [samples => pcm]);
message!(Utterance, published: |m| Some(m.decoded_ns));
message!(CollabState, published: |m| Some(m.stamp_ns), counted: [n_forces => forces]);
message!(SsmStatus, published: |m| Some(m.stamp_ns));
message!(BarrierStatus, published: |m| Some(m.stamp_ns));
message!(ControlBehaviour, published: |m| Some(m.stamp_ns));
message!(CommanderStats, published: |m| Some(m.stamp_ns));
message!(InputAudit, published: |m| Some(m.stamp_ns), stream: |m| m.service.iter().fold(0u64, |a, &b| a.wrapping_mul(31).wrapping_add(u64::from(b))));
message!(BoxStatus, published: |m| Some(m.stamp_ns), counted: [dof => tau_j, tau_ext_hat]);
message!(BridgeRequests, published: |m| Some(m.stamp_ns));
message!(CameraStatus, published: |m| Some(m.stamp_ns), stream: |m| u64::from(m.camera));
message!(MicStatus, published: |m| Some(m.stamp_ns));
