//! The run report, built from what flowed on the channels (pure: feed it
//! messages, ask for the report).

use std::collections::BTreeMap;

use phri_config::{Invalid, ResidualConfig};
use phri_ipc::{
    residual_flags, BodyPart, ContactEvent, ContactPhase, ControlMode, ControlStatus, FrameHeader,
    RepulsionResult, Residual, RobotStats, Truth, LATENCY_BINS,
};
use serde::Serialize;

use crate::realtime::RealtimeReport;
use crate::residual_model::ResidualModel;

/// `torque_loop.latency_us`.
#[derive(Clone, Debug, Default, Serialize)]
pub struct Percentiles {
    /// median, in the unit of the key that holds it
    pub p50: f64,
    /// 99th percentile
    pub p99: f64,
    /// largest
    pub max: f64,
}

/// `torque_loop` in the report: the robot's loop as `robot/stats` tells it,
/// summed over the robot's restarts.
#[derive(Clone, Debug, Default, Serialize)]
pub struct TorqueLoop {
    /// control periods run
    pub cycles: u64,
    /// periods whose command did not arrive before the next period began
    pub missed_deadlines: u64,
    /// state published → command received \[µs\]
    pub latency_us: Percentiles,
    /// periods run with the brakes engaged (start-up's wait included)
    pub braked_cycles: u64,
    /// periods the robot's own loop woke more than half a period late
    pub overruns: u64,
    /// the cycles the run's time held, those the loop did not run, and
    /// start-up's braked wait
    #[serde(flatten)]
    pub pace: crate::robot_pace::PaceReport,
}

/// `services.NAME` in the report: one supervised service.
#[derive(Clone, Debug, Default, Serialize)]
pub struct ServiceReport {
    /// restarts over the run
    pub restarts: u32,
    /// it was running when the run ended
    pub alive_at_end: bool,
}

/// One ground-truth contact episode.
#[derive(Clone, Debug, Serialize)]
pub struct ContactReport {
    /// when it began \[s\], the report's time base
    pub t_start_s: f64,
    /// when it was last seen \[s\]
    pub t_end_s: f64,
    /// robot link touched
    pub link: String,
    /// human body part
    pub part: String,
    /// largest contact force \[N\] (ground truth)
    pub peak_force_n: f64,
    /// the scenario meant it (a collaboration's touch, a scripted push):
    /// not a collision
    pub intended: bool,
    /// first collision flag of the residual after the contact began \[ms\], null if none
    pub detected_after_ms: Option<f64>,
    /// when some joint's true τ_ext first reached twice its collision threshold [ms after start], null if never
    pub reached_twice_threshold_after_ms: Option<f64>,
    /// detection delay counted from that moment \[ms\]
    pub detected_after_twice_threshold_ms: Option<f64>,
    /// first-order bound −ln(1 − θ/F)/K_I + 2 ms for F = 2θ \[ms\]
    pub bound_ms: f64,
    /// when the observer's model fed with the true τ_ext (the residual an
    /// exact model would read) first reached a collision threshold [ms after
    /// start], null if never
    pub model_crossed_threshold_after_ms: Option<f64>,
    /// the largest that model residual got during the contact, in
    /// multiples of the threshold (below 1: no observer of this bandwidth
    /// could flag the contact)
    pub model_peak_over_threshold: f64,
}

/// Times of the torque loop's events (detection, reaction, resume, …) are on
/// the robot's clock (state stamps); the supervisor's own (restart, exit) on
/// CLOCK_MONOTONIC. Both start at the run's start and differ only by the time
/// the robot's loop slipped when this machine stalled it.
#[derive(Clone, Debug, Serialize)]
pub struct Event {
    /// when \[s\] since the run's start
    pub t_s: f64,
    /// what happened: `detection`, `reaction`, `protective_stop`, `restart`,
    /// `exit`, `frozen`, ...
    pub kind: String,
    /// the service it concerns (`control`, `dynamics`, the robot's, ...)
    pub service: String,
    /// in words
    pub detail: String,
}

/// What happened right after a controller (re)started.
#[derive(Clone, Debug, Serialize)]
pub struct Resync {
    /// first status of the new controller \[s\]
    pub t_s: f64,
    /// largest true joint speed in the following 0.5 s [rad/s]
    pub max_joint_speed_rad_s: f64,
    /// largest change of the true joint positions in the following 0.5 s \[rad\]
    pub max_joint_travel_rad: f64,
}

/// Where the arm stood when a restarted simulator published its first state.
#[derive(Clone, Debug, Serialize)]
pub struct SimRestart {
    /// first state of the new simulator \[s\]
    pub t_s: f64,
    /// largest change of a true joint position against the predecessor's last state \[rad\]
    pub arm_jump_rad: f64,
}

/// `task` in the report: how far the controller's task got.
#[derive(Clone, Debug, Default, Serialize)]
pub struct TaskReport {
    /// task waypoints reached, summed over the controller's restarts
    pub waypoints_reached: u64,
    /// when the last of them was reached \[s\], null if none
    pub last_waypoint_t_s: Option<f64>,
}

/// `perception` in the report.
#[derive(Clone, Debug, Default, Serialize)]
pub struct PerceptionReport {
    /// camera frames published, every camera's (`cameras[i].frames`)
    pub frames: u64,
    /// frames that never got a result from every repulsion worker
    pub dropped_frames: u64,
    /// capture → the last worker's result \[ms\]
    pub frame_to_repulsion_ms: Percentiles,
    /// the frame's arrival at ingestion → the last worker's result \[ms\]
    /// (frames whose results all carry the arrival)
    pub arrival_to_repulsion_ms: Percentiles,
    /// ingestion's own time: the frame's arrival → its publication on
    /// `perception/depth` \[ms\] (frames seen with the arrival)
    pub ingest_ms: Percentiles,
    /// the distance computation of a frame: the sum over every worker of its
    /// compute time \[ms\] (complete frames)
    pub repulsion_compute_ms: Percentiles,
    /// the frame's arrival → its skeleton on `perception/skeleton` \[ms\]
    /// (every camera's frames whose skeleton was seen)
    pub arrival_to_skeleton_ms: Percentiles,
    /// each camera's own figures (the keys above pool every camera's frames)
    pub cameras: Vec<crate::camera_report::CameraReport>,
}

/// `robot` in the report: the arm the cell drove.
#[derive(Clone, Debug, Default, Serialize)]
pub struct RobotReport {
    /// `sim` (phri-sim's arm) or `franka` (an arm behind FCI, phri-franka)
    pub kind: String,
    /// the arm's name (`[robot] name`: `lwr4`, `fr3`, …)
    pub name: String,
    /// the arm's model name in its URDF
    pub model: String,
    /// the robot's state → command latency \[µs\] (the torque loop's: the
    /// adapter's or the simulator's)
    pub latency_us: Percentiles,
    /// periods whose command came too late (the torque loop's)
    pub missed_deadlines: u64,
    /// FCI's `control_command_success_rate`, mean over the states phri
    /// controlled the arm (null: no control box)
    pub control_command_success_rate: Option<f64>,
    /// ... its lowest
    pub control_command_success_rate_min: Option<f64>,
    /// every error of the control box, with its time
    pub box_errors: Vec<crate::box_report::BoxErrorReport>,
    /// the control box's automatic error recoveries the adapter ran
    pub box_recoveries: u64,
    /// the largest change of a true joint position from one robot state to
    /// the next of the same robot process over the run \[rad\]: a jump (after
    /// a stop, after a controller's takeover or a resume) shows here
    pub max_joint_step_rad: f64,
    /// ... when it came \[s\] (null: no step measured)
    pub max_joint_step_t_s: Option<f64>,
    /// the largest change of a true joint position across a restart of the
    /// robot's process (its first state against its predecessor's last)
    /// \[rad\]: how far the arm moved while nothing of phri served it (a real
    /// arm's control box holds it on its own then)
    pub max_restart_step_rad: f64,
    /// ... when it came \[s\] (null: no restart)
    pub max_restart_step_t_s: Option<f64>,
    /// what the robot refused: the control box's states, commands not from
    /// the slot's controller or malformed (`box_report`)
    pub refused: crate::box_report::RobotRefused,
}

/// `--report` JSON.
#[derive(Clone, Debug, Serialize)]
pub struct Report {
    /// the run was clean: every service ran to the end as configured, nothing
    /// of the evaluation was lost; otherwise `degraded` says why
    pub clean: bool,
    /// why the run was degraded (a service that kept crashing, a start that
    /// failed, an intruder on `robot/command`, lost ground truth, ...)
    pub degraded: Vec<String>,
    /// what the evaluation lost on the way (a stalled supervisor)
    pub evaluation: Evaluation,
    /// length of the run \[s\], from the cell's start to its end
    pub duration_s: f64,
    /// the scenario's name
    pub scenario: String,
    /// the arm (set by the supervisor)
    pub robot: RobotReport,
    /// the robot's torque loop
    pub torque_loop: TorqueLoop,
    /// per service: its restarts, and whether it ran at the end
    pub services: BTreeMap<String, ServiceReport>,
    /// every ground-truth contact episode, with its detection delays
    pub contacts: Vec<ContactReport>,
    /// collisions the residual flagged outside every contact episode (and
    /// the grace after one)
    pub false_detections: u64,
    /// collisions the controller detected (reactions entered)
    pub detections: u64,
    /// protective stops the controller entered
    pub protective_stops: u64,
    /// what happened, in time order
    pub events: Vec<Event>,
    /// the task's progress
    pub task: TaskReport,
    /// smallest human-robot surface distance (ground truth) \[m\], null without a human
    pub min_distance_m: Option<f64>,
    /// controller (re)starts after the first, and how the arm moved right after
    pub resyncs: Vec<Resync>,
    /// simulator (re)starts after the first, and how far the arm jumped
    pub sim_restarts: Vec<SimRestart>,
    /// null when the cell ran without perception
    pub perception: Option<PerceptionReport>,
    /// per service, the CPU its processes used over the run against its
    /// budget (set by the supervisor)
    pub cpu: BTreeMap<String, crate::cpu::CpuReport>,
    /// the supervisor's own CPU: its time over the run, start-up included,
    /// its share of one core over the run's duration (not a service: no
    /// budget; null before the run's end)
    pub supervisor_cpu: Option<crate::cpu::CpuReport>,
    /// the collaboration layer (empty lists when nothing happened)
    pub collaboration: crate::collab_report::CollabReport,
    /// the voice layer's microphone
    pub voice: crate::mic_report::VoiceReport,
    /// ISO/TS 15066: every contact against its body region's force limit
    /// (Annex A): region, transient or quasi-static, limit and margin
    pub iso_ts_15066: IsoSection,
    /// real-time scheduling as the services got it
    pub realtime: RealtimeReport,
    /// protective stops by cause: `stale_residual`, `stale_perception`
    /// (a service's input was late: the run is not clean), `request` (a
    /// `stop` request: the person's word, not a fault)
    pub protective_stop_causes: BTreeMap<String, u64>,
    /// the run in one line, as the supervisor prints it last: `clean`, or
    /// `degraded (…)` naming what a user must know about
    pub summary: String,
    /// what the readers of the owned channels refused (strangers, stamps
    /// from the future or past their bound), per reader and channel
    pub inputs: crate::owned::InputsReport,
    /// the controllers: the hot standby's takeovers
    pub control: crate::standby_report::ControlReport,
    /// the residual services: the hot standby's beside the first
    pub dynamics: crate::standby_report::DynamicsReport,
    /// the control-barrier filter (`[avoidance] law = "cbf"`; null under
    /// the paper's law)
    pub barrier: Option<crate::barrier_report::BarrierReport>,
}

