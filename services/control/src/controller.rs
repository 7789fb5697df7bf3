//! The controller's state machine and torque laws.

use nalgebra::Vector3;
use phri_dynamics::VelocityEstimator;
use phri_ipc::control_mode as mode;
use phri_model::{Data, Model};

use crate::avoidance::Avoidance;
use crate::config::{ControlConfig, Reaction};
use crate::limits::{LimitActivity, Limits};
use crate::task::{Approach, Clik, ClikGains, Path};

/// The newest residual, as the controller sees it.
#[derive(Clone, Copy, Debug)]
pub struct ResidualView<'a> {
    /// stamp of the joint state the residual was computed from [ns]
    pub state_stamp_ns: u64,
    /// residual [Nm]
    pub r: &'a [f64],
    /// the observer is past its warm-up
    pub valid: bool,
    /// some joint passed its contact level
    pub contact: bool,
    /// some joint (or the norm) passed its collision level
    pub collision: bool,
}

/// One control period's inputs.
#[derive(Clone, Copy, Debug)]
pub struct ControlInput<'a> {
    /// measurement time of `q` [ns, robot clock]
    pub state_stamp_ns: u64,
    /// measured joint positions [rad]
    pub q: &'a [f64],
    pub residual: Option<ResidualView<'a>>,
    /// newest repulsion results; `None`: this controller runs without perception
    pub perception: Option<PerceptionView<'a>>,
}

/// The newest perception results, as the controller sees them.
#[derive(Clone, Copy, Debug)]
pub struct PerceptionView<'a> {
    /// capture time of the oldest of the workers' newest results [ns, robot
    /// clock]; 0 while some worker has not answered yet
    pub capture_ns: u64,
    /// newest result per control point, indexed by point (0: the end effector)
    pub points: &'a [phri_ipc::PointRepulsion],
}

/// One control period's outputs (borrowed from the controller).
#[derive(Debug)]
pub struct ControlOutput<'a> {
    /// joint torque [Nm], limits enforced
    pub tau: &'a [f64],
    /// [`phri_ipc::control_mode`]
    pub mode: u32,
    pub limits: LimitActivity,
}

#[derive(Debug, thiserror::Error)]
pub enum ControlError {
    #[error("config [control]: {0}")]
    Config(String),
}

/// Recent joint references with their path time, for the retreat.
struct History {
    n: usize,
    cap: usize,
    data: Vec<f64>,
    count: usize,
}

impl History {
    fn new(n: usize, cap: usize) -> History {
        History {
            n,
            cap,
            data: vec![0.0; cap * (n + 1)],
            count: 0,
        }
    }

    fn push(&mut self, s: f64, q: &[f64]) {
        let at = (self.count % self.cap) * (self.n + 1);
        self.data[at] = s;
        self.data[at + 1..at + 1 + self.n].copy_from_slice(q);
        self.count += 1;
    }

    fn available(&self) -> usize {
        self.count.min(self.cap)
    }

    fn clear(&mut self) {
        self.count = 0;
    }

    /// Entry `back` steps before the newest (0 = newest), interpolated; writes q, returns s.
    fn at(&self, back: f64, q: &mut [f64]) -> f64 {
        let max_back = (self.available().max(1) - 1) as f64;
        let back = back.clamp(0.0, max_back);
        let (i0, frac) = (back.floor() as usize, back.fract());
        let i1 = (i0 + 1).min(max_back as usize);
        let slot = |i: usize| ((self.count - 1 - i) % self.cap) * (self.n + 1);
        let (a, b) = (slot(i0), slot(i1));
        for k in 0..self.n {
            q[k] = self.data[a + 1 + k] * (1.0 - frac) + self.data[b + 1 + k] * frac;
        }
        self.data[a] * (1.0 - frac) + self.data[b] * frac
    }
}

