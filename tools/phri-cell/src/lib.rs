//! The whole cell in one process, in lock-step: the single in-process runner.
//!
//! Every service's pure step runs here exactly as its `main.rs` runs it, and
//! the steps talk through the same messages the channels carry: the robot
//! link ([`phri_sim::RobotLink`]: reuse the last command, brake after 20
//! missing) and the simulated arm publish a [`JointState`]; the residual
//! ([`phri_dynamics::DynamicsStep`]) answers it with a [`Residual`]; the camera,
//! ingestion and the repulsion workers turn the world into
//! [`RepulsionResult`]s (and the simulated tracker's skeletons the wave
//! recogniser `phri-gesture` reads); the controller reads them through
//! [`phri_control::inputs`] and answers with a [`TorqueCommand`], which the
//! robot link takes at the next period. Time is the robot's: one
//! [`Cell::tick`] is one control period. The camera samples the world every
//! `1 / rate_hz`, and a frame's results reach the controller
//! `perception_latency_ms` later (the multi-process cell measures p99 about
//! 6 ms capture → repulsion).
//!
//! Deterministic: the same configuration, scenario and offset give the same
//! run, so scenarios can be swept over the moment the person arrives
//! ([`CellOptions::human_time_offset_s`]) and asserted in tests. Services can
//! be taken down for a while ([`Outage`]): what a crashed process would
//! leave behind (nothing new on its channels) is what the others see.

use std::collections::VecDeque;

use phri_config::Loaded;
use phri_control::inputs::CollabInput;
use phri_control::write_collab_state;
use phri_control::{write_messages, ControlInput, Controller, RepulsionInputs, Stamps};
use phri_dynamics::DynamicsStep;
use phri_gesture::WaveDetector;
use phri_ipc::{
    CollabState, ControlMode, ControlStatus, HandObservation, HriRequest, JointState,
    RepulsionResult, Residual, Skeleton, TorqueCommand, WorldState, Zeroed,
};
use phri_model::Model;
use phri_perception::ingest::StateHistory;
use phri_sim::{fill_state, fill_world, CycleTiming, LinkOutput, RobotLink, Simulator};

mod outage;
mod standby;
mod summary;
pub mod trace;
pub mod truth;

pub use outage::{Down, Outage, OutageError};
pub use summary::{CellSummary, ContactEpisode, GestureRequest, StandbySummary};