/// `iso_ts_15066` in the report: every contact judged against its body
/// region's limit and speed and separation monitoring's counts
/// ([`phri_iso15066::Judged`], its keys at this level), and the violations of
/// the standard's own protective separation distance beside the configured
/// one's (`ssm_violations`).
#[derive(Clone, Debug, Default, PartialEq, Serialize)]
pub struct IsoSection {
    /// the contacts judged and speed and separation monitoring's counts
    /// (their keys at this level)
    #[serde(flatten)]
    pub judged: phri_iso15066::Judged,
    /// violations of the protective separation distance computed with
    /// ISO 13855's human speed (2.0 m/s within 0.5 m, 1.6 m/s beyond) in
    /// place of the configured one (`[ssm] human_speed`), the other terms
    /// as configured: what the standard's own S_p would have counted
    pub ssm_violations_standard: u64,
}

impl std::ops::Deref for IsoSection {
    type Target = phri_iso15066::Judged;
    fn deref(&self) -> &phri_iso15066::Judged {
        &self.judged
    }
}

impl std::ops::DerefMut for IsoSection {
    fn deref_mut(&mut self) -> &mut phri_iso15066::Judged {
        &mut self.judged
    }
}

/// The controller's perception staleness bound until the configuration's
/// is given ([`Evaluator::with_stale_bounds`]) [ns].
const DEFAULT_PERCEPTION_MAX_AGE_NS: u64 = 100_000_000;

/// The bounds past which the controller's safety inputs are stale
/// (`[control] residual_max_age_ms`, `perception_max_age_ms`): a protective
/// stop entered with an input older than its bound was caused by that
/// input's service; one entered with both fresh, by a `stop` request.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct StaleBounds {
    /// \[ns\]
    pub residual_ns: u64,
    /// \[ns\]; `None`: the cell has no perception
    pub perception_ns: Option<u64>,
}

impl StaleBounds {
    /// The bounds of `[control]`, for a cell with or without perception.
    pub fn from_config(control: &phri_config::ControlConfig, perception: bool) -> StaleBounds {
        StaleBounds {
            residual_ns: (control.residual_max_age_ms * 1e6) as u64,
            perception_ns: perception.then_some((control.perception_max_age_ms * 1e6) as u64),
        }
    }

    /// Why a protective stop entered with `status` began.
    pub fn cause(&self, status: &ControlStatus) -> StopCause {
        // u64::MAX: no residual (or no perception result) at all
        if status.residual_age_ns > self.residual_ns {
            StopCause::StaleResidual
        } else if self
            .perception_ns
            .is_some_and(|b| status.perception_age_ns > b)
        {
            StopCause::StalePerception
        } else {
            StopCause::Request
        }
    }
}

/// Why a protective stop began (see [`StaleBounds::cause`]).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum StopCause {
    /// the residual was older than its bound (dynamics late or down)
    StaleResidual,
    /// perception was older than its bound (camera, ingestion or a worker
    /// late or down)
    StalePerception,
    /// both inputs fresh: a `stop` request
    Request,
    /// a restarted controller holds while a hand is at the robot
    ControllerRestart,
}

impl StopCause {
    /// its key in `protective_stop_causes`
    pub fn key(self) -> &'static str {
        match self {
            StopCause::StaleResidual => "stale_residual",
            StopCause::StalePerception => "stale_perception",
            StopCause::Request => "request",
            StopCause::ControllerRestart => "controller_restart",
        }
    }

    /// the event's words
    pub fn detail(self) -> &'static str {
        match self {
            StopCause::StaleResidual => "the residual is stale (dynamics late or down)",
            StopCause::StalePerception => {
                "perception is stale with a person near (camera, ingestion or a worker late or down)"
            }
            StopCause::Request => "a stop request",
            StopCause::ControllerRestart => {
                "the restarted controller holds while a hand is at the robot"
            }
        }
    }

    /// caused by a service rather than a person's word
    pub fn by_service(self) -> bool {
        self != StopCause::Request
    }
}

/// `evaluation` in the report: samples that never reached the evaluator.
/// Contact episodes come from `sim/contacts` (deeply queued); a lost
/// `sim/truth` sample (1 kHz, 256 deep) only coarsens the detection timing.
#[derive(Clone, Debug, Default, Serialize)]
pub struct Evaluation {
    /// `sim/truth` samples missing from the stream (gaps in its numbering)
    pub truth_samples_lost: u64,
    /// `sim/contacts` events missing from the stream
    pub contact_events_lost: u64,
}

/// What the evaluator needs to know about the detector.
#[derive(Clone, Debug, PartialEq)]
pub struct DetectorInfo {
    /// per-joint collision thresholds \[Nm\]
    pub collision_threshold: Vec<f64>,
    /// observer gain [1/s] (the smallest, for the bound)
    pub gain: f64,
    /// `[dynamics]`, whose step response gives the bound
    pub dynamics: ResidualConfig,
}

impl DetectorInfo {
    /// The detector of `[dynamics]` for a robot of `joints` joints: its
    /// collision thresholds, and its smallest gain K_I (the slowest joint
    /// bounds the detection delay).
    pub fn from_config(dynamics: &ResidualConfig, joints: usize) -> Result<DetectorInfo, Invalid> {
        let collision_threshold = dynamics
            .collision_threshold
            .resolve(joints, "dynamics.collision_threshold")?;
        let gain = dynamics
            .gain
            .resolve(joints, "dynamics.gain")?
            .into_iter()
            .fold(f64::INFINITY, f64::min);
        Ok(DetectorInfo {
            collision_threshold,
            gain,
            dynamics: dynamics.clone(),
        })
    }
}

struct Episode {
    robot_object: i32,
    part: i32,
    t_start: f64,
    t_last: f64,
    peak: f64,
    intended: bool,
    t_twice: Option<f64>,
    t_detect: Option<f64>,
    /// when the model residual first reached a threshold
    t_model: Option<f64>,
    /// the model residual's largest ratio to the thresholds
    model_peak: f64,
    closed: bool,
}

/// Counters of a stream whose publisher may restart (then its counters restart at 0).
#[derive(Default)]
struct Restartable<T> {
    last_seq: u64,
    base: T,
    last: T,
}

/// Builds the [`Report`].
pub struct Evaluator {
    /// the microphone's figures
    mic: crate::mic_report::MicEval,
    t0_ns: u64,
    det: DetectorInfo,
    /// the residual an exact model would read, from the true τ_ext
    model: ResidualModel,
    /// when the task last reached a waypoint [s]
    last_waypoint_t: Option<f64>,
    /// the service serving `robot/state`
    robot_service: String,
    link_names: Vec<String>,
    episodes: Vec<Episode>,
    collision_edges: Vec<f64>,
    last_collision: bool,
    /// when the collision flag was last raised [s]
    last_collision_t: Option<f64>,
    min_distance: f64,
    events: Vec<Event>,
    stats: Restartable<(u64, u64, u64, u64, u64)>,
    hist_base: Vec<u64>,
    hist_last: Vec<u64>,
    latency_max_ns: u64,
    status: Restartable<(u64, u64, u64, u64)>,
    /// the controller's last mode (`None`: no status yet from this controller)
    last_mode: Option<u32>,
    /// the controller restarted and has not run its task since: a stop on
    /// fresh inputs is its hold (a hand at the robot)
    restart_pending: bool,
    /// who made the last `stop` request the controller accepted (`voice`,
    /// `gesture`, `cli`), until a protective stop names it
    stop_source: Option<String>,
    /// the last `stop` request seen: its source and number (collab/state
    /// repeats the last answered request every period)
    stop_seen: Option<(String, u64)>,
    /// each resync, the robot-clock stamp of the state its controller
    /// answered first [ns], and the true joints at that state (its reference)
    resyncs: Vec<(Resync, u64, Vec<f64>)>,
    seen_status: bool,
    /// the last status taken: its publication time [ns, CLOCK_MONOTONIC]
    /// and its state's time [ns, the robot's clock]
    status_stamps: (u64, u64),
    /// the newest truth: sequence number and true joint positions
    truth_seq: u64,
    truth_q: Vec<f64>,
    sim_restarts: Vec<SimRestart>,
    /// largest change of a true joint position between consecutive states
    /// of one robot process [rad], and when [s]
    max_joint_step: f64,
    max_joint_step_t: Option<f64>,
    /// ... across a restart of the robot's process [rad], and when [s]
    max_restart_step: f64,
    max_restart_step_t: Option<f64>,
    /// the robot state of the newest truth, and the arm there [rad]
    state_seq: u64,
    state_q: Vec<f64>,
    /// every camera's frames, results and latencies
    cameras: crate::camera_report::CamerasEval,
    /// why the run was degraded (see [`Report::degraded`])
    degraded: Vec<String>,
    /// CLOCK_MONOTONIC − robot clock [ns], from the newest controller status
    /// (which carries both): robot-clock stamps are reported on the monotonic
    /// time base of every other event
    robot_to_mono_ns: i64,
    /// ground-truth samples missing from the `sim/truth` stream (a stalled reader)
    truth_lost: u64,
    /// contact events missing from the `sim/contacts` stream
    events_lost: u64,
    last_event_seq: u64,
    /// contact episodes come from `sim/contacts` (then truth only refines them)
    events_seen: bool,
    /// how the causes of protective stops are told apart (`None`: not told)
    stale: Option<StaleBounds>,
    /// protective stops by cause
    stop_causes: BTreeMap<String, u64>,
    /// real-time scheduling as the services got it
    realtime: RealtimeReport,
    /// speed and separation monitoring as `control/ssm` told it (contacts are added at the end)
    ssm: phri_iso15066::Judged,
    /// violations of the standard's S_p: the counts of the controllers
    /// before the one publishing now, and its newest
    ssm_standard: (u64, u64),
    /// the newest `control/ssm` counts (limited periods, violations), to
    /// tell a restarted controller's
    ssm_last: (u64, u64),
    /// the control period [s]
    period_s: f64,
    /// the robot loop's pace (`robot/stats`)
    pace: crate::robot_pace::RobotPace,
}

/// `n` and `what`, in the plural unless `n` is 1.
fn plural(n: u64, what: &str) -> String {
    if n == 1 {
        format!("1 {what}")
    } else {
        format!("{n} {what}s")
    }
}

/// Episodes end after this long without the contact [s].
const CONTACT_GAP_S: f64 = 0.05;
/// A collision flag within this long after a contact ended still belongs to it [s].
const DETECTION_GRACE_S: f64 = 0.5;
/// A collision flag raised again within this long of its last period [s]
/// is the same detection (a residual that hovers at the threshold).
const DETECTION_MERGE_S: f64 = 0.1;

