//! phri's configuration model: one place that loads `deploy/phri.toml`, a
//! scenario and `--set` overrides into typed, validated sections, used by the
//! supervisor, every service, the lock-step cell and the tools.
//!
//! Defaults are written once: `deploy/phri.toml`, embedded here at build time
//! ([`DEFAULTS`]), is the base every configuration is merged over, so a file
//! needs only the keys it changes. Order of precedence (last wins): the
//! defaults, the configuration file, the scenario's `[config]`, `--set`.
//! Unknown sections and keys are refused, naming them; values are range-checked
//! ([`Config::validate`]) and, given the robot model, checked against it
//! ([`Config::check_model`]: joint counts, link names).

#![deny(missing_docs)]

pub mod avoidance;
pub mod check;
pub mod collaboration;
pub mod control;
pub mod dynamics;
pub mod error;
pub mod human_script;
pub mod keys;
pub mod merge;
pub mod page;
pub mod per_joint;
pub mod perception;
pub mod ranges;
pub mod record;
pub mod robot;
pub mod ros2;
pub mod scenario;
pub mod sim;
pub mod ssm;
pub mod supervisor;
pub mod trust;
pub mod urdf;
pub mod voice;

use std::collections::BTreeMap;
use std::path::{Path, PathBuf};

use serde::{Deserialize, Serialize};
use toml::{Table, Value};

pub use avoidance::{AvoidanceConfig, AvoidanceLaw};
pub use collaboration::{
    CollaborationConfig, Facing, GestureConfig, OnRequest, SkeletonConfig, SkeletonSource,
};
pub use control::{AvoidanceParams, BodyAvoidance, ControlConfig, PathPace};
pub use dynamics::ResidualConfig;
pub use error::{ConfigError, Invalid};
pub use human_script::{Hand, HumanScript, Keyframe, Push, ScriptError, Wave};
pub use merge::{apply_set, merge};
pub use per_joint::PerJoint;
pub use perception::{
    valid_topic, CameraConfig, CameraSource, DepthSource, FusedDirection, IngestConfig,
    PointConfig, RepulsionConfig,
};
pub use record::{Compression, RecordConfig};
pub use robot::{CapsuleConfig, RobotSection, DEFAULT_ROBOT, DEFAULT_ROBOT_FILE};
pub use ros2::Ros2Config;
pub use scenario::VoiceLine;
pub use scenario::{Scenario, ScenarioError};
pub use sim::SimConfig;
pub use ssm::{HumanSpeed, SsmConfig};
pub use supervisor::{
    camera_of, derive_camera_services, ServiceSpec, SupervisorConfig, CAMERA_SOURCE_BINARIES,
    TRACKER_BINARY,
};
pub use voice::{AudioConfig, AudioSource, MicConfig, MicSource, VoiceConfig};

/// The default configuration: `deploy/phri.toml` as built.
pub const DEFAULTS: &str = include_str!("../../../deploy/phri.toml");

/// Where the defaults' relative paths (`[robot] urdf`) resolve when a
/// configuration file does not say otherwise.
pub const DEFAULT_DEPLOY_DIR: &str = concat!(env!("CARGO_MANIFEST_DIR"), "/../../deploy");

/// The most services one supervisor runs. `supervisor/health` lists the
/// first [`phri_ipc::MAX_SERVICES`] of them in start order (its size is a
/// contract with outside readers); `state.json`, the report and the
/// How old the residual a controller acts on gets when the first residual
/// service is gone, with the hot standby: the first's is two periods
/// behind before the controller calls the standby's, which is acted on a
/// period later \[ms\] (`control.residual_max_age_ms` must be longer).
pub const STANDBY_RESIDUAL_LAG_MS: f64 = 3.0;

/// supervisor's own watch cover every one.
pub const MAX_ROSTER: usize = 2 * phri_ipc::MAX_SERVICES;

/// `[scenario]`: which scenario the cell runs (set by the supervisor in the
/// merged file it hands to the services).
#[derive(Clone, Debug, Default, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields, default)]
pub struct ScenarioSection {
    /// the scenario's name ("": none)
    pub name: String,
    /// absolute path of the scenario file ("": none, free motion without a person)
    pub file: String,
}

/// The whole configuration, typed.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct Config {
    /// `[robot]`: the arm, its model and its collision capsules
    pub robot: RobotSection,
    /// `[supervisor]`: how the supervisor runs the cell
    pub supervisor: SupervisorConfig,
    /// `[services.NAME]`: every service the supervisor may start, by name
    pub services: BTreeMap<String, ServiceSpec>,
    /// `[sim]`: the simulated arm
    pub sim: SimConfig,
    /// the first camera (`[camera]`, or the first `[[camera]]`)
    pub camera: CameraConfig,
    /// every camera, the first included (`[[camera]]` lists several; each
    /// entry over the defaults of `[camera]`)
    #[serde(skip)]
    pub cameras: Vec<CameraConfig>,
    /// `[perception]`: depth ingestion
    pub perception: IngestConfig,
    /// `[repulsion]`: the repulsion workers and their control points
    pub repulsion: RepulsionConfig,
    /// `[dynamics]`: the momentum residual and contact detection
    pub dynamics: ResidualConfig,
    /// `[control]`: the controller's task, reactions and avoidance
    pub control: ControlConfig,
    /// `[ssm]`: speed and separation monitoring (ISO/TS 15066 5.5.4)
    pub ssm: SsmConfig,
    /// `[avoidance]`: the law that evades what perception sees (the paper's or a control-barrier filter)
    pub avoidance: AvoidanceConfig,
    /// `[record]`: what the recorder keeps of the depth frames
    pub record: RecordConfig,
    /// `[skeleton]`: the people a camera sees
    pub skeleton: SkeletonConfig,
    /// `[gesture]`: the waving detector
    pub gesture: GestureConfig,
    /// `[collaboration]`: the controller's collaboration phases
    pub collaboration: CollaborationConfig,
    /// `[voice]`: offline command recognition
    pub voice: VoiceConfig,
    /// `[audio]`: the microphone stand-in `phri-mic`
    pub audio: AudioConfig,
    /// `[mic]`: the microphone behind `audio/mic`
    pub mic: MicConfig,
    /// `[ros2]`: the ROS 2 bridge
    pub ros2: Ros2Config,
    /// `[scenario]`: the scenario the cell runs
    #[serde(default)]
    pub scenario: ScenarioSection,
}

