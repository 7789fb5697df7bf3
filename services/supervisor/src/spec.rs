//! `[supervisor]` and `[services.NAME]` sections of `deploy/phri.toml`.

use std::collections::BTreeMap;

use serde::{Deserialize, Serialize};

/// How the supervisor behaves.
#[derive(Clone, Debug, Deserialize, Serialize)]
#[serde(default, deny_unknown_fields)]
pub struct SupervisorConfig {
    /// first restart delay after a crash [ms]; doubles on each quick crash
    pub restart_backoff_min_ms: u64,
    /// largest restart delay [ms]
    pub restart_backoff_max_ms: u64,
    /// a service that ran this long is healthy again: the back-off resets [s]
    pub stable_after_s: f64,
    /// time a service gets to exit after SIGTERM before SIGKILL [ms]
    pub shutdown_grace_ms: u64,
    /// health publication rate [Hz]
    pub health_hz: f64,
    /// a service silent on its output channel this long is reported frozen [ms]
    pub heartbeat_timeout_ms: u64,
}

impl Default for SupervisorConfig {
    fn default() -> Self {
        SupervisorConfig {
            restart_backoff_min_ms: 50,
            restart_backoff_max_ms: 2000,
            stable_after_s: 5.0,
            shutdown_grace_ms: 2000,
            health_hz: 10.0,
            heartbeat_timeout_ms: 200,
        }
    }
}

/// One supervised service.
#[derive(Clone, Debug, Deserialize, Serialize)]
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
    /// pause after starting it before starting the next one [ms]
    #[serde(default)]
    pub start_delay_ms: u64,
    /// disabled services are not started
    #[serde(default = "yes")]
    pub enabled: bool,
    /// channel the service publishes on continuously; silence there while it
    /// runs means it is frozen (it is then killed and restarted)
    #[serde(default)]
    pub heartbeat: Option<String>,
    /// silence on `heartbeat` longer than this is frozen [ms] (default: the
    /// supervisor's `heartbeat_timeout_ms`)
    #[serde(default)]
    pub heartbeat_timeout_ms: Option<u64>,
    /// services whose silence explains this one's (it is not judged while they are silent)
    #[serde(default)]
    pub depends_on: Vec<String>,
    /// CPUs the service may run on (empty: any); the torque loop shares one
    /// so that a stall of that CPU pauses the robot and its controller alike
    #[serde(default)]
    pub cpus: Vec<usize>,
}

fn yes() -> bool {
    true
}

/// `[services]`: name → spec, in start order.
pub fn services(table: &toml::Table) -> Result<Vec<(String, ServiceSpec)>, String> {
    let Some(v) = table.get("services") else {
        return Err("[services] is missing: nothing to supervise".into());
    };
    let map: BTreeMap<String, ServiceSpec> = v
        .clone()
        .try_into()
        .map_err(|e: toml::de::Error| format!("[services]: {}", e.message()))?;
    let mut list: Vec<(String, ServiceSpec)> = map.into_iter().filter(|(_, s)| s.enabled).collect();
    list.sort_by_key(|(name, s)| (s.order, name.clone()));
    if list.len() > phri_ipc::MAX_SERVICES {
        return Err(format!(
            "[services]: at most {} services",
            phri_ipc::MAX_SERVICES
        ));
    }
    Ok(list)
}