/// Why a cell could not be built or stepped: the service at fault and what it said.
#[derive(Debug, thiserror::Error)]
pub enum CellError {
    #[error(transparent)]
    Config(#[from] phri_config::ConfigError),
    #[error("{service}: {message}")]
    Step {
        service: &'static str,
        message: String,
    },
    #[error("perception latency must be a finite number ≥ 0 ms, got {0}")]
    Latency(f64),
    #[error("outage of camera {camera}: the cell has {cameras} camera(s) ([[camera]])")]
    NoSuchCamera { camera: usize, cameras: usize },
}

fn step_err(service: &'static str) -> impl Fn(&dyn std::fmt::Display) -> CellError {
    move |e| CellError::Step {
        service,
        message: e.to_string(),
    }
}

/// How to run the cell beyond the configuration.
#[derive(Clone, Debug)]
pub struct CellOptions {
    /// the human script runs this far ahead of the robot \[s\] (negative: the
    /// person arrives later, meeting the arm at another phase of its cycle),
    /// on top of `[sim] human_offset_s`
    pub human_time_offset_s: f64,
    /// capture → repulsion results at the controller \[ms\]
    pub perception_latency_ms: f64,
    /// run the perception pipeline (camera, ingestion, workers)
    pub perception: bool,
    /// services that are down for a while (deterministic fault injection)
    pub outages: Vec<Outage>,
    /// replace every camera's distances by the truth ([`truth::rewrite`]):
    /// what the avoidance does with perception that hides nothing
    pub truth_perception: bool,
    /// run the hot standby beside the controller (`standby`;
    /// `phri-lockstep` follows `[control] standby`)
    pub standby: bool,
}

impl Default for CellOptions {
    fn default() -> Self {
        CellOptions {
            human_time_offset_s: 0.0,
            perception_latency_ms: 6.5,
            perception: true,
            outages: Vec::new(),
            truth_perception: false,
            standby: false,
        }
    }
}

/// A frame's repulsion results on their way to the controller.
struct InFlight {
    ready_ns: u64,
    /// the camera whose frame it is
    camera: usize,
    /// per camera, its workers' results
    results: Vec<Vec<RepulsionResult>>,
    /// the frame's skeleton, the request recognised on it, the refined hand
    skeleton: Skeleton,
    request: Option<HriRequest>,
    hand: Option<HandObservation>,
}

/// The perception side: every camera's step ([`phri_perception::Perception`]:
/// camera, tracker, ingestion, workers) and the wave recogniser.
struct Perception {
    cameras: phri_perception::Perception,
    history: StateHistory,
    world: WorldState,
    period_ns: u64,
    next_capture_ns: u64,
    /// the captures so far: whose turn is next ([`phri_perception::Perception::turn`])
    turn: u64,
    /// per camera, its newest observation of the collaborative hand
    hands: [Option<HandObservation>; phri_ipc::MAX_CAMERAS],
    /// the widest spread of the cameras' captures the controller takes the
    /// hand from, its perception's staleness bound \[ns\]
    spread_ns: u64,
    latency_ns: u64,
    in_flight: VecDeque<InFlight>,
    gesture: WaveDetector,
    /// with [`CellOptions::truth_perception`]: the control points' link
    /// radii \[m\] and eq. 16's parameters
    truth: Option<(Vec<f64>, phri_depth::RepulsionParams)>,
}

/// The person's voice: the simulated room's audio (a scenario's `[[voice]]`
/// lines) in 20 ms chunks on robot time, and the recogniser on them.
struct Voice {
    listener: phri_voice::Listener,
    playback: phri_voice::mic::Playback,
    chunk: phri_ipc::AudioChunk,
    /// the next chunk to play
    next: u64,
    skeleton_max_age_ns: u64,
}

/// The cell. `sim`, `controller` and the messages are public for tests that look inside.
pub struct Cell {
    pub sim: Simulator,
    link: RobotLink,
    dynamics: DynamicsStep,
    pub controller: Controller,
    /// the hot standby and both controllers' places ([`CellOptions::standby`])
    pair: Option<Box<standby::Pair>>,
    repulsion: RepulsionInputs,
    avoidance: bool,
    perception: Option<Perception>,
    /// the recogniser, when the scenario speaks
    voice: Option<Voice>,
    /// the robot's newest state, as published
    pub state: JointState,
    /// the newest residual the controller has received (kept while dynamics is down)
    pub residual: Option<Residual>,
    /// the newest command the robot has received (kept while the controller is down)
    pub command: Option<TorqueCommand>,
    /// the newest skeleton and refined hand the controller has received
    pub skeleton: Option<Skeleton>,
    pub hand: Option<HandObservation>,
    /// requests that reached the controller since its last period
    requests: Vec<HriRequest>,
    pub status: ControlStatus,
    link_out: LinkOutput,
    seq: u64,
    t_ns: u64,
    outages: Vec<Outage>,
    summary: summary::Accounting,
}

impl Cell {
    /// Build every step from a loaded configuration (its scenario gives the person).
    pub fn new(loaded: &Loaded, model: Model, opts: &CellOptions) -> Result<Cell, CellError> {
        let cfg = &loaded.config;
        let n = model.nv();
        let mut sim =
            Simulator::from_scenario(model.clone(), cfg.sim.clone(), &loaded.scenario, None)
                .map_err(|e| step_err("sim")(&e))?;
        sim.set_human_time_offset(cfg.sim.human_offset_s + opts.human_time_offset_s);
        let period_ns = (cfg.sim.dt_s * 1e9).round() as u64;
        let link = RobotLink::new(n, period_ns).map_err(|e| step_err("sim")(&e))?;
        let dynamics = DynamicsStep::new(model.clone(), &cfg.dynamics)
            .map_err(|e| step_err("dynamics")(&e))?;
        let avoidance = cfg.control.avoidance && opts.perception;
        let mut ctl_cfg = cfg.clone();
        ctl_cfg.control.avoidance = avoidance;
        let controller = Controller::from_config(model.clone(), &ctl_cfg)
            .map_err(|e| step_err("control")(&e))?;
        let pair = match opts.standby {
            true => Some(Box::new(standby::Pair::new(
                Controller::from_config(model.clone(), &ctl_cfg)
                    .map_err(|e| step_err("control_standby")(&e))?,
                ctl_cfg.control.clone(),
            ))),
            false => None,
        };
        let perception = if avoidance {
            if !(opts.perception_latency_ms.is_finite() && opts.perception_latency_ms >= 0.0) {
                return Err(CellError::Latency(opts.perception_latency_ms));
            }
            let mut world = WorldState::zeroed();
            world.dof = n as u32;
            let mut cameras = phri_perception::Perception::new(&model, cfg)
                .map_err(|e| step_err(e.service())(&e))?;
            // the truth replaces every distance: the workers place the points only
            cameras.set_positions_only(opts.truth_perception);
            Some(Perception {
                cameras,
                history: StateHistory::new(n, 200),
                world,
                period_ns: (1e9 / cfg.camera.rate_hz) as u64,
                next_capture_ns: 0,
                turn: 0,
                hands: [None; phri_ipc::MAX_CAMERAS],
                spread_ns: (cfg.control.perception_max_age_ms * 1e6) as u64,
                latency_ns: (opts.perception_latency_ms * 1e6) as u64,
                in_flight: VecDeque::new(),
                gesture: WaveDetector::new(&cfg.gesture).map_err(|e| step_err("gesture")(&e))?,
                truth: opts.truth_perception.then(|| {
                    let radii = cfg.repulsion.points.iter().map(|p| p.radius).collect();
                    (radii, cfg.repulsion.params)
                }),
            })
        } else {
            None
        };
        for o in &opts.outages {
            if let Down::Camera(camera) = o.service {
                if camera >= cfg.cameras.len() {
                    return Err(CellError::NoSuchCamera {
                        camera,
                        cameras: cfg.cameras.len(),
                    });
                }
            }
        }
        let voice = if loaded.scenario.voice.is_empty() {
            None
        } else {
            let file = std::path::Path::new(&cfg.scenario.file);
            let mut clips = Vec::with_capacity(loaded.scenario.voice.len());
            for line in &loaded.scenario.voice {
                clips.push(phri_voice::mic::Clip {
                    start: (line.t * phri_ipc::AUDIO_RATE_HZ as f64).round() as u64,
                    samples: phri_voice::wav::read(&line.path(file))
                        .map_err(|e| step_err("mic")(&e))?,
                });
            }
            let mut chunk = phri_ipc::AudioChunk::zeroed();
            chunk.rate_hz = phri_ipc::AUDIO_RATE_HZ;
            chunk.samples = phri_ipc::AUDIO_CHUNK_SAMPLES as u32;
            Some(Voice {
                listener: phri_voice::Listener::new(&cfg.voice)
                    .map_err(|e| step_err("voice")(&e))?,
                playback: phri_voice::mic::Playback::new(
                    clips,
                    cfg.audio.noise_dbfs,
                    cfg.audio.seed,
                ),
                chunk,
                next: 0,
                skeleton_max_age_ns: (cfg.voice.skeleton_max_age_ms * 1e6) as u64,
            })
        };
        let mut state = JointState::zeroed();
        state.dof = n as u32;
        Ok(Cell {
            voice,
            link_out: *link.output(),
            sim,
            link,
            dynamics,
            controller,
            pair,
            repulsion: RepulsionInputs::for_cell(cfg),
            avoidance,
            perception,
            state,
            residual: None,
            command: None,
            status: ControlStatus::zeroed(),
            skeleton: None,
            hand: None,
            requests: Vec::with_capacity(8),
            seq: 0,
            t_ns: 0,
            outages: opts.outages.clone(),
            summary: summary::Accounting::new(cfg.sim.dt_s),
        })
    }

