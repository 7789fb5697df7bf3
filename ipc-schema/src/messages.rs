//! Message types. All are plain data: `#[repr(C)]`, no pointers, fixed size.

use iceoryx2::prelude::*;

/// Largest number of joints a message carries.
pub const MAX_DOF: usize = 12;
/// Largest number of simultaneous contacts in [`Truth`].
pub const MAX_CONTACTS: usize = 8;
/// Latency histogram bins of [`RobotStats`]: 1 µs each, the last one collects everything above.
pub const LATENCY_BINS: usize = 2000;
/// Services tracked in [`Health`].
pub const MAX_SERVICES: usize = 16;
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
}

/// Measured joint state, published by the robot every control period.
#[derive(Debug, Clone, Copy, ZeroCopySend)]
#[repr(C)]
#[type_name("phri::JointState")]
pub struct JointState {
    pub seq: u64,
    /// measurement time [ns]: the robot's cycle clock (CLOCK_MONOTONIC at
    /// start, then exactly one period per state)
    pub stamp_ns: u64,
    /// when the robot published it [ns, CLOCK_MONOTONIC]
    pub published_ns: u64,
    pub dof: u32,
    /// [`robot_status`] bits
    pub status: u32,
    /// measured joint positions [rad or m] (encoders; no velocities)
    pub q: [f64; MAX_DOF],
    /// joint torque applied in the last period [Nm] (command after limits, or brake torque)
    pub tau: [f64; MAX_DOF],
    /// wrist force/torque [N, Nm]: force then moment, base frame, at the last link's origin
    pub wrench: [f64; 6],
    /// `seq` of the command applied in the last period (0: none yet)
    pub command_seq: u64,
    /// consecutive periods without a fresh command
    pub missed_commands: u32,
    pub _pad: u32,
}

/// Control modes reported in [`TorqueCommand::mode`] and [`ControlStatus::mode`].
pub mod control_mode {
    /// waiting for the first fresh inputs, re-syncing to the measured state
    pub const SYNC: u32 = 0;
    /// executing the task
    pub const TASK: u32 = 1;
    /// reacting to a detected collision
    pub const REACTION: u32 = 2;
    /// holding still because a safety input is stale
    pub const PROTECTIVE_STOP: u32 = 3;
    /// reaction over, waiting for the residual to settle before resuming
    pub const RECOVER: u32 = 4;
    /// slowed down because perception is stale
    pub const SLOW: u32 = 5;

    pub fn name(mode: u32) -> &'static str {
        match mode {
            SYNC => "sync",
            TASK => "task",
            REACTION => "reaction",
            PROTECTIVE_STOP => "protective_stop",
            RECOVER => "recover",
            SLOW => "slow",
            _ => "unknown",
        }
    }
}