impl Evaluator {
    /// An evaluator of a run that started at `t0_ns` [ns, CLOCK_MONOTONIC]:
    /// `link_names` are the robot model's collision objects by index
    /// (`ContactTruth::robot_object`); body parts are named by [`BodyPart`].
    pub fn new(t0_ns: u64, det: DetectorInfo, link_names: Vec<String>) -> Evaluator {
        let joints = det.collision_threshold.len();
        // per-joint gains where the configuration resolves for these joints
        let gains = det
            .dynamics
            .gain
            .resolve(joints, "dynamics.gain")
            .unwrap_or_else(|_| vec![det.gain; joints]);
        let model = ResidualModel::new(&det.dynamics, gains, det.collision_threshold.clone());
        Evaluator {
            t0_ns,
            det,
            model,
            last_waypoint_t: None,
            robot_service: "sim".into(),
            link_names,
            episodes: Vec::new(),
            collision_edges: Vec::new(),
            last_collision: false,
            last_collision_t: None,
            min_distance: f64::INFINITY,
            events: Vec::new(),
            stats: Restartable::default(),
            hist_base: vec![0; LATENCY_BINS],
            hist_last: vec![0; LATENCY_BINS],
            latency_max_ns: 0,
            status: Restartable::default(),
            last_mode: None,
            restart_pending: false,
            stop_source: None,
            stop_seen: None,
            resyncs: Vec::new(),
            seen_status: false,
            status_stamps: (0, 0),
            truth_seq: 0,
            truth_q: Vec::new(),
            sim_restarts: Vec::new(),
            max_joint_step: 0.0,
            max_joint_step_t: None,
            max_restart_step: 0.0,
            max_restart_step_t: None,
            state_seq: 0,
            state_q: Vec::new(),
            cameras: crate::camera_report::CamerasEval::new(DEFAULT_PERCEPTION_MAX_AGE_NS),
            mic: crate::mic_report::MicEval::default(),
            degraded: Vec::new(),
            robot_to_mono_ns: 0,
            truth_lost: 0,
            events_lost: 0,
            last_event_seq: 0,
            events_seen: false,
            stale: None,
            stop_causes: BTreeMap::new(),
            realtime: RealtimeReport {
                permitted: true,
                ..Default::default()
            },
            ssm: phri_iso15066::Judged::default(),
            ssm_standard: (0, 0),
            ssm_last: (0, 0),
            period_s: 0.001,
            pace: crate::robot_pace::RobotPace::new(0.001),
        }
    }

    /// The control period \[s\] (1 ms unless told).
    pub fn with_period(mut self, period_s: f64) -> Evaluator {
        if period_s > 0.0 && period_s.is_finite() {
            self.period_s = period_s;
            self.pace = crate::robot_pace::RobotPace::new(period_s);
        }
        self
    }

    /// The simulator's truth reached this run (contact episodes or samples).
    pub fn has_truth(&self) -> bool {
        self.events_seen || self.truth_seq > 0
    }

    /// A `control/ssm` message: speed and separation monitoring's counts.
    pub fn on_ssm(&mut self, m: &phri_ipc::SsmStatus) {
        let t = self.t(m.stamp_ns);
        let (base, last) = self.ssm_standard;
        // a count below the last seen: a restarted controller's, counted anew
        // (as Judged::ssm_counts does with the configured one's)
        let restarted = m.violations_standard < last
            || m.limited_periods < self.ssm_last.0
            || m.violations < self.ssm_last.1;
        self.ssm_last = (m.limited_periods, m.violations);
        self.ssm_standard = match restarted {
            true => (base + last, m.violations_standard),
            false => (base, m.violations_standard),
        };
        self.ssm.ssm_counts(
            m.enabled != 0,
            m.limited_periods,
            m.violations,
            t,
            self.period_s,
        );
    }

    /// Tell protective stops apart by cause with these bounds.
    pub fn with_stale_bounds(mut self, bounds: StaleBounds) -> Evaluator {
        if let Some(b) = bounds.perception_ns {
            self.cameras = crate::camera_report::CamerasEval::new(b);
        }
        self.stale = Some(bounds);
        self
    }

    /// The service that serves `robot/state` (`sim`, or `franka` with a
    /// robot outside): the one its brake events name.
    pub fn with_robot_service(mut self, service: &str) -> Evaluator {
        self.robot_service = service.to_string();
        self
    }

    /// The sensors as configured: each camera's source by index, the
    /// microphone's source and device.
    pub fn with_sensors(
        mut self,
        cameras: Vec<String>,
        skeletons: Vec<String>,
        mic: (&str, &str),
    ) -> Evaluator {
        self.cameras.set_sources(cameras);
        self.cameras.set_skeleton_sources(skeletons);
        self.mic = crate::mic_report::MicEval::new(mic.0, mic.1);
        self
    }

    /// A camera's process said what it did (`camera/status`).
    pub fn on_camera_status(&mut self, m: &phri_ipc::CameraStatus) {
        self.cameras.on_status(m);
    }

    /// The microphone said what it did (`audio/mic/status`).
    pub fn on_mic_status(&mut self, m: &phri_ipc::MicStatus) {
        self.mic.on_status(m);
    }

    /// The run ended at `now_ns` \[CLOCK_MONOTONIC\]: what the robot's loop
    /// does from here on, while the services are stopped, is the shutdown's.
    pub fn on_stop(&mut self, now_ns: u64) {
        self.pace.on_stop(now_ns);
    }

    /// Real-time scheduling as the services got it (the run is degraded
    /// when any lacked something).
    pub fn set_realtime(&mut self, realtime: RealtimeReport) {
        self.realtime = realtime;
    }

    /// A robot-clock stamp [ns] on the report's time base [s since t0].
    fn t_robot(&self, ns: u64) -> f64 {
        self.t((ns as i64).saturating_add(self.robot_to_mono_ns).max(0) as u64)
    }

    /// The open episode of `(robot_object, part)`, or a new one starting at `t`.
    fn episode(&mut self, robot_object: i32, part: i32, intended: bool, t: f64) -> &mut Episode {
        let i = match self
            .episodes
            .iter()
            .position(|e| !e.closed && e.robot_object == robot_object && e.part == part)
        {
            Some(i) => i,
            None => {
                self.episodes.push(Episode {
                    robot_object,
                    part,
                    t_start: t,
                    t_last: t,
                    peak: 0.0,
                    intended,
                    t_twice: None,
                    t_detect: None,
                    t_model: None,
                    model_peak: 0.0,
                    closed: false,
                });
                self.episodes.len() - 1
            }
        };
        &mut self.episodes[i]
    }

    /// A contact event from `sim/contacts`: episodes begin, grow and end here
    /// (the truth stream refines them but may lose samples).
    pub fn on_contact_event(&mut self, m: &ContactEvent) {
        if m.seq <= self.last_event_seq {
            // a new simulator numbers its events from 1 again
            self.last_event_seq = 0;
        }
        self.events_lost += m.seq.saturating_sub(self.last_event_seq + 1);
        self.last_event_seq = m.seq;
        self.events_seen = true;
        let (t_start, t) = (self.t_robot(m.start_ns), self.t_robot(m.stamp_ns));
        let e = self.episode(m.robot_object, m.human_part, m.intended != 0, t_start);
        e.t_start = e.t_start.min(t_start);
        e.t_last = e.t_last.max(t);
        e.peak = e.peak.max(m.peak_force_n);
        if ContactPhase::try_from(m.phase) == Ok(ContactPhase::End) {
            e.closed = true;
        }
    }

    /// Ground truth lost on the way (see [`Report::evaluation`]).
    pub fn truth_samples_lost(&self) -> u64 {
        self.truth_lost
    }

    /// Mark the run degraded for `reason` (kept once per distinct reason).
    pub fn degrade(&mut self, reason: impl Into<String>) {
        let r = reason.into();
        if !self.degraded.contains(&r) {
            self.degraded.push(r);
        }
    }

    /// Seconds since the cell started at `ns` \[ns, CLOCK_MONOTONIC\].
    pub fn time_s(&self, ns: u64) -> f64 {
        self.t(ns)
    }

    fn t(&self, ns: u64) -> f64 {
        (ns as f64 - self.t0_ns as f64) * 1e-9
    }

    /// Add an event ([`Event`]) at `t_ns` \[ns, CLOCK_MONOTONIC\]: the
    /// supervisor's own (a restart, an exit, a frozen service, ...).
    pub fn event(&mut self, t_ns: u64, kind: &str, service: &str, detail: impl Into<String>) {
        let t_s = self.t(t_ns);
        self.events.push(Event {
            t_s,
            kind: kind.into(),
            service: service.into(),
            detail: detail.into(),
        });
    }

    /// The largest change of a true joint position from one robot state to
    /// the next of the same robot process \[rad\], and when it came \[s\].
    pub fn max_joint_step(&self) -> (f64, Option<f64>) {
        (self.max_joint_step, self.max_joint_step_t)
    }

    /// The largest change of a true joint position across a restart of the
    /// robot's process \[rad\], and when it came \[s\].
    pub fn max_restart_step(&self) -> (f64, Option<f64>) {
        (self.max_restart_step, self.max_restart_step_t)
    }

    /// A `sim/truth` sample: the contact episodes and their peak forces, the
    /// model residual, the nearest distance, the arm's steps and jumps.
    pub fn on_truth(&mut self, m: &Truth) {
        let t = self.t_robot(m.stamp_ns);
        if m.seq > self.truth_seq + 1 && self.truth_seq > 0 {
            self.truth_lost += m.seq - self.truth_seq - 1;
        }
        if m.min_distance.is_finite() {
            self.min_distance = self.min_distance.min(m.min_distance);
        }
        let n = (m.dof as usize).min(m.tau_ext.len());
        if m.seq < self.truth_seq && self.truth_q.len() == n {
            // a new simulator: how far from its predecessor's last state?
            let jump = m.q[..n]
                .iter()
                .zip(&self.truth_q)
                .fold(0.0f64, |a, (x, y)| a.max((x - y).abs()));
            self.sim_restarts.push(SimRestart {
                t_s: t,
                arm_jump_rad: jump,
            });
        }
        // the arm's step from one robot state to the next, and apart from
        // it across a restart of the robot (its first state against its
        // predecessor's last); truths between two states, or across lost
        // states, are no step
        if m.state_seq != self.state_seq {
            let restart = m.state_seq < self.state_seq;
            if (restart || m.state_seq == self.state_seq + 1) && self.state_q.len() == n {
                let step = m.q[..n]
                    .iter()
                    .zip(&self.state_q)
                    .fold(0.0f64, |a, (x, y)| a.max((x - y).abs()));
                let (max, at) = if restart {
                    (&mut self.max_restart_step, &mut self.max_restart_step_t)
                } else {
                    (&mut self.max_joint_step, &mut self.max_joint_step_t)
                };
                if step > *max || at.is_none() {
                    (*max, *at) = (step, Some(t));
                }
            }
            self.state_seq = m.state_seq;
            self.state_q.clear();
            self.state_q.extend_from_slice(&m.q[..n]);
        }
        self.truth_seq = m.seq;
        self.truth_q.clear();
        self.truth_q.extend_from_slice(&m.q[..n]);
        let twice = (0..n).any(|i| {
            self.det
                .collision_threshold
                .get(i)
                .is_some_and(|th| m.tau_ext[i].abs() >= 2.0 * th)
        });
        for c in m
            .contacts
            .iter()
            .take((m.n_contacts as usize).min(m.contacts.len()))
        {
            let f = (c.force[0].powi(2) + c.force[1].powi(2) + c.force[2].powi(2)).sqrt();
            let e = self.episode(c.robot_object, c.human_part, c.intended != 0, t);
            e.t_last = e.t_last.max(t);
            e.peak = e.peak.max(f);
            if twice && e.t_twice.is_none() {
                e.t_twice = Some(t);
            }
        }
        let ratio = self.model.step(t, &m.tau_ext[..n]);
        for e in self
            .episodes
            .iter_mut()
            .filter(|e| t >= e.t_start && t <= e.t_last + DETECTION_GRACE_S)
        {
            e.model_peak = e.model_peak.max(ratio);
            if ratio >= 1.0 && e.t_model.is_none() {
                e.t_model = Some(t);
            }
        }
        // with contact events, episodes end with their `end` event; without
        // them (an older simulator), after a gap in the truth
        let events = self.events_seen;
        for e in self.episodes.iter_mut().filter(|e| !e.closed && !events) {
            if t - e.t_last > CONTACT_GAP_S {
                e.closed = true;
            }
        }
        // like with like: the states from the one the new controller
        // answered first on, on the robot's clock (never a sample from before
        // a stall, mapped onto the report's time base with a stale offset)
        for (r, from_ns, q0) in self.resyncs.iter_mut() {
            if m.stamp_ns >= *from_ns && m.stamp_ns <= *from_ns + 500_000_000 {
                if q0.is_empty() {
                    q0.extend_from_slice(&m.q[..n]);
                }
                r.max_joint_speed_rad_s = m.qd[..n]
                    .iter()
                    .fold(r.max_joint_speed_rad_s, |a, v| a.max(v.abs()));
                r.max_joint_travel_rad = m.q[..n]
                    .iter()
                    .zip(q0.iter())
                    .fold(r.max_joint_travel_rad, |a, (x, y)| a.max((x - y).abs()));
            }
        }
    }