    /// Robot time \[ns\].
    pub fn time_ns(&self) -> u64 {
        self.t_ns
    }

    /// The controller's mode after the last tick.
    pub fn mode(&self) -> ControlMode {
        self.controller.mode()
    }

    /// What the robot did in the last period (brakes, fresh command, ...).
    pub fn link_output(&self) -> &LinkOutput {
        &self.link_out
    }

    fn down(&self, what: Down) -> bool {
        let now_s = self.t_ns as f64 * 1e-9;
        self.outages
            .iter()
            .any(|o| o.service == what && now_s >= o.from_s && now_s < o.to_s)
    }

    /// One control period: the robot decides on the newest command it has
    /// (fresh, reused, or the brakes), the arm moves one period and publishes
    /// its state; the camera captures when due and the results whose latency
    /// elapsed reach the controller; the residual and the controller answer.
    pub fn tick(&mut self) -> Result<ControlMode, CellError> {
        self.robot();
        if !self.down(Down::Perception) {
            self.perceive()?;
        } else if let Some(p) = self.perception.as_mut() {
            // the pipeline is dead: what was in flight is lost with it
            p.in_flight.clear();
            p.history.push_state(&self.state);
        }
        self.listen()?;
        if !self.down(Down::Dynamics) {
            self.dynamics
                .step(&self.state)
                .map_err(|e| step_err("dynamics")(&e))?;
            self.residual = Some(*self.dynamics.seal(self.t_ns, 0));
        }
        self.control()?;
        let mode = self.in_charge().mode();
        self.summary.mode(mode, self.t_ns);
        let ssm = (
            self.in_charge().ssm_enabled(),
            self.in_charge().ssm_counters(),
        );
        self.summary.ssm(ssm.0, ssm.1, self.t_ns);
        self.summary.account(
            &self.sim,
            mode,
            &self.link_out,
            self.residual.as_ref(),
            self.t_ns,
        );
        Ok(mode)
    }