/// A configuration as loaded: typed, its scenario, and the merged table
/// (what the supervisor writes for its services).
#[derive(Clone, Debug)]
pub struct Loaded {
    /// the configuration, typed and validated
    pub config: Config,
    /// the scenario the cell runs (free motion when none)
    pub scenario: Scenario,
    /// the merged table, paths made absolute
    pub table: Table,
    /// the file it was loaded from (`<defaults>` when none)
    pub origin: PathBuf,
    /// the robot file merged under it, and its keys (to name it in errors
    /// about a key it alone gives)
    pub robot_origin: PathBuf,
    robot_keys: Table,
    /// what the configuration file alone gave
    file_keys: Table,
    /// the scenario's `[config]` and its file (to name it as a value's origin)
    scenario_keys: Table,
    scenario_origin: Option<PathBuf>,
    /// the `--set` flags, as given
    sets: Vec<String>,
}

/// Where a value of the merged configuration came from (last wins in this
/// order): the built-in defaults, the robot file, the configuration file,
/// the scenario's `[config]`, a `--set`.
#[derive(Clone, Debug, PartialEq, Eq)]
pub enum Origin {
    /// `deploy/phri.toml` as built
    Defaults,
    /// the arm's robot file
    RobotFile(PathBuf),
    /// the `--config` file
    File(PathBuf),
    /// the scenario's `[config]`
    Scenario(PathBuf),
    /// a `--set` flag, as typed (`--set control.avoidance=false`)
    Set(String),
}

impl std::fmt::Display for Origin {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        match self {
            Origin::Defaults => write!(f, "the built-in defaults (deploy/phri.toml)"),
            Origin::RobotFile(p) => write!(f, "robot file {}", p.display()),
            Origin::File(p) => write!(f, "{}", p.display()),
            Origin::Scenario(p) => write!(f, "scenario {}", p.display()),
            Origin::Set(s) => write!(f, "{s}"),
        }
    }
}

/// A safety function switched off on purpose, and what switched it off.
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct SafetyOff {
    /// the function, in a few words (`collision avoidance`)
    pub function: &'static str,
    /// the key that switched it off (`control.avoidance`)
    pub key: String,
    /// where that key's value came from
    pub origin: Origin,
}

impl std::fmt::Display for SafetyOff {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        write!(
            f,
            "{} switched off ({} by {})",
            self.function, self.key, self.origin
        )
    }
}

fn parse_table(text: &str, origin: &str) -> Result<Table, ConfigError> {
    text.parse::<Table>().map_err(|e: toml::de::Error| {
        let at = e.span().map_or(text.len(), |s| s.start);
        let line = scenario::locate(text, at, false).0;
        let message = e.message().trim();
        // a file that ends in the middle of a key (cut short) has no message of its own
        let message = match message.is_empty() {
            true if text[at.min(text.len())..].trim().is_empty() => {
                "the file ends in the middle of a key or value (cut short?)".to_string()
            }
            true => "not valid TOML".to_string(),
            false => message.to_string(),
        };
        ConfigError::Parse {
            origin: origin.to_string(),
            message: format!("line {line}: {message}"),
        }
    })
}

/// The defaults as a table: `deploy/phri.toml` with the default arm's
/// robot file merged over it, both as built.
pub fn defaults_table() -> Table {
    // the embedded files are checked by this crate's tests
    let mut table = parse_table(DEFAULTS, "<defaults>").unwrap_or_default();
    merge(
        &mut table,
        &parse_table(DEFAULT_ROBOT_FILE, "<default robot>").unwrap_or_default(),
    );
    table
}

/// The default arm's robot file in [`DEFAULT_DEPLOY_DIR`].
fn default_robot_path() -> PathBuf {
    Path::new(DEFAULT_DEPLOY_DIR)
        .join("robots")
        .join(DEFAULT_ROBOT)
        .join("robot.toml")
}

/// The defaults with `[robot] urdf` made absolute (the default robot file's,
/// in [`DEFAULT_DEPLOY_DIR`]) and `[robot] file` set.
fn defaults_table_resolved() -> Table {
    let mut table = defaults_table();
    let robot = default_robot_path();
    absolute_urdf(&mut table, &robot);
    set_robot_file(&mut table, &robot);
    table
}

/// `[robot] file` = `path`.
fn set_robot_file(table: &mut Table, path: &Path) {
    let path = std::fs::canonicalize(path).unwrap_or_else(|_| path.to_path_buf());
    if let Some(Value::Table(robot)) = table.get_mut("robot") {
        robot.insert("file".into(), Value::String(path.display().to_string()));
    }
}