    /// A residual of `dynamics/residual`: a collision flag detects the
    /// contacts it falls in, and a new one is a `detection` event.
    pub fn on_residual(&mut self, m: &Residual) {
        if m.flags & residual_flags::VALID == 0 {
            return;
        }
        let t = self.t_robot(m.state_stamp_ns);
        let collision = m.flags & residual_flags::COLLISION != 0;
        if collision {
            for e in self.episodes.iter_mut() {
                if e.t_detect.is_none() && t >= e.t_start && t <= e.t_last + DETECTION_GRACE_S {
                    e.t_detect = Some(t);
                }
            }
            let again = self
                .last_collision_t
                .is_some_and(|tl| t - tl <= DETECTION_MERGE_S);
            self.last_collision_t = Some(t);
            if !self.last_collision && !again {
                self.collision_edges.push(t);
                let detail = if m.isolated_joint >= 0 {
                    format!(
                        "isolated joint {} (link {} or beyond), |r| = {:.1} Nm",
                        m.isolated_joint + 1,
                        m.isolated_joint + 1,
                        m.norm
                    )
                } else {
                    format!("|r| = {:.1} Nm", m.norm)
                };
                self.events.push(Event {
                    t_s: t,
                    kind: "detection".into(),
                    service: "dynamics".into(),
                    detail,
                });
            }
        }
        self.last_collision = collision;
    }

    /// The controller accepted `stop` request `seq` from `source`
    /// (`collab/state`, which repeats it every period): the protective stop
    /// it causes names it.
    pub fn stop_requested_by(&mut self, source: &str, seq: u64) {
        let seen = Some((source.to_string(), seq));
        if self.stop_seen != seen {
            self.stop_seen = seen;
            self.stop_source = Some(source.to_string());
        }
    }

    /// The controller's `control/status`: waypoints, detections, protective
    /// stops and their causes, mode changes as events (`reaction_name`: the
    /// configured reaction, for the `reaction` event), controller restarts.
    pub fn on_status(&mut self, m: &ControlStatus, reaction_name: &str) {
        // published before the last one taken, or answering an older state:
        // a controller stopped in charge that, resumed as the standby,
        // finishes the period it was stopped in (its number would read as a
        // restart that never was; the robot's clock goes on across restarts)
        let stamps = (m.stamp_ns, m.state_stamp_ns);
        let (last, last_state) = self.status_stamps;
        if self.seen_status && (stamps.0 < last || stamps.1 < last_state) {
            return;
        }
        self.status_stamps = stamps;
        // one time base: the status's publish time (CLOCK_MONOTONIC); its pair
        // of stamps maps the robot's clock (truth, residual) onto it
        if m.state_stamp_ns > 0 && m.stamp_ns > 0 {
            self.robot_to_mono_ns = m.stamp_ns as i64 - m.state_stamp_ns as i64;
        }
        let t = self.t(m.stamp_ns);
        let now = (
            m.waypoints_reached,
            m.detections,
            m.protective_stops,
            m.resumes,
        );
        if self.seen_status && m.seq < self.status.last_seq {
            self.resyncs.push((
                Resync {
                    t_s: t,
                    max_joint_speed_rad_s: 0.0,
                    max_joint_travel_rad: 0.0,
                },
                m.state_stamp_ns,
                Vec::new(),
            ));
        }
        self.seen_status = true;
        if m.seq < self.status.last_seq {
            // the controller restarted: keep what its predecessor counted
            let l = self.status.last;
            self.status.base = (
                self.status.base.0 + l.0,
                self.status.base.1 + l.1,
                self.status.base.2 + l.2,
                self.status.base.3 + l.3,
            );
            self.status.last = (0, 0, 0, 0);
            self.last_mode = None;
            self.restart_pending = true;
        }
        if now.0 > self.status.last.0 {
            self.last_waypoint_t = Some(t);
        }
        if now.3 > self.status.last.3 {
            self.events.push(Event {
                t_s: t,
                kind: "resume".into(),
                service: "control".into(),
                detail: "task resumed".into(),
            });
        }
        if self.last_mode != Some(m.mode) {
            match ControlMode::try_from(m.mode) {
                Ok(ControlMode::Reaction) => self.events.push(Event {
                    t_s: t,
                    kind: "reaction".into(),
                    service: "control".into(),
                    detail: reaction_name.into(),
                }),
                Ok(ControlMode::ProtectiveStop) => {
                    let cause = self.stale.map(|b| match b.cause(m) {
                        StopCause::Request if self.restart_pending => StopCause::ControllerRestart,
                        c => c,
                    });
                    let detail = match cause {
                        Some(cause) => {
                            *self.stop_causes.entry(cause.key().into()).or_default() += 1;
                            match (cause, self.stop_source.take()) {
                                (StopCause::Request, Some(source)) => {
                                    format!("{} ({source})", cause.detail())
                                }
                                _ => cause.detail().to_string(),
                            }
                        }
                        None => "a safety input is stale, or a stop was requested".to_string(),
                    };
                    self.events.push(Event {
                        t_s: t,
                        kind: "protective_stop".into(),
                        service: "control".into(),
                        detail,
                    })
                }
                Ok(ControlMode::Slow) => self.events.push(Event {
                    t_s: t,
                    kind: "slow".into(),
                    service: "control".into(),
                    detail: "perception stale, nothing near: slowed down".into(),
                }),
                Ok(ControlMode::Task)
                    if self.last_mode.is_none_or(|l| l == ControlMode::Sync as u32) =>
                {
                    self.events.push(Event {
                        t_s: t,
                        kind: "sync".into(),
                        service: "control".into(),
                        detail: "re-synced to the measured state, task started".into(),
                    })
                }
                _ => {}
            }
            if m.mode == ControlMode::Task as u32 {
                self.restart_pending = false;
            }
            self.last_mode = Some(m.mode);
        }
        self.status.last_seq = m.seq;
        self.status.last = now;
    }

    /// How far the robot's loop is behind the wall clock \[ns\]: the periods
    /// it did not run ([`crate::robot_pace::PaceReport::cycles_short`]).
    pub fn robot_behind_ns(&self) -> u64 {
        let period_ns = (self.period_s * 1e9).round() as u64;
        self.pace.report().cycles_short.saturating_mul(period_ns)
    }

    /// The robot's `robot/stats`: its loop's counters and latency histogram
    /// (summed over its restarts), missed deadlines and brakes as events.
    pub fn on_stats(&mut self, m: &RobotStats) {
        self.pace.on_stats(m);
        let t = self.t(m.stamp_ns);
        let now = (
            m.cycles,
            m.missed_deadlines,
            m.braked_cycles,
            m.brake_events,
            m.overruns,
        );
        if m.seq < self.stats.last_seq {
            let l = self.stats.last;
            self.stats.base = (
                self.stats.base.0 + l.0,
                self.stats.base.1 + l.1,
                self.stats.base.2 + l.2,
                self.stats.base.3 + l.3,
                self.stats.base.4 + l.4,
            );
            for (b, l) in self.hist_base.iter_mut().zip(self.hist_last.iter_mut()) {
                *b += *l;
                *l = 0;
            }
            self.stats.last = (0, 0, 0, 0, 0);
        }
        if now.1 > self.stats.last.1 {
            // when the loop missed, to the statistics' resolution (10 Hz)
            self.events.push(Event {
                t_s: t,
                kind: "missed_deadlines".into(),
                service: self.robot_service.clone(),
                detail: format!(
                    "{} commands missed since the last statistics",
                    now.1 - self.stats.last.1
                ),
            });
        }
        if now.3 > self.stats.last.3 {
            self.events.push(Event {
                t_s: t,
                kind: "brake".into(),
                service: self.robot_service.clone(),
                detail: "more than 20 consecutive commands missing: brakes engaged".into(),
            });
        }
        self.stats.last_seq = m.seq;
        self.stats.last = now;
        for (l, &h) in self.hist_last.iter_mut().zip(m.latency_hist.iter()) {
            *l = h as u64;
        }
        self.latency_max_ns = self.latency_max_ns.max(m.latency_max_ns);
    }

    /// Camera `camera` published a frame.
    pub fn on_frame(&mut self, camera: usize, h: &FrameHeader) {
        self.cameras.on_frame(camera, h);
    }

    /// Camera `camera`'s ingestion published a frame.
    pub fn on_filtered(&mut self, camera: usize, h: &FrameHeader) {
        self.cameras.on_filtered(camera, h);
    }

    /// A repulsion worker answered a frame of camera `camera`.
    pub fn on_repulsion(&mut self, camera: usize, m: &RepulsionResult) {
        self.cameras.on_repulsion(camera, m);
    }

    /// Camera `camera`'s body tracker published the people of a frame.
    pub fn on_skeleton(&mut self, camera: usize, m: &phri_ipc::Skeleton) {
        self.cameras.on_skeleton(camera, m);
    }

    fn perception(&self) -> Option<PerceptionReport> {
        self.cameras.report()
    }

    fn percentile(hist: &[u64], p: f64) -> f64 {
        let total: u64 = hist.iter().sum();
        if total == 0 {
            return 0.0;
        }
        let target = (p * total as f64).ceil().max(1.0) as u64;
        let mut acc = 0;
        for (i, &h) in hist.iter().enumerate() {
            acc += h;
            if acc >= target {
                // upper edge of the 1 µs bin
                return (i + 1) as f64;
            }
        }
        hist.len() as f64
    }