    /// The controller in charge: the robot's state says which (the first
    /// without a standby).
    pub fn in_charge(&self) -> &Controller {
        match &self.pair {
            Some(p) if p.in_charge(&self.state) == 1 => &p.standby,
            _ => &self.controller,
        }
    }

    /// Per camera of `[[camera]]`: the point-periods its distance was the
    /// fused one (empty with one camera's cell counted as `[0]`).
    pub fn cameras_gave(&self) -> &[u64] {
        self.repulsion.gave()
    }

    /// The hot standby's controller, if it runs.
    pub fn standby(&self) -> Option<&Controller> {
        self.pair.as_ref().map(|p| &p.standby)
    }

    /// The robot link's figures of the two command slots.
    pub fn commanders(&self) -> &phri_ipc::CommanderStats {
        self.link.commanders()
    }

    /// The robot link and the arm: one period, then the new state.
    fn robot(&mut self) {
        let timing = CycleTiming {
            state_published_ns: self.t_ns,
            command_event_ns: 0,
            now_ns: self.t_ns,
            behind_schedule_ns: 0,
            standby_asked: false,
        };
        self.link_out = match &self.pair {
            Some(p) => self.link.cycle_slots(
                [p.slots.commands[0].as_ref(), p.slots.commands[1].as_ref()],
                self.seq,
                &timing,
            ),
            None => self.link.cycle(self.command.as_ref(), self.seq, &timing),
        };
        self.sim.step(self.link_out.torque(), self.link_out.brake);
        self.seq += 1;
        self.t_ns += self.link.period_ns();
        fill_state(
            &self.sim,
            &self.link_out,
            self.seq,
            self.t_ns,
            self.t_ns,
            &mut self.state,
        );
    }