/// The arm named `name` (`[robot] name`): its robot file, parsed, with its
/// `[robot] urdf` made absolute, and where it is. A file named by
/// `[robot] file` (`given`, written by the loader for the services) comes
/// first, then `robots/<name>/robot.toml` beside the configuration file
/// `config_path`, then in [`DEFAULT_DEPLOY_DIR`].
pub fn robot_file(
    name: &str,
    given: Option<&str>,
    config_path: &Path,
) -> Result<(Table, PathBuf), ConfigError> {
    let valid = !name.is_empty()
        && name
            .chars()
            .all(|c| c.is_ascii_alphanumeric() || c == '_' || c == '-');
    let beside = config_path
        .parent()
        .unwrap_or(Path::new("."))
        .join("robots");
    let builtin = Path::new(DEFAULT_DEPLOY_DIR).join("robots");
    let given = given
        .filter(|g| !g.is_empty())
        .map(PathBuf::from)
        .filter(|g| g.is_file() && g.parent().and_then(|d| d.file_name()) == Some(name.as_ref()));
    let found = given.or_else(|| {
        valid
            .then(|| {
                [&beside, &builtin]
                    .into_iter()
                    .map(|d| d.join(name).join("robot.toml"))
                    .find(|p| p.is_file())
            })
            .flatten()
    });
    let Some(path) = found else {
        let mut known: Vec<String> = [&beside, &builtin]
            .iter()
            .filter_map(|d| std::fs::read_dir(d).ok())
            .flat_map(|entries| entries.flatten())
            .filter(|e| e.path().join("robot.toml").is_file())
            .filter_map(|e| e.file_name().to_str().map(String::from))
            .collect();
        known.sort();
        known.dedup();
        return Err(ConfigError::NoRobot {
            name: name.to_string(),
            by: config_path.display().to_string(),
            dir: beside.display().to_string(),
            known: if known.is_empty() {
                "none".into()
            } else {
                known.join(", ")
            },
        });
    };
    let text = crate::check::read_text(&path)?;
    let mut table = parse_table(&text, &path.display().to_string())?;
    absolute_urdf(&mut table, &path);
    Ok((table, path))
}

/// With an arm outside the cell (`[robot] ip`: the hybrid cell), its
/// adapter `[services.franka]` runs in the simulator's place on the torque
/// loop's CPU, and the simulator, serving the person and the world only,
/// moves beside perception (CPU 0, priority at most 60); what depended on
/// the simulator's states depends on the adapter's. In the merged table, so
/// that every service sees the same cell.
/// A `[[camera]]` entry over the defaults of `[camera]`: an entry names
/// what differs.
fn over_camera_defaults(entry: &Table) -> Table {
    let mut t = match defaults_table_resolved().get("camera") {
        Some(Value::Table(d)) => d.clone(),
        _ => Table::new(),
    };
    merge(&mut t, entry);
    t
}

/// Entry `i` of `[[camera]]`, typed; an error names the entry and the key.
fn camera_from_value(value: &Value, i: usize, origin: &str) -> Result<CameraConfig, ConfigError> {
    let key_err = |message: String| ConfigError::Key {
        origin: origin.to_string(),
        key: format!("camera[{i}]"),
        message,
    };
    let Value::Table(t) = value else {
        return Err(key_err("a [[camera]] entry must be a table".into()));
    };
    let entry = over_camera_defaults(t);
    let text = toml::to_string(&entry).map_err(|e| key_err(e.to_string()))?;
    toml::from_str(&text).map_err(|e: toml::de::Error| key_err(e.message().trim_end().to_string()))
}

/// `[control] standby = false` drops the hot standby's services (its
/// controller and its residual); with them, the first controller is judged
/// frozen after the standby's silence too (`heartbeat_timeout_ms`, unless
/// its own is given).
fn standby(table: &mut Table) {
    let on = table
        .get("control")
        .and_then(|c| c.get("standby"))
        .and_then(|v| v.as_bool())
        != Some(false);
    let Some(Value::Table(services)) = table.get_mut("services") else {
        return;
    };
    if !on {
        for name in ["control_standby", "dynamics_standby"] {
            if let Some(Value::Table(s)) = services.get_mut(name) {
                s.insert("enabled".into(), Value::Boolean(false));
            }
        }
        return;
    }
    let Some(Value::Table(standby)) = services.get_mut("control_standby") else {
        return;
    };
    let Some(timeout) = standby.get("heartbeat_timeout_ms").cloned() else {
        return;
    };
    if let Some(Value::Table(control)) = services.get_mut("control") {
        control.entry("heartbeat_timeout_ms").or_insert(timeout);
    }
}

fn hybrid(table: &mut Table) -> Result<(), Invalid> {
    let outside = table
        .get("robot")
        .and_then(|r| r.get("ip"))
        .and_then(|v| v.as_str())
        .is_some_and(|ip| !ip.trim().is_empty());
    if !outside {
        return Ok(());
    }
    let Some(Value::Table(services)) = table.get_mut("services") else {
        return Err(Invalid::new(
            "robot.ip",
            "no [services] to drive the arm with",
        ));
    };
    let Some(Value::Table(franka)) = services.get_mut("franka") else {
        return Err(Invalid::new(
            "robot.ip",
            "the configuration has no [services.franka] (phri-franka) to drive the arm with",
        ));
    };
    franka.insert("enabled".into(), Value::Boolean(true));
    if let Some(Value::Table(sim)) = services.get_mut("sim") {
        sim.insert("cpus".into(), Value::Array(vec![Value::Integer(0)]));
        let prio = sim
            .get("rt_priority")
            .and_then(|p| p.as_integer())
            .unwrap_or(0)
            .min(60);
        sim.insert("rt_priority".into(), Value::Integer(prio));
    }
    for (name, spec) in services.iter_mut() {
        if name == "franka" {
            continue;
        }
        if let Some(Value::Array(deps)) = spec.get_mut("depends_on") {
            for d in deps.iter_mut() {
                if d.as_str() == Some("sim") {
                    *d = Value::String("franka".into());
                }
            }
        }
    }
    Ok(())
}

