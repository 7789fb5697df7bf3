//! `[supervisor]` and `[services.NAME]`: how the cell is started and watched.

use std::collections::BTreeMap;

use serde::{Deserialize, Serialize};

use crate::check::positive;
use crate::error::Invalid;

/// How the supervisor behaves (defaults: `deploy/phri.toml`).
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct SupervisorConfig {
    /// first restart delay after a crash \[ms\]; doubles on each quick crash
    pub restart_backoff_min_ms: u64,
    /// largest restart delay \[ms\]
    pub restart_backoff_max_ms: u64,
    /// a service that ran this long is healthy again: the back-off resets \[s\]
    pub stable_after_s: f64,
    /// time a service gets to exit after SIGTERM before SIGKILL \[ms\]
    pub shutdown_grace_ms: u64,
    /// health publication rate \[Hz\]
    pub health_hz: f64,
    /// a watched service that does not beat on its liveness service for
    /// this long is frozen (its deadline unless it sets its own) \[ms\]
    pub heartbeat_timeout_ms: u64,
    /// services of a cell whose supervisor has published nothing for this
    /// long stop safely (the robot braked) \[s\]; long enough for a new
    /// supervisor to take the cell over
    pub deadman_s: f64,
    /// a service restarted more than this many times within
    /// `crash_loop_window_s` ends the run (ordered shutdown, a degraded
    /// report, non-zero exit) instead of crash-looping until the end
    pub crash_loop_restarts: u32,
    /// the window of `crash_loop_restarts` \[s\]
    pub crash_loop_window_s: f64,
    /// start-up lasts this long after the last service is started \[s\]: a
    /// service that exits before then fails the start (everything started is
    /// stopped, the supervisor exits non-zero) instead of being restarted
    pub startup_s: f64,
    /// refuse to start when SCHED_FIFO at the services' priorities, or their
    /// CPU pinning, is not permitted (`--require-rt`); otherwise the cell
    /// runs under the normal scheduler and its report says it was degraded
    pub require_rt: bool,
    /// the supervisor's own watch loop runs under SCHED_FIFO at this
    /// priority (1-99; 0: the normal scheduler) where the machine permits:
    /// above every process under the normal scheduler, below every
    /// real-time service (perception runs at 20-22, the torque loop at
    /// 76-80), so it never delays them; a real-time service spinning on its
    /// CPU pushes it to another
    #[serde(default = "watchdog_priority")]
    pub rt_priority: i32,
}

/// The supervisor's default SCHED_FIFO priority.
fn watchdog_priority() -> i32 {
    15
}

impl SupervisorConfig {
    /// Range checks of every field; the dead-man's time spans at least 5
    /// health periods.
    pub fn validate(&self) -> Result<(), Invalid> {
        positive("supervisor", "stable_after_s", self.stable_after_s)?;
        positive("supervisor", "health_hz", self.health_hz)?;
        positive("supervisor", "deadman_s", self.deadman_s)?;
        positive(
            "supervisor",
            "crash_loop_window_s",
            self.crash_loop_window_s,
        )?;
        positive("supervisor", "startup_s", self.startup_s)?;
        if self.deadman_s * self.health_hz < 5.0 {
            return Err(Invalid::new(
                "supervisor.deadman_s",
                format!(
                    "{} s is less than 5 health periods at {} Hz",
                    self.deadman_s, self.health_hz
                ),
            ));
        }
        if self.restart_backoff_min_ms > self.restart_backoff_max_ms {
            return Err(Invalid::new(
                "supervisor.restart_backoff_min_ms",
                "larger than restart_backoff_max_ms",
            ));
        }
        if !(0..=99).contains(&self.rt_priority) {
            return Err(Invalid::new(
                "supervisor.rt_priority",
                format!("{} is outside 0-99", self.rt_priority),
            ));
        }
        if self.heartbeat_timeout_ms == 0 {
            return Err(Invalid::new(
                "supervisor.heartbeat_timeout_ms",
                "must be at least 1",
            ));
        }
        Ok(())
    }
}

/// One supervised service (`[services.NAME]`).
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct ServiceSpec {
    /// executable name, looked up beside the supervisor's own executable
    pub binary: String,
    /// start order (low first); shutdown runs in reverse
    #[serde(default)]
    pub order: i32,
    /// SCHED_FIFO priority (0: normal scheduler)
    #[serde(default)]
    pub rt_priority: i32,
    /// restart when it exits
    #[serde(default = "yes")]
    pub restart: bool,
    /// extra arguments
    #[serde(default)]
    pub args: Vec<String>,
    /// pause after starting it before starting the next one \[ms\]
    #[serde(default)]
    pub start_delay_ms: u64,
    /// disabled services are not started
    #[serde(default = "yes")]
    pub enabled: bool,
    /// channel the service publishes on continuously; set, the service is
    /// watched: its loop beats on `liveness/<name>`, and silence there past
    /// its deadline while it runs means it is frozen (it is then killed and
    /// restarted)
    #[serde(default)]
    pub heartbeat: Option<String>,
    /// its liveness deadline: no beat for longer than this is frozen \[ms\]
    /// (default: the supervisor's `heartbeat_timeout_ms`)
    #[serde(default)]
    pub heartbeat_timeout_ms: Option<u64>,
    /// services whose silence explains this one's (it is not judged while they are silent)
    #[serde(default)]
    pub depends_on: Vec<String>,
    /// CPUs the service may run on (empty: any)
    #[serde(default)]
    pub cpus: Vec<usize>,
    /// the share of one core the service may use, on average over the time
    /// it ran (0-1; past it the run is degraded; none: not judged)
    #[serde(default)]
    pub cpu_budget: Option<f64>,
}

