//! `[control]` section of `deploy/phri.toml`.

use serde::Deserialize;

use crate::avoidance::AvoidanceParams;

/// Reaction strategies of the paper's portfolio (Sect. IV, Fig. 2).
#[derive(Clone, Copy, Debug, Deserialize, PartialEq, Eq)]
#[serde(rename_all = "snake_case")]
pub enum Reaction {
    /// τ = M (K_R r − D_R q̇) + C q̇ + g − r (eq. 9): the arm yields along τ_ext
    Reflex,
    /// q̇_r = K_Q r (eq. 13) tracked by the joint loop
    Admittance,
    /// freeze the reference where the collision was detected
    Stop,
    /// τ = g(q) (+ light damping): zero-gravity
    Float,
    /// time-scaled retreat back along the path just travelled
    Retreat,
}

impl Reaction {
    pub const ALL: [Reaction; 5] = [
        Reaction::Reflex,
        Reaction::Admittance,
        Reaction::Stop,
        Reaction::Float,
        Reaction::Retreat,
    ];

    pub fn name(self) -> &'static str {
        match self {
            Reaction::Reflex => "reflex",
            Reaction::Admittance => "admittance",
            Reaction::Stop => "stop",
            Reaction::Float => "float",
            Reaction::Retreat => "retreat",
        }
    }

    pub fn index(self) -> u32 {
        Reaction::ALL.iter().position(|r| *r == self).unwrap_or(0) as u32
    }
}

/// Controller settings (every field has a default; see `deploy/phri.toml`).
#[derive(Clone, Debug, Deserialize)]
#[serde(default, deny_unknown_fields)]
pub struct ControlConfig {
    /// Cartesian waypoints of the end effector [m], base frame, visited cyclically
    pub waypoints: Vec<[f64; 3]>,
    /// duration of each segment between waypoints [s]
    pub segment_time_s: f64,
    /// link whose origin is the end effector (empty: the deepest link)
    pub ee_link: String,
    /// posture the null space pulls towards [rad] (empty: the initial measured posture)
    pub posture: Vec<f64>,
    /// null-space posture gain [1/s]
    pub posture_gain: f64,
    /// Cartesian error gain of the inverse kinematics [1/s]
    pub clik_gain: f64,
    /// damping of the pseudoinverse [m]
    pub damping: f64,
    /// joint tracking: stiffness [1/s²] and damping [1/s] of the computed-torque law
    pub kp: f64,
    pub kd: f64,
    /// fraction of each joint's velocity limit the reference may use
    pub velocity_scale: f64,
    /// largest end-effector speed when approaching the path [m/s]
    pub approach_speed: f64,
    /// after the approach, the path's time law ṡ ramps smoothly from 0 to 1 over this [s]
    pub path_ramp_s: f64,
    /// end-effector distance within which a waypoint counts as reached [m]
    pub waypoint_tolerance: f64,
    /// reaction to a detected collision
    pub reaction: Reaction,
    /// reflex gains K_R [1/(kg m² s²)·…] and D_R [1/s] of eq. 9
    pub reflex_gain: f64,
    pub reflex_damping: f64,
    /// admittance gain K_Q of eq. 13 [rad/(N m s)]
    pub admittance_gain: f64,
    /// joint damping while floating [Nm s/rad]
    pub float_damping: f64,
    /// retreat: how far back along the path [s of path time] and how fast the time law turns [s]
    pub retreat_path_s: f64,
    pub retreat_ramp_s: f64,
    /// least time spent reacting before recovering [s]
    pub reaction_min_s: f64,
    /// resume the task once the residual stayed below the contact level for `resume_quiet_s`
    pub resume: bool,
    pub resume_quiet_s: f64,
    /// a residual older than this (measured from the state it answers) is stale [ms]
    pub residual_max_age_ms: f64,
    /// keep this far inside the position limits [rad]
    pub position_margin: f64,
    /// collision avoidance from perception (paper Sect. V); off: the task ignores perception
    pub avoidance: bool,
    /// SNS and velocity-bound settings of the avoidance
    pub avoidance_params: AvoidanceParams,
    /// the end effector's position feedback is capped at this speed [m/s], below
    /// the repulsion's V_max, so that repulsion always wins near an obstacle
    pub feedback_max_speed: f64,
    /// perception results older than this are stale [ms]: with an obstacle last
    /// seen nearer than `near_distance_m` a protective stop, otherwise the task slows down
    pub perception_max_age_ms: f64,
    pub near_distance_m: f64,
    /// stale this long: protective stop whatever was seen last [ms]
    pub perception_stop_after_ms: f64,
    /// speed scale while perception is stale
    pub slow_scale: f64,
    /// repulsive vectors arrive at the frame rate: low-pass them with this time constant [s]
    pub repulsion_filter_s: f64,
    /// under avoidance the reference velocity changes by at most this per second [rad/s²]
    /// (no jerk from frame-rate steps, which the residual would see)
    pub reference_accel_limit: f64,
}

impl Default for ControlConfig {
    fn default() -> Self {
        ControlConfig {
            waypoints: vec![[0.45, -0.35, 0.45], [0.55, 0.0, 0.30], [0.45, 0.35, 0.45]],
            segment_time_s: 4.0 / 3.0,
            ee_link: String::new(),
            posture: Vec::new(),
            posture_gain: 2.0,
            clik_gain: 20.0,
            damping: 0.02,
            kp: 400.0,
            kd: 40.0,
            velocity_scale: 0.8,
            approach_speed: 0.15,
            path_ramp_s: 0.5,
            waypoint_tolerance: 0.03,
            reaction: Reaction::Reflex,
            reflex_gain: 2.0,
            reflex_damping: 12.0,
            admittance_gain: 0.05,
            float_damping: 0.5,
            retreat_path_s: 0.6,
            retreat_ramp_s: 0.1,
            reaction_min_s: 0.3,
            resume: true,
            resume_quiet_s: 1.0,
            residual_max_age_ms: 5.0,
            position_margin: 0.05,
            avoidance: true,
            avoidance_params: AvoidanceParams::default(),
            feedback_max_speed: 0.1,
            perception_max_age_ms: 100.0,
            perception_stop_after_ms: 2000.0,
            near_distance_m: 0.5,
            slow_scale: 0.3,
            repulsion_filter_s: 0.05,
            reference_accel_limit: 10.0,
        }
    }
}