/// `key` (`section.key`, `section.list[i].key`) is given in `table`.
fn gives(table: &Table, key: &str) -> bool {
    let mut at: Option<&Value> = None;
    for (i, part) in key.split('.').enumerate() {
        let (name, index) = match part.split_once('[') {
            Some((n, rest)) => (n, rest.trim_end_matches(']').parse::<usize>().ok()),
            None => (part, None),
        };
        let next = match (i, at) {
            (0, _) => table.get(name),
            (_, Some(Value::Table(t))) => t.get(name),
            _ => None,
        };
        at = match (next, index) {
            (Some(Value::Array(a)), Some(k)) => a.get(k),
            (v, None) => v,
            _ => None,
        };
        if at.is_none() {
            return false;
        }
    }
    true
}

/// `[robot] urdf` resolved against `base_file` ([`resolve`]) and made absolute.
fn absolute_urdf(table: &mut Table, base_file: &Path) {
    let urdf = table
        .get("robot")
        .and_then(|r| r.get("urdf"))
        .and_then(|u| u.as_str())
        .map(|u| resolve(base_file, u));
    if let (Some(urdf), Some(Value::Table(robot))) = (urdf, table.get_mut("robot")) {
        let urdf = std::fs::canonicalize(&urdf).unwrap_or(urdf);
        robot.insert("urdf".into(), Value::String(urdf.display().to_string()));
    }
}

/// The recording directories a camera replays (`[camera] replay_dir`, each
/// `[[camera]]`'s, and the older `[perception] png_dir`) resolved against
/// `base_file` ([`resolve`]) and made absolute, so that the services, which
/// load the merged file from elsewhere, find them.
fn absolute_dirs(table: &mut Table, base_file: &Path) {
    let fix = |t: &mut Table, key: &str| {
        let dir = t
            .get(key)
            .and_then(|v| v.as_str())
            .filter(|d| !d.is_empty());
        if let Some(dir) = dir.map(|d| resolve(base_file, d)) {
            let dir = std::fs::canonicalize(&dir).unwrap_or(dir);
            t.insert(key.into(), Value::String(dir.display().to_string()));
        }
    };
    match table.get_mut("camera") {
        Some(Value::Table(c)) => fix(c, "replay_dir"),
        Some(Value::Array(list)) => {
            for c in list.iter_mut() {
                if let Value::Table(c) = c {
                    fix(c, "replay_dir");
                }
            }
        }
        _ => {}
    }
    if let Some(Value::Table(p)) = table.get_mut("perception") {
        fix(p, "png_dir");
    }
}

/// `path` as given if absolute, else relative to the directory of `base_file`,
/// then to the current directory, then to the defaults' directory.
pub fn resolve(base_file: &Path, path: &str) -> PathBuf {
    let p = Path::new(path);
    if p.is_absolute() {
        return p.to_path_buf();
    }
    let candidates = [
        base_file.parent().map(|d| d.join(p)),
        Some(p.to_path_buf()),
        Some(Path::new(DEFAULT_DEPLOY_DIR).join(p)),
    ];
    candidates
        .into_iter()
        .flatten()
        .find(|c| c.exists())
        .unwrap_or_else(|| p.to_path_buf())
}

impl Config {
    /// The defaults (`deploy/phri.toml` as built), typed.
    pub fn defaults() -> Config {
        // the embedded file is checked by this crate's tests
        Config::from_table(&defaults_table_resolved(), "<defaults>")
            .expect("deploy/phri.toml is a valid configuration")
    }

    /// Type a merged table: unknown sections and keys are refused, naming them.
    pub fn from_table(table: &Table, origin: &str) -> Result<Config, ConfigError> {
        const KNOWN: &[&str] = &[
            "robot",
            "supervisor",
            "services",
            "sim",
            "camera",
            "perception",
            "repulsion",
            "dynamics",
            "control",
            "ssm",
            "avoidance",
            "record",
            "skeleton",
            "gesture",
            "collaboration",
            "voice",
            "audio",
            "mic",
            "ros2",
            "scenario",
        ];
        if let Some(k) = table.keys().find(|k| !KNOWN.contains(&k.as_str())) {
            return Err(ConfigError::UnknownSection {
                origin: origin.to_string(),
                section: k.clone(),
                known: KNOWN.join(", "),
            });
        }
        // several cameras: the first types `camera`, each `cameras`
        let several = match table.get("camera") {
            Some(Value::Array(list)) => Some(list.clone()),
            _ => None,
        };
        if let Some(list) = &several {
            let mut first = table.clone();
            let Some(head) = list.first() else {
                return Err(ConfigError::Key {
                    origin: origin.to_string(),
                    key: "camera".into(),
                    message: "[[camera]] lists no camera".into(),
                });
            };
            let head = head
                .as_table()
                .map(over_camera_defaults)
                .unwrap_or_default();
            first.insert("camera".into(), Value::Table(head));
            let mut config = Config::from_table(&first, origin)?;
            config.cameras = list
                .iter()
                .enumerate()
                .map(|(i, c)| camera_from_value(c, i, origin))
                .collect::<Result<_, _>>()?;
            if config.cameras.len() > phri_ipc::MAX_CAMERAS {
                return Err(ConfigError::Key {
                    origin: origin.to_string(),
                    key: "camera".into(),
                    message: format!(
                        "[[camera]] lists {} cameras, at most {}",
                        config.cameras.len(),
                        phri_ipc::MAX_CAMERAS
                    ),
                });
            }
            derive_camera_services(&mut config.services, config.cameras.len());
            config.apply_camera_sources();
            return Ok(config);
        }
        // through text, so that an error's position names the key
        let text = toml::to_string(table).map_err(|e| ConfigError::Parse {
            origin: origin.to_string(),
            message: e.to_string(),
        })?;
        let mut config: Config = toml::from_str(&text).map_err(|e: toml::de::Error| {
            let key = e
                .span()
                .map(|s| {
                    scenario::locate(&text, s.start, e.message().starts_with("missing field")).1
                })
                .unwrap_or_default();
            ConfigError::Key {
                origin: origin.to_string(),
                key: if key.is_empty() { "<top>".into() } else { key },
                message: e.message().trim_end().to_string(),
            }
        })?;
        config.control.avoidance_params.v_max_repulsion = config.repulsion.params.v_max;
        config.cameras = vec![config.camera.clone()];
        config.apply_camera_sources();
        let law = config.avoidance.law;
        config
            .repulsion
            .points
            .retain(|p| p.law.is_none_or(|l| l == law));
        Ok(config)
    }

