//! What a service binary does before its loop: arguments, configuration,
//! shutdown handlers, real-time scheduling, and one-line errors.

use std::path::{Path, PathBuf};
use std::process::ExitCode;

use serde::de::DeserializeOwned;
use toml::Table;

use crate::{load_config, section, Args, Shutdown};

/// Everything a service's `main` needs.
pub struct ServiceContext {
    /// service name as the supervisor knows it
    pub name: String,
    /// merged configuration (`--config` file plus `--set`s)
    pub config: Table,
    pub config_path: PathBuf,
    /// iceoryx2 prefix of this run
    pub prefix: String,
    /// SCHED_FIFO priority (0: normal scheduler)
    pub rt_priority: i32,
    pub shutdown: Shutdown,
    pub args: Args,
}

/// Environment variable the supervisor sets for every service: when the cell
/// started [ns, CLOCK_MONOTONIC]. A restarted simulator continues the
/// scenario's clock from it instead of replaying the scenario from the start.
pub const CELL_START_ENV: &str = "PHRI_CELL_START_NS";

/// Environment variable the supervisor sets for every service: the run
/// directory (state files, report). A restarted simulator finds the arm's
/// last state there.
pub const RUN_DIR_ENV: &str = "PHRI_RUN_DIR";

/// The run directory from [`RUN_DIR_ENV`], if set and not empty.
pub fn run_dir() -> Option<PathBuf> {
    std::env::var_os(RUN_DIR_ENV)
        .filter(|s| !s.is_empty())
        .map(PathBuf::from)
}

/// The cell's start time from [`CELL_START_ENV`], if set, valid and not in the future.
pub fn cell_start_ns() -> Option<u64> {
    let t = std::env::var(CELL_START_ENV)
        .ok()?
        .trim()
        .parse::<u64>()
        .ok()?;
    (t <= crate::now_ns()).then_some(t)
}

/// Flags every service accepts: `--config FILE --prefix P --rt-priority N --set k=v`.
pub const COMMON_FLAGS: &[&str] = &["--config", "--prefix", "--rt-priority", "--set", "--name"];

impl ServiceContext {
    /// Parse the process arguments (`extra` are service-specific valued flags).
    pub fn from_args(default_name: &str, extra: &[&str]) -> Result<ServiceContext, String> {
        let valued: Vec<&str> = COMMON_FLAGS.iter().chain(extra.iter()).copied().collect();
        let args = Args::parse(std::env::args().skip(1), &valued, &[])?;
        let config_path = PathBuf::from(args.get("--config").unwrap_or("deploy/phri.toml"));
        let sets = args.all("--set");
        let config = load_config(&config_path, &[], &sets).map_err(|e| e.to_string())?;
        let prefix = args
            .get("--prefix")
            .map(str::to_string)
            .or_else(|| std::env::var("PHRI_PREFIX").ok())
            .unwrap_or_else(|| "phri_".to_string());
        let rt_priority = args.parse_value::<i32>("--rt-priority")?.unwrap_or(0);
        let shutdown = Shutdown::install().map_err(|e| format!("signal handlers: {e}"))?;
        let name = args.get("--name").unwrap_or(default_name).to_string();
        Ok(ServiceContext {
            name,
            config,
            config_path,
            prefix,
            rt_priority,
            shutdown,
            args,
        })
    }

    /// Deserialize `[name]`, errors naming the section and key.
    pub fn section<T: DeserializeOwned>(&self, name: &str) -> Result<T, String> {
        section(&self.config, name).map_err(|e| format!("{}: {e}", self.config_path.display()))
    }

    /// `[robot] urdf`, relative to the configuration file's directory.
    pub fn robot_urdf(&self) -> Result<PathBuf, String> {
        let urdf = self
            .config
            .get("robot")
            .and_then(|r| r.get("urdf"))
            .and_then(|u| u.as_str())
            .ok_or_else(|| format!("{}: [robot] urdf is missing", self.config_path.display()))?;
        Ok(resolve(&self.config_path, urdf))
    }

    /// The robot model of `[robot] urdf`, refused when it has more joints than
    /// the messages carry (`max_dof`), with an error naming the file.
    pub fn robot_model(&self, max_dof: usize) -> Result<phri_model::Model, String> {
        let urdf = self.robot_urdf()?;
        let model = phri_model::Model::from_urdf_file(&urdf).map_err(|e| e.to_string())?;
        if model.nv() > max_dof {
            return Err(format!(
                "{}: {} joints, messages carry at most {max_dof}",
                urdf.display(),
                model.nv()
            ));
        }
        Ok(model)
    }

    /// Switch to SCHED_FIFO if configured and permitted; say what happened on stderr.
    pub fn go_realtime(&self) {
        if self.rt_priority > 0 {
            if let Err(e) = crate::rt::make_realtime(self.rt_priority) {
                eprintln!("{}: {e}; running under {}", self.name, crate::rt::policy());
            }
        }
    }
}

/// `path` as given if absolute, else relative to the directory of `base_file`
/// (and, failing that, to the current directory).
pub fn resolve(base_file: &Path, path: &str) -> PathBuf {
    let p = Path::new(path);
    if p.is_absolute() {
        return p.to_path_buf();
    }
    let beside = base_file
        .parent()
        .map(|d| d.join(p))
        .unwrap_or_else(|| p.to_path_buf());
    if beside.exists() {
        beside
    } else {
        p.to_path_buf()
    }
}

/// Run a service body; print its error as one line and exit non-zero.
pub fn run(name: &str, body: impl FnOnce() -> Result<(), String>) -> ExitCode {
    match body() {
        Ok(()) => ExitCode::SUCCESS,
        Err(e) => {
            eprintln!("{name}: {e}");
            ExitCode::from(2)
        }
    }
}