    /// Every camera, ingestion and the workers when a frame is due
    /// ([`phri_perception::Perception`], the steps the binaries run); deliver
    /// what is ready.
    fn perceive(&mut self) -> Result<(), CellError> {
        let dark: [bool; phri_ipc::MAX_CAMERAS] =
            std::array::from_fn(|c| self.down(Down::Camera(c)));
        let Some(p) = self.perception.as_mut() else {
            return Ok(());
        };
        let now = self.t_ns;
        p.history.push_state(&self.state);
        for (c, &d) in dark.iter().enumerate() {
            p.cameras.set_dark(c, d);
        }
        // several cameras capture in turn, a period over N apart (as the
        // camera services do); every camera dark: no frame at all (none in
        // flight is lost)
        if now >= p.next_capture_ns && p.cameras.any_lit() {
            let cameras = p.cameras.cameras().max(1) as u64;
            p.next_capture_ns = now + p.period_ns / cameras;
            let camera = p.cameras.turn(p.turn);
            p.turn += 1;
            fill_world(&self.sim, self.seq, now, &mut p.world);
            let ready_ns = now + p.latency_ns;
            let period_s = p.period_ns as f64 * 1e-9;
            let mut skeleton = *p
                .cameras
                .capture_one(camera, &p.world, now, period_s, &p.history)
                .map_err(|e| step_err(e.service())(&e))?;
            skeleton.published_ns = ready_ns;
            // the first live camera's new view leads the gesture's steps
            let leads = p.cameras.leads(camera);
            let mut request = None;
            let wave = match leads {
                true => p.gesture.step(&skeleton),
                false => None,
            };
            if let Some(w) = wave {
                self.summary.gesture(&w);
                request = Some(phri_gesture::follow_request(&w, self.seq, ready_ns));
            }
            // ingestion reads the controller's collab/state, as the service does
            let mut collab = CollabState::zeroed();
            let controller = match &self.pair {
                Some(pair) if pair.in_charge(&self.state) == 1 => &pair.standby,
                _ => &self.controller,
            };
            write_collab_state(controller, &self.state, self.seq, now, &mut collab);
            let hand = p
                .cameras
                .perceive_one(camera, &p.history, Some(&collab), ready_ns)
                .map_err(|e| step_err(e.service())(&e))?;
            let mut results: Vec<Vec<RepulsionResult>> = (0..p.cameras.cameras())
                .map(|c| match c == camera {
                    true => p.cameras.results(c).to_vec(),
                    false => Vec::new(),
                })
                .collect();
            if let Some((radii, params)) = &p.truth {
                for r in results.iter_mut().flatten() {
                    truth::rewrite(r, self.sim.human_capsules(), radii, params);
                }
            }
            p.in_flight.push_back(InFlight {
                ready_ns,
                camera,
                results,
                skeleton,
                request,
                hand,
            });
            if leads {
                self.summary.frame();
            }
        }
        while p.in_flight.front().is_some_and(|x| x.ready_ns <= now) {
            if let Some(done) = p.in_flight.pop_front() {
                for (camera, results) in done.results.iter().enumerate() {
                    for r in results {
                        self.repulsion
                            .push_camera(camera, r)
                            .map_err(|e| step_err("control")(&e))?;
                    }
                }
                self.skeleton = Some(done.skeleton);
                // the controller's choice among the cameras' hands
                if let Some(slot) = p.hands.get_mut(done.camera) {
                    *slot = done.hand.or(*slot);
                }
                let hands: [Option<&HandObservation>; phri_ipc::MAX_CAMERAS] =
                    std::array::from_fn(|c| p.hands[c].as_ref());
                if let Some(h) = phri_ipc::best_hand(&hands, p.spread_ns) {
                    self.hand = Some(*h);
                }
                if let Some(r) = done.request {
                    self.requests.push(r);
                }
            }
        }
        Ok(())
    }

    /// The microphone's chunks that have been captured by now, through the
    /// recogniser (decoding takes no robot time here); a command it accepts
    /// reaches the controller this period.
    fn listen(&mut self) -> Result<(), CellError> {
        let Some(v) = self.voice.as_mut() else {
            return Ok(());
        };
        let now = self.t_ns;
        let chunks = phri_voice::mic::due(Some(v.next), now, u64::MAX);
        if chunks.is_empty() {
            return Ok(()); // 49 periods of 50: no chunk captured yet
        }
        v.next = chunks.end;
        let hands = phri_voice::Hands::of(self.skeleton.as_ref(), now, v.skeleton_max_age_ns);
        for k in chunks {
            v.chunk.seq = k + 1;
            v.chunk.capture_ns = k * phri_voice::mic::CHUNK_NS;
            v.chunk.published_ns = now;
            v.playback
                .fill(k * phri_ipc::AUDIO_CHUNK_SAMPLES as u64, &mut v.chunk.pcm);
            let heard = v
                .listener
                .step(&v.chunk, &hands, || now)
                .map_err(|e| step_err("voice")(&e))?;
            if let Some(h) = heard {
                self.summary.voice(&h.utterance);
                if let Some(r) = h.request {
                    self.requests.push(r);
                }
            }
        }
        Ok(())
    }