    /// Each camera's source decides its service's binary (a Kinect is
    /// served by `phri-freenect`, a ROS 2 camera by `phri-camera-ros2`, the
    /// simulation and a replay by `phri-camera`); `[perception] source =
    /// "png"`, the older way to replay, becomes the first camera's replay.
    fn apply_camera_sources(&mut self) {
        if self.perception.source == DepthSource::Png {
            let p = &self.perception;
            for c in [&mut self.camera]
                .into_iter()
                .chain(self.cameras.first_mut())
            {
                c.source = CameraSource::Replay;
                c.replay_dir = p.png_dir.clone();
                c.depth_scale_m = p.png_depth_scale;
                c.rate_hz = p.png_rate_hz;
                c.replay_loop = p.png_loop;
            }
            self.perception.source = DepthSource::Camera;
        }
        // a camera's depth tracker runs only where its skeletons come from depth
        let depth: Vec<bool> = (0..self.cameras.len())
            .map(|i| self.skeleton_source(i) == SkeletonSource::Depth)
            .collect();
        for spec in self.services.values_mut() {
            if spec.binary == TRACKER_BINARY {
                let camera = camera_of(&spec.args).unwrap_or(0);
                spec.enabled &= depth.get(camera).copied().unwrap_or(false);
                continue;
            }
            if !CAMERA_SOURCE_BINARIES.contains(&spec.binary.as_str()) {
                continue;
            }
            let camera = camera_of(&spec.args).and_then(|i| self.cameras.get(i));
            if let Some(c) = camera {
                spec.binary = c.source.binary().to_string();
            }
        }
    }

    /// Where camera `camera`'s skeletons come from: `[skeleton] source`,
    /// and always the depth tracker for a camera that is not simulated.
    pub fn skeleton_source(&self, camera: usize) -> SkeletonSource {
        match self.cameras.get(camera).map(|c| c.source) {
            Some(CameraSource::Sim) | None => self.skeleton.source,
            Some(_) => SkeletonSource::Depth,
        }
    }

    /// Which source each camera runs, by camera index (for the report).
    pub fn camera_sources(&self) -> Vec<CameraSource> {
        self.cameras.iter().map(|c| c.source).collect()
    }

    /// Range checks of every section, naming the key at fault.
    pub fn validate(&self) -> Result<(), Invalid> {
        self.robot.validate()?;
        self.supervisor.validate()?;
        for (name, s) in &self.services {
            s.validate(name)?;
        }
        let enabled = self.services.values().filter(|s| s.enabled).count();
        if enabled > MAX_ROSTER {
            return Err(Invalid::new(
                "services",
                format!(
                    "at most {MAX_ROSTER} enabled services, got {enabled} (each further camera adds two; \
                     disable some, e.g. services.voice.enabled = false)"
                ),
            ));
        }
        self.sim.validate()?;
        // the older replay keys first: a camera replaying them names them
        self.perception.validate()?;
        self.camera.validate()?;
        for (i, c) in self.cameras.iter().enumerate() {
            c.validate().map_err(|e| {
                Invalid::new(
                    e.key.replacen("camera", &format!("camera[{i}]"), 1),
                    e.reason,
                )
            })?;
        }
        self.repulsion.validate()?;
        self.dynamics.validate()?;
        self.control.validate()?;
        // the standby's residual is called once the first's is two periods
        // behind and acted on a period later: a bound as short would stop
        // the arm whenever the first residual service is replaced
        if self.control.standby && self.control.residual_max_age_ms <= STANDBY_RESIDUAL_LAG_MS {
            return Err(Invalid::new(
                "control.residual_max_age_ms",
                format!(
                    "{} ms: with the hot standby it must be more than {STANDBY_RESIDUAL_LAG_MS} ms \
                     (the standby's residual is called once the first's is 2 ms behind, and acted on a period later)",
                    self.control.residual_max_age_ms
                ),
            ));
        }
        self.ssm.validate()?;
        self.avoidance.validate()?;
        self.record.validate()?;
        self.skeleton.validate()?;
        self.gesture.validate()?;
        self.collaboration.validate()?;
        self.voice.validate()?;
        self.audio.validate()?;
        self.mic.validate()?;
        self.ros2.validate()?;
        // the safe ranges of the safety-relevant settings, in one place
        ranges::check(self)?;
        Ok(())
    }