/// Joint torque command, answering one [`JointState`].
#[derive(Debug, Clone, Copy, ZeroCopySend)]
#[repr(C)]
#[type_name("phri::TorqueCommand")]
pub struct TorqueCommand {
    pub seq: u64,
    /// publish time [ns]
    pub stamp_ns: u64,
    /// the state this command answers
    pub state_seq: u64,
    pub state_stamp_ns: u64,
    pub dof: u32,
    /// [`control_mode`]
    pub mode: u32,
    /// motor torque [Nm], limits already enforced
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
#[derive(Debug, Clone, Copy, ZeroCopySend)]
#[repr(C)]
#[type_name("phri::Residual")]
pub struct Residual {
    pub seq: u64,
    /// publish time [ns]
    pub stamp_ns: u64,
    pub state_seq: u64,
    pub state_stamp_ns: u64,
    pub dof: u32,
    /// [`residual_flags`]
    pub flags: u32,
    /// last joint whose residual passed its contact threshold (−1: none): the
    /// colliding link is this joint's link or one after it (paper Sect. III)
    pub isolated_joint: i32,
    pub _pad: u32,
    /// residual r ≈ τ_ext [Nm]
    pub r: [f64; MAX_DOF],
    /// joint velocity estimated from positions [rad/s]
    pub qd: [f64; MAX_DOF],
    /// ‖r‖ [Nm]
    pub norm: f64,
    /// time spent computing [ns]
    pub compute_ns: u64,
}

/// Controller status, one per command.
#[derive(Debug, Clone, Copy, ZeroCopySend)]
#[repr(C)]
#[type_name("phri::ControlStatus")]
pub struct ControlStatus {
    pub seq: u64,
    /// publish time [ns, CLOCK_MONOTONIC]
    pub stamp_ns: u64,
    pub state_seq: u64,
    /// measurement time of the state answered [ns, robot clock]
    pub state_stamp_ns: u64,
    /// [`control_mode`]
    pub mode: u32,
    /// configured reaction strategy (index into the controller's list)
    pub reaction: u32,
    /// task waypoints reached since start
    pub waypoints_reached: u64,
    pub detections: u64,
    pub protective_stops: u64,
    pub resumes: u64,
    /// age of the residual used [ns] (u64::MAX: none)
    pub residual_age_ns: u64,
    /// joint reference [rad]
    pub q_ref: [f64; MAX_DOF],
    /// end-effector position [m], base frame
    pub ee: [f64; 3],
    /// time spent computing [ns]
    pub compute_ns: u64,
    /// state published → this controller woke [ns]
    pub wake_latency_ns: u64,
    /// age of the perception results used [ns] (u64::MAX: none)
    pub perception_age_ns: u64,
    /// smallest obstacle distance of the control points last seen [m]
    pub min_distance: f64,
    /// largest repulsion risk ‖V_Call‖/V_max over the control points [0, 1]
    pub risk: f64,
    /// SNS task scale [0, 1]
    pub task_scale: f64,
}

/// One contact in [`Truth`].
#[derive(Debug, Clone, Copy, Default, ZeroCopySend)]
#[repr(C)]
#[type_name("phri::ContactTruth")]
pub struct ContactTruth {
    /// index into the robot model's collision objects
    pub robot_object: i32,
    /// human body part index (simulator's numbering)
    pub human_part: i32,
    /// 1 when the part is designated collaborative
    pub intended: u32,
    pub _pad: u32,
    /// force on the robot [N], base frame
    pub force: [f64; 3],
    /// contact point [m], base frame
    pub point: [f64; 3],
    /// penetration [m]
    pub depth: f64,
}

/// Simulator ground truth. For evaluation only.
#[derive(Debug, Clone, Copy, ZeroCopySend)]
#[repr(C)]
#[type_name("phri::Truth")]
pub struct Truth {
    pub seq: u64,
    pub stamp_ns: u64,
    /// the [`JointState`] published with this truth
    pub state_seq: u64,
    pub n_contacts: u32,
    pub dof: u32,
    /// true external joint torque [Nm]
    pub tau_ext: [f64; MAX_DOF],
    pub q: [f64; MAX_DOF],
    pub qd: [f64; MAX_DOF],
    /// human-robot surface distance [m] (negative: penetration; +inf: no human)
    pub min_distance: f64,
    pub contacts: [ContactTruth; MAX_CONTACTS],
}

/// Robot loop statistics, cumulative since the robot process started.
#[derive(Debug, Clone, Copy, ZeroCopySend)]
#[repr(C)]
#[type_name("phri::RobotStats")]
pub struct RobotStats {
    pub seq: u64,
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
    /// largest state-published → command-received latency [ns]
    pub latency_max_ns: u64,
    /// latency histogram, 1 µs bins; the last bin holds everything above
    pub latency_hist: [u32; LATENCY_BINS],
}

/// One supervised service in [`Health`].
#[derive(Debug, Clone, Copy, ZeroCopySend)]
#[repr(C)]
#[type_name("phri::ServiceHealth")]
pub struct ServiceHealth {
    /// service name, UTF-8, zero padded
    pub name: [u8; 32],
    pub pid: i32,
    /// 1 while the process runs
    pub alive: u32,
    pub restarts: u32,
    pub _pad: u32,
    /// last start [ns]
    pub started_ns: u64,
}

impl ServiceHealth {
    pub fn name_str(&self) -> &str {
        let end = self
            .name
            .iter()
            .position(|&b| b == 0)
            .unwrap_or(self.name.len());
        std::str::from_utf8(&self.name[..end]).unwrap_or("?")
    }
}

/// Supervisor's view of the services.
#[derive(Debug, Clone, Copy, ZeroCopySend)]
#[repr(C)]
#[type_name("phri::Health")]
pub struct Health {
    pub seq: u64,
    pub stamp_ns: u64,
    pub count: u32,
    pub _pad: u32,
    pub services: [ServiceHealth; MAX_SERVICES],
}

/// A zeroed value of a plain-data message (all fields are numbers).
pub trait Zeroed: Sized + Copy {
    fn zeroed() -> Self {
        // SAFETY: every message type is #[repr(C)] of integers and floats, for
        // which all-zero bytes are a valid value.
        unsafe { std::mem::zeroed() }
    }
}

impl Zeroed for JointState {}
impl Zeroed for TorqueCommand {}
impl Zeroed for Residual {}
impl Zeroed for ControlStatus {}
impl Zeroed for Truth {}
impl Zeroed for RobotStats {}
impl Zeroed for Health {}

/// One capsule of the simulated world: segment `a`–`b` swept by `radius` [m], base frame.
#[derive(Debug, Clone, Copy, Default, ZeroCopySend)]
#[repr(C)]
#[type_name("phri::WorldCapsule")]
pub struct WorldCapsule {
    pub a: [f64; 3],
    pub b: [f64; 3],
    pub radius: f64,
    /// human body part index (simulator's numbering)
    pub part: i32,
    pub _pad: u32,
}

/// The simulated world a simulated camera sees: the arm's true joints and the
/// human's capsules, on the robot's clock. Simulation only.
#[derive(Debug, Clone, Copy, ZeroCopySend)]
#[repr(C)]
#[type_name("phri::WorldState")]
pub struct WorldState {
    pub seq: u64,
    /// [ns, robot clock]
    pub stamp_ns: u64,
    pub dof: u32,
    pub n_human: u32,
    /// true joint positions [rad]
    pub q: [f64; MAX_DOF],
    pub human: [WorldCapsule; MAX_HUMAN_CAPSULES],
}

/// Header of a depth frame (`camera/depth`, `perception/depth`): the payload
/// is `width × height` `u16` depths in millimetres, row-major, 0 = no reading.
#[derive(Debug, Clone, Copy, Default, ZeroCopySend)]
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
    pub width: u32,
    pub height: u32,
    /// pinhole intrinsics [px]
    pub fx: f64,
    pub fy: f64,
    pub cx: f64,
    pub cy: f64,
    /// metres per depth unit (0.001: millimetres)
    pub depth_scale: f64,
    /// camera pose in the base frame: rotation (row-major 3×3, camera axes:
    /// x right, y down, z forward) then translation [m]
    pub pose_r: [f64; 9],
    pub pose_t: [f64; 3],
    /// joint state used to remove the robot's own pixels (perception/depth only)
    pub q: [f64; MAX_DOF],
    /// stamp of that joint state [ns, robot clock] (0: none)
    pub q_stamp_ns: u64,
    pub dof: u32,
    /// pixels removed as the robot's own
    pub removed_pixels: u32,
    /// valid pixels left
    pub valid_pixels: u32,
    pub _pad: u32,
}

