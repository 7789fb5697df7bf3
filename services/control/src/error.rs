//! Why a controller could not be built, or an input message was refused;
//! each error names the configuration key, link or channel at fault.

use phri_model::LengthError;

/// Why [`crate::Controller`] could not be built from its configuration.
#[derive(Debug, thiserror::Error)]
pub enum ControlError {
    /// a `[control]` value out of range ([`phri_config::ControlConfig::validate`])
    #[error(transparent)]
    Invalid(#[from] phri_config::Invalid),
    /// a configured link the robot model does not have
    #[error("{key}: the robot has no link '{link}'")]
    UnknownLink {
        /// the configuration key that names the link
        key: String,
        /// the link named
        link: String,
    },
    /// a per-joint list (`control.posture`) with another count than the model's joints
    #[error("control.{0}")]
    Length(#[from] LengthError),
    /// the control period (`sim.dt_s`) is not a positive number of seconds
    #[error("sim.dt_s: the control period {period_s} s is not a positive number")]
    Period {
        /// the period given \[s\]
        period_s: f64,
    },
    /// more joints than the messages (and the controller's stack buffers) carry
    #[error("the robot has {joints} joints, the controller handles at most {max}")]
    TooManyJoints {
        /// the model's joints
        joints: usize,
        /// the most the controller handles (`phri_ipc::MAX_DOF`)
        max: usize,
    },
    /// `[control] avoidance` without repulsion workers or control points
    #[error("repulsion.points: control.avoidance needs at least one control point (the first is the end effector)")]
    NoControlPoints,
    /// the control-barrier filter's solver could not be set up (`[avoidance] law = "cbf"`)
    #[error("avoidance.law = \"cbf\": the filter's solver: {0}")]
    Solver(#[from] phri_qp::QpError),
}

/// A message the controller refuses as an input: the channel and field at fault.
#[derive(Clone, Copy, Debug, PartialEq, Eq, thiserror::Error)]
pub enum InputError {
    /// a joint-space message for another robot
    #[error("{channel}: message {seq} has dof {got}, the model has {expected} joints")]
    Dof {
        /// the channel the message came on
        channel: &'static str,
        /// the message's sequence number
        seq: u64,
        /// the model's joints
        expected: usize,
        /// the message's dof
        got: u32,
    },
    /// a repulsion result from a worker the configuration does not have
    #[error(
        "perception/repulsion: worker {worker} is not one of the {workers} configured workers"
    )]
    Worker {
        /// the worker the result names
        worker: u32,
        /// the workers configured
        workers: usize,
    },
    /// a repulsion result of a camera the cell does not have
    #[error(
        "perception/repulsion: camera {camera} is not one of the {cameras} configured cameras"
    )]
    Camera {
        /// the camera the result came from
        camera: usize,
        /// the cameras configured
        cameras: usize,
    },
    /// a repulsion result that claims more points than the message carries
    #[error("perception/repulsion: worker {worker}: n_points {n_points} is above {max}")]
    PointCount {
        /// the worker the result names
        worker: u32,
        /// the points the result claims
        n_points: u32,
        /// the most points a result carries
        max: usize,
    },
    /// a repulsion result with a non-finite repulsive vector, or a NaN distance
    #[error("perception/repulsion: worker {worker}: point {point}: v_call not finite or min_distance NaN")]
    NonFinite {
        /// the worker the result names
        worker: u32,
        /// the control point at fault
        point: u32,
    },
    /// a repulsion result for a control point the configuration does not have
    #[error("perception/repulsion: worker {worker}: point {point} is not one of the {points} configured control points")]
    Point {
        /// the worker the result names
        worker: u32,
        /// the control point the result names
        point: u32,
        /// the control points configured
        points: usize,
    },
}