    /// Checks against the robot model: per-joint lists have one value per
    /// joint, named links exist, and every joint moves some mass at the start
    /// posture `sim.q0` (`M(q0)` positive definite), naming the joint that does not.
    pub fn check_model(&self, model: &phri_model::Model) -> Result<(), Invalid> {
        let n = model.nv();
        let len = |key: &str, v: &[f64]| {
            if v.len() == n {
                Ok(())
            } else {
                Err(Invalid::new(
                    key,
                    format!("has {} values, the robot has {n} joints", v.len()),
                ))
            }
        };
        len("sim.q0", &self.sim.q0)?;
        self.sim
            .viscous_friction
            .resolve(n, "sim.viscous_friction")?;
        self.sim
            .coulomb_friction
            .resolve(n, "sim.coulomb_friction")?;
        self.sim
            .brake_torque_max
            .resolve(n, "sim.brake_torque_max")?;
        let d = &self.dynamics;
        d.gain.resolve(n, "dynamics.gain")?;
        d.contact_threshold
            .resolve(n, "dynamics.contact_threshold")?;
        d.collision_threshold
            .resolve(n, "dynamics.collision_threshold")?;
        d.viscous_friction.resolve(n, "dynamics.viscous_friction")?;
        d.coulomb_friction.resolve(n, "dynamics.coulomb_friction")?;
        if !self.control.posture.is_empty() {
            len("control.posture", &self.control.posture)?;
        }
        let link = |key: String, name: &str| {
            if name.is_empty() || model.frame_id(name).is_ok() {
                Ok(())
            } else {
                Err(Invalid::new(key, format!("the robot has no link '{name}'")))
            }
        };
        for (i, c) in self.robot.capsules.iter().enumerate() {
            if model.frame_id(&c.link).is_err() {
                return Err(Invalid::new(
                    format!("robot.capsules[{i}].link"),
                    format!("the robot has no link '{}'", c.link),
                ));
            }
        }
        link("control.ee_link".into(), &self.control.ee_link)?;
        link("dynamics.ft_link".into(), &d.ft_link)?;
        link(
            "collaboration.robot_link".into(),
            &self.collaboration.robot_link,
        )?;
        link(
            "collaboration.wrist_link".into(),
            &self.collaboration.wrist_link,
        )?;
        for (i, p) in self.repulsion.points.iter().enumerate() {
            link(format!("repulsion.points[{i}].link"), &p.link)?;
        }
        ranges::check_model(self, model)?;
        if let Some(joint) = singular_at(model, &self.sim.q0) {
            return Err(Invalid::new(
                "robot.urdf",
                format!(
                    "joint '{joint}' of {} moves no mass at the start posture sim.q0 \
                     (the joint-space inertia matrix is singular there)",
                    self.robot.urdf
                ),
            ));
        }
        Ok(())
    }
}

/// The joint at which `M(q)` stops being positive definite, if it does: a
/// pivot of its Cholesky factor at or below 1e-9 of the largest diagonal
/// entry means that joint's motion moves nothing its predecessors do not
/// (no mass off its axis, or coaxial with another joint through massless
/// links). The model refuses joints that move no mass at any `q`; this
/// catches the configuration-dependent cases at the posture the cell starts in.
fn singular_at<'m>(model: &'m phri_model::Model, q: &[f64]) -> Option<&'m str> {
    let mut data = phri_model::Data::new(model);
    let mut m = phri_model::crba(model, &mut data, q).ok()?.clone();
    let largest = m.diagonal().amax();
    phri_model::cholesky_factor(m.as_view_mut(), largest * 1e-9)
        .err()
        .and_then(|e| model.joints.get(e.index))
        .map(|j| j.name.as_str())
}

/// `name` as a scenario: a file, or `NAME.toml` in `scenarios/` beside the configuration.
pub fn find_scenario(name: &str, config_path: &Path) -> Result<PathBuf, ConfigError> {
    let dir = config_path
        .parent()
        .unwrap_or(Path::new("."))
        .join("scenarios");
    let candidates = [
        PathBuf::from(name),
        dir.join(format!("{name}.toml")),
        Path::new(DEFAULT_DEPLOY_DIR)
            .join("scenarios")
            .join(format!("{name}.toml")),
    ];
    candidates.into_iter().find(|p| p.is_file()).ok_or_else(|| {
        let mut known: Vec<String> = [dir.clone(), Path::new(DEFAULT_DEPLOY_DIR).join("scenarios")]
            .iter()
            .filter_map(|d| std::fs::read_dir(d).ok())
            .flat_map(|entries| entries.flatten())
            .filter_map(|e| {
                let p = e.path();
                (p.extension()? == "toml").then(|| p.file_stem()?.to_str().map(String::from))?
            })
            .collect();
        known.sort();
        known.dedup();
        ConfigError::NoScenario {
            name: name.to_string(),
            dir: dir.display().to_string(),
            known: if known.is_empty() {
                "none".into()
            } else {
                known.join(", ")
            },
        }
    })
}

/// The overlay of scenario `name` (found beside `path`): its `[config]`
/// and its `[scenario] name` and `file`; the scenario and its file.
fn scenario_overlay(
    name: &str,
    path: &Path,
) -> Result<(Table, Option<Scenario>, Option<PathBuf>), ConfigError> {
    let file = find_scenario(name, path)?;
    let abs = std::fs::canonicalize(&file).unwrap_or(file);
    let s = Scenario::from_file(&abs)?;
    let mut over = Table::new();
    merge(&mut over, &s.config);
    let mut sect = Table::new();
    sect.insert("name".into(), Value::String(s.name.clone()));
    sect.insert("file".into(), Value::String(abs.display().to_string()));
    over.insert("scenario".into(), Value::Table(sect));
    Ok((over, Some(s), Some(abs)))
}

