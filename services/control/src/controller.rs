//! The torque-loop controller: one short [`Controller::step`] that applies
//! the paper's hierarchy in order — safety inputs fresh? → reaction to a
//! detected collision (the mode transition) → the active behaviour →
//! avoidance (eqs. 19-20, SNS) → torque law → limits.

use nalgebra::Vector3;
use phri_config::{Config, ControlConfig, PointConfig};
use phri_estimation::VelocityEstimator;
use phri_ipc::{CollabPhase, ControlMode, Reaction, RequestKind, MAX_DOF};
use phri_model::{check_len, Data, Model};

use crate::collab::RobotState;
use crate::error::ControlError;
use crate::history::PathHistory;
use crate::inputs::{ControlInput, PerceptionView};
use crate::limits::{LimitActivity, Limits};
use crate::modes::collaborate::Collaboration;
use crate::modes::reaction::{ReactionIo, ReactionState};
use crate::modes::restart_hold::{Hold, RestartHold};
use crate::modes::task::TaskState;
use crate::modes::{self, protective_stop, recover, sync, Behaviour, CartesianRef, Conditions};
use crate::reference::{JointReference, TrackingGains};
use crate::resolve::{Faults, Resolver};
use crate::safety::{Safety, SafetyMonitor};
use crate::snapshot::{self, snapshot_fields, Layout, Reader, Snapshot, SnapshotError, Writer};
use crate::terms::DynamicsTerms;

/// Cut-off of the controller's velocity estimate from positions \[Hz\].
const VELOCITY_CUTOFF_HZ: f64 = 60.0;

/// A gap between two states longer than this many control periods counts as this many.
const MAX_GAP_PERIODS: f64 = 10.0;

/// What the controller takes besides `[control]`.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct ControllerParams {
    /// control period \[s\]: the robot's state period (`[sim] dt_s`); the
    /// retreat's history holds one entry per period
    pub period_s: f64,
}

impl ControllerParams {
    /// From the configuration: the period is `[sim] dt_s`.
    pub fn from_config(cfg: &Config) -> ControllerParams {
        ControllerParams {
            period_s: cfg.sim.dt_s,
        }
    }
}

/// One control period's outputs (borrowed from the controller).
#[derive(Debug)]
pub struct ControlOutput<'a> {
    /// joint torque \[Nm\], limits enforced
    pub tau: &'a [f64],
    /// the mode of this period
    pub mode: ControlMode,
    /// what the limiter had to do
    pub limits: LimitActivity,
}

/// Counts since the start.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub struct ControlCounters {
    /// task waypoints reached
    pub waypoints_reached: u64,
    /// collisions reacted to
    pub detections: u64,
    /// protective stops entered
    pub protective_stops: u64,
    /// task resumptions after a reaction or a stop
    pub resumes: u64,
    /// model calls refused (dynamics, kinematics, Jacobians): each left its
    /// fail-safe (the last good term, zero velocity, a zero position)
    pub model_errors: u64,
    /// avoidance or SNS refusals (the reference velocity then decays to zero)
    pub avoidance_errors: u64,
}

snapshot_fields!(ControlCounters {
    waypoints_reached,
    detections,
    protective_stops,
    resumes,
    model_errors,
    avoidance_errors
});

/// The torque-loop controller. `step` is pure and allocation-free.
pub struct Controller {
    model: Model,
    data: Data,
    cfg: ControlConfig,
    params: ControllerParams,
    n: usize,
    limits: Limits,
    /// velocity limits of the reference [rad/s]
    vmax_ref: Vec<f64>,
    /// null-space posture \[rad\] (empty until the first start: the measured one)
    posture: Vec<f64>,
    velocity: VelocityEstimator,
    terms: DynamicsTerms,
    safety: SafetyMonitor,
    resolver: Resolver,
    reference: JointReference,
    history: PathHistory,
    task: TaskState,
    reaction: ReactionState,
    /// the collaboration layer (`None`: `[collaboration] enabled = false`)
    collab: Option<Collaboration>,
    /// a restarted controller's hold while a hand is at the robot (`None`: not restarted, or over)
    restart: Option<RestartHold>,
    /// the hold's judgement of this period
    hold: Hold,
    mode: ControlMode,
    last_stamp: Option<u64>,
    /// controller time \[s\]: the sum of the periods seen
    t: f64,
    /// recovering: since when the residual is quiet \[s\]
    quiet_since: Option<f64>,
    /// `on_request = "complete"`: the task's segments ended when the request
    /// was accepted (the approach waits for the next to end)
    collab_from_segment: Option<u64>,
    /// a `stop` request this period without a collaboration layer to
    /// answer it (it is the person's word all the same); taken by the
    /// period's conditions
    stop_asked: bool,
    /// end-effector position at the measured joints \[m\], base frame
    ee: Vector3<f64>,
    /// the task's latest end-effector reference \[m\], base frame
    task_x_d: Vector3<f64>,
    accel: Vec<f64>,
    tau: Vec<f64>,
    counters: ControlCounters,
}