/// The torque-loop controller. `step` is pure and allocation-free.
pub struct Controller {
    model: Model,
    data: Data,
    cfg: ControlConfig,
    limits: Limits,
    clik: Clik,
    path: Path,
    velocity: VelocityEstimator,
    n: usize,
    vmax_ref: Vec<f64>,
    posture: Vec<f64>,
    // state
    mode: u32,
    last_stamp: Option<u64>,
    t: f64,
    s: f64,
    approach: Option<Approach>,
    q_ref: Vec<f64>,
    qd_ref: Vec<f64>,
    qd_ref_prev: Vec<f64>,
    q_hold: Vec<f64>,
    /// end-effector position held in `recover` \[m\], base frame
    x_hold: Vector3<f64>,
    reaction_t0: f64,
    quiet_since: Option<f64>,
    history: History,
    retreat_u: f64,
    retreat_total: f64,
    /// progress of the path's time-law ramp, 0 → 1
    ramp_u: f64,
    last_target: usize,
    // outputs and counters
    tau: Vec<f64>,
    zeros: Vec<f64>,
    m_diag: Vec<f64>,
    gravity: Vec<f64>,
    bias: Vec<f64>,
    accel: Vec<f64>,
    pub waypoints_reached: u64,
    pub detections: u64,
    pub protective_stops: u64,
    pub resumes: u64,
    ee: Vector3<f64>,
    residual_age_ns: u64,
    // avoidance
    avoidance: Avoidance,
    /// control points: (link frame, point in it); 0 is the end effector
    points: Vec<(usize, Vector3<f64>)>,
    jac_ee: nalgebra::Matrix6xX<f64>,
    jac_point: nalgebra::Matrix6xX<f64>,
    perception_age_ns: u64,
    last_min_distance: f64,
    /// largest risk ‖V_Call‖/V_max over the control points in the last step
    pub risk: f64,
    /// task scale of the last SNS solution
    pub task_scale: f64,
    /// low-passed repulsive vectors per control point [m/s]
    v_call_filtered: Vec<Vector3<f64>>,
}

impl Controller {
    pub fn new(model: Model, cfg: ControlConfig) -> Result<Controller, ControlError> {
        let n = model.nv();
        let err = ControlError::Config;
        if cfg.waypoints.len() < 2 {
            return Err(err("waypoints: need at least two".into()));
        }
        if cfg.waypoints.iter().flatten().any(|x| !x.is_finite()) {
            return Err(err("waypoints: not finite".into()));
        }
        let positive = [
            ("segment_time_s", cfg.segment_time_s),
            ("kp", cfg.kp),
            ("kd", cfg.kd),
            ("velocity_scale", cfg.velocity_scale),
            ("approach_speed", cfg.approach_speed),
            ("residual_max_age_ms", cfg.residual_max_age_ms),
        ];
        if let Some((name, _)) = positive.iter().find(|(_, v)| !(v.is_finite() && *v > 0.0)) {
            return Err(err(format!("{name}: must be positive")));
        }
        if !cfg.posture.is_empty() && cfg.posture.len() != n {
            return Err(err(format!(
                "posture: expected {n} values, got {}",
                cfg.posture.len()
            )));
        }
        let ee_frame = if cfg.ee_link.is_empty() {
            model.frames.len() - 1
        } else {
            model
                .frame_id(&cfg.ee_link)
                .map_err(|_| err(format!("ee_link: unknown link '{}'", cfg.ee_link)))?
        };
        let limits = Limits::from_model(&model, cfg.position_margin);
        let vmax_ref = limits
            .velocity
            .iter()
            .map(|v| {
                if v.is_finite() {
                    v * cfg.velocity_scale
                } else {
                    2.0
                }
            })
            .collect();
        let history_len = ((cfg.retreat_path_s.max(0.0) + 0.5) / 0.001).ceil() as usize + 2;
        Ok(Controller {
            data: Data::new(&model),
            clik: Clik::new(&model, ee_frame),
            path: Path {
                waypoints: cfg
                    .waypoints
                    .iter()
                    .map(|w| Vector3::new(w[0], w[1], w[2]))
                    .collect(),
                segment_time: cfg.segment_time_s,
            },
            velocity: VelocityEstimator::new(n, 60.0),
            n,
            vmax_ref,
            posture: cfg.posture.clone(),
            mode: mode::SYNC,
            last_stamp: None,
            t: 0.0,
            s: 0.0,
            approach: None,
            q_ref: vec![0.0; n],
            qd_ref: vec![0.0; n],
            qd_ref_prev: vec![0.0; n],
            q_hold: vec![0.0; n],
            x_hold: Vector3::zeros(),
            reaction_t0: 0.0,
            quiet_since: None,
            history: History::new(n, history_len),
            retreat_u: 0.0,
            retreat_total: 0.0,
            ramp_u: 0.0,
            last_target: 0,
            tau: vec![0.0; n],
            zeros: vec![0.0; n],
            m_diag: vec![0.0; n],
            gravity: vec![0.0; n],
            bias: vec![0.0; n],
            accel: vec![0.0; n],
            waypoints_reached: 0,
            detections: 0,
            protective_stops: 0,
            resumes: 0,
            ee: Vector3::zeros(),
            residual_age_ns: u64::MAX,
            avoidance: Avoidance::new(&model, cfg.avoidance_params),
            points: Vec::new(),
            jac_ee: phri_model::Data::jacobian_buffer(&model),
            jac_point: phri_model::Data::jacobian_buffer(&model),
            perception_age_ns: u64::MAX,
            last_min_distance: 0.0,
            risk: 0.0,
            task_scale: 1.0,
            v_call_filtered: Vec::new(),
            limits,
            model,
            cfg,
        })
    }

