//! `[control]`: the torque loop's task, reactions, freshness limits and avoidance.

use phri_ipc::Reaction;
use serde::{Deserialize, Serialize};

use crate::check::{finite, non_negative, positive, within};
use crate::error::Invalid;

const S: &str = "control";

/// Controller settings (defaults and their reasons: `deploy/phri.toml`).
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct ControlConfig {
    /// Cartesian waypoints of the end effector \[m\], base frame, visited cyclically
    pub waypoints: Vec<[f64; 3]>,
    /// duration of each segment between waypoints \[s\]
    pub segment_time_s: f64,
    /// link whose origin is the end effector (empty: the deepest link)
    pub ee_link: String,
    /// posture the null space pulls towards \[rad\] (empty: the initial measured posture)
    pub posture: Vec<f64>,
    /// null-space posture gain [1/s]
    pub posture_gain: f64,
    /// Cartesian error gain of the inverse kinematics [1/s]
    pub clik_gain: f64,
    /// damping of the pseudoinverse \[m\]
    pub damping: f64,
    /// joint tracking stiffness of the computed-torque law [1/s²]
    pub kp: f64,
    /// joint tracking damping of the computed-torque law [1/s]
    pub kd: f64,
    /// fraction of each joint's velocity limit the reference may use
    pub velocity_scale: f64,
    /// largest end-effector speed when approaching the path [m/s]
    pub approach_speed: f64,
    /// after the approach, the path's time law ṡ ramps smoothly from 0 to 1 over this \[s\]
    pub path_ramp_s: f64,
    /// end-effector distance within which a waypoint counts as reached \[m\]
    pub waypoint_tolerance: f64,
    /// reaction to a detected collision
    pub reaction: Reaction,
    /// reflex gain K_R of eq. 9 [1/s²·1/Nm]
    pub reflex_gain: f64,
    /// reflex damping D_R of eq. 9 [1/s]
    pub reflex_damping: f64,
    /// admittance gain K_Q of eq. 13 [rad/(N m s)]
    pub admittance_gain: f64,
    /// joint damping while floating [Nm s/rad]
    pub float_damping: f64,
    /// retreat: how far back along the path [s of path time]
    pub retreat_path_s: f64,
    /// retreat: how fast the time law turns \[s\]
    pub retreat_ramp_s: f64,
    /// least time spent reacting before recovering \[s\]
    pub reaction_min_s: f64,
    /// a hot standby controller (`[services.control_standby]`) answers every
    /// state too, adopting the behaviour of the one in charge, and takes
    /// over in the same period when that one misses; false: one controller
    pub standby: bool,
    /// true (the default): the controller not in charge rests through a
    /// state the one in charge has already answered when it looks (takes its
    /// inputs and the path history of the behaviours it receives, neither
    /// steps nor answers; one state in 64 it steps all the same, to compare
    /// the answers); it still takes over in the same period. False: it
    /// steps and answers every state
    pub standby_rests: bool,
    /// the controller on `robot/command/standby`, not in charge, wakes this
    /// often to take the behaviours and inputs queued since, and rests; the
    /// robot wakes it at once (`robot/state/standby`) for a state the one
    /// in charge has not answered, and for every state while it is in
    /// charge. 0: it is woken by every state \[ms\]
    pub standby_wake_ms: f64,
    /// resume the task once the residual stayed below the contact level for `resume_quiet_s`
    pub resume: bool,
    /// how long the residual must stay below the contact level before the
    /// task resumes \[s\]
    pub resume_quiet_s: f64,
    /// a residual older than this (measured from the state it answers) is stale \[ms\]
    pub residual_max_age_ms: f64,
    /// keep this far inside the position limits \[rad\]
    pub position_margin: f64,
    /// collision avoidance from perception (paper Sect. V); off: the task ignores perception
    pub avoidance: bool,
    /// SNS and velocity-bound settings of the avoidance
    pub avoidance_params: AvoidanceParams,
    /// the end effector's position feedback is capped at this speed [m/s], below
    /// the repulsion's V_max, so that repulsion always wins near an obstacle
    pub feedback_max_speed: f64,
    /// the rest of the end effector's position feedback (away from or
    /// beside its obstacle, or with none near) is capped at this [m/s]
    pub feedback_free_speed: f64,
    /// the end effector's feedback may beat its repulsion by a net approach
    /// speed of `approach_gain × (clearance − approach_clearance_m)`: a path
    /// through a person's reach is followed up to this clearance \[m\] ...
    pub approach_clearance_m: f64,
    /// ... at this gain [1/s] (0: the repulsion always wins)
    pub approach_gain: f64,
    /// perception results older than this are stale \[ms\]: with an obstacle last
    /// seen nearer than `near_distance_m` a protective stop, otherwise the task slows down
    pub perception_max_age_ms: f64,
    /// an obstacle last seen nearer than this makes stale perception a
    /// protective stop \[m\]
    pub near_distance_m: f64,
    /// stale this long: protective stop whatever was seen last \[ms\]
    pub perception_stop_after_ms: f64,
    /// speed scale while perception is stale
    pub slow_scale: f64,
    /// repulsive vectors arrive at the frame rate: low-pass them with this time constant \[s\]
    pub repulsion_filter_s: f64,
    /// under avoidance the reference velocity changes by at most this per second [rad/s²]
    pub reference_accel_limit: f64,
    /// what slows the task's path near an obstacle
    pub path_pace: PathPace,
    /// how the body control points (all but the end effector) avoid
    pub body_avoidance: BodyAvoidance,
    /// `null_space`: each body point's speed away from its obstacle, as a
    /// task below the end effector's, is this times `‖V_Call(P)‖`
    pub body_repulsion_gain: f64,
}