impl Controller {
    /// A controller for `model` with the settings of `[control]` and `params`.
    pub fn new(
        model: Model,
        cfg: ControlConfig,
        params: ControllerParams,
    ) -> Result<Controller, ControlError> {
        let n = model.nv();
        if n > MAX_DOF {
            return Err(ControlError::TooManyJoints {
                joints: n,
                max: MAX_DOF,
            });
        }
        if !(params.period_s.is_finite() && params.period_s > 0.0) {
            return Err(ControlError::Period {
                period_s: params.period_s,
            });
        }
        cfg.validate()?;
        if !cfg.posture.is_empty() {
            check_len("posture", n, cfg.posture.len())?;
        }
        let ee_frame = if cfg.ee_link.is_empty() {
            model.frames.len() - 1
        } else {
            model
                .frame_id(&cfg.ee_link)
                .map_err(|_| ControlError::UnknownLink {
                    key: "control.ee_link".into(),
                    link: cfg.ee_link.clone(),
                })?
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
        Ok(Controller {
            data: Data::new(&model),
            n,
            vmax_ref,
            // room for the measured posture taken at the first start, without allocating then
            posture: {
                let mut p = Vec::with_capacity(n);
                p.extend_from_slice(&cfg.posture);
                p
            },
            velocity: VelocityEstimator::new(n, VELOCITY_CUTOFF_HZ),
            terms: DynamicsTerms::new(n),
            safety: SafetyMonitor::default(),
            resolver: Resolver::new(&model, ee_frame, &cfg),
            reference: JointReference::new(n),
            history: PathHistory::for_span(n, cfg.retreat_path_s.max(0.0) + 0.5, params.period_s),
            task: TaskState::new(&cfg),
            reaction: ReactionState::new(&cfg, params.period_s),
            collab: None,
            restart: None,
            hold: Hold::Clear,
            mode: ControlMode::Sync,
            last_stamp: None,
            t: 0.0,
            quiet_since: None,
            collab_from_segment: None,
            stop_asked: false,
            ee: Vector3::zeros(),
            task_x_d: Vector3::zeros(),
            accel: vec![0.0; n],
            tau: vec![0.0; n],
            counters: ControlCounters::default(),
            limits,
            model,
            cfg,
            params,
        })
    }

    /// The controller of a loaded configuration: `[control]`, the period of
    /// `[sim] dt_s` and, with avoidance, the control points of `[repulsion]`.
    pub fn from_config(model: Model, cfg: &Config) -> Result<Controller, ControlError> {
        let mut c = Controller::new(
            model,
            cfg.control.clone(),
            ControllerParams::from_config(cfg),
        )?;
        if cfg.control.avoidance {
            if cfg.repulsion.workers == 0 || cfg.repulsion.points.is_empty() {
                return Err(ControlError::NoControlPoints);
            }
            c.resolver
                .set_ssm(cfg.ssm.enabled.then_some(&cfg.ssm), cfg.cameras.len());
            c.resolver.set_law(&cfg.avoidance)?;
            if c.resolver.cbf_law() {
                c.task.pass_held_waypoints(cfg.avoidance.pass_after_s);
            }
            c.set_control_points(&cfg.repulsion.points)?;
        }
        if cfg.collaboration.enabled {
            c.collab = Some(Collaboration::new(&c.model, cfg)?);
        }
        Ok(c)
    }

    /// This controller replaces one that crashed or froze (its process was
    /// restarted), perhaps mid-collaboration: the collaboration is over
    /// (`controller_restart`), and the task waits while a tracked hand is at
    /// the robot (a protective stop until every hand stayed
    /// `restart_clear_m` away for `release_s`). Without the collaboration
    /// layer, or without a body tracker (`[skeleton] enabled = false`: no
    /// collaboration could run), nothing changes. Call it before the first step.
    pub fn restarted(&mut self) {
        if let Some(c) = self.collab.as_mut() {
            c.restarted(self.t);
            let cfg = c.machine().config();
            // without a body tracker nobody collaborated: nothing to judge
            self.restart = c
                .sees_hands()
                .then(|| RestartHold::new(cfg.restart_clear_m, cfg.release_s));
        }
    }

    /// The control points of the repulsion workers (`[repulsion] points`), in
    /// their configured order; the first is the end effector.
    pub fn set_control_points(&mut self, points: &[PointConfig]) -> Result<(), ControlError> {
        self.resolver.set_control_points(&self.model, points)
    }

    /// One control period.
    pub fn step(&mut self, input: &ControlInput<'_>) -> ControlOutput<'_> {
        let n = self.n;
        let q = input.q;
        if q.len() != n || q.iter().any(|x| !x.is_finite()) {
            return self.refuse_state();
        }
        let dt = self.advance_clock(input.state_stamp_ns);
        let mut qd = [0.0; MAX_DOF];
        qd[..n].copy_from_slice(self.velocity.update(q, dt));
        let qd = &qd[..n];

        // 1. the safety inputs: a fresh residual, fresh perception?
        let safety = self.safety.assess(input, &self.cfg, n);
        self.measure(q, qd);
        self.observe_collaboration(q, dt, &safety, input);
        self.hold = self.judge_restart(q, input);

        // 2. the reaction to a detected collision, and every other change of mode
        let next = modes::next_mode(self.mode, &self.conditions(&safety));
        self.switch_to(next, q);

        // 3. the active behaviour
        let behaviour = self.behave(q, qd, dt, &safety, input);

        // 4. avoidance (eqs. 19-20, SNS; CLIK without perception), then tracking
        if let Behaviour::Cartesian(c) = behaviour {
            let fresh = input.perception.filter(|_| safety.perception_fresh);
            self.resolve(&c, dt, input.perception.is_some(), fresh);
            self.track(q, qd, dt, &c);
        } else {
            self.resolver.skip_ssm_period();
        }

        // 5. the torque law: τ = M a + C q̇ + g [− r for the reflex, eq. 9]
        let minus_r = matches!(behaviour, Behaviour::Joint { minus_r: true });
        self.torque_law(input.residual.filter(|_| minus_r).map(|r| r.r));

        // 6. the limits of the model
        let limits = self.limits.apply(
            q,
            qd,
            &self.terms.m_diag,
            &self.terms.gravity,
            &mut self.tau,
        );
        ControlOutput {
            tau: &self.tau,
            mode: self.mode,
            limits,
        }
    }

    /// The behaviour state after the last step, written into `buf` (room:
    /// [`snapshot::BEHAVIOUR_BYTES`] holds the default configurations'):
    /// the bytes written. Allocates nothing. What it holds and leaves out:
    /// [`snapshot`].
    pub fn save_behaviour(&self, buf: &mut [u8]) -> Result<usize, SnapshotError> {
        let have = buf.len();
        // one pass: the header's place first, filled once the length is known
        let mut w = Writer::new(buf);
        snapshot::write_header(&mut w, &Layout::BLANK);
        self.save_state(&mut w);
        let (len, overflowed) = (w.len(), w.overflowed());
        if overflowed {
            return Err(SnapshotError::BufferTooSmall { need: len, have });
        }
        let layout = self.layout_of(len);
        debug_assert_eq!(layout, self.behaviour_layout());
        snapshot::write_header(&mut Writer::new(buf), &layout);
        Ok(len)
    }

    /// Adopt a peer's behaviour state (saved by a controller of the same
    /// configuration after its step of the previous state, whether this one
    /// stepped that state or missed it; bytes after the snapshot's length
    /// are ignored). A snapshot of
    /// another robot or configuration, a truncated or malformed one is
    /// refused, and on any error `self` is left unchanged: the header and
    /// length are checked, then a dry run reads and validates all of it,
    /// then it is loaded. Allocates nothing.
    pub fn adopt_behaviour(&mut self, bytes: &[u8]) -> Result<(), SnapshotError> {
        let body = snapshot::check_header(bytes, &self.behaviour_layout())?;
        snapshot::load_checked(self, body, Controller::load_state)
    }

    /// Follow a peer's path history from its behaviour state (`bytes`, as
    /// [`Controller::adopt_behaviour`] takes it) without adopting the rest:
    /// its newest entry is taken when it is the one after this controller's
    /// ([`PathHistory::follow`]). What a hot standby resting through the
    /// periods the one in charge answers does with each behaviour it
    /// receives, so that after taking over, a retreat walks back the same
    /// entries. A malformed snapshot is refused and changes nothing.
    /// Allocates nothing.
    pub fn follow_behaviour(&mut self, bytes: &[u8]) -> Result<(), SnapshotError> {
        let n = self.n;
        let body = snapshot::any_body(bytes, n as u32)?;
        let mut r = Reader::new(body);
        let pushes = r.u64();
        let s = r.f64();
        let mut q = [0.0; MAX_DOF];
        for x in q[..n].iter_mut() {
            *x = r.f64();
        }
        r.finish_prefix(snapshot::HEADER_BYTES)?;
        if s.is_finite() && q[..n].iter().all(|x| x.is_finite()) {
            self.history.follow(pushes, s, &q[..n]);
        }
        Ok(())
    }

    /// The snapshot's layout for this configuration: its length (a counting
    /// pass) and a fingerprint of the sizes the configuration sets.
    fn behaviour_layout(&self) -> Layout {
        let mut count = Writer::new(&mut []);
        snapshot::write_header(&mut count, &Layout::BLANK);
        self.save_state(&mut count);
        self.layout_of(count.len())
    }

    /// The layout of a snapshot of `bytes` bytes of this configuration.
    fn layout_of(&self, bytes: usize) -> Layout {
        let sizes = [
            self.n as u64,
            self.resolver.control_points() as u64,
            u64::from(self.resolver.ssm_enabled()),
            u64::from(self.collab.is_some()),
            self.task.waypoints() as u64,
            self.history.capacity() as u64,
            bytes as u64,
        ];
        Layout {
            dof: self.n as u32,
            bytes,
            fingerprint: snapshot::fingerprint(&sizes),
        }
    }

    /// The behaviour state, in the order [`Controller::load_state`] reads it.
    /// It begins with the path history's record (for
    /// [`Controller::follow_behaviour`], whatever the layout after it).
    fn save_state(&self, w: &mut Writer<'_>) {
        let n = self.n;
        // the path history: its count of pushes, its newest entry
        w.u64(self.history.pushes());
        let (s, q) = self.history.newest().unwrap_or((0.0, &[]));
        w.f64(s);
        for i in 0..n {
            w.f64(q.get(i).copied().unwrap_or(0.0));
        }
        self.mode.save(w);
        self.t.save(w);
        self.last_stamp.save(w);
        self.quiet_since.save(w);
        self.collab_from_segment.save(w);
        self.hold.save(w);
        // the posture: empty until the first start, then n joints; n slots always
        w.u64(self.posture.len() as u64);
        for i in 0..n {
            w.f64(self.posture.get(i).copied().unwrap_or(0.0));
        }
        self.counters.save(w);
        // the velocity estimate: the last positions, q̇, whether it saw any
        let (last_q, qd, primed) = self.velocity.state();
        snapshot::save_slice(w, last_q);
        snapshot::save_slice(w, qd);
        w.bool(primed);
        self.task_x_d.save(w);
        self.safety.save(w);
        self.resolver.save(w);
        self.reference.save(w);
        // the path history: the count of its entries only
        w.u64(self.history.available() as u64);
        self.task.save(w);
        self.reaction.save(w);
        w.bool(self.collab.is_some());
        if let Some(c) = &self.collab {
            c.save(w);
        }
        w.bool(self.restart.is_some());
        match &self.restart {
            Some(h) => h.save(w),
            None => RestartHold::new(0.0, 0.0).save(w),
        }
    }

    /// Load what [`Controller::save_state`] wrote (nothing stored on a dry run).
    fn load_state(&mut self, r: &mut Reader<'_>) {
        let n = self.n;
        let pushes = r.u64();
        // the newest entry: the follower's (this history holds it already)
        for _ in 0..=n {
            r.f64();
        }
        if r.applying() {
            self.history.set_pushes(pushes);
        }
        self.mode.load(r);
        self.t.load(r);
        self.last_stamp.load(r);
        self.quiet_since.load(r);
        self.collab_from_segment.load(r);
        self.hold.load(r);
        let posture_len = r.usize();
        if posture_len != 0 && posture_len != n {
            r.fail();
        }
        let mut posture = [0.0; MAX_DOF];
        for p in posture[..n].iter_mut() {
            *p = r.f64();
        }
        if r.applying() {
            // within the capacity reserved at construction: no allocation
            self.posture.clear();
            self.posture.extend_from_slice(&posture[..posture_len]);
        }
        self.counters.load(r);
        let last_q = snapshot::load_joints(r, n);
        let qd = snapshot::load_joints(r, n);
        let primed = r.bool();
        if r.applying() {
            // the lengths were checked: n joints
            let taken = self.velocity.set_state(&last_q[..n], &qd[..n], primed);
            debug_assert!(taken);
        }
        self.task_x_d.load(r);
        self.safety.load(r);
        self.resolver.load(r);
        self.reference.load(r);
        let entries = r.usize();
        if r.applying() {
            // the peer's newest entries are (of a standby adopting every
            // period) this one's newest: keep as many as both hold
            self.history.keep_newest(entries);
        }
        self.task.load(r);
        self.reaction.load(r);
        if r.bool() != self.collab.is_some() {
            r.fail();
        }
        if let Some(c) = self.collab.as_mut() {
            c.load(r);
        }
        let restarted = r.bool();
        let mut hold = match (&self.restart, &self.collab) {
            (Some(h), _) => h.clone(),
            (None, Some(c)) => {
                let cfg = c.machine().config();
                RestartHold::new(cfg.restart_clear_m, cfg.release_s)
            }
            (None, None) => RestartHold::new(0.0, 0.0),
        };
        hold.load(r);
        if restarted && self.collab.is_none() {
            r.fail();
        }
        r.store(&mut self.restart, restarted.then_some(hold));
    }

    /// A malformed state (wrong length, not finite): never act on it; hold
    /// the last reference with gravity only.
    fn refuse_state(&mut self) -> ControlOutput<'_> {
        self.tau.copy_from_slice(&self.terms.gravity);
        ControlOutput {
            tau: &self.tau,
            mode: self.mode,
            limits: LimitActivity {
                non_finite: true,
                ..Default::default()
            },
        }
    }

    /// The period since the last state \[s\] (0 for the first or a repeated
    /// stamp, at most [`MAX_GAP_PERIODS`] periods), added to the controller's time.
    fn advance_clock(&mut self, stamp_ns: u64) -> f64 {
        let dt = match self.last_stamp {
            Some(t0) if stamp_ns > t0 => {
                ((stamp_ns - t0) as f64 * 1e-9).min(MAX_GAP_PERIODS * self.params.period_s)
            }
            _ => 0.0,
        };
        self.last_stamp = Some(stamp_ns);
        self.t += dt;
        dt
    }

    /// The model terms and the end effector at the measured state, from one
    /// pass of the kinematics shared by both. A state the model refuses
    /// keeps the last terms and end effector (counted).
    fn measure(&mut self, q: &[f64], qd: &[f64]) {
        let errors = self.terms.update(&self.model, &mut self.data, q, qd);
        self.counters.model_errors += errors;
        if errors == 0 {
            let frame = self.resolver.ee_frame();
            self.ee = phri_model::frame_placement(&self.model, &self.data, frame).p;
            if let Some(c) = self.collab.as_mut() {
                c.share_kinematics(&self.data, q);
            }
        }
    }

    /// Requests may have been lost before this controller read them (its
    /// queue stayed full past the publishers' wait): one of them may have
    /// been a `stop`, so the next step stops as if it had been.
    pub fn requests_lost(&mut self) {
        self.stop_asked = true;
    }

    /// The collaboration's requests, hand, force and phase of this period.
    fn observe_collaboration(&mut self, q: &[f64], dt: f64, s: &Safety, input: &ControlInput<'_>) {
        let Some(collab) = self.collab.as_mut() else {
            let stop = RequestKind::Stop as u32;
            self.stop_asked |= input.collab.requests.iter().any(|r| r.kind == stop);
            return;
        };
        use ControlMode::*;
        let robot = match self.mode {
            Task | Slow | Approach | Contact | Follow => RobotState::Available,
            Reaction | Recover | BackOff => RobotState::Reacting,
            Sync | ProtectiveStop => RobotState::Stopped,
        };
        collab.observe(
            self.t,
            dt,
            input.state_stamp_ns,
            q,
            input.residual.filter(|r| r.valid).map(|r| r.r),
            robot,
            // a collaboration needs to see: any stale safety input ends it
            // (the task may go on slowly blind; an approach may not)
            !s.residual_fresh || !s.perception_fresh || s.perception_stop,
            &input.collab,
            input.perception.as_ref().filter(|_| s.perception_fresh),
        );
    }

    /// A restarted controller's hold: is a tracked hand at the robot?
    fn judge_restart(&mut self, q: &[f64], input: &ControlInput<'_>) -> Hold {
        let (Some(hold), Some(collab)) = (self.restart.as_mut(), self.collab.as_mut()) else {
            return Hold::Clear;
        };
        let gap = collab.nearest_hand_gap(q, input.state_stamp_ns, input.collab.skeleton);
        let judged = hold.step(self.t, gap);
        if judged == Hold::Clear {
            self.restart = None;
        }
        judged
    }

    fn conditions(&mut self, s: &Safety) -> Conditions {
        if self.mode == ControlMode::Recover {
            if s.contact || s.collision {
                self.quiet_since = None;
            } else {
                self.quiet_since.get_or_insert(self.t);
            }
        }
        let quiet = self
            .quiet_since
            .is_some_and(|since| self.t - since >= self.cfg.resume_quiet_s);
        let collab = self
            .collab
            .as_ref()
            .map(Collaboration::phase)
            .filter(|p| *p != CollabPhase::Idle);
        // `on_request = "complete"`: the task's segment in progress ends first
        let completes = self
            .collab
            .as_ref()
            .is_some_and(Collaboration::completes_segment);
        let reached = self.task.segments_ended();
        let segment_done = match (collab, self.mode) {
            (Some(_), ControlMode::Task | ControlMode::Slow) if completes => {
                reached > *self.collab_from_segment.get_or_insert(reached)
            }
            _ => true,
        };
        if collab.is_none() {
            self.collab_from_segment = None;
        }
        Conditions {
            residual_fresh: s.residual_fresh,
            collision: s.collision,
            contact: s.contact,
            perception_fresh: s.perception_fresh,
            perception_stop: s.perception_stop,
            reaction_done: self.reaction.done(self.t),
            may_resume: self.cfg.resume && quiet,
            collab,
            segment_done,
            collab_collision: self.collab.as_ref().is_some_and(Collaboration::collision),
            rearming: self.collab.as_ref().is_some_and(Collaboration::rearming),
            stop_requested: self.collab.as_mut().is_some_and(Collaboration::take_stop)
                | std::mem::take(&mut self.stop_asked),
            restart: self.hold,
        }
    }

    /// Enter `next` from the current mode (its entry actions and counts).
    fn switch_to(&mut self, next: ControlMode, q: &[f64]) {
        use ControlMode::*;
        let from = self.mode;
        match (from, next) {
            _ if next == from => {}
            (Task | Slow, Task | Slow) => {}
            (Approach | Contact | Follow | BackOff, Approach | Contact | Follow | BackOff) => {}
            (_, Approach | Contact | Follow | BackOff) => {
                let ee = self.ee;
                if let Some(c) = self.collab.as_mut() {
                    c.enter(ee);
                }
            }
            (_, Task | Slow) => {
                if from == Recover {
                    self.counters.resumes += 1;
                }
                self.start_task(q);
            }
            (_, Reaction) => {
                self.counters.detections += 1;
                self.quiet_since = None;
                self.reference.hold_here(q);
                self.reaction.enter(self.t, self.history.available());
            }
            (_, ProtectiveStop) => {
                self.counters.protective_stops += 1;
                protective_stop::enter(&mut self.reference, q);
            }
            (_, Recover) => {
                recover::enter(&mut self.reference, q, self.ee);
                self.quiet_since = None;
            }
            (_, Sync) => self.reference.hold_here(q),
        }
        self.mode = next;
    }

    /// Re-sync to the measured state and approach the path smoothly.
    fn start_task(&mut self, q: &[f64]) {
        self.reference.hold_here(q);
        if self.posture.is_empty() {
            self.posture.extend_from_slice(q);
        }
        self.task.start(self.ee);
        self.history.clear();
    }

    /// The active mode's behaviour for this period.
    fn behave(
        &mut self,
        q: &[f64],
        qd: &[f64],
        dt: f64,
        s: &Safety,
        input: &ControlInput<'_>,
    ) -> Behaviour {
        let gains = self.gains();
        match self.mode {
            ControlMode::Sync => sync::step(
                &mut self.reference,
                q,
                qd,
                self.t == 0.0,
                gains,
                &mut self.accel,
            ),
            ControlMode::ProtectiveStop => {
                protective_stop::step(&self.reference, q, qd, gains, &mut self.accel)
            }
            ControlMode::Task | ControlMode::Slow => {
                // under the barrier filter the path waits as much as the
                // filter holds the end effector back, not by its repulsion
                let c = match self.resolver.cbf_law() {
                    false => self
                        .task
                        .step(dt, (s.speed_scale, 1.0), &s.ee_v_call, &self.ee),
                    true => {
                        let scale = (s.speed_scale, self.resolver.path_scale());
                        self.task.step(dt, scale, &Vector3::zeros(), &self.ee)
                    }
                };
                self.counters.waypoints_reached = self.task.waypoints_reached();
                self.task_x_d = c.x_d;
                Behaviour::Cartesian(c)
            }
            ControlMode::Recover => {
                let evading = s.perception_fresh && input.perception.is_some();
                recover::step(&self.reference, q, qd, evading, gains, &mut self.accel)
            }
            ControlMode::Approach
            | ControlMode::Contact
            | ControlMode::Follow
            | ControlMode::BackOff => {
                match self.collab.as_mut() {
                    Some(c) => Behaviour::Cartesian(c.reference(self.ee, dt, s.speed_scale)),
                    // unreachable: no collaboration, no collaboration mode; hold
                    None => protective_stop::step(&self.reference, q, qd, gains, &mut self.accel),
                }
            }
            ControlMode::Reaction => {
                let (b, path_time) = self.reaction.step(ReactionIo {
                    q,
                    qd,
                    dt,
                    t: self.t,
                    residual: input.residual.map(|r| r.r).filter(|r| r.len() == q.len()),
                    reference: &mut self.reference,
                    limits: &self.limits,
                    history: &self.history,
                    terms: &mut self.terms,
                    gains,
                    accel: &mut self.accel,
                });
                if let Some(s) = path_time {
                    self.task.set_path_time(s);
                }
                b
            }
        }
    }

    /// Resolve a Cartesian reference into the joint reference: SNS under
    /// avoidance when the controller runs with perception (`fresh`: the
    /// results, if fresh), CLIK otherwise.
    fn resolve(
        &mut self,
        c: &CartesianRef,
        dt: f64,
        with_perception: bool,
        fresh: Option<PerceptionView<'_>>,
    ) {
        self.resolver.set_drives(&self.data.m, &self.terms.bias);
        let (model, data, rf, cfg) = (&self.model, &mut self.data, &mut self.reference, &self.cfg);
        // the perception's age now (capture → this command) [s]: the
        // barrier filter's d_s, and speed and separation monitoring's T_r
        // outside the collaboration
        let age_s = self.safety.perception_age_ns as f64 * 1e-9 + self.params.period_s;
        let ssm = matches!(
            self.mode,
            ControlMode::Task | ControlMode::Slow | ControlMode::Recover
        )
        .then_some(age_s);
        self.resolver
            .set_perception_age(age_s, dt, c.collab_hand.is_some());
        let faults: Faults = if with_perception {
            self.resolver
                .avoid(model, data, rf, c, dt, cfg, &self.posture, fresh, ssm)
        } else {
            self.resolver
                .clik(model, data, rf, c, dt, cfg, &self.posture, &self.vmax_ref)
        };
        self.counters.model_errors += faults.model;
        self.counters.avoidance_errors += faults.avoidance;
    }

    /// Keep the resolved reference inside the position limits, record the
    /// task's path in the history, and track it.
    fn track(&mut self, q: &[f64], qd: &[f64], dt: f64, c: &CartesianRef) {
        self.limits.clamp_position(&mut self.reference.q_ref);
        if let Some(s) = c.path_time {
            self.history.push(s, &self.reference.q_ref);
        }
        let gains = self.gains();
        self.reference.track(q, qd, dt, gains, &mut self.accel);
    }

    /// `τ = M(q) a + C(q, q̇) q̇ + g(q)`, minus the residual `r` when given (eq. 9).
    fn torque_law(&mut self, minus_r: Option<&[f64]>) {
        let n = self.n;
        for i in 0..n {
            let mut t = self.terms.bias[i];
            for k in 0..n {
                t += self.data.m[(i, k)] * self.accel[k];
            }
            if let Some(r) = minus_r {
                t -= r[i];
            }
            self.tau[i] = t;
        }
    }

    fn gains(&self) -> TrackingGains {
        TrackingGains {
            kp: self.cfg.kp,
            kd: self.cfg.kd,
        }
    }

    /// The robot model.
    pub fn model(&self) -> &Model {
        &self.model
    }

    /// What the controller was built with besides `[control]`.
    pub fn params(&self) -> &ControllerParams {
        &self.params
    }

    /// The current mode (the last step's).
    pub fn mode(&self) -> ControlMode {
        self.mode
    }

    /// The configured reaction strategy.
    pub fn reaction(&self) -> Reaction {
        self.reaction.strategy()
    }

    /// The last torque \[Nm\] (limits enforced).
    pub fn tau(&self) -> &[f64] {
        &self.tau
    }

    /// Joint reference \[rad\].
    pub fn q_ref(&self) -> &[f64] {
        &self.reference.q_ref
    }

    /// Estimated joint velocity [rad/s] of the last step.
    pub fn velocity(&self) -> &[f64] {
        self.velocity.velocity()
    }

    /// End-effector position at the measured joints \[m\], base frame.
    pub fn ee(&self) -> Vector3<f64> {
        self.ee
    }

    /// The task's latest end-effector reference \[m\], base frame (where its
    /// path is, whether or not the end effector follows it).
    pub fn task_reference(&self) -> Vector3<f64> {
        self.task_x_d
    }

    /// The task's segments ended since the start (path segments, reached or
    /// not, and rejoining approaches).
    pub fn task_segments_ended(&self) -> u64 {
        self.task.segments_ended()
    }

    /// Entries of the retreat's path history held (one per period of the
    /// task since its last start, at most its room).
    pub fn path_history_entries(&self) -> usize {
        self.history.available()
    }

    /// The collaboration layer (`None`: disabled).
    pub fn collaboration(&self) -> Option<&Collaboration> {
        self.collab.as_ref()
    }

    /// Counts since the start.
    pub fn counters(&self) -> &ControlCounters {
        &self.counters
    }

    /// What the control-barrier filter did so far (none under the paper's law).
    pub fn cbf_counters(&self) -> Option<crate::cbf::CbfCounters> {
        self.resolver
            .cbf_law()
            .then(|| self.resolver.cbf_counters())
    }

    /// What speed and separation monitoring did so far.
    pub fn ssm_counters(&self) -> crate::resolve::SsmCounters {
        self.resolver.ssm_counters()
    }

    /// What speed and separation monitoring saw in the last step.
    pub fn ssm_period(&self) -> crate::resolve::SsmPeriod {
        self.resolver.ssm_period()
    }

    /// Speed and separation monitoring is configured (`[ssm] enabled`).
    pub fn ssm_enabled(&self) -> bool {
        self.resolver.ssm_enabled()
    }

    /// Model calls refused since the start (each with its fail-safe).
    pub fn model_errors(&self) -> u64 {
        self.counters.model_errors
    }

    /// Age of the perception results used in the last step \[ns\] (u64::MAX: none).
    pub fn perception_age_ns(&self) -> u64 {
        self.safety.perception_age_ns
    }

    /// Smallest obstacle distance of the control points last seen \[m\].
    pub fn last_min_distance(&self) -> f64 {
        self.safety.last_min_distance
    }

    /// Age of the residual used in the last step \[ns\] (u64::MAX: none).
    pub fn residual_age_ns(&self) -> u64 {
        self.safety.residual_age_ns
    }

    /// Largest risk ‖V_Call‖/V_max over the control points in the last step.
    pub fn risk(&self) -> f64 {
        self.safety.risk
    }

    /// Task scale of the last SNS solution.
    pub fn task_scale(&self) -> f64 {
        self.resolver.task_scale()
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::inputs::ResidualView;

    const Q0: [f64; 7] = [0.0, -0.4, 0.0, 1.8, 0.0, -0.6, 0.0];
    const MS: u64 = 1_000_000;

    fn lwr4() -> Model {
        Model::from_urdf_file(concat!(
            env!("CARGO_MANIFEST_DIR"),
            "/../../deploy/robots/kuka_lwr4.urdf"
        ))
        .unwrap()
    }

    fn controller(reaction: Reaction) -> Controller {
        let cfg = ControlConfig {
            reaction,
            ..Config::defaults().control
        };
        Controller::new(lwr4(), cfg, ControllerParams { period_s: 0.001 }).unwrap()
    }

    /// A residual computed from the state at `stamp_ms`.
    fn residual(stamp_ms: u64, r: &[f64], collision: bool) -> ResidualView<'_> {
        ResidualView {
            state_stamp_ns: stamp_ms * MS,
            r,
            valid: true,
            contact: collision,
            collision,
        }
    }

    fn input<'a>(stamp_ms: u64, q: &'a [f64], r: Option<ResidualView<'a>>) -> ControlInput<'a> {
        ControlInput {
            state_stamp_ns: stamp_ms * MS,
            q,
            residual: r,
            perception: None,
            collab: Default::default(),
        }
    }

    /// `M(q) a + C(q, q̇) q̇ + g(q)` from the model directly.
    fn computed_torque(model: &Model, q: &[f64], qd: &[f64], a: &[f64]) -> Vec<f64> {
        let mut data = Data::new(model);
        phri_model::crba(model, &mut data, q).unwrap();
        let m = data.m.clone();
        let b = phri_model::rnea(model, &mut data, q, qd, &[0.0; 7])
            .unwrap()
            .clone();
        (0..7)
            .map(|i| b[i] + (0..7).map(|k| m[(i, k)] * a[k]).sum::<f64>())
            .collect()
    }

    #[test]
    fn reflex_torque_is_eq_9() {
        let mut c = controller(Reaction::Reflex);
        let zero = [0.0; 7];
        let out = c.step(&input(1, &Q0, Some(residual(1, &zero, false))));
        assert_eq!(out.mode, ControlMode::Task, "fresh inputs start the task");
        // the arm moved a little (q̇ ≠ 0) and the residual reports a collision
        let q: Vec<f64> = Q0
            .iter()
            .enumerate()
            .map(|(i, x)| x + 1e-4 * i as f64)
            .collect();
        let r = [3.0, -2.0, 1.5, 2.0, -1.0, 0.5, 0.3];
        let out = c.step(&input(2, &q, Some(residual(2, &r, true))));
        assert_eq!(out.mode, ControlMode::Reaction);
        assert_eq!(out.limits, LimitActivity::default());
        let tau = out.tau.to_vec();
        // τ = M (K_R r − D_R q̇) + C q̇ + g − r
        let cfg = Config::defaults().control;
        let qd = c.velocity().to_vec();
        assert!(qd[6] > 0.01, "the estimate sees the motion: {qd:?}");
        let a: Vec<f64> = (0..7)
            .map(|i| cfg.reflex_gain * r[i] - cfg.reflex_damping * qd[i])
            .collect();
        let expected = computed_torque(c.model(), &q, &qd, &a);
        for i in 0..7 {
            assert!(
                (tau[i] - (expected[i] - r[i])).abs() < 1e-9,
                "joint {i}: {} vs {}",
                tau[i],
                expected[i] - r[i]
            );
        }
        assert_eq!(c.counters().detections, 1);
    }

    #[test]
    fn protective_stop_holds_where_it_stopped_and_recovers_first() {
        let mut c = controller(Reaction::Stop);
        let zero = [0.0; 7];
        c.step(&input(1, &Q0, Some(residual(1, &zero, false))));
        // the residual stops at 1 ms: from 7 ms on it is older than 5 ms
        for k in 2..=6 {
            let out = c.step(&input(k, &Q0, Some(residual(1, &zero, false))));
            assert_eq!(out.mode, ControlMode::Task);
        }
        let model = lwr4();
        let g = phri_model::gravity(&model, &mut Data::new(&model), &Q0)
            .unwrap()
            .clone();
        let out = c.step(&input(7, &Q0, Some(residual(1, &zero, false))));
        assert_eq!(out.mode, ControlMode::ProtectiveStop);
        // at the hold, at rest: gravity alone
        for i in 0..7 {
            assert!((out.tau[i] - g[i]).abs() < 1e-9);
        }
        // pushed away from the hold: a = K_P (q_hold − q) − K_D q̇ pulls it back
        let mut q = Q0;
        q[1] += 0.001;
        let out = c.step(&input(8, &q, Some(residual(1, &zero, false))));
        assert_eq!(out.mode, ControlMode::ProtectiveStop);
        assert_eq!(out.limits, LimitActivity::default());
        let tau = out.tau.to_vec();
        let cfg = Config::defaults().control;
        let qd = c.velocity().to_vec();
        let a: Vec<f64> = (0..7)
            .map(|i| cfg.kp * (Q0[i] - q[i]) - cfg.kd * qd[i])
            .collect();
        let expected = computed_torque(&model, &q, &qd, &a);
        for i in 0..7 {
            assert!((tau[i] - expected[i]).abs() < 1e-9, "joint {i}");
        }
        assert!(tau[1] < g[1], "pulls joint 1 back");
        assert_eq!(c.counters().protective_stops, 1, "one stop, counted once");
        // fresh again: recover (holding), never straight back to the task
        let out = c.step(&input(9, &Q0, Some(residual(9, &zero, false))));
        assert_eq!(out.mode, ControlMode::Recover);
    }

    #[test]
    fn sync_waits_for_a_residual_without_counting_stops() {
        let mut c = controller(Reaction::Reflex);
        for k in 1..=20 {
            let out = c.step(&input(k, &Q0, None));
            assert_eq!(out.mode, ControlMode::Sync);
        }
        assert_eq!(c.counters().protective_stops, 0);
        assert_eq!(c.q_ref(), Q0, "holds where it was first measured");
        let zero = [0.0; 7];
        let out = c.step(&input(21, &Q0, Some(residual(21, &zero, false))));
        assert_eq!(out.mode, ControlMode::Task);
    }

    #[test]
    fn recovering_resumes_after_a_quiet_residual() {
        let mut c = controller(Reaction::Stop);
        let zero = [0.0; 7];
        let r = [10.0, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0];
        c.step(&input(1, &Q0, Some(residual(1, &zero, false))));
        assert_eq!(
            c.step(&input(2, &Q0, Some(residual(2, &r, true)))).mode,
            ControlMode::Reaction
        );
        // reaction_min_s = 0.3 s, then recover; resume_quiet_s = 1 s later the task
        let mut modes: Vec<(ControlMode, u64)> = vec![(ControlMode::Reaction, 2)];
        for k in 3..1400 {
            let m = c.step(&input(k, &Q0, Some(residual(k, &zero, false)))).mode;
            if modes.last().map(|x| x.0) != Some(m) {
                modes.push((m, k));
            }
        }
        let names: Vec<ControlMode> = modes.iter().map(|x| x.0).collect();
        assert_eq!(
            names,
            [
                ControlMode::Reaction,
                ControlMode::Recover,
                ControlMode::Task
            ]
        );
        let (recovered, resumed) = (modes[1].1, modes[2].1);
        assert!(
            (301..=304).contains(&recovered),
            "recovered at {recovered} ms"
        );
        assert!(
            (1000..=1003).contains(&(resumed - recovered)),
            "resumed at {resumed} ms"
        );
        assert_eq!(c.counters().resumes, 1);
    }

    fn refused(cfg: &Config) -> ControlError {
        match Controller::from_config(lwr4(), cfg) {
            Ok(_) => panic!("accepted"),
            Err(e) => e,
        }
    }

    #[test]
    fn malformed_configurations_name_the_key() {
        let cfg = Config::defaults();
        let params = ControllerParams { period_s: 0.0 };
        let Err(e) = Controller::new(lwr4(), cfg.control.clone(), params) else {
            panic!("a zero period accepted")
        };
        assert!(e.to_string().starts_with("sim.dt_s"), "{e}");
        let mut bad = cfg.clone();
        bad.control.posture = vec![0.0; 3];
        let e = refused(&bad);
        assert_eq!(e.to_string(), "control.posture: expected length 7, got 3");
        let mut bad = cfg.clone();
        bad.control.ee_link = "lwr_hand".into();
        let e = refused(&bad);
        assert_eq!(
            e.to_string(),
            "control.ee_link: the robot has no link 'lwr_hand'"
        );
        let mut bad = cfg.clone();
        bad.repulsion.points[1].link = "nope".into();
        let e = refused(&bad);
        assert_eq!(
            e.to_string(),
            "repulsion.points[1].link: the robot has no link 'nope'"
        );
        let mut bad = cfg.clone();
        bad.repulsion.points.clear();
        assert!(matches!(refused(&bad), ControlError::NoControlPoints));
        let mut bad = cfg.clone();
        bad.control.kp = -1.0;
        let e = refused(&bad);
        assert!(e.to_string().starts_with("control.kp"), "{e}");
        // without avoidance no control points are needed
        bad = cfg;
        bad.control.avoidance = false;
        bad.repulsion.points.clear();
        assert!(Controller::from_config(lwr4(), &bad).is_ok());
    }

    #[test]
    fn the_history_holds_the_retreat_at_any_period() {
        let cfg = Config::defaults().control;
        for period_s in [0.001, 0.002, 0.004] {
            let c = Controller::new(lwr4(), cfg.clone(), ControllerParams { period_s }).unwrap();
            // room for the retreat and half a second more, one entry per period
            let want = ((cfg.retreat_path_s + 0.5) / period_s).ceil() as usize;
            let mut h = c.history.clone();
            for k in 0..2 * want {
                h.push(k as f64, &Q0);
            }
            assert!(h.available() >= want && h.available() <= want + 2);
        }
    }
}