    pub fn model(&self) -> &Model {
        &self.model
    }

    pub fn mode(&self) -> u32 {
        self.mode
    }

    pub fn reaction(&self) -> Reaction {
        self.cfg.reaction
    }

    pub fn q_ref(&self) -> &[f64] {
        &self.q_ref
    }

    /// End-effector position at the measured joints [m], base frame.
    pub fn ee(&self) -> Vector3<f64> {
        self.ee
    }

    /// The control points of the repulsion workers, in their configured order
    /// (the first is the end effector): link name and point in the link frame [m].
    pub fn set_control_points(
        &mut self,
        points: &[(String, [f64; 3])],
    ) -> Result<(), ControlError> {
        self.points = points
            .iter()
            .enumerate()
            .map(|(i, (link, xyz))| {
                let f = self.model.frame_id(link).map_err(|_| {
                    ControlError::Config(format!("control point {i}: unknown link '{link}'"))
                })?;
                Ok((f, Vector3::from(*xyz)))
            })
            .collect::<Result<_, _>>()?;
        self.v_call_filtered = vec![Vector3::zeros(); points.len()];
        Ok(())
    }

    /// Age of the perception results used in the last step [ns] (u64::MAX: none).
    pub fn perception_age_ns(&self) -> u64 {
        self.perception_age_ns
    }

    /// Smallest obstacle distance of the control points last seen [m].
    pub fn last_min_distance(&self) -> f64 {
        self.last_min_distance
    }

    /// Age of the residual used in the last step [ns] (u64::MAX: none).
    pub fn residual_age_ns(&self) -> u64 {
        self.residual_age_ns
    }

    fn hold_here(&mut self, q: &[f64]) {
        self.q_hold.copy_from_slice(q);
        self.q_ref.copy_from_slice(q);
        self.qd_ref.fill(0.0);
        self.qd_ref_prev.fill(0.0);
    }

    /// Re-sync to the measured state and approach the path smoothly.
    fn start_task(&mut self, q: &[f64]) {
        self.hold_here(q);
        if self.posture.is_empty() {
            self.posture.extend_from_slice(q);
        }
        let from = self.clik.position(&self.model, &mut self.data, q);
        let (to, _) = self.path.sample(self.s);
        self.approach = Some(Approach::new(from, to, self.cfg.approach_speed));
        self.history.clear();
        self.ramp_u = 0.0;
        self.last_target = self.path.target_index(self.s);
        self.mode = mode::TASK;
    }

    fn enter_reaction(&mut self, q: &[f64]) {
        self.detections += 1;
        self.reaction_t0 = self.t;
        self.quiet_since = None;
        self.hold_here(q);
        self.retreat_u = 0.0;
        self.retreat_total =
            (self.cfg.retreat_path_s / 0.001).min((self.history.available().max(1) - 1) as f64);
        self.mode = mode::REACTION;
    }

