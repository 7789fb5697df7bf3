//! Service names: what flows, from whom. Publish-subscribe services and the
//! event services that wake their readers share the name.

/// [`crate::JointState`] from the robot (simulated or real adapter), 1 kHz. Event: new state.
pub const ROBOT_STATE: &str = "robot/state";
/// [`crate::TorqueCommand`] to the robot, one publisher only (the controller). Event: new command.
pub const ROBOT_COMMAND: &str = "robot/command";
/// [`crate::RobotStats`] from the robot adapter: loop timing and latency histogram, 10 Hz.
pub const ROBOT_STATS: &str = "robot/stats";
/// [`crate::Truth`]: simulator ground truth for evaluation only, 1 kHz. No controller may read it.
pub const SIM_TRUTH: &str = "sim/truth";
/// [`crate::Residual`] from the dynamics service, 1 kHz. Event: new residual.
pub const DYNAMICS_RESIDUAL: &str = "dynamics/residual";
/// [`crate::ControlStatus`] from the controller, 1 kHz.
pub const CONTROL_STATUS: &str = "control/status";
/// [`crate::Health`] from the supervisor, 10 Hz.
pub const SUPERVISOR_HEALTH: &str = "supervisor/health";

/// Every publish-subscribe service of the cell, for tools that list or record them.
pub const ALL: &[&str] = &[
    ROBOT_STATE,
    ROBOT_COMMAND,
    ROBOT_STATS,
    SIM_TRUTH,
    DYNAMICS_RESIDUAL,
    CONTROL_STATUS,
    SUPERVISOR_HEALTH,
    SIM_WORLD,
    CAMERA_DEPTH,
    PERCEPTION_DEPTH,
    PERCEPTION_REPULSION,
    FAULT_DEPTH,
];

/// Channels that carry messages only while a tool injects something (no
/// publisher in a healthy cell): monitors and tests must not expect traffic.
pub const ON_DEMAND: &[&str] = &[FAULT_DEPTH];

/// [`crate::WorldState`]: the simulated world for the simulated camera, 1 kHz. Simulation only.
pub const SIM_WORLD: &str = "sim/world";
/// Raw depth frames from the camera (`[u16]` with a [`crate::FrameHeader`]), 30 Hz.
pub const CAMERA_DEPTH: &str = "camera/depth";
/// Validated depth frames without the robot's own pixels (`[u16]` with a [`crate::FrameHeader`]). Event: new frame.
pub const PERCEPTION_DEPTH: &str = "perception/depth";
/// [`crate::RepulsionResult`] from every repulsion worker (one publisher each).
pub const PERCEPTION_REPULSION: &str = "perception/repulsion";
/// [`crate::DepthFault`] from `phri-fault` to the simulated camera: frames to corrupt or delay (testing only).
pub const FAULT_DEPTH: &str = "fault/depth";