fn yes() -> bool {
    true
}

impl ServiceSpec {
    /// Checks of one service's entry (`name` is its key under `[services]`).
    pub fn validate(&self, name: &str) -> Result<(), Invalid> {
        let key = |k: &str| format!("services.{name}.{k}");
        if self.binary.is_empty() || self.binary.contains('/') {
            return Err(Invalid::new(
                key("binary"),
                format!(
                    "'{}' must be a file name beside phri-supervisor",
                    self.binary
                ),
            ));
        }
        if !(0..=99).contains(&self.rt_priority) {
            return Err(Invalid::new(
                key("rt_priority"),
                format!("{} is not in 0..=99", self.rt_priority),
            ));
        }
        if let Some(b) = self.cpu_budget {
            if !(b > 0.0 && b <= 1.0) {
                return Err(Invalid::new(
                    key("cpu_budget"),
                    format!("{b} is not a share of one core in (0, 1]"),
                ));
            }
        }
        if let Some(h) = &self.heartbeat {
            if !phri_ipc::ALL.contains(&h.as_str()) && phri_ipc::camera_of_channel(h).is_none() {
                return Err(Invalid::new(
                    key("heartbeat"),
                    format!("'{h}' is not a channel of the cell"),
                ));
            }
        }
        Ok(())
    }
}

/// The binaries that serve a camera's frames, one per source
/// ([`crate::CameraSource::binary`]): a camera's service runs the one its
/// `[camera] source` names, whichever of them the service lists.
pub const CAMERA_SOURCE_BINARIES: &[&str] = &["phri-camera", "phri-freenect", "phri-camera-ros2"];

/// The depth person tracker's binary: run for a camera whose skeletons
/// come from depth ([`crate::Config::skeleton_source`]), disabled otherwise.
pub const TRACKER_BINARY: &str = "phri-tracker";

/// The binaries that run once per camera: the camera (or its driver), its
/// ingestion and its person tracker. Repulsion workers serve every camera's
/// frames.
pub const PER_CAMERA_BINARIES: &[&str] = &[
    "phri-camera",
    "phri-freenect",
    "phri-camera-ros2",
    "phri-perception",
    TRACKER_BINARY,
];

/// The services of cameras after the first, derived from the first's: for
/// each service of a [`PER_CAMERA_BINARIES`] binary that has no `--camera`
/// argument, and each camera `i` in `1..cameras`, a service `NAME-i` with
/// `--camera i` added, its heartbeat on camera `i`'s channel and its
/// dependencies on other per-camera services turned to camera `i`'s. A
/// service of that name already configured is kept as it is.
pub fn derive_camera_services(services: &mut BTreeMap<String, ServiceSpec>, cameras: usize) {
    let per_camera = |s: &ServiceSpec| {
        PER_CAMERA_BINARIES.contains(&s.binary.as_str())
            && !s.args.iter().any(|a| a.starts_with("--camera"))
    };
    let firsts: Vec<(String, ServiceSpec)> = services
        .iter()
        .filter(|(_, s)| per_camera(s))
        .map(|(n, s)| (n.clone(), s.clone()))
        .collect();
    let is_first = |name: &str| firsts.iter().any(|(n, _)| n == name);
    for i in 1..cameras {
        for (name, spec) in &firsts {
            let derived = format!("{name}-{i}");
            if services.contains_key(&derived) {
                continue;
            }
            let mut s = spec.clone();
            s.args.extend(["--camera".to_string(), i.to_string()]);
            s.heartbeat = s.heartbeat.map(|h| phri_ipc::for_camera(&h, i).to_string());
            s.depends_on = s
                .depends_on
                .iter()
                .map(|d| match is_first(d) {
                    true => format!("{d}-{i}"),
                    false => d.clone(),
                })
                .collect();
            services.insert(derived, s);
        }
    }
}

/// The camera index a service's arguments give (`--camera I`; 0 without).
pub fn camera_of(args: &[String]) -> Option<usize> {
    match args.iter().position(|a| a == "--camera") {
        Some(k) => args.get(k + 1)?.parse().ok(),
        None => match args.iter().find_map(|a| a.strip_prefix("--camera=")) {
            Some(v) => v.parse().ok(),
            None => Some(0),
        },
    }
}
