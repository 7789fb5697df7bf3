//! The whole cell in one process, in lock-step: the simulated robot, the
//! camera, depth ingestion, the repulsion workers, the residual observer and
//! the controller, each through the same pure `step` its service's `main.rs`
//! wires to channels. Time is the robot's: one [`Cell::tick`] is one control
//! period. The camera samples the world every `1 / rate_hz`, and a frame's
//! repulsion results reach the controller `perception_latency_ms` later (the
//! multi-process cell measures p99 6.4 ms capture → repulsion).
//!
//! Deterministic: the same configuration, scenario and offset give the same
//! run, so scenarios can be swept over the moment the person arrives (see
//! [`CellOptions::human_time_offset_s`]) and asserted in tests.

use std::collections::VecDeque;
use std::path::{Path, PathBuf};

use phri_control::{ControlConfig, ControlInput, Controller, PerceptionView, ResidualView};
use phri_dynamics::{ResidualConfig, ResidualObserver};
use phri_ipc::{control_mode, FrameHeader, PointRepulsion, WorldState, Zeroed};
use phri_model::Model;
use phri_perception::camera::CameraSim;
use phri_perception::ingest::{Ingest, StateHistory};
use phri_perception::repulsion::Worker;
use phri_perception::{CameraConfig, IngestConfig, RepulsionConfig};
use phri_sim::{Scenario, SimConfig, Simulator};

/// Why a cell could not be built or stepped.
#[derive(Debug, thiserror::Error)]
pub enum CellError {
    #[error("{0}")]
    Config(String),
    #[error("{path}: {message}")]
    File { path: PathBuf, message: String },
    #[error("{service}: {message}")]
    Step {
        service: &'static str,
        message: String,
    },
}

/// How to run the cell beyond `deploy/phri.toml`.
#[derive(Clone, Debug)]
pub struct CellOptions {
    /// the human script runs this far ahead of the robot \[s\] (negative: the
    /// person arrives later, meeting the arm at another phase of its cycle)
    pub human_time_offset_s: f64,
    /// capture → repulsion results at the controller [ms]
    pub perception_latency_ms: f64,
    /// run the perception pipeline (camera, ingestion, workers)
    pub perception: bool,
    /// services that are down for a while (deterministic fault injection)
    pub outages: Vec<Outage>,
}

/// Which service an [`Outage`] takes down.
#[derive(Clone, Copy, Debug, PartialEq, Eq, serde::Serialize)]
#[serde(rename_all = "snake_case")]
pub enum Down {
    /// no new depth frames or repulsion results reach the controller
    Perception,
    /// the residual stops: the controller keeps seeing the last one, ageing
    Dynamics,
}

/// A service down from `from_s` to `to_s` (robot time \[s\]).
#[derive(Clone, Copy, Debug, serde::Serialize)]
pub struct Outage {
    pub service: Down,
    pub from_s: f64,
    pub to_s: f64,
}

impl std::str::FromStr for Outage {
    type Err = String;
    /// `perception:FROM:TO` or `dynamics:FROM:TO` (seconds)
    fn from_str(s: &str) -> Result<Outage, String> {
        let bad = || format!("outage: expected perception|dynamics:FROM:TO (seconds), got '{s}'");
        let mut it = s.split(':');
        let service = match it.next() {
            Some("perception") => Down::Perception,
            Some("dynamics") => Down::Dynamics,
            _ => return Err(bad()),
        };
        let mut num = || {
            it.next()
                .and_then(|x| x.trim().parse::<f64>().ok())
                .ok_or_else(bad)
        };
        let (from_s, to_s) = (num()?, num()?);
        if !(from_s.is_finite() && to_s.is_finite() && to_s >= from_s) {
            return Err(bad());
        }
        Ok(Outage {
            service,
            from_s,
            to_s,
        })
    }
}

impl Default for CellOptions {
    fn default() -> Self {
        CellOptions {
            human_time_offset_s: 0.0,
            perception_latency_ms: 6.5,
            perception: true,
            outages: Vec::new(),
        }
    }
}