/// What slows the task's path near an obstacle (`[control] path_pace`).
#[derive(Clone, Copy, Debug, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum PathPace {
    /// the component of the end effector's repulsive vector against the
    /// path's direction, over `V_max`: the path runs on while the end
    /// effector goes around an obstacle beside it (eq. 19)
    Opposing,
    /// the end effector's whole risk `‖V_Call(P_e)‖/V_max`, whatever its
    /// direction (phri's first pace law)
    Risk,
}

/// How the body control points avoid (`[control] body_avoidance`).
#[derive(Clone, Copy, Debug, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum BodyAvoidance {
    /// eq. 20's velocity bounds, and each point's repulsion as a task of
    /// lower priority in the null space of the end effector's (SNS with a
    /// task hierarchy): the arm moves away, the end effector keeps its path
    NullSpace,
    /// the paper's eq. 20 only: motions toward an obstacle are slowed, none
    /// moves away
    Bounds,
}

/// SNS and joint-velocity-bound settings of the avoidance (`[control.avoidance_params]`).
#[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct AvoidanceParams {
    /// joint acceleration limit of the joint-limit bounds, all joints [rad/s²]
    pub accel_limit: f64,
    /// horizon `T` of the `(Q − q)/T` term of the joint-limit bounds \[s\]
    pub horizon_s: f64,
    /// `V_max` of eq. 16: the largest repulsive speed, full risk [m/s]. Not a
    /// key of its own: always `[repulsion.params] v_max` (one value, one place).
    #[serde(skip)]
    pub v_max_repulsion: f64,
    /// damping `λ` of the pseudoinverse [m/s]
    pub damping: f64,
    /// keep this far inside the model's position limits \[rad\]
    pub position_margin: f64,
}

impl ControlConfig {
    /// Range checks of every field (joint counts and links are checked against the model).
    pub fn validate(&self) -> Result<(), Invalid> {
        if self.waypoints.len() < 2 {
            return Err(Invalid::new("control.waypoints", "need at least two"));
        }
        finite(S, "waypoints", self.waypoints.as_flattened())?;
        for (name, v) in [
            ("segment_time_s", self.segment_time_s),
            ("kp", self.kp),
            ("kd", self.kd),
            ("velocity_scale", self.velocity_scale),
            ("approach_speed", self.approach_speed),
            ("path_ramp_s", self.path_ramp_s),
            ("residual_max_age_ms", self.residual_max_age_ms),
            ("perception_max_age_ms", self.perception_max_age_ms),
            ("perception_stop_after_ms", self.perception_stop_after_ms),
            ("feedback_max_speed", self.feedback_max_speed),
            ("feedback_free_speed", self.feedback_free_speed),
            ("reference_accel_limit", self.reference_accel_limit),
            ("retreat_ramp_s", self.retreat_ramp_s),
        ] {
            positive(S, name, v)?;
        }
        for (name, v) in [
            ("posture_gain", self.posture_gain),
            ("clik_gain", self.clik_gain),
            ("damping", self.damping),
            ("waypoint_tolerance", self.waypoint_tolerance),
            ("reflex_gain", self.reflex_gain),
            ("reflex_damping", self.reflex_damping),
            ("admittance_gain", self.admittance_gain),
            ("float_damping", self.float_damping),
            ("retreat_path_s", self.retreat_path_s),
            ("reaction_min_s", self.reaction_min_s),
            ("resume_quiet_s", self.resume_quiet_s),
            ("position_margin", self.position_margin),
            ("near_distance_m", self.near_distance_m),
            ("repulsion_filter_s", self.repulsion_filter_s),
            ("body_repulsion_gain", self.body_repulsion_gain),
            ("approach_clearance_m", self.approach_clearance_m),
            ("approach_gain", self.approach_gain),
        ] {
            non_negative(S, name, v)?;
        }
        within(S, "slow_scale", self.slow_scale, 0.0, 1.0)?;
        finite(S, "posture", &self.posture)?;
        let a = &self.avoidance_params;
        const A: &str = "control.avoidance_params";
        positive(A, "accel_limit", a.accel_limit)?;
        non_negative(A, "horizon_s", a.horizon_s)?;
        non_negative(A, "damping", a.damping)?;
        non_negative(A, "position_margin", a.position_margin)?;
        Ok(())
    }
}