    /// What a user must know about the run: the report's `degraded` lines
    /// (the reasons given to [`Evaluator::degrade`] first, then refused
    /// real-time scheduling, missed deadlines, protective stops a service
    /// caused, restarts, lost evaluation samples, a robot that never cycled,
    /// perception that never delivered a frame, unintended contacts,
    /// contacts never detected, contacts over their ISO/TS 15066 limit,
    /// violations of the protective separation distance, requests dropped)
    /// and the summary line (`clean`, or `degraded (…)` with each in a few
    /// words), judged from the finished report `r`.
    fn verdict(&self, r: &Report) -> (Vec<String>, String) {
        let mut lines = self.degraded.clone();
        let mut words: Vec<String> = Vec::new();
        words.extend(self.realtime.kinds().into_iter().map(String::from));
        lines.extend(self.realtime.degraded());
        if !self.realtime.permitted {
            if let Some(why) = &self.realtime.refusal {
                lines.push(format!("real-time: {why}"));
            }
        }
        let missed_deadlines = r.torque_loop.missed_deadlines;
        if missed_deadlines > 0 {
            let w = plural(missed_deadlines, "missed deadline");
            lines.push(format!("torque loop: {w}"));
            words.push(w);
        }
        let tl = &r.torque_loop;
        for (line, word) in
            crate::robot_pace::finding(tl.cycles, tl.overruns, tl.braked_cycles, &tl.pace)
        {
            lines.push(line);
            words.push(word);
        }
        let by_service: Vec<(&String, &u64)> = self
            .stop_causes
            .iter()
            .filter(|(k, _)| {
                k.as_str() != StopCause::Request.key()
                    && k.as_str() != StopCause::ControllerRestart.key()
            })
            .collect();
        let stops: u64 = by_service.iter().map(|(_, n)| **n).sum();
        if stops > 0 {
            let each: Vec<String> = by_service.iter().map(|(k, n)| format!("{k} {n}")).collect();
            lines.push(format!(
                "{} on a stale safety input ({})",
                plural(stops, "protective stop"),
                each.join(", ")
            ));
            words.push(format!(
                "{} on a stale input",
                plural(stops, "protective stop")
            ));
        }
        let holds = self
            .stop_causes
            .get(StopCause::ControllerRestart.key())
            .copied()
            .unwrap_or(0);
        if holds > 0 {
            lines.push(format!(
                "{} of a restarted controller while a hand was at the robot",
                plural(holds, "protective stop")
            ));
            words.push(plural(holds, "restart hold"));
        }
        let restarted: Vec<String> = r
            .services
            .iter()
            .filter(|(_, s)| s.restarts > 0)
            .map(|(n, s)| format!("{n} {}", s.restarts))
            .collect();
        if !restarted.is_empty() {
            lines.push(format!("restarts: {}", restarted.join(", ")));
            words.push(format!("restarts: {}", restarted.join(", ")));
        }
        if self.events_lost > 0 {
            lines.push(format!(
                "the evaluation lost {} contact events of sim/contacts: contacts may be missing",
                self.events_lost
            ));
            words.push(format!(
                "{} lost",
                plural(self.events_lost, "contact event")
            ));
        }
        if self.truth_lost > 0 {
            lines.push(format!(
                "the evaluation lost {} ground-truth samples of sim/truth: contact timing coarser",
                self.truth_lost
            ));
            words.push(format!(
                "{} lost",
                plural(self.truth_lost, "ground-truth sample")
            ));
        }
        for (line, word) in crate::cpu::over_budget(&r.cpu) {
            lines.push(line);
            words.push(word);
        }
        for (line, word) in Self::safety_findings(r, self.has_perception()) {
            lines.push(line);
            words.push(word);
        }
        // the reasons given by the supervisor, in their own words, last
        words.extend(self.degraded.iter().cloned());
        let summary = if lines.is_empty() {
            "clean".to_string()
        } else {
            format!("degraded ({})", words.join("; "))
        };
        (lines, summary)
    }

    /// The cell ran perception (a staleness bound for it was given).
    fn has_perception(&self) -> bool {
        self.stale.is_some_and(|b| b.perception_ns.is_some())
    }

    /// What the run did to the person and how the cell's parts delivered,
    /// from the finished report: (a `degraded` line, its words in the
    /// summary) for each of a robot that never cycled, perception that
    /// never delivered a frame (`perception`: the cell runs it),
    /// unintended contacts, unintended contacts never detected, contacts
    /// over their ISO/TS 15066 limit (intended ones too: a touch of the
    /// collaboration within its limit is no finding), violations of the
    /// protective separation distance (the configured and the standard's),
    /// and requests dropped.
    fn safety_findings(r: &Report, perception: bool) -> Vec<(String, String)> {
        let mut out = Vec::new();
        if r.torque_loop.cycles == 0 {
            out.push((
                "torque loop: the robot never cycled (0 cycles): nothing was controlled"
                    .to_string(),
                "0 cycles".to_string(),
            ));
        }
        if perception && r.perception.as_ref().is_none_or(|p| p.frames == 0) {
            out.push((
                "perception: no camera frame arrived: the cell ran blind".to_string(),
                "no perception frame".to_string(),
            ));
        }
        let unintended: Vec<&ContactReport> = r.contacts.iter().filter(|c| !c.intended).collect();
        if !unintended.is_empty() {
            let peak = unintended
                .iter()
                .map(|c| c.peak_force_n)
                .fold(0.0f64, f64::max);
            let n = unintended.len() as u64;
            out.push((
                format!(
                    "{} (ground truth; the largest {peak:.1} N)",
                    plural(n, "unintended contact")
                ),
                plural(n, "unintended contact"),
            ));
        }
        let undetected = unintended
            .iter()
            .filter(|c| c.detected_after_ms.is_none())
            .count() as u64;
        if undetected > 0 {
            let w = format!("{} never detected", plural(undetected, "contact"));
            out.push((format!("{w} by the residual (unintended, ground truth)"), w));
        }
        let iso = &r.iso_ts_15066;
        if iso.over_limit > 0 {
            let n = iso.over_limit as u64;
            let w = format!("{} over the ISO/TS 15066 limit", plural(n, "contact"));
            let worst = iso
                .min_margin_n
                .map_or(String::new(), |m| format!(" (the worst {:.1} N over)", -m));
            out.push((format!("{w}{worst}"), w));
        }
        if iso.ssm_violations > 0 {
            let w = plural(iso.ssm_violations, "SSM violation");
            out.push((
                format!("{w}: a control point approached inside the configured protective separation distance for longer than the stop time"),
                w,
            ));
        }
        if iso.ssm_violations_standard > 0 {
            let w = format!(
                "{} of the standard's S_p",
                plural(iso.ssm_violations_standard, "SSM violation")
            );
            out.push((
                format!("{w}: a control point approached inside the protective separation distance with ISO 13855's human speed for longer than the stop time"),
                w,
            ));
        }
        let dropped = r.collaboration.requests_dropped;
        if dropped > 0 {
            let w = format!("{} dropped", plural(dropped, "request"));
            out.push((
                format!("hri/request: {w} before the controller acted on them"),
                w,
            ));
        }
        out
    }

    /// Judge the finished report `r` (after the supervisor added what other
    /// evaluators found: the collaboration, a real arm's estimated contacts):
    /// `clean`, `degraded` and `summary` from everything in it.
    pub fn conclude(&self, r: &mut Report) {
        let (degraded, summary) = self.verdict(r);
        r.clean = degraded.is_empty();
        r.degraded = degraded;
        r.summary = summary;
    }

    /// The run's contacts, each with its detection delays against the
    /// detector's bound.
    fn contacts(&self) -> Vec<ContactReport> {
        // a force of twice the threshold: the residual's step response
        // reaches one half (first order alone: ln 2 / K_I), plus 2 ms
        let bound_ms = self
            .det
            .dynamics
            .time_to_reach(self.det.gain, 0.5)
            .unwrap_or(f64::INFINITY)
            * 1000.0
            + 2.0;
        self.episodes
            .iter()
            .map(|e| {
                let ms = |x: Option<f64>, from: f64| {
                    x.map(|t| ((t - from) * 1e3 * 1000.0).round() / 1000.0)
                };
                ContactReport {
                    t_start_s: e.t_start,
                    t_end_s: e.t_last,
                    link: self
                        .link_names
                        .get(e.robot_object as usize)
                        .cloned()
                        .unwrap_or_else(|| format!("#{}", e.robot_object)),
                    part: u32::try_from(e.part)
                        .ok()
                        .and_then(|p| BodyPart::try_from(p).ok())
                        .map_or_else(|| format!("#{}", e.part), |p| p.name().to_string()),
                    peak_force_n: e.peak,
                    intended: e.intended,
                    detected_after_ms: ms(e.t_detect, e.t_start),
                    reached_twice_threshold_after_ms: ms(e.t_twice, e.t_start),
                    detected_after_twice_threshold_ms: e.t_twice.and_then(|t2| ms(e.t_detect, t2)),
                    bound_ms,
                    model_crossed_threshold_after_ms: ms(e.t_model, e.t_start),
                    model_peak_over_threshold: (e.model_peak * 1000.0).round() / 1000.0,
                }
            })
            .collect()
    }

    /// Detections outside every contact episode (and its grace).
    fn false_detections(&self) -> u64 {
        self.collision_edges
            .iter()
            .filter(|&&t| {
                !self
                    .episodes
                    .iter()
                    .any(|e| t >= e.t_start && t <= e.t_last + DETECTION_GRACE_S)
            })
            .count() as u64
    }