/// One contact episode between the person and the arm.
#[derive(Clone, Debug, serde::Serialize)]
pub struct ContactEpisode {
    /// start and end, robot time \[s\]
    pub t_start_s: f64,
    pub t_end_s: f64,
    pub link: String,
    pub part: String,
    pub intended: bool,
    /// largest contact force [N]
    pub peak_force_n: f64,
    /// the controller's mode when it began
    pub mode: String,
}

/// What a run produced.
#[derive(Clone, Debug, Default, serde::Serialize)]
pub struct CellSummary {
    pub duration_s: f64,
    pub contacts: Vec<ContactEpisode>,
    pub unintended_contacts: usize,
    /// smallest true surface distance person ↔ arm \[m\]
    pub min_distance_m: f64,
    /// when it was smallest, robot time \[s\]
    pub min_distance_t_s: f64,
    pub waypoints: u64,
    pub detections: u64,
    pub frames: u64,
    /// periods spent in protective stop
    pub protective_stop_s: f64,
}

struct Pending {
    ready_ns: u64,
    capture_ns: u64,
    points: Vec<PointRepulsion>,
}

/// The perception side: camera, ingestion and the repulsion workers.
struct Perception {
    camera: CameraSim,
    ingest: Ingest,
    history: StateHistory,
    workers: Vec<Worker>,
    frame: Vec<u16>,
    filtered: Vec<u16>,
    world: WorldState,
    period_ns: u64,
    next_capture_ns: u64,
    latency_ns: u64,
    pending: VecDeque<Pending>,
    seq: u64,
}

/// The cell. Fields are public for tests that look inside.
pub struct Cell {
    pub sim: Simulator,
    pub observer: ResidualObserver,
    pub controller: Controller,
    perception: Option<Perception>,
    points: Vec<PointRepulsion>,
    capture_ns: u64,
    tau: Vec<f64>,
    r: Vec<f64>,
    t_ns: u64,
    summary: CellSummary,
    open: Vec<(usize, usize, usize)>, // (collision, part, episode index) in contact now
    mode: u32,
    outages: Vec<Outage>,
    /// the last residual the controller received (kept while dynamics is down)
    last_residual: (u64, bool, bool, bool),
}

/// Load `config` (usually `deploy/phri.toml`), merge the scenario file's
/// configuration and then `sets` (`section.key=value`) over it.
pub fn load(
    config: &Path,
    scenario: &Path,
    sets: &[&str],
) -> Result<(toml::Table, Scenario, Model), CellError> {
    let scen = Scenario::from_file(scenario).map_err(|e| CellError::Config(e.to_string()))?;
    let table = phri_runtime::config::load_config(config, std::slice::from_ref(&scen.config), sets)
        .map_err(|e| CellError::Config(e.to_string()))?;
    let urdf = table
        .get("robot")
        .and_then(|r| r.get("urdf"))
        .and_then(|u| u.as_str())
        .ok_or_else(|| {
            CellError::Config(format!("{}: [robot] urdf is missing", config.display()))
        })?;
    let urdf = phri_runtime::service::resolve(config, urdf);
    let model = Model::from_urdf_file(&urdf).map_err(|e| CellError::File {
        path: urdf.clone(),
        message: e.to_string(),
    })?;
    Ok((table, scen, model))
}

fn section<T: serde::de::DeserializeOwned>(t: &toml::Table, name: &str) -> Result<T, CellError> {
    phri_runtime::config::section(t, name).map_err(|e| CellError::Config(e.to_string()))
}