    fn enter_recover(&mut self, q: &[f64]) {
        self.hold_here(q);
        self.x_hold = self.clik.position(&self.model, &mut self.data, q);
        self.quiet_since = None;
        self.mode = mode::RECOVER;
    }

    /// One control period.
    pub fn step(&mut self, input: &ControlInput<'_>) -> ControlOutput<'_> {
        let n = self.n;
        let q = input.q;
        if q.len() != n || q.iter().any(|x| !x.is_finite()) {
            // never act on a malformed state: hold the last reference with gravity only
            self.tau.copy_from_slice(&self.gravity);
            return ControlOutput {
                tau: &self.tau,
                mode: self.mode,
                limits: LimitActivity {
                    non_finite: true,
                    ..Default::default()
                },
            };
        }
        let dt = match self.last_stamp {
            Some(t0) if input.state_stamp_ns > t0 => {
                ((input.state_stamp_ns - t0) as f64 * 1e-9).min(0.01)
            }
            _ => 0.0,
        };
        self.last_stamp = Some(input.state_stamp_ns);
        self.t += dt;
        self.velocity.update(q, dt);
        let qd: &[f64] = self.velocity.velocity();
        let qd: [f64; phri_ipc::MAX_DOF] = {
            let mut a = [0.0; phri_ipc::MAX_DOF];
            a[..n].copy_from_slice(qd);
            a
        };
        let qd = &qd[..n];

        // freshness of the residual, in measurement time (deterministic)
        let (fresh, collision, contact) = match &input.residual {
            Some(r) if r.r.len() == n => {
                self.residual_age_ns = input.state_stamp_ns.saturating_sub(r.state_stamp_ns);
                let fresh =
                    r.valid && (self.residual_age_ns as f64) <= self.cfg.residual_max_age_ms * 1e6;
                (fresh, fresh && r.collision, fresh && r.contact)
            }
            _ => {
                self.residual_age_ns = u64::MAX;
                (false, false, false)
            }
        };

        // dynamics at the measured state
        let _ = phri_model::crba(&self.model, &mut self.data, q);
        for i in 0..n {
            self.m_diag[i] = self.data.m[(i, i)];
        }
        if let Ok(g) = phri_model::gravity(&self.model, &mut self.data, q) {
            self.gravity.copy_from_slice(g.as_slice());
        }
        if let Ok(b) = phri_model::rnea(&self.model, &mut self.data, q, qd, &self.zeros) {
            self.bias.copy_from_slice(b.as_slice());
        }
        self.ee = self.clik.position(&self.model, &mut self.data, q);

        // perception: fresh, stale (slow down), or stale with a person last seen near (stop)
        let v_max_rep = self.cfg.avoidance_params.v_max_repulsion.max(1e-9);
        let (p_fresh, p_stop) = match &input.perception {
            None => {
                self.perception_age_ns = u64::MAX;
                (true, false)
            }
            Some(v) => {
                self.perception_age_ns = if v.capture_ns == 0 {
                    u64::MAX
                } else {
                    input.state_stamp_ns.saturating_sub(v.capture_ns)
                };
                let age_ms = self.perception_age_ns as f64 * 1e-6;
                let fresh = age_ms <= self.cfg.perception_max_age_ms;
                if fresh {
                    self.last_min_distance = v
                        .points
                        .iter()
                        .filter(|p| p.active != 0)
                        .map(|p| p.min_distance)
                        .fold(f64::INFINITY, f64::min);
                }
                // blind with a person last seen near: stop at once; blind for long: stop anyway
                let near = self.last_min_distance < self.cfg.near_distance_m;
                (
                    fresh,
                    !fresh && (near || age_ms > self.cfg.perception_stop_after_ms),
                )
            }
        };
        let perception = input.perception.filter(|_| p_fresh);
        self.risk = perception.map_or(0.0, |v| {
            v.points
                .iter()
                .map(|p| Vector3::from(p.v_call).norm() / v_max_rep)
                .fold(0.0, f64::max)
                .min(1.0)
        });
        let ee_risk = perception.and_then(|v| v.points.first()).map_or(0.0, |p| {
            (Vector3::from(p.v_call).norm() / v_max_rep).min(1.0)
        });
        let speed_scale = if p_fresh {
            1.0
        } else {
            self.cfg.slow_scale.clamp(0.0, 1.0)
        };

        // transitions
        match self.mode {
            mode::SYNC => {
                if self.last_stamp.is_some() && self.t == 0.0 {
                    self.hold_here(q);
                }
                if fresh && p_fresh {
                    self.start_task(q);
                }
            }
            // not a guard: while stopped with a stale input this arm must still match,
            // or the stop would fall through to `recover`
            #[allow(clippy::collapsible_match)]
            _ if !fresh || p_stop => {
                if self.mode != mode::PROTECTIVE_STOP {
                    self.protective_stops += 1;
                    self.hold_here(q);
                    self.mode = mode::PROTECTIVE_STOP;
                }
            }
            mode::PROTECTIVE_STOP => self.enter_recover(q),
            mode::TASK | mode::SLOW => {
                if collision {
                    self.enter_reaction(q);
                } else {
                    self.mode = if p_fresh { mode::TASK } else { mode::SLOW };
                }
            }
            mode::REACTION => {
                let min_done = self.t - self.reaction_t0 >= self.cfg.reaction_min_s;
                let retreat_done = self.cfg.reaction != Reaction::Retreat
                    || self.retreat_total - self.retreat_u < 0.5;
                if min_done && retreat_done && !contact {
                    self.enter_recover(q);
                }
            }
            mode::RECOVER => {
                if collision {
                    self.enter_reaction(q);
                } else if contact {
                    self.quiet_since = None;
                } else {
                    let since = *self.quiet_since.get_or_insert(self.t);
                    if self.cfg.resume && self.t - since >= self.cfg.resume_quiet_s {
                        self.resumes += 1;
                        self.start_task(q);
                    }
                }
            }
            _ => {}
        }

        // torque law of the mode: τ = M a + (C q̇ + g) [− r for the reflex]
        let (kp, kd) = (self.cfg.kp, self.cfg.kd);
        let mut minus_r = false;
        match self.mode {
            mode::TASK | mode::SLOW => {
                // time scaling: slower when perception is stale, and near obstacles in
                // front of the end effector (risk f: ṡ scaled by 1 − f)
                let time_scale = speed_scale * (1.0 - ee_risk);
                let (x_d, xd_d) = match self.approach.as_mut() {
                    Some(a) => {
                        let out = a.step(dt * time_scale);
                        if a.done() {
                            self.approach = None;
                        }
                        out
                    }
                    None => {
                        // time scaling: ṡ = smoothstep(u) ramps 0 → 1, so that a path resumed
                        // mid-segment starts without a jump in velocity or acceleration
                        self.ramp_u = (self.ramp_u + dt / self.cfg.path_ramp_s.max(1e-3)).min(1.0);
                        let u = self.ramp_u;
                        let rate = u * u * (3.0 - 2.0 * u) * time_scale;
                        self.s += dt * rate;
                        let (x, dx) = self.path.sample(self.s);
                        let dx = dx * rate;
                        // waypoint reached: the segment ended with the end effector there
                        let target = self.path.target_index(self.s);
                        if target != self.last_target {
                            if (self.ee - self.path.waypoints[self.last_target]).norm()
                                <= self.cfg.waypoint_tolerance
                            {
                                self.waypoints_reached += 1;
                            }
                            self.last_target = target;
                        }
                        (x, dx)
                    }
                };
                if input.perception.is_some() {
                    self.avoid_step(&x_d, &xd_d, dt, perception, speed_scale);
                } else {
                    let gains = ClikGains {
                        clik: self.cfg.clik_gain,
                        posture: self.cfg.posture_gain,
                        damping: self.cfg.damping,
                    };
                    let qd_ref = self.clik.step(
                        &self.model,
                        &mut self.data,
                        &mut self.q_ref,
                        &x_d,
                        &xd_d,
                        dt,
                        gains,
                        &self.posture,
                        &self.vmax_ref,
                    );
                    self.qd_ref.copy_from_slice(qd_ref);
                }
                self.limits.clamp_position(&mut self.q_ref);
                self.history.push(self.s, &self.q_ref);
                self.track_reference(q, qd, dt);
            }
            // waiting to resume with someone in view: hold the end effector where it
            // stopped, but keep evading (eq. 19/20) instead of standing in their way;
            // with nothing near the repulsion is zero and this is a plain hold
            mode::RECOVER if p_fresh && input.perception.is_some() => {
                let x_hold = self.x_hold;
                self.avoid_step(&x_hold, &Vector3::zeros(), dt, perception, 1.0);
                self.limits.clamp_position(&mut self.q_ref);
                self.track_reference(q, qd, dt);
            }
            mode::REACTION => match (self.cfg.reaction, &input.residual) {
                (Reaction::Reflex, Some(r)) => {
                    for i in 0..n {
                        self.accel[i] =
                            self.cfg.reflex_gain * r.r[i] - self.cfg.reflex_damping * qd[i];
                    }
                    minus_r = true;
                }
                (Reaction::Admittance, Some(r)) => {
                    for i in 0..n {
                        self.qd_ref[i] = self.cfg.admittance_gain * r.r[i];
                        self.q_ref[i] += self.qd_ref[i] * dt;
                    }
                    self.limits.clamp_position(&mut self.q_ref);
                    for i in 0..n {
                        self.accel[i] = kp * (self.q_ref[i] - q[i]) + kd * (self.qd_ref[i] - qd[i]);
                    }
                }
                (Reaction::Float, _) => {
                    // τ = g − D q̇: no inertial term
                    for i in 0..n {
                        self.accel[i] = 0.0;
                        self.bias[i] = self.gravity[i] - self.cfg.float_damping * qd[i];
                    }
                }
                (Reaction::Retreat, _) => {
                    // time law: the retreat speed ramps from 0 to 1 (path time runs backwards at
                    // ṡ = −1) and back to 0 at the end; u counts history entries (one per period)
                    let ramp = self.cfg.retreat_ramp_s.max(1e-3);
                    let left_s = (self.retreat_total - self.retreat_u) * 0.001;
                    let sigma = ((self.t - self.reaction_t0) / ramp)
                        .min(1.0)
                        .min(left_s / (0.5 * ramp))
                        .max(0.05);
                    self.retreat_u = (self.retreat_u + sigma * dt * 1000.0).min(self.retreat_total);
                    let prev: [f64; phri_ipc::MAX_DOF] = {
                        let mut a = [0.0; phri_ipc::MAX_DOF];
                        a[..n].copy_from_slice(&self.q_ref);
                        a
                    };
                    self.s = self.history.at(self.retreat_u, &mut self.q_ref);
                    for i in 0..n {
                        self.qd_ref[i] = if dt > 0.0 {
                            (self.q_ref[i] - prev[i]) / dt
                        } else {
                            0.0
                        };
                        self.accel[i] = kp * (self.q_ref[i] - q[i]) + kd * (self.qd_ref[i] - qd[i]);
                    }
                }
                // stop, or a strategy whose residual vanished: hold where detected
                _ => self.hold_accel(q, qd),
            },
            _ => self.hold_accel(q, qd),
        }
        for i in 0..n {
            let mut t = self.bias[i];
            for k in 0..n {
                t += self.data.m[(i, k)] * self.accel[k];
            }
            if minus_r {
                if let Some(r) = &input.residual {
                    t -= r.r[i];
                }
            }
            self.tau[i] = t;
        }
        let limits = self
            .limits
            .apply(q, qd, &self.m_diag, &self.gravity, &mut self.tau);
        ControlOutput {
            tau: &self.tau,
            mode: self.mode,
            limits,
        }
    }

    /// The task under avoidance (paper Sect. V): the end effector's repulsive
    /// velocity adds to its task velocity (eq. 19); every other control point
    /// shapes the joint velocity bounds (eq. 20); SNS solves the task within
    /// them and the joint-limit bounds. Moves `q_ref`, writes `qd_ref`.
    fn avoid_step(
        &mut self,
        x_d: &Vector3<f64>,
        xd_d: &Vector3<f64>,
        dt: f64,
        perception: Option<PerceptionView<'_>>,
        speed_scale: f64,
    ) {
        let ee = self.clik.frame();
        let ok = phri_model::forward_kinematics(&self.model, &mut self.data, &self.q_ref).is_ok()
            && phri_model::point_jacobian(
                &self.model,
                &self.data,
                ee,
                &Vector3::zeros(),
                &mut self.jac_ee,
            )
            .is_ok();
        if !ok || self.avoidance.begin(&self.q_ref).is_err() {
            self.qd_ref.fill(0.0);
            return;
        }
        let x = phri_model::frame_placement(&self.model, &self.data, ee).p;
        // position feedback capped below the repulsion's V_max
        let mut fb = (x_d - x) * self.cfg.clik_gain;
        let cap = self.cfg.feedback_max_speed;
        if fb.norm() > cap {
            fb *= cap / fb.norm();
        }
        let xdot_task = xd_d + fb;
        let mut v_ee = Vector3::zeros();
        let alpha = if self.cfg.repulsion_filter_s > 0.0 {
            1.0 - (-dt / self.cfg.repulsion_filter_s).exp()
        } else {
            1.0
        };
        if let Some(v) = perception {
            for (k, &(frame, xyz)) in self.points.iter().enumerate() {
                let Some(p) = v.points.get(k) else { break };
                let target = if p.active == 0 {
                    Vector3::zeros()
                } else {
                    Vector3::from(p.v_call)
                };
                let Some(f) = self.v_call_filtered.get_mut(k) else {
                    break;
                };
                *f += (target - *f) * alpha;
                let v_call = *f;
                if v_call.norm() < 1e-6 {
                    continue;
                }
                if k == 0 {
                    v_ee = v_call;
                } else if phri_model::point_jacobian(
                    &self.model,
                    &self.data,
                    frame,
                    &xyz,
                    &mut self.jac_point,
                )
                .is_ok()
                {
                    let _ = self.avoidance.add_point(&self.jac_point, v_call);
                }
            }
        }
        // slew-limited towards the SNS solution (which stays within the bounds
        // it was computed for; the limit only delays reaching it)
        let dv = self.cfg.reference_accel_limit * dt;
        match self
            .avoidance
            .solve(&self.jac_ee, &xdot_task, &v_ee, speed_scale)
        {
            Ok(out) => {
                self.task_scale = out.scale;
                for (r, &target) in self.qd_ref.iter_mut().zip(out.qd) {
                    *r += (target - *r).clamp(-dv, dv);
                }
            }
            Err(_) => {
                self.task_scale = 0.0;
                for r in self.qd_ref.iter_mut() {
                    *r -= r.clamp(-dv, dv);
                }
            }
        }
        for (q, v) in self.q_ref.iter_mut().zip(&self.qd_ref) {
            *q += v * dt;
        }
    }

    /// Computed-torque acceleration tracking `q_ref`, `qd_ref` (feed-forward
    /// from the reference's change over `dt`).
    fn track_reference(&mut self, q: &[f64], qd: &[f64], dt: f64) {
        let (kp, kd) = (self.cfg.kp, self.cfg.kd);
        for i in 0..self.n {
            let qdd_ref = if dt > 0.0 {
                (self.qd_ref[i] - self.qd_ref_prev[i]) / dt
            } else {
                0.0
            };
            self.accel[i] = qdd_ref + kp * (self.q_ref[i] - q[i]) + kd * (self.qd_ref[i] - qd[i]);
        }
        self.qd_ref_prev.copy_from_slice(&self.qd_ref);
    }

    fn hold_accel(&mut self, q: &[f64], qd: &[f64]) {
        for i in 0..self.n {
            self.accel[i] = self.cfg.kp * (self.q_hold[i] - q[i]) - self.cfg.kd * qd[i];
        }
    }
}