/// An error about a key of the merged table, named by what gave the key
/// (`blame`). A missing key that no file `given` is the robot file's of arm
/// `name` (at `robot_origin`): the defaults leave the arm's keys to it.
fn reblame(
    e: ConfigError,
    blame: &dyn Fn(&str) -> String,
    given: impl Fn(&str) -> bool,
    (robot_origin, name): (&str, &str),
) -> ConfigError {
    match e {
        ConfigError::Key { key, message, .. }
            if message.starts_with("missing field") && !given(&key) =>
        {
            ConfigError::Key {
                origin: robot_origin.to_string(),
                key,
                message: format!(
                    "{message} (the robot file of arm '{name}' must give it: is it complete?)"
                ),
            }
        }
        ConfigError::Key { key, message, .. } => ConfigError::Key {
            origin: blame(&key),
            key,
            message,
        },
        ConfigError::UnknownSection { section, known, .. } => ConfigError::UnknownSection {
            origin: blame(&section),
            section,
            known,
        },
        e => e,
    }
}

/// The run's scenario: the one named (`scen`), else the file's own
/// `[scenario] file` (its `[config]` merged already), else free motion;
/// the recordings it pulls in checked (read only if no one else could
/// write them) and its person's links named after the configuration's.
fn resolved_scenario(scen: Option<Scenario>, config: &Config) -> Result<Scenario, ConfigError> {
    let mut scenario = match scen {
        Some(s) => s,
        None if !config.scenario.file.is_empty() => {
            let mut s = Scenario::from_file(&config.scenario.file)?;
            s.config = Table::new(); // merged already
            s
        }
        None => Scenario::free_motion(),
    };
    if !config.scenario.file.is_empty() {
        let scenario_file = PathBuf::from(&config.scenario.file);
        for v in &scenario.voice {
            let wav = v.path(&scenario_file);
            if wav.exists() {
                crate::trust::check_file(&wav)?;
            }
        }
    }
    if let Some(h) = scenario.human.as_mut() {
        h.name_link_roles(&config.collaboration.wrist_link, &config.control.ee_link);
    }
    Ok(scenario)
}

impl Loaded {
    /// Load `path` over the defaults; then `scenario` (a file or a name in
    /// `scenarios/` beside `path`: its `[config]` merges over the file); then
    /// `sets` (`section.key=value`). Without `scenario`, the file's own
    /// `[scenario] file` (written by the supervisor) gives the person's script,
    /// its `[config]` already merged.
    pub fn load(path: &Path, scenario: Option<&str>, sets: &[&str]) -> Result<Loaded, ConfigError> {
        let text = crate::check::read_text(path)?;
        Self::load_text(&text, path, scenario, sets)
    }

    /// As [`Loaded::load`], from the file's text (`path` names it and anchors relative paths).
    pub fn load_text(
        text: &str,
        path: &Path,
        scenario: Option<&str>,
        sets: &[&str],
    ) -> Result<Loaded, ConfigError> {
        let origin = path.display().to_string();
        let file = parse_table(text, &origin)?;
        // over the file: the scenario's [config], its name and file, --set
        let (mut over, scen, scenario_origin) = match scenario {
            Some(name) => scenario_overlay(name, path)?,
            None => (Table::new(), None, None),
        };
        let scenario_keys = over.clone();
        for s in sets {
            apply_set(&mut over, s)?;
        }
        // the arm the file, the scenario or a --set names, its robot file
        // under the file: defaults < robot file < file < scenario < --set
        let mut named = file.clone();
        merge(&mut named, &over);
        let robot_key = |key: &str| {
            named
                .get("robot")
                .and_then(|r| r.get(key))
                .and_then(|v| v.as_str())
                .map(String::from)
        };
        let name = robot_key("name").unwrap_or_else(|| DEFAULT_ROBOT.into());
        let (robot, robot_path) =
            robot_file(&name, robot_key("file").as_deref(), path).map_err(|e| match e {
                ConfigError::NoRobot {
                    name,
                    by,
                    dir,
                    known,
                } => ConfigError::NoRobot {
                    name,
                    by: merge::set_giving(sets, "robot.name").unwrap_or(by),
                    dir,
                    known,
                },
                e => e,
            })?;
        let mut table = parse_table(DEFAULTS, "<defaults>")?;
        merge(&mut table, &robot);
        // relative paths anchored at the file that gave them
        let mut file = file;
        absolute_urdf(&mut file, path);
        absolute_dirs(&mut file, path);
        merge(&mut table, &file);
        absolute_urdf(&mut over, path);
        absolute_dirs(&mut over, path);
        merge(&mut table, &over);
        set_robot_file(&mut table, &robot_path);
        // an error about a key names what gave it: a --set, the file, the
        // scenario, the robot file
        let robot_origin = robot_path.display().to_string();
        let blame = |key: &str| {
            merge::set_giving(sets, key).unwrap_or_else(|| {
                match !gives(&file, key) && !gives(&over, key) && gives(&robot, key) {
                    true => robot_origin.clone(),
                    false => origin.clone(),
                }
            })
        };
        standby(&mut table);
        hybrid(&mut table).map_err(|invalid| ConfigError::Invalid {
            origin: blame("robot.ip"),
            invalid,
        })?;
        let config = Config::from_table(&table, &origin).map_err(|e| {
            // a key no one gave: the defaults leave the arm's keys to its
            // robot file, so that file lacks it (cut short, or incomplete)
            // unless the key is in an entry of a list another file gave
            let given = |key: &str| key.contains('[') && (gives(&file, key) || gives(&over, key));
            reblame(e, &blame, given, (robot_origin.as_str(), name.as_str()))
        })?;
        config.validate().map_err(|invalid| ConfigError::Invalid {
            origin: blame(&invalid.key),
            invalid,
        })?;
        let scenario = resolved_scenario(scen, &config)?;
        let file_keys = file;
        Ok(Loaded {
            config,
            scenario,
            table,
            origin: path.to_path_buf(),
            robot_origin: robot_path,
            robot_keys: robot,
            file_keys,
            scenario_keys,
            scenario_origin,
            sets: sets.iter().map(|s| s.to_string()).collect(),
        })
    }