impl Cell {
    /// Build every step from the merged configuration `table`.
    pub fn new(
        table: &toml::Table,
        scenario: &Scenario,
        model: Model,
        opts: &CellOptions,
    ) -> Result<Cell, CellError> {
        let cfg =
            |service: &'static str| move |message: String| CellError::Step { service, message };
        let sim_cfg: SimConfig = section(table, "sim")?;
        let res_cfg: ResidualConfig = section(table, "dynamics")?;
        let ctl_cfg: ControlConfig = section(table, "control")?;
        let rep_cfg: RepulsionConfig = section(table, "repulsion")?;
        let avoidance = ctl_cfg.avoidance && opts.perception;
        let mut sim = Simulator::from_scenario(model.clone(), sim_cfg, scenario, None)
            .map_err(|e| cfg("sim")(e.to_string()))?;
        sim.set_human_time_offset(opts.human_time_offset_s);
        let observer = ResidualObserver::new(model.clone(), &res_cfg)
            .map_err(|e| cfg("dynamics")(e.to_string()))?;
        let mut controller =
            Controller::new(model.clone(), ctl_cfg).map_err(|e| cfg("control")(e.to_string()))?;
        let n_points = rep_cfg.points.len();
        let perception = if avoidance {
            let points: Vec<(String, [f64; 3])> = rep_cfg
                .points
                .iter()
                .map(|p| (p.link.clone(), p.xyz))
                .collect();
            controller
                .set_control_points(&points)
                .map_err(|e| cfg("control")(e.to_string()))?;
            let cam_cfg: CameraConfig = section(table, "camera")?;
            let ing_cfg: IngestConfig = section(table, "perception")?;
            if !(cam_cfg.rate_hz > 0.0 && cam_cfg.rate_hz <= 1000.0) {
                return Err(CellError::Config(
                    "[camera] rate_hz must be in (0, 1000]".into(),
                ));
            }
            if !(opts.perception_latency_ms >= 0.0) {
                return Err(CellError::Config(
                    "perception latency must be ≥ 0 ms".into(),
                ));
            }
            let camera = CameraSim::new(model.clone(), &cam_cfg).map_err(cfg("camera"))?;
            let pixels = camera.pixels();
            let workers = (0..rep_cfg.workers)
                .map(|w| Worker::new(model.clone(), &rep_cfg, w))
                .collect::<Result<Vec<_>, _>>()
                .map_err(cfg("repulsion"))?;
            let mut world = WorldState::zeroed();
            world.dof = model.nv() as u32;
            Some(Perception {
                camera,
                ingest: Ingest::new(
                    model.clone(),
                    ing_cfg.self_filter,
                    ing_cfg.max_state_gap_ms,
                    ing_cfg.max_frame_age_ms,
                ),
                history: StateHistory::new(model.nv(), 200),
                workers,
                frame: vec![0; pixels],
                filtered: vec![0; pixels],
                world,
                period_ns: (1e9 / cam_cfg.rate_hz) as u64,
                next_capture_ns: 0,
                latency_ns: (opts.perception_latency_ms * 1e6) as u64,
                pending: VecDeque::new(),
                seq: 0,
            })
        } else {
            None
        };
        let n = model.nv();
        Ok(Cell {
            sim,
            observer,
            controller,
            perception,
            points: vec![PointRepulsion::default(); n_points],
            capture_ns: 0,
            tau: vec![0.0; n],
            r: vec![0.0; n],
            t_ns: 0,
            summary: CellSummary {
                min_distance_m: f64::INFINITY,
                ..Default::default()
            },
            open: Vec::new(),
            mode: control_mode::SYNC,
            outages: opts.outages.clone(),
            last_residual: (0, false, false, false),
        })
    }

    /// Robot time \[ns\].
    pub fn time_ns(&self) -> u64 {
        self.t_ns
    }

    /// The controller's mode after the last tick.
    pub fn mode(&self) -> u32 {
        self.mode
    }