/// Result for one control point.
#[derive(Debug, Clone, Copy, Default, ZeroCopySend)]
#[repr(C)]
#[type_name("phri::PointRepulsion")]
pub struct PointRepulsion {
    /// control point index (in the configured list)
    pub point: u32,
    /// 1 when something was within the surveillance region
    pub active: u32,
    /// repulsive velocity V_Call [m/s], base frame (eqs. 16-18)
    pub v_call: [f64; 3],
    /// minimum distance to an obstacle pixel [m] (ρ when none)
    pub min_distance: f64,
    /// the closest obstacle point [m], base frame
    pub obstacle: [f64; 3],
    /// the control point at the frame's joint state [m], base frame
    pub position: [f64; 3],
}

/// One repulsion worker's result for one frame (`perception/repulsion`).
#[derive(Debug, Clone, Copy, ZeroCopySend)]
#[repr(C)]
#[type_name("phri::RepulsionResult")]
pub struct RepulsionResult {
    pub seq: u64,
    /// the frame this answers
    pub frame_seq: u64,
    /// the frame's capture time [ns, robot clock]
    pub capture_ns: u64,
    /// publish time [ns, CLOCK_MONOTONIC]
    pub published_ns: u64,
    /// the frame's capture time [ns, CLOCK_MONOTONIC]
    pub frame_capture_wall_ns: u64,
    pub worker: u32,
    /// workers in the configuration
    pub workers: u32,
    pub n_points: u32,
    pub _pad: u32,
    /// processing time [ns]
    pub compute_ns: u64,
    pub points: [PointRepulsion; MAX_POINTS_PER_WORKER],
}

impl Zeroed for WorldState {}
impl Zeroed for FrameHeader {}
impl Zeroed for RepulsionResult {}

/// Kinds of [`DepthFault`]: what the simulated camera does to its next frames.
pub mod depth_fault {
    /// flying pixels: 2 % of the pixels get random depths (0.5-4 m)
    pub const NOISE: u32 = 1;
    /// every pixel 0 (no return): a blind frame
    pub const ZEROS: u32 = 2;
    /// the header's image size disagrees with the payload
    pub const SIZE: u32 = 3;
    /// capture time one second in the past
    pub const STALE: u32 = 4;
    /// publish every frame `delay_ms` late for `duration_s`
    pub const DELAY: u32 = 5;

    /// Every kind with its name, for command lines and JSON.
    pub const ALL: [(u32, &str); 5] = [
        (NOISE, "noise"),
        (ZEROS, "zeros"),
        (SIZE, "size"),
        (STALE, "stale"),
        (DELAY, "delay"),
    ];

    pub fn name(kind: u32) -> &'static str {
        ALL.iter()
            .find(|(k, _)| *k == kind)
            .map_or("unknown", |(_, n)| n)
    }

    pub fn from_name(name: &str) -> Option<u32> {
        ALL.iter().find(|(_, n)| *n == name).map(|(k, _)| *k)
    }
}

/// A fault for the simulated camera to inject into its depth frames
/// (`phri-fault camera corrupt|delay`), for testing what perception faults
/// cost. A real camera driver ignores this channel.
#[derive(Debug, Clone, Copy, ZeroCopySend)]
#[repr(C)]
#[type_name("phri::DepthFault")]
pub struct DepthFault {
    pub seq: u64,
    /// when it was sent [ns, CLOCK_MONOTONIC]
    pub stamp_ns: u64,
    /// one of [`depth_fault`]
    pub kind: u32,
    /// corruptions: how many consecutive frames
    pub frames: u32,
    /// [`depth_fault::DELAY`]: extra capture → publish delay [ms]
    pub delay_ms: f64,
    /// [`depth_fault::DELAY`]: how long \[s\]
    pub duration_s: f64,
}

impl Zeroed for DepthFault {}