    /// The defaults alone, with the default scenario (free motion).
    pub fn defaults() -> Loaded {
        let table = defaults_table_resolved();
        Loaded {
            config: Config::defaults(),
            scenario: Scenario::free_motion(),
            table,
            origin: PathBuf::from("<defaults>"),
            robot_origin: default_robot_path(),
            robot_keys: parse_table(DEFAULT_ROBOT_FILE, "<default robot>").unwrap_or_default(),
            file_keys: Table::new(),
            scenario_keys: Table::new(),
            scenario_origin: None,
            sets: Vec::new(),
        }
    }

    /// Where the value of `key` (`section.key`) came from: the last of a
    /// `--set`, the scenario's `[config]`, the configuration file, the robot
    /// file that gives it, else the built-in defaults.
    pub fn origin_of(&self, key: &str) -> Origin {
        let sets: Vec<&str> = self.sets.iter().map(String::as_str).collect();
        if let Some(flag) = merge::set_giving(&sets, key) {
            return Origin::Set(flag);
        }
        if let Some(s) = &self.scenario_origin {
            if gives(&self.scenario_keys, key) {
                return Origin::Scenario(s.clone());
            }
        }
        if gives(&self.file_keys, key) {
            return Origin::File(self.origin.clone());
        }
        if gives(&self.robot_keys, key) {
            return Origin::RobotFile(self.robot_origin.clone());
        }
        Origin::Defaults
    }

    /// What to name for a key that does not fit the arm's model: what gave
    /// it, or, for a value of the built-in defaults, the robot file (which
    /// should have given one that fits its arm).
    fn blame_model(&self, key: &str) -> String {
        // `control.waypoints[2]` is given where `control.waypoints` is
        let base = key.split('[').next().unwrap_or(key);
        match self.origin_of(base) {
            Origin::Set(flag) => flag,
            Origin::Scenario(p) | Origin::File(p) | Origin::RobotFile(p) => p.display().to_string(),
            Origin::Defaults => self.robot_origin.display().to_string(),
        }
    }

    /// The safety functions this configuration switches off on purpose
    /// (`control.avoidance = false`, `ssm.enabled = false`, a service of the
    /// perception or the residual dropped), each with what switched it off:
    /// every run of such a configuration is reported degraded, naming them.
    pub fn safety_off(&self) -> Vec<SafetyOff> {
        let c = &self.config;
        let mut out = Vec::new();
        let mut off = |function: &'static str, key: String| {
            let origin = self.origin_of(&key);
            out.push(SafetyOff {
                function,
                key,
                origin,
            });
        };
        if !c.control.avoidance {
            off("collision avoidance", "control.avoidance".into());
        }
        if !c.ssm.enabled {
            off("speed and separation monitoring", "ssm.enabled".into());
        }
        // services whose absence leaves a function without its input
        for (name, spec) in &c.services {
            if spec.enabled {
                continue;
            }
            let function = match spec.binary.as_str() {
                b if CAMERA_SOURCE_BINARIES.contains(&b)
                    || b == "phri-perception"
                    || b == "phri-repulsion" =>
                {
                    "collision avoidance (perception)"
                }
                "phri-dynamics" if !spec.args.iter().any(|a| a == "--standby") => {
                    "collision detection (the residual)"
                }
                _ => continue,
            };
            off(function, format!("services.{name}.enabled"));
        }
        out
    }

    /// The robot description's path (absolute once loaded).
    pub fn urdf(&self) -> PathBuf {
        PathBuf::from(&self.config.robot.urdf)
    }

    /// The robot model, refused when it has more joints than the messages
    /// carry or when the configuration does not fit it.
    pub fn model(&self) -> Result<phri_model::Model, ConfigError> {
        let path = self.urdf();
        // what the URDF is, before the model reads it: a file no one else
        // can write, and the description of an arm, not of a forest
        let urdf_origin = self.blame_model("robot.urdf");
        let text = crate::trust::open_trusted(&path)
            .map_err(ConfigError::from)
            .and_then(|f| {
                urdf::read_bounded(f, &path).map_err(|source| ConfigError::Io {
                    path: path.clone(),
                    source,
                })
            })?;
        urdf::check_size(&text).map_err(|invalid| ConfigError::Urdf {
            origin: urdf_origin,
            path: path.clone(),
            invalid,
        })?;
        let mut model =
            phri_model::Model::from_urdf_file_locked(&path, &self.config.robot.locked_joints)
                .map_err(|source| ConfigError::Model {
                    path: path.clone(),
                    source,
                })?;
        if model.nv() > phri_ipc::MAX_DOF {
            return Err(ConfigError::TooManyJoints {
                path,
                joints: model.nv(),
                max: phri_ipc::MAX_DOF,
            });
        }
        let checked = self.config.check_model(&model).and_then(|_| {
            let armature = self
                .config
                .robot
                .armature
                .resolve(model.nv(), "robot.armature")?;
            model
                .set_armature(&armature)
                .map_err(|e| Invalid::new("robot.armature", e.to_string()))?;
            for (i, c) in self.config.robot.capsules.iter().enumerate() {
                model
                    .add_capsule(&c.link, &c.a.into(), &c.b.into(), c.radius)
                    .map_err(|e| Invalid::new(format!("robot.capsules[{i}]"), e.to_string()))?;
            }
            Ok(())
        });
        checked.map_err(|invalid| ConfigError::Invalid {
            origin: self.blame_model(&invalid.key),
            invalid,
        })?;
        Ok(model)
    }

    /// The merged table as TOML (what the supervisor hands its services).
    pub fn to_toml(&self) -> String {
        toml::to_string(&self.table).unwrap_or_default()
    }
}