    /// The controllers that are up answer the newest state with a command
    /// and a status (the one in charge's); with the hot standby, each first
    /// adopts the behaviour the one in charge left after the state before.
    fn control(&mut self) -> Result<(), CellError> {
        let n = self.sim.model().nv();
        self.repulsion.fuse(self.state.stamp_ns);
        let perception = self.avoidance.then_some(&self.repulsion);
        let mut input =
            ControlInput::from_messages(&self.state, self.residual.as_ref(), perception, n)
                .map_err(|e| step_err("control")(&e))?;
        input.collab = CollabInput {
            requests: &self.requests,
            skeleton: self.skeleton.as_ref(),
            hand: self.hand.as_ref(),
        };
        let up = [!self.down(Down::Control), !self.down(Down::Standby)];
        let stamps = Stamps {
            woke_ns: self.t_ns,
            done_ns: self.t_ns,
        };
        let Some(pair) = self.pair.as_mut() else {
            if up[0] {
                self.controller.step(&input);
                let mut cmd = self.command.unwrap_or_else(TorqueCommand::zeroed);
                let seq = self.status.seq + 1;
                write_messages(
                    &self.controller,
                    &self.state,
                    seq,
                    stamps,
                    &mut cmd,
                    &mut self.status,
                );
                self.command = Some(cmd);
            }
            self.requests.clear();
            return Ok(());
        };
        let in_charge = pair.in_charge(&self.state);
        // the one not in charge rests through a state the one in charge answers
        let steps = [0, 1].map(|slot| up[slot] && !pair.slots.rests(slot, &self.state, up));
        for slot in 0..2 {
            if steps[slot] {
                let controller = match slot {
                    0 => &mut self.controller,
                    _ => &mut pair.standby,
                };
                pair.slots.adopt(slot, controller, &self.state);
            }
        }
        for slot in 0..2 {
            if !steps[slot] {
                continue;
            }
            let controller = match slot {
                0 => &mut self.controller,
                _ => &mut pair.standby,
            };
            controller.step(&input);
            let mut cmd = pair.slots.commands[slot].unwrap_or_else(TorqueCommand::zeroed);
            let mut status = self.status;
            write_messages(
                controller,
                &self.state,
                self.status.seq + 1,
                stamps,
                &mut cmd,
                &mut status,
            );
            pair.slots.answered(slot, controller, &self.state, cmd);
            if slot == in_charge {
                self.status = status;
            }
        }
        // the one not in charge keeps the path history of the behaviour the
        // one in charge left (as phri-control does with each it receives)
        for slot in (0..2).filter(|&s| up[s] && s != in_charge) {
            let controller = match slot {
                0 => &mut self.controller,
                _ => &mut pair.standby,
            };
            pair.slots.follow(slot, controller, &self.state);
        }
        self.command = pair.slots.commands[in_charge];
        self.requests.clear();
        Ok(())
    }

    /// Take a service down for a while, from now on (see [`CellOptions::outages`]).
    pub fn add_outage(&mut self, outage: Outage) {
        self.outages.push(outage);
    }

    /// Replace the controller (a restarted controller process): it re-syncs
    /// to the measured state as a new process does.
    pub fn restart_controller(&mut self, controller: Controller) {
        self.controller = controller;
        if let Some(p) = self.pair.as_mut() {
            p.slots.restarted(0);
        }
    }

    /// Replace the hot standby's controller (a restarted process): it
    /// commands again once it adopted the behaviour of the one in charge.
    /// Without a standby, nothing happens.
    pub fn restart_standby(&mut self, controller: Controller) {
        if let Some(p) = self.pair.as_mut() {
            p.standby = controller;
            p.slots.restarted(1);
        }
    }

    /// Replace the residual service by a new one (a restarted process starts
    /// from scratch: warm-up, no memory of the momentum).
    pub fn restart_dynamics(&mut self, dynamics: DynamicsStep) {
        self.dynamics = dynamics;
    }

    /// A request reaches the controller at its next period (as `phri-hri` or
    /// a voice recogniser would send it).
    pub fn request(&mut self, r: HriRequest) {
        self.requests.push(r);
    }

    /// The run so far.
    pub fn summary(&self) -> CellSummary {
        let mut s = self.summary.summary(&self.sim, self.in_charge().counters());
        if let Some(b) = self.in_charge().cbf_counters() {
            let dt = self.link.period_ns() as f64 * 1e-9;
            s.barrier = Some(summary::BarrierSummary {
                braking_s: b.braking_periods as f64 * dt,
                slack_s: b.slack_periods as f64 * dt,
                failed_periods: b.infeasible_periods,
                max_iterations: b.max_iterations,
            });
        }
        if self.pair.is_some() {
            let c = self.link.commanders();
            s.standby = Some(summary::StandbySummary {
                takeovers: c.takeovers,
                max_takeover_diff_nm: c.max_takeover_diff_nm,
                max_answer_diff_nm: c.max_answer_diff_nm,
                periods_commanded: c.periods,
                both_answered: c.both_answered,
                missed_deadlines: self.link.stats().missed_deadlines,
            });
        }
        s
    }
}