    /// One control period: the robot applies the last command; the camera
    /// captures when due; results whose latency elapsed reach the
    /// controller; the residual and the controller answer.
    pub fn tick(&mut self) -> Result<u32, CellError> {
        let dt_ns = (self.sim.config().dt_s * 1e9).round() as u64;
        let m = self.sim.step(&self.tau, false).clone();
        self.t_ns += dt_ns;
        let now = self.t_ns;
        let now_s = now as f64 * 1e-9;
        let down = |what: Down| {
            self.outages
                .iter()
                .any(|o| o.service == what && now_s >= o.from_s && now_s < o.to_s)
        };
        let (perception_down, dynamics_down) = (down(Down::Perception), down(Down::Dynamics));
        if let Some(p) = self.perception.as_mut() {
            p.history.push(now, &m.q);
            if perception_down {
                // the pipeline is dead: what was in flight is lost with it
                p.pending.clear();
            } else if now >= p.next_capture_ns {
                p.next_capture_ns = now + p.period_ns;
                p.seq += 1;
                phri_sim::world::fill_world(&self.sim, p.seq, now, &mut p.world);
                let mut header = FrameHeader::zeroed();
                p.camera
                    .step(&p.world, &mut p.frame, &mut header)
                    .map_err(|message| CellError::Step {
                        service: "camera",
                        message,
                    })?;
                header.capture_ns = now;
                let ready_ns = now + p.latency_ns;
                match p
                    .ingest
                    .step(&mut header, &p.frame, &p.history, ready_ns, &mut p.filtered)
                {
                    Ok(_) => {
                        let mut points = Vec::new();
                        for w in p.workers.iter_mut() {
                            let out = w.step(&header, &p.filtered).map_err(|message| {
                                CellError::Step {
                                    service: "repulsion",
                                    message,
                                }
                            })?;
                            points.extend_from_slice(out);
                        }
                        p.pending.push_back(Pending {
                            ready_ns,
                            capture_ns: now,
                            points,
                        });
                        self.summary.frames += 1;
                    }
                    Err(e) => {
                        return Err(CellError::Step {
                            service: "perception",
                            message: e.to_string(),
                        })
                    }
                }
            }
            while p.pending.front().is_some_and(|x| x.ready_ns <= now) {
                if let Some(done) = p.pending.pop_front() {
                    for r in &done.points {
                        if let Some(slot) = self.points.get_mut(r.point as usize) {
                            *slot = *r;
                        }
                    }
                    self.capture_ns = done.capture_ns;
                }
            }
        }
        let out = self
            .observer
            .step(now as f64 * 1e-9, &m.q, &m.tau_applied, m.wrench.as_ref())
            .map_err(|e| CellError::Step {
                service: "dynamics",
                message: e.to_string(),
            })?;
        if !dynamics_down {
            self.r.copy_from_slice(out.r);
            self.last_residual = (
                now,
                out.valid,
                out.detection.contact,
                out.detection.collision,
            );
        }
        let (stamp, valid, contact, collision) = self.last_residual;
        let view = ResidualView {
            state_stamp_ns: stamp,
            r: &self.r,
            valid,
            contact,
            collision,
        };
        let perception = self.perception.as_ref().map(|_| PerceptionView {
            capture_ns: self.capture_ns,
            points: &self.points,
        });
        let o = self.controller.step(&ControlInput {
            state_stamp_ns: now,
            q: &m.q,
            residual: Some(view),
            perception,
        });
        self.tau.copy_from_slice(o.tau);
        self.mode = o.mode;
        self.account();
        Ok(self.mode)
    }

    fn account(&mut self) {
        let t = self.sim.truth();
        let s = &mut self.summary;
        let dt = self.sim.config().dt_s;
        s.duration_s += dt;
        if t.min_distance < s.min_distance_m {
            s.min_distance_m = t.min_distance;
            s.min_distance_t_s = self.t_ns as f64 * 1e-9;
        }
        if self.mode == control_mode::PROTECTIVE_STOP {
            s.protective_stop_s += dt;
        }
        let now_s = self.t_ns as f64 * 1e-9;
        let mut still = Vec::with_capacity(t.contacts.len());
        for c in &t.contacts {
            let part = c.part as usize;
            let key = (c.collision, part);
            let idx = match self.open.iter().find(|o| (o.0, o.1) == key) {
                Some(o) => o.2,
                None => {
                    s.contacts.push(ContactEpisode {
                        t_start_s: now_s,
                        t_end_s: now_s,
                        link: c.link(self.sim.model()).to_string(),
                        part: c.part.name().to_string(),
                        intended: c.intended,
                        peak_force_n: 0.0,
                        mode: control_mode::name(self.mode).to_string(),
                    });
                    if !c.intended {
                        s.unintended_contacts += 1;
                    }
                    s.contacts.len() - 1
                }
            };
            let e = &mut s.contacts[idx];
            e.t_end_s = now_s;
            e.peak_force_n = e.peak_force_n.max(c.force.norm());
            still.push((key.0, key.1, idx));
        }
        self.open = still;
    }

    /// The run so far.
    pub fn summary(&self) -> CellSummary {
        let mut s = self.summary.clone();
        s.waypoints = self.controller.waypoints_reached;
        s.detections = self.controller.detections;
        s
    }
}