    /// The report at the end of the run.
    pub fn report(
        &self,
        end_ns: u64,
        scenario: &str,
        services: BTreeMap<String, ServiceReport>,
    ) -> Report {
        let (s, b) = (self.stats.last, self.stats.base);
        let hist: Vec<u64> = self
            .hist_base
            .iter()
            .zip(&self.hist_last)
            .map(|(a, b)| a + b)
            .collect();
        let contacts = self.contacts();
        let false_detections = self.false_detections();
        let st = (
            self.status.base.0 + self.status.last.0,
            self.status.base.1 + self.status.last.1,
            self.status.base.2 + self.status.last.2,
        );
        let mut events = self.events.clone();
        events.sort_by(|a, b| a.t_s.total_cmp(&b.t_s));
        let missed = s.1 + b.1;
        let mut iso_ts_15066 = IsoSection {
            judged: self.ssm.clone(),
            ssm_violations_standard: self.ssm_standard.0 + self.ssm_standard.1,
        };
        for c in &contacts {
            let touching = ((c.t_start_s, c.t_end_s), c.link.as_str(), c.part.as_str());
            let truth = phri_iso15066::ForceSource::Truth;
            iso_ts_15066.contact(touching, c.peak_force_n, c.intended, truth);
        }
        let mut report = Report {
            clean: false,
            degraded: Vec::new(),
            realtime: self.realtime.clone(),
            protective_stop_causes: self.stop_causes.clone(),
            summary: String::new(),
            inputs: Default::default(),
            control: Default::default(),
            barrier: None,
            dynamics: Default::default(),
            evaluation: Evaluation {
                truth_samples_lost: self.truth_lost,
                contact_events_lost: self.events_lost,
            },
            duration_s: self.t(end_ns),
            scenario: scenario.to_string(),
            robot: RobotReport::default(),
            torque_loop: TorqueLoop {
                cycles: s.0 + b.0,
                missed_deadlines: missed,
                latency_us: Percentiles {
                    p50: Self::percentile(&hist, 0.5),
                    p99: Self::percentile(&hist, 0.99),
                    max: self.latency_max_ns as f64 / 1000.0,
                },
                braked_cycles: s.2 + b.2,
                overruns: s.4 + b.4,
                pace: self.pace.report(),
            },
            services,
            contacts,
            false_detections,
            detections: st.1,
            protective_stops: st.2,
            events,
            task: TaskReport {
                waypoints_reached: st.0,
                last_waypoint_t_s: self.last_waypoint_t,
            },
            min_distance_m: self.min_distance.is_finite().then_some(self.min_distance),
            resyncs: self.resyncs.iter().map(|(r, _, _)| r.clone()).collect(),
            sim_restarts: self.sim_restarts.clone(),
            perception: self.perception(),
            cpu: BTreeMap::new(),
            supervisor_cpu: None,
            voice: self.mic.report(),
            collaboration: Default::default(),
            iso_ts_15066,
        };
        self.conclude(&mut report);
        report
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use phri_ipc::Zeroed;

    fn eval() -> Evaluator {
        Evaluator::new(
            0,
            DetectorInfo {
                collision_threshold: vec![5.0; 7],
                gain: 100.0,
                dynamics: phri_config::Config::defaults().dynamics,
            },
            vec!["link_a".into()],
        )
    }

    /// An evaluator whose robot ran 1000 cycles (a run that never cycled is degraded).
    fn cycled() -> Evaluator {
        let mut e = eval();
        let mut s = RobotStats::zeroed();
        s.seq = 1;
        s.cycles = 1000;
        e.on_stats(&s);
        e
    }

    /// As [`cycled`], of a cell with perception (these bounds) whose camera
    /// delivered a frame.
    fn seeing(bounds: StaleBounds) -> Evaluator {
        let mut e = cycled().with_stale_bounds(bounds);
        e.on_frame(0, &FrameHeader::zeroed());
        e
    }

    fn truth(t_ms: u64, force: f64, tau: f64) -> Truth {
        let mut m = Truth::zeroed();
        m.stamp_ns = t_ms * 1_000_000;
        m.dof = 7;
        m.tau_ext[0] = tau;
        if force > 0.0 {
            m.n_contacts = 1;
            m.contacts[0].force = [force, 0.0, 0.0];
        }
        m.min_distance = if force > 0.0 { -0.01 } else { 0.2 };
        m
    }

    #[test]
    fn the_largest_joint_step_is_kept_between_consecutive_robot_states_and_apart_across_restarts() {
        let mut e = eval();
        let e_at = |e: &mut Evaluator, seq: u64, state: u64, q3: f64| {
            let mut m = truth(seq, 0.0, 0.0);
            m.seq = seq;
            m.state_seq = state;
            m.q[3] = q3;
            e.on_truth(&m);
        };
        for (seq, q3) in [(1, 0.0), (2, 0.001), (3, 0.003), (4, 0.0035)] {
            e_at(&mut e, seq, seq, q3);
        }
        // a truth between two states (the same state again), then states lost
        e_at(&mut e, 5, 4, 0.0035);
        e_at(&mut e, 6, 9, 0.02);
        assert_eq!(e.max_restart_step(), (0.0, None));
        // the robot restarted: its first state against its predecessor's
        // last, counted apart
        e_at(&mut e, 7, 1, 0.0205);
        assert!((e.max_joint_step().0 - 0.002).abs() < 1e-12);
        assert!((e.max_restart_step().0 - 0.0005).abs() < 1e-12);
        e_at(&mut e, 8, 2, 0.0235);
        e_at(&mut e, 9, 1, 0.0335);
        let (step, at) = e.max_joint_step();
        assert!((step - 0.003).abs() < 1e-12, "{step}");
        assert!((at.unwrap() - 0.008).abs() < 1e-9);
        let (step, at) = e.max_restart_step();
        assert!((step - 0.01).abs() < 1e-12, "{step}");
        assert!((at.unwrap() - 0.009).abs() < 1e-9);
    }

    fn residual(t_ms: u64, collision: bool) -> Residual {
        let mut r = Residual::zeroed();
        r.state_stamp_ns = t_ms * 1_000_000;
        r.flags = residual_flags::VALID
            | if collision {
                residual_flags::COLLISION
            } else {
                0
            };
        r
    }

    /// The perception figures of one frame answered by two workers: capture
    /// → the last result, arrival → the last result, ingestion's own time
    /// (counted once per frame), and the workers' compute times summed.
    #[test]
    fn a_frame_s_latencies_from_capture_and_arrival_and_its_compute() {
        let mut e = eval();
        let ms = 1_000_000u64;
        let mut cam = FrameHeader::zeroed();
        cam.seq = 7;
        e.on_frame(0, &cam);
        let mut filtered = FrameHeader::zeroed();
        filtered.seq = 7;
        filtered.ingest_ns = (ms / 2) as u32;
        e.on_filtered(0, &filtered);
        // the same frame seen again (another header's value) is not counted
        filtered.ingest_ns = ms as u32;
        e.on_filtered(0, &filtered);
        // captured at 100 ms, arrived at ingestion at 102 ms
        let answer = |worker: u32, published_ms: u64, compute_ms: u64| {
            let mut m = RepulsionResult::zeroed();
            m.frame_seq = 7;
            m.frame_capture_wall_ns = 100 * ms;
            m.worker = worker;
            m.workers = 2;
            m.published_ns = published_ms * ms;
            m.since_arrival_ns = ((published_ms - 102) * ms) as u32;
            m.compute_ns = compute_ms * ms / 10;
            m
        };
        e.on_repulsion(0, &answer(0, 103, 3));
        assert!(e.perception().unwrap().frame_to_repulsion_ms.max == 0.0);
        e.on_repulsion(0, &answer(1, 104, 4));
        let p = e.perception().unwrap();
        assert_eq!(p.frames, 1);
        assert!((p.frame_to_repulsion_ms.p50 - 4.0).abs() < 1e-9, "{p:?}");
        assert!((p.arrival_to_repulsion_ms.p50 - 2.0).abs() < 1e-9, "{p:?}");
        assert!((p.ingest_ms.p50 - 0.5).abs() < 1e-9, "{p:?}");
        assert!((p.ingest_ms.max - 0.5).abs() < 1e-9, "{p:?}");
        assert!((p.repulsion_compute_ms.p50 - 0.7).abs() < 1e-9, "{p:?}");
    }

    #[test]
    fn contact_episode_detection_delay_and_false_detections() {
        let mut e = eval();
        for t in 0..100 {
            e.on_truth(&truth(t, 0.0, 0.0));
            e.on_residual(&residual(t, false));
        }
        // contact from 100 to 200 ms; τ_ext reaches 2θ = 10 at 110 ms; flag at 115 ms
        for t in 100..200 {
            e.on_truth(&truth(t, 50.0, (t - 100) as f64));
            e.on_residual(&residual(t, (115..150).contains(&t)));
        }
        for t in 200..1000 {
            e.on_truth(&truth(t, 0.0, 0.0));
            e.on_residual(&residual(t, (900..910).contains(&t)));
        }
        let r = e.report(1_000_000_000, "x", BTreeMap::new());
        assert_eq!(r.contacts.len(), 1);
        let c = &r.contacts[0];
        assert_eq!(c.link, "link_a");
        assert_eq!(c.detected_after_ms, Some(15.0));
        assert_eq!(c.reached_twice_threshold_after_ms, Some(10.0));
        assert_eq!(c.detected_after_twice_threshold_ms, Some(5.0));
        // ln 2/K_I = 6.93 ms alone; behind the 60 Hz velocity filter 9.84 ms; + 2 ms
        assert!((c.bound_ms - 11.84).abs() < 0.01, "{}", c.bound_ms);
        assert_eq!(r.false_detections, 1);
        assert_eq!(r.min_distance_m, Some(-0.01));
        assert_eq!(r.events.iter().filter(|e| e.kind == "detection").count(), 2);
    }

    #[test]
    fn a_flag_that_chatters_at_the_threshold_is_one_detection() {
        let mut e = eval();
        // raised every other period from 100 to 300 ms, then again at 500 ms
        for t in 0..1000 {
            e.on_truth(&truth(t, 0.0, 0.0));
            let on = ((100..300).contains(&t) && t % 2 == 0) || (500..510).contains(&t);
            e.on_residual(&residual(t, on));
        }
        let r = e.report(1_000_000_000, "x", BTreeMap::new());
        assert_eq!(r.events.iter().filter(|e| e.kind == "detection").count(), 2);
        assert_eq!(r.false_detections, 2);
    }

    #[test]
    fn counters_survive_publisher_restarts() {
        let mut e = eval();
        let mut s = RobotStats::zeroed();
        s.seq = 10;
        s.cycles = 1000;
        s.missed_deadlines = 2;
        s.latency_hist[50] = 1000;
        e.on_stats(&s);
        let mut s2 = RobotStats::zeroed();
        s2.seq = 1;
        s2.cycles = 500;
        s2.latency_hist[100] = 500;
        e.on_stats(&s2);
        let r = e.report(0, "x", BTreeMap::new());
        assert_eq!(r.torque_loop.cycles, 1500);
        assert_eq!(r.torque_loop.missed_deadlines, 2);
        assert_eq!(r.torque_loop.latency_us.p50, 51.0);
        assert_eq!(r.torque_loop.latency_us.p99, 101.0);
        // the misses are placed in time: one event where they grew
        let missed: Vec<_> = r
            .events
            .iter()
            .filter(|e| e.kind == "missed_deadlines")
            .collect();
        assert_eq!(missed.len(), 1, "{missed:?}");
        assert!(missed[0].detail.starts_with("2 "), "{}", missed[0].detail);
    }

    #[test]
    fn the_detector_comes_from_the_dynamics_section() {
        let mut d = phri_config::Config::defaults().dynamics;
        let det = DetectorInfo::from_config(&d, 7).unwrap();
        assert_eq!(det.collision_threshold, [8.0, 8.0, 6.0, 6.0, 4.0, 3.0, 2.0]);
        assert_eq!(det.gain, 100.0);
        d.gain = phri_config::PerJoint::Each(vec![100.0, 100.0, 80.0, 100.0, 100.0, 100.0, 100.0]);
        assert_eq!(DetectorInfo::from_config(&d, 7).unwrap().gain, 80.0);
        let err = DetectorInfo::from_config(&d, 6).unwrap_err();
        assert_eq!(err.key, "dynamics.collision_threshold");
    }

    #[test]
    fn contacts_name_the_body_part_by_its_wire_number() {
        let mut e = eval();
        let mut m = truth(0, 30.0, 0.0);
        m.contacts[0].human_part = BodyPart::ForearmRight as i32;
        e.on_truth(&m);
        m.contacts[0].human_part = 99;
        m.contacts[0].robot_object = 3;
        e.on_truth(&m);
        let r = e.report(1_000_000, "x", BTreeMap::new());
        assert_eq!(r.contacts[0].part, "forearm_right");
        assert_eq!(
            (r.contacts[1].link.as_str(), r.contacts[1].part.as_str()),
            ("#3", "#99")
        );
    }

    #[test]
    fn waypoints_add_up_across_a_controller_restart_with_the_time_of_the_last() {
        let mut e = eval();
        let status = |seq: u64, t_ms: u64, waypoints: u64| {
            let mut m = ControlStatus::zeroed();
            m.seq = seq;
            m.state_stamp_ns = t_ms * 1_000_000;
            m.stamp_ns = m.state_stamp_ns;
            m.mode = ControlMode::Task as u32;
            m.waypoints_reached = waypoints;
            m
        };
        for (seq, t_ms, w) in [(1, 100, 0), (2, 900, 1), (3, 1500, 2), (4, 1600, 2)] {
            e.on_status(&status(seq, t_ms, w), "reflex");
        }
        let r = e.report(5_000_000_000, "x", BTreeMap::new());
        assert_eq!(r.task.waypoints_reached, 2);
        assert_eq!(r.task.last_waypoint_t_s, Some(1.5));
        // the new controller counts from 0 again
        e.on_status(&status(1, 2000, 0), "reflex");
        e.on_status(&status(2, 3000, 1), "reflex");
        let r = e.report(5_000_000_000, "x", BTreeMap::new());
        assert_eq!(r.task.waypoints_reached, 3);
        assert_eq!(r.task.last_waypoint_t_s, Some(3.0));
    }

    #[test]
    fn mode_changes_are_events_and_a_new_controller_resyncs() {
        let mut e = eval();
        let status = |seq: u64, t_ms: u64, mode: ControlMode| {
            let mut m = ControlStatus::zeroed();
            m.seq = seq;
            m.state_stamp_ns = t_ms * 1_000_000;
            // published 50 µs after the state it answers
            m.stamp_ns = m.state_stamp_ns + 50_000;
            m.mode = mode as u32;
            m
        };
        let modes = [
            ControlMode::Sync,
            ControlMode::Task,
            ControlMode::Reaction,
            ControlMode::Recover,
            ControlMode::Task,
            ControlMode::ProtectiveStop,
            ControlMode::Slow,
        ];
        for (i, mode) in modes.into_iter().enumerate() {
            e.on_status(&status(i as u64 + 1, i as u64 * 100, mode), "admittance");
            e.on_status(
                &status(i as u64 + 1, i as u64 * 100 + 1, mode),
                "admittance",
            );
        }
        // a new controller: its sequence starts over, straight into the task
        e.on_status(&status(1, 1000, ControlMode::Task), "admittance");
        let r = e.report(2_000_000_000, "x", BTreeMap::new());
        let kinds: Vec<(&str, &str)> = r
            .events
            .iter()
            .map(|e| (e.kind.as_str(), e.detail.as_str()))
            .collect();
        assert_eq!(
            kinds.iter().map(|k| k.0).collect::<Vec<_>>(),
            ["sync", "reaction", "protective_stop", "slow", "sync"]
        );
        assert_eq!(kinds[1].1, "admittance");
        assert_eq!(r.resyncs.len(), 1);
        assert!(
            (r.resyncs[0].t_s - 1.00005).abs() < 1e-12,
            "{}",
            r.resyncs[0].t_s
        );
        // the travel after the restart counts from the state the new
        // controller answered first: a true state from before (a stall's
        // backlog, delivered late) is not its reference
        let truth = |seq: u64, t_ms: u64, q0: f64| {
            let mut m = Truth::zeroed();
            m.seq = seq;
            m.stamp_ns = t_ms * 1_000_000;
            m.dof = 7;
            m.q[0] = q0;
            m
        };
        e.on_truth(&truth(1, 990, 0.39));
        e.on_truth(&truth(2, 1000, 0.0));
        e.on_truth(&truth(3, 1100, 0.004));
        e.on_truth(&truth(4, 1600, 0.2));
        let r = e.report(2_000_000_000, "x", BTreeMap::new());
        assert!(
            (r.resyncs[0].max_joint_travel_rad - 0.004).abs() < 1e-12,
            "{:?}",
            r.resyncs[0]
        );
    }

    fn event(seq: u64, t_ms: u64, start_ms: u64, phase: ContactPhase, peak: f64) -> ContactEvent {
        let mut m = ContactEvent::zeroed();
        m.seq = seq;
        m.stamp_ns = t_ms * 1_000_000;
        m.start_ns = start_ms * 1_000_000;
        m.episode = 1;
        m.phase = phase as u32;
        m.peak_force_n = peak;
        m
    }

    #[test]
    fn contacts_survive_a_stalled_reader_and_losses_are_counted() {
        // the truth of a 135 N contact at 2.0-2.4 s is lost (the reader was
        // stopped and its queue overflowed): the contact events still give it
        let mut e = eval();
        e.on_truth(&truth(1999, 0.0, 0.0));
        e.on_contact_event(&event(1, 2000, 2000, ContactPhase::Begin, 20.0));
        e.on_contact_event(&event(2, 2100, 2000, ContactPhase::Update, 135.0));
        e.on_contact_event(&event(3, 2400, 2000, ContactPhase::End, 135.0));
        let mut t = truth(2900, 0.0, 0.0);
        t.seq = 2900;
        let mut first = truth(1999, 0.0, 0.0);
        first.seq = 1999;
        let mut e2 = eval();
        e2.on_truth(&first);
        e2.on_truth(&t);
        assert_eq!(e2.truth_samples_lost(), 900);
        e.on_truth(&t);
        let r = e.report(3_000_000_000, "x", BTreeMap::new());
        assert_eq!(r.contacts.len(), 1, "{:?}", r.contacts);
        assert_eq!(r.contacts[0].peak_force_n, 135.0);
        assert!((r.contacts[0].t_start_s - 2.0).abs() < 1e-9);
        assert!((r.contacts[0].t_end_s - 2.4).abs() < 1e-9);
        // an unintended contact, never detected, over the face's limit: none of it clean
        assert!(!r.clean, "{:?}", r.degraded);
        assert_eq!(
            r.summary,
            "degraded (0 cycles; 1 unintended contact; 1 contact never detected; 1 contact over the ISO/TS 15066 limit)"
        );
        // judged against its region (part 0 is the head: the face, where no
        // transient contact is allowed)
        let iso = &r.iso_ts_15066;
        assert_eq!(iso.contacts.len(), 1);
        let c = &iso.contacts[0];
        assert_eq!(
            (c.part.as_str(), c.region, c.kind),
            ("head", "face", "transient")
        );
        assert_eq!((c.limit_n, c.within_limit, iso.over_limit), (0.0, false, 1));
        // a lost contact event makes the run's evaluation degraded
        let mut e = eval();
        e.on_contact_event(&event(1, 2000, 2000, ContactPhase::Begin, 20.0));
        e.on_contact_event(&event(3, 2400, 2000, ContactPhase::End, 135.0));
        let r = e.report(3_000_000_000, "x", BTreeMap::new());
        assert!(
            !r.clean && r.evaluation.contact_events_lost == 1,
            "{:?}",
            r.degraded
        );
        // a restarted simulator numbers its events from 1 again: nothing lost
        let mut e = eval();
        e.on_contact_event(&event(5, 2000, 2000, ContactPhase::Begin, 20.0));
        e.on_contact_event(&event(1, 2500, 2500, ContactPhase::Begin, 20.0));
        assert_eq!(e.events_lost, 4, "the first stream began at 5");
    }

    #[test]
    fn the_separation_monitors_counts_reach_the_iso_section_with_their_times() {
        let mut e = eval().with_period(0.002);
        let ssm = |t_ms: u64, limited: u64, violations: u64| phri_ipc::SsmStatus {
            stamp_ns: t_ms * 1_000_000,
            enabled: 1,
            limited_periods: limited,
            violations,
            ..phri_ipc::SsmStatus::zeroed()
        };
        e.on_ssm(&ssm(1000, 0, 0));
        e.on_ssm(&ssm(1500, 250, 0));
        let mut m = ssm(2500, 500, 1);
        m.violations_standard = 3;
        e.on_ssm(&m);
        // a restarted controller counts from 0
        e.on_ssm(&ssm(3000, 100, 0));
        let mut m = ssm(4000, 100, 1);
        m.violations_standard = 2;
        e.on_ssm(&m);
        let r = e.report(5_000_000_000, "walk-in", BTreeMap::new());
        let iso = &r.iso_ts_15066;
        assert!(iso.ssm_enabled);
        assert!(
            (iso.ssm_limited_s - 1.2).abs() < 1e-9,
            "{}",
            iso.ssm_limited_s
        );
        assert_eq!(iso.ssm_violations, 2);
        assert_eq!(iso.ssm_violation_times_s, [2.5, 4.0]);
        let json = serde_json::to_value(&r).unwrap();
        assert_eq!(json["iso_ts_15066"]["ssm_violations"], 2);
        // the standard's own S_p beside it, added up across the restart
        assert_eq!(json["iso_ts_15066"]["ssm_violations_standard"], 5);
        assert_eq!(
            r.summary,
            "degraded (0 cycles; 2 SSM violations; 5 SSM violations of the standard's S_p)"
        );
    }

    #[test]
    fn robot_clock_stamps_are_mapped_onto_the_monotonic_time_base() {
        // the robot's clock lags CLOCK_MONOTONIC by 300 ms (its schedule slipped)
        let mut e = eval();
        let mut s = ControlStatus::zeroed();
        s.seq = 1;
        s.state_stamp_ns = 10_000_000_000;
        s.stamp_ns = 10_300_000_000;
        s.mode = ControlMode::Sync as u32;
        e.on_status(&s, "reflex");
        s.seq = 2;
        s.mode = ControlMode::Task as u32;
        e.on_status(&s, "reflex");
        e.on_contact_event(&event(1, 11_000, 11_000, ContactPhase::Begin, 20.0));
        e.on_contact_event(&event(2, 11_200, 11_000, ContactPhase::End, 20.0));
        let r = e.report(20_000_000_000, "x", BTreeMap::new());
        assert!(
            (r.contacts[0].t_start_s - 11.3).abs() < 1e-9,
            "{}",
            r.contacts[0].t_start_s
        );
        assert!((r.events[0].t_s - 10.3).abs() < 1e-9, "{:?}", r.events);
    }

    /// `clean` means nothing a user must know about happened: each of
    /// these makes the run degraded, and the summary line says which.
    #[test]
    fn clean_means_nothing_a_user_must_know_about_happened() {
        let services = |restarts: u32| {
            let mut m = BTreeMap::new();
            m.insert(
                "control".to_string(),
                ServiceReport {
                    restarts,
                    alive_at_end: true,
                },
            );
            m
        };
        // nothing happened
        let r = cycled().report(1_000_000_000, "x", services(0));
        assert!(r.clean && r.degraded.is_empty(), "{:?}", r.degraded);
        assert_eq!(r.summary, "clean");
        // a missed deadline
        let mut e = eval();
        let mut s = RobotStats::zeroed();
        s.seq = 1;
        s.cycles = 1000;
        s.missed_deadlines = 3;
        e.on_stats(&s);
        let r = e.report(1_000_000_000, "x", services(0));
        assert!(!r.clean);
        assert_eq!(r.summary, "degraded (3 missed deadlines)");
        // a restart
        let r = cycled().report(1_000_000_000, "x", services(1));
        assert!(!r.clean);
        assert_eq!(r.summary, "degraded (restarts: control 1)");
        // lost ground truth
        let mut e = cycled();
        let mut first = truth(1, 0.0, 0.0);
        first.seq = 1;
        e.on_truth(&first);
        let mut later = truth(10, 0.0, 0.0);
        later.seq = 10;
        e.on_truth(&later);
        let r = e.report(1_000_000_000, "x", services(0));
        assert!(!r.clean);
        assert_eq!(r.summary, "degraded (8 ground-truth samples lost)");
        // refused real-time scheduling
        let mut e = cycled();
        e.set_realtime(
            crate::realtime::RealtimeWatch::new(Some("SCHED_FIFO 80 refused".into())).report(),
        );
        let r = e.report(1_000_000_000, "x", services(0));
        assert!(!r.clean);
        assert_eq!(r.summary, "degraded (no real-time scheduling)");
        assert!(r
            .degraded
            .iter()
            .any(|l| l.contains("SCHED_FIFO 80 refused")));
        // the supervisor's own reasons come first in `degraded`, and in its words
        let mut e = cycled();
        e.degrade("dier ended 3 times");
        let r = e.report(1_000_000_000, "x", services(3));
        assert_eq!(r.degraded[0], "dier ended 3 times");
        assert_eq!(
            r.summary,
            "degraded (restarts: control 3; dier ended 3 times)"
        );
        // a robot that never cycled
        let r = eval().report(1_000_000_000, "x", services(0));
        assert!(!r.clean);
        assert_eq!(r.summary, "degraded (0 cycles)");
        // a cell with perception whose cameras never delivered a frame; one
        // without perception is not missing any
        let bounds = StaleBounds {
            residual_ns: 5_000_000,
            perception_ns: Some(100_000_000),
        };
        let mut e = cycled().with_stale_bounds(bounds);
        let r = e.report(1_000_000_000, "x", services(0));
        assert_eq!(r.summary, "degraded (no perception frame)");
        e.on_frame(0, &FrameHeader::zeroed());
        assert!(e.report(1_000_000_000, "x", services(0)).clean);
        let blind = cycled().with_stale_bounds(StaleBounds {
            perception_ns: None,
            ..bounds
        });
        assert!(blind.report(1_000_000_000, "x", services(0)).clean);
        // a contact: unintended and detected (a collision the cell reacted to)
        let contact = |intended: u32, peak: f64, detect: bool| {
            let mut e = cycled();
            let mut m = event(1, 2000, 2000, ContactPhase::Begin, peak);
            m.intended = intended;
            m.human_part = BodyPart::ForearmRight as i32;
            e.on_contact_event(&m);
            if detect {
                e.on_residual(&residual(2010, true));
            }
            let mut m = event(2, 2100, 2000, ContactPhase::End, peak);
            m.intended = intended;
            m.human_part = BodyPart::ForearmRight as i32;
            e.on_contact_event(&m);
            e.report(3_000_000_000, "x", services(0))
        };
        let r = contact(0, 60.0, true);
        assert!(!r.clean);
        assert_eq!(r.summary, "degraded (1 unintended contact)");
        assert!(
            r.degraded[0].starts_with("1 unintended contact (ground truth; the largest 60.0 N)"),
            "{:?}",
            r.degraded
        );
        // ... never detected
        let r = contact(0, 60.0, false);
        assert_eq!(
            r.summary,
            "degraded (1 unintended contact; 1 contact never detected)"
        );
        // ... over its region's limit (the lower arm: 320 N transient)
        let r = contact(0, 400.0, true);
        assert_eq!(
            r.summary,
            "degraded (1 unintended contact; 1 contact over the ISO/TS 15066 limit)"
        );
        // an intended touch of the collaboration within its limit is no finding;
        // over its limit it is
        let r = contact(1, 60.0, false);
        assert!(r.clean, "{:?}", r.degraded);
        let r = contact(1, 400.0, false);
        assert_eq!(
            r.summary,
            "degraded (1 contact over the ISO/TS 15066 limit)"
        );
        // speed and separation monitoring violated
        let mut e = cycled();
        e.on_ssm(&phri_ipc::SsmStatus {
            stamp_ns: 500_000_000,
            enabled: 1,
            violations: 2,
            ..phri_ipc::SsmStatus::zeroed()
        });
        let r = e.report(1_000_000_000, "x", services(0));
        assert_eq!(r.summary, "degraded (2 SSM violations)");
        // requests dropped (the supervisor fills the collaboration, then concludes)
        let e = cycled();
        let mut r = e.report(1_000_000_000, "x", services(0));
        assert!(r.clean);
        r.collaboration.requests_dropped = 145;
        e.conclude(&mut r);
        assert!(!r.clean);
        assert_eq!(r.summary, "degraded (145 requests dropped)");
        // concluding again judges afresh, nothing counted twice
        e.conclude(&mut r);
        assert_eq!(r.degraded.len(), 1, "{:?}", r.degraded);
    }

    /// The robot's own loop falling behind is a slip the summary names
    /// with its counts; start-up's braked wait for the first command, and
    /// its late wake-ups, are reported apart and are none.
    #[test]
    fn a_robot_loop_that_fell_behind_or_braked_after_start_up_degrades_the_run() {
        let services = |_: u32| BTreeMap::<String, ServiceReport>::new();
        let stats = |seq: u64, t_ms: u64, cycles: u64, braked: u64, overruns: u64| {
            let mut s = RobotStats::zeroed();
            (s.seq, s.stamp_ns, s.cycles) = (seq, t_ms * 1_000_000, cycles);
            (s.braked_cycles, s.overruns) = (braked, overruns);
            s
        };
        // 200 braked periods before the first command, 2 of them woken
        // late while the services started, then on time
        let mut e = eval();
        e.on_stats(&stats(1, 100, 100, 100, 2));
        e.on_stats(&stats(2, 300, 300, 200, 2));
        e.on_stats(&stats(3, 10_000, 10_000, 200, 2));
        let r = e.report(10_000_000_000, "x", services(0));
        assert!(r.clean, "{:?}", r.degraded);
        assert_eq!(r.torque_loop.pace.startup_braked_cycles, 200);
        assert_eq!(r.torque_loop.pace.startup_overruns, 2);
        assert_eq!(r.torque_loop.overruns, 2);
        assert_eq!(r.torque_loop.pace.cycles_short, 0);
        // the loop woke late 1 500 times and ran 1 000 periods short
        e.on_stats(&stats(4, 20_000, 19_000, 200, 1_502));
        let r = e.report(20_000_000_000, "x", services(0));
        assert_eq!(
            r.summary,
            "degraded (robot loop behind: 1 500 overruns, 8 % of periods)"
        );
        assert_eq!(r.torque_loop.pace.cycles_short, 1_000);
        assert!(
            r.degraded[0].contains("1 000 cycles short"),
            "{:?}",
            r.degraded
        );
        // braked again in mid-run
        let mut e = eval();
        e.on_stats(&stats(1, 100, 100, 100, 0));
        e.on_stats(&stats(2, 300, 300, 200, 0));
        e.on_stats(&stats(3, 400, 400, 230, 0));
        let r = e.report(1_000_000_000, "x", services(0));
        assert_eq!(r.summary, "degraded (30 braked cycles)");
        let json = serde_json::to_value(&r).unwrap();
        assert_eq!(json["torque_loop"]["startup_braked_cycles"], 200);
        assert_eq!(json["torque_loop"]["startup_overruns"], 0);
        assert_eq!(json["torque_loop"]["cycles_expected"], 300);
    }

    /// A protective stop a service caused (its input went stale) degrades
    /// the run; one a `stop` request caused is the person's word: clean.
    #[test]
    fn a_status_published_before_the_last_taken_is_no_controller_restart() {
        let status = |seq: u64, stamp_ms: u64| {
            let mut m = ControlStatus::zeroed();
            m.seq = seq;
            m.stamp_ns = stamp_ms * 1_000_000;
            m.state_stamp_ns = m.stamp_ns;
            m.mode = ControlMode::Task as u32;
            m
        };
        let mut e = eval();
        for seq in 1..=5 {
            e.on_status(&status(seq, seq * 10), "reflex");
        }
        // the controller stopped in charge at its status 3 finishes that
        // period once resumed, after the standby's 4 and 5; or it was
        // stopped before its step was done and publishes it late
        e.on_status(&status(3, 35), "reflex");
        let mut late = status(3, 30);
        late.stamp_ns = 55_000_000;
        e.on_status(&late, "reflex");
        e.on_status(&status(6, 60), "reflex");
        let r = e.report(1_000_000_000, "x", BTreeMap::new());
        assert!(r.resyncs.is_empty(), "{:?}", r.resyncs);
        // the start's own
        let syncs = r.events.iter().filter(|e| e.kind == "sync").count();
        assert_eq!(syncs, 1, "{:?}", r.events);
        // a restarted controller (published later, numbered from 1 again) is one
        e.on_status(&status(1, 70), "reflex");
        let r = e.report(1_000_000_000, "x", BTreeMap::new());
        assert_eq!(r.resyncs.len(), 1);
    }

    #[test]
    fn protective_stops_are_told_apart_by_cause() {
        let bounds = StaleBounds {
            residual_ns: 5_000_000,
            perception_ns: Some(100_000_000),
        };
        let status = |seq: u64, mode: ControlMode, residual_ms: u64, perception_ms: u64| {
            let mut m = ControlStatus::zeroed();
            m.seq = seq;
            m.state_stamp_ns = seq * 1_000_000;
            m.stamp_ns = m.state_stamp_ns + 50_000;
            m.mode = mode as u32;
            m.residual_age_ns = residual_ms * 1_000_000;
            m.perception_age_ns = perception_ms * 1_000_000;
            m
        };
        let run = |stop: ControlStatus| {
            let mut e = seeing(bounds);
            e.on_status(&status(1, ControlMode::Task, 1, 30), "reflex");
            e.on_status(&stop, "reflex");
            e.report(1_000_000_000, "x", BTreeMap::new())
        };
        // a stop request: both inputs fresh
        let r = run(status(2, ControlMode::ProtectiveStop, 1, 30));
        assert!(r.clean, "{:?}", r.degraded);
        assert_eq!(r.protective_stop_causes["request"], 1);
        let ev = r
            .events
            .iter()
            .find(|e| e.kind == "protective_stop")
            .unwrap();
        assert_eq!(ev.detail, "a stop request");
        // the request's source, when collab/state told it first
        let mut e = seeing(bounds);
        e.on_status(&status(1, ControlMode::Task, 1, 30), "reflex");
        e.stop_requested_by("voice", 3);
        e.stop_requested_by("voice", 3);
        e.on_status(&status(2, ControlMode::ProtectiveStop, 1, 30), "reflex");
        let r = e.report(1_000_000_000, "x", BTreeMap::new());
        let ev = r
            .events
            .iter()
            .find(|e| e.kind == "protective_stop")
            .unwrap();
        assert_eq!(ev.detail, "a stop request (voice)");
        // the residual stale (dynamics killed)
        let r = run(status(2, ControlMode::ProtectiveStop, 12, 30));
        assert!(!r.clean);
        assert_eq!(r.protective_stop_causes["stale_residual"], 1);
        assert_eq!(r.summary, "degraded (1 protective stop on a stale input)");
        // no residual at all
        let mut m = status(2, ControlMode::ProtectiveStop, 1, 30);
        m.residual_age_ns = u64::MAX;
        assert_eq!(run(m).protective_stop_causes["stale_residual"], 1);
        // perception stale (a camera killed)
        let r = run(status(2, ControlMode::ProtectiveStop, 1, 250));
        assert!(!r.clean);
        assert_eq!(r.protective_stop_causes["stale_perception"], 1);
        // a cell without perception: its age says nothing
        let mut e = cycled().with_stale_bounds(StaleBounds {
            perception_ns: None,
            ..bounds
        });
        let mut m = status(2, ControlMode::ProtectiveStop, 1, 0);
        m.perception_age_ns = u64::MAX;
        e.on_status(&m, "reflex");
        let r = e.report(1_000_000_000, "x", BTreeMap::new());
        assert!(r.clean && r.protective_stop_causes["request"] == 1);
        // a restarted controller (its status sequence starts again) holds on
        // fresh inputs before its task: its hold, not a request; once it ran
        // its task, a stop on fresh inputs is a request again
        // (published after its predecessor's last, answering later states)
        let restarted = |seq: u64, mode: ControlMode| {
            let mut m = status(seq, mode, 1, 30);
            m.stamp_ns += 600_000_000;
            m.state_stamp_ns += 600_000_000;
            m
        };
        let mut e = seeing(bounds);
        e.on_status(&status(500, ControlMode::Contact, 1, 30), "reflex");
        e.on_status(&restarted(3, ControlMode::Sync), "reflex");
        e.on_status(&restarted(4, ControlMode::ProtectiveStop), "reflex");
        e.on_status(&restarted(5, ControlMode::Recover), "reflex");
        e.on_status(&restarted(6, ControlMode::Task), "reflex");
        e.on_status(&restarted(7, ControlMode::ProtectiveStop), "reflex");
        let r = e.report(1_000_000_000, "x", BTreeMap::new());
        assert_eq!(r.protective_stop_causes["controller_restart"], 1);
        assert_eq!(r.protective_stop_causes["request"], 1);
        assert_eq!(r.summary, "degraded (1 restart hold)");
        let ev = r
            .events
            .iter()
            .find(|e| e.kind == "protective_stop")
            .unwrap();
        assert_eq!(
            ev.detail,
            "the restarted controller holds while a hand is at the robot"
        );
    }
}
