//! `phri-supervisor`: starts the services of `[services]`, restarts what dies
//! (with back-off), kills what freezes, publishes `supervisor/health`, shuts
//! everything down in reverse order on SIGINT/SIGTERM or after `--duration`,
//! leaves no process and no shared-memory file behind, and writes `--report`.

use std::collections::BTreeMap;
use std::path::{Path, PathBuf};
use std::process::{Child, Command, ExitCode, Stdio};
use std::time::Duration;

use phri_ipc::*;
use phri_runtime::config::{apply_set, merge};
use phri_runtime::{now_ns, sleep_until_ns, Args, Shutdown};
use phri_supervisor::process::{
    process_matches, Proc, ServiceState, SupervisorState, STATE_VERSION,
};
use phri_supervisor::report::{DetectorInfo, Evaluator, ServiceReport};
use phri_supervisor::restart::RestartPolicy;
use phri_supervisor::spec::{services, ServiceSpec, SupervisorConfig};

const USAGE: &str = "usage: phri-supervisor [--config deploy/phri.toml] [--scenario NAME|FILE] [--duration SECONDS] [--report FILE] [--set section.key=value]... [--prefix P] [--run-dir DIR]";

fn main() -> ExitCode {
    phri_runtime::service::run("phri-supervisor", body)
}

struct Supervised {
    name: String,
    spec: ServiceSpec,
    child: Option<Proc>,
    policy: RestartPolicy,
    restart_at: Option<u64>,
    last_heartbeat_ns: u64,
    started_ns: u64,
}

/// A scenario file: `name`, `duration_s`, `[config]` overrides (the rest is the simulator's).
struct ScenarioInfo {
    name: String,
    path: Option<PathBuf>,
    duration_s: Option<f64>,
    config: toml::Table,
}

fn load_scenario(arg: Option<&str>, deploy_dir: &Path) -> Result<ScenarioInfo, String> {
    let Some(arg) = arg else {
        return Ok(ScenarioInfo {
            name: "free-motion".into(),
            path: None,
            duration_s: None,
            config: toml::Table::new(),
        });
    };
    let candidates = [
        PathBuf::from(arg),
        deploy_dir.join("scenarios").join(format!("{arg}.toml")),
    ];
    let path = candidates.iter().find(|p| p.is_file()).ok_or_else(|| {
        format!(
            "--scenario: '{arg}' is neither a file nor a scenario in {}",
            deploy_dir.join("scenarios").display()
        )
    })?;
    let text = std::fs::read_to_string(path).map_err(|e| format!("{}: {e}", path.display()))?;
    let table: toml::Table = text
        .parse()
        .map_err(|e: toml::de::Error| format!("{}: {}", path.display(), e.message()))?;
    let name = table
        .get("name")
        .and_then(|v| v.as_str())
        .map(str::to_string)
        .unwrap_or_else(|| {
            path.file_stem()
                .map(|s| s.to_string_lossy().into_owned())
                .unwrap_or_default()
        });
    let duration_s = table
        .get("duration_s")
        .and_then(|v| v.as_float().or_else(|| v.as_integer().map(|i| i as f64)));
    let config = match table.get("config") {
        Some(toml::Value::Table(t)) => t.clone(),
        Some(_) => return Err(format!("{}: [config] must be a table", path.display())),
        None => toml::Table::new(),
    };
    let abs = std::fs::canonicalize(path).map_err(|e| format!("{}: {e}", path.display()))?;
    Ok(ScenarioInfo {
        name,
        path: Some(abs),
        duration_s,
        config,
    })
}

/// `state.json` (pids, for people and scripts) and `supervisor.state` (bincode,
/// for a supervisor that takes over), each replaced atomically.
fn write_state(run_dir: &Path, prefix: &str, cell_start_ns: u64, list: &[Supervised]) {
    let services: serde_json::Map<String, serde_json::Value> = list.iter().map(|s| (s.name.clone(), serde_json::json!({"pid": s.child.as_ref().map(|c| c.pid()), "restarts": s.policy.restarts}))).collect();
    let v = serde_json::json!({"supervisor_pid": std::process::id(), "prefix": prefix, "services": services});
    let state = SupervisorState {
        version: STATE_VERSION,
        supervisor_pid: std::process::id(),
        prefix: prefix.to_string(),
        cell_start_ns,
        services: list
            .iter()
            .map(|s| ServiceState {
                name: s.name.clone(),
                pid: s.child.as_ref().map_or(0, |c| c.pid()),
                restarts: s.policy.restarts,
            })
            .collect(),
    };
    for (name, bytes) in [
        ("state.json", v.to_string().into_bytes()),
        (STATE_FILE, state.encode()),
    ] {
        let tmp = run_dir.join(format!("{name}.tmp"));
        if std::fs::write(&tmp, bytes).is_ok() {
            let _ = std::fs::rename(&tmp, run_dir.join(name));
        }
    }
}

const STATE_FILE: &str = "supervisor.state";

fn body() -> Result<(), String> {
    let args = Args::parse(
        std::env::args().skip(1),
        &[
            "--config",
            "--scenario",
            "--duration",
            "--report",
            "--set",
            "--prefix",
            "--run-dir",
        ],
        &["--help"],
    )?;
    if args.has("--help") {
        println!("{USAGE}");
        return Ok(());
    }
    let config_path = std::fs::canonicalize(args.get("--config").unwrap_or("deploy/phri.toml"))
        .map_err(|e| {
            format!(
                "{}: {e}",
                args.get("--config").unwrap_or("deploy/phri.toml")
            )
        })?;
    let deploy_dir = config_path
        .parent()
        .map(Path::to_path_buf)
        .unwrap_or_default();
    let duration_arg = args.parse_value::<f64>("--duration")?;
    if duration_arg.is_some_and(|d| !(d > 0.0)) {
        return Err("--duration: must be positive".into());
    }
    let scenario = load_scenario(args.get("--scenario"), &deploy_dir)?;
    let text = std::fs::read_to_string(&config_path)
        .map_err(|e| format!("{}: {e}", config_path.display()))?;
    let mut table: toml::Table = text
        .parse()
        .map_err(|e: toml::de::Error| format!("{}: {}", config_path.display(), e.message()))?;
    merge(&mut table, &scenario.config);
    for s in args.all("--set") {
        apply_set(&mut table, s).map_err(|e| e.to_string())?;
    }
    // paths absolute, the scenario named, so that services read one self-contained file
    let urdf = table
        .get("robot")
        .and_then(|r| r.get("urdf"))
        .and_then(|u| u.as_str())
        .ok_or_else(|| format!("{}: [robot] urdf is missing", config_path.display()))?;
    let urdf = phri_runtime::service::resolve(&config_path, urdf);
    let urdf = std::fs::canonicalize(&urdf)
        .map_err(|e| format!("[robot] urdf {}: {e}", urdf.display()))?;
    apply_set(&mut table, &format!("robot.urdf=\"{}\"", urdf.display()))
        .map_err(|e| e.to_string())?;
    if let Some(p) = &scenario.path {
        apply_set(&mut table, &format!("scenario.file=\"{}\"", p.display()))
            .map_err(|e| e.to_string())?;
    }
    apply_set(&mut table, &format!("scenario.name=\"{}\"", scenario.name))
        .map_err(|e| e.to_string())?;
    let sup: SupervisorConfig =
        phri_runtime::section(&table, "supervisor").map_err(|e| e.to_string())?;
    let specs = services(&table)?;
    let duration_s = duration_arg.or(scenario.duration_s);

    let prefix = args
        .get("--prefix")
        .map(str::to_string)
        .unwrap_or_else(|| format!("phri{}_", std::process::id()));
    let run_dir = PathBuf::from(
        args.get("--run-dir")
            .map(str::to_string)
            .unwrap_or_else(|| format!("/tmp/phri-run-{prefix}")),
    );
    std::fs::create_dir_all(&run_dir).map_err(|e| format!("{}: {e}", run_dir.display()))?;
    let merged_path = run_dir.join("config.toml");
    std::fs::write(
        &merged_path,
        toml::to_string(&table).map_err(|e| e.to_string())?,
    )
    .map_err(|e| format!("{}: {e}", merged_path.display()))?;
    let bin_dir = std::env::current_exe()
        .map_err(|e| e.to_string())?
        .parent()
        .map(Path::to_path_buf)
        .unwrap_or_default();
    for (name, spec) in &specs {
        if !bin_dir.join(&spec.binary).is_file() {
            return Err(format!(
                "[services.{name}] binary '{}' not found in {} (build with: cargo build --release)",
                spec.binary,
                bin_dir.display()
            ));
        }
    }

    let shutdown = Shutdown::install().map_err(|e| format!("signal handlers: {e}"))?;
    let s = |x: IpcError| x.to_string();
    let node = node("supervisor", &prefix).map_err(s)?;
    let health_pub = publisher::<Health>(&node, SUPERVISOR_HEALTH).map_err(s)?;
    let stats_sub = subscriber::<RobotStats>(&node, ROBOT_STATS, 8).map_err(s)?;
    let truth_sub = subscriber::<Truth>(&node, SIM_TRUTH, DRAIN).map_err(s)?;
    let residual_sub = subscriber::<Residual>(&node, DYNAMICS_RESIDUAL, DRAIN).map_err(s)?;
    let status_sub = subscriber::<ControlStatus>(&node, CONTROL_STATUS, DRAIN).map_err(s)?;
    let frames_sub = frame_subscriber(&node, CAMERA_DEPTH).map_err(s)?;
    let filtered_sub = frame_subscriber(&node, PERCEPTION_DEPTH).map_err(s)?;
    let repulsion_sub =
        subscriber::<RepulsionResult>(&node, PERCEPTION_REPULSION, DRAIN).map_err(s)?;

    // evaluation needs the detector's thresholds and the names of links and parts
    let model = phri_model_names(&urdf);
    let dyn_table = table
        .get("dynamics")
        .and_then(|v| v.as_table())
        .cloned()
        .unwrap_or_default();
    let floats = |key: &str, default: Vec<f64>| -> Vec<f64> {
        dyn_table
            .get(key)
            .and_then(|v| v.as_array())
            .map(|a| {
                a.iter()
                    .filter_map(|x| x.as_float().or_else(|| x.as_integer().map(|i| i as f64)))
                    .collect()
            })
            .unwrap_or(default)
    };
    let thresholds = floats(
        "collision_threshold",
        vec![8.0, 8.0, 6.0, 6.0, 4.0, 3.0, 2.0],
    );
    let gain = floats("gain", vec![100.0])
        .into_iter()
        .fold(f64::INFINITY, f64::min);
    let t0 = now_ns();
    let mut eval = Evaluator::new(
        t0,
        DetectorInfo {
            collision_threshold: thresholds,
            gain: if gain.is_finite() { gain } else { 100.0 },
        },
        model,
        part_names(),
    );
    let reaction_name = table
        .get("control")
        .and_then(|c| c.get("reaction"))
        .and_then(|r| r.as_str())
        .unwrap_or("reflex")
        .to_string();

    // a supervisor of this run that died leaves its state: take its services over
    let previous = std::fs::read(run_dir.join(STATE_FILE))
        .ok()
        .and_then(|b| SupervisorState::decode(&b))
        .filter(|p| p.prefix == prefix);
    if let Some(p) = &previous {
        if p.supervisor_pid != std::process::id()
            && process_matches(p.supervisor_pid, &["phri-supervisor", prefix.as_str()])
        {
            return Err(format!(
                "a supervisor (pid {}) already runs the cell of prefix {prefix}",
                p.supervisor_pid
            ));
        }
    }
    // the cell's clock survives a takeover
    let cell_start_ns = previous
        .as_ref()
        .map(|p| p.cell_start_ns)
        .filter(|&t| t > 0 && t <= t0)
        .unwrap_or(t0);

    let spawn = |name: &str, spec: &ServiceSpec| -> Result<Child, String> {
        use std::os::unix::process::CommandExt;
        let mut cmd = Command::new(bin_dir.join(&spec.binary));
        cmd.arg("--config")
            .arg(&merged_path)
            .arg("--prefix")
            .arg(&prefix)
            .arg("--name")
            .arg(name)
            .arg("--rt-priority")
            .arg(spec.rt_priority.to_string())
            .args(&spec.args)
            .env(
                phri_runtime::service::CELL_START_ENV,
                cell_start_ns.to_string(),
            )
            .env(phri_runtime::service::RUN_DIR_ENV, &run_dir)
            .stdin(Stdio::null());
        // own process group: a terminal's Ctrl-C reaches the supervisor only, which stops the rest in order
        cmd.process_group(0);
        let online = std::thread::available_parallelism().map_or(1, |n| n.get());
        let cpus: Vec<usize> = spec.cpus.iter().copied().filter(|&c| c < online).collect();
        if !cpus.is_empty() {
            // SAFETY: between fork and exec only async-signal-safe calls: CPU_SET on a
            // stack value and sched_setaffinity.
            unsafe {
                cmd.pre_exec(move || {
                    let mut set: libc::cpu_set_t = std::mem::zeroed();
                    for &c in &cpus {
                        libc::CPU_SET(c, &mut set);
                    }
                    libc::sched_setaffinity(0, std::mem::size_of::<libc::cpu_set_t>(), &set);
                    Ok(())
                });
            }
        }
        cmd.spawn()
            .map_err(|e| format!("[services.{name}]: cannot start {}: {e}", spec.binary))
    };

    let mut list: Vec<Supervised> = Vec::new();
    for (name, spec) in specs {
        let adopt = previous
            .as_ref()
            .and_then(|p| p.services.iter().find(|s| s.name == name))
            .filter(|s| {
                process_matches(
                    s.pid,
                    &[&format!("--prefix {prefix}"), &format!("--name {name}")],
                )
            });
        let now = now_ns();
        let mut policy = RestartPolicy::default();
        policy.started(now);
        let child = match adopt {
            Some(prev) => {
                policy.restarts = prev.restarts;
                eprintln!(
                    "phri-supervisor: adopted {name} (pid {}) from the previous supervisor",
                    prev.pid
                );
                Proc::Adopted {
                    pid: prev.pid,
                    prefix: format!("--prefix {prefix}"),
                }
            }
            None => {
                let child = spawn(&name, &spec)?;
                eprintln!("phri-supervisor: started {name} (pid {})", child.id());
                Proc::Child(child)
            }
        };
        let adopted = matches!(child, Proc::Adopted { .. });
        list.push(Supervised {
            name,
            spec: spec.clone(),
            child: Some(child),
            policy,
            restart_at: None,
            last_heartbeat_ns: now,
            started_ns: now,
        });
        if spec.start_delay_ms > 0 && !adopted {
            std::thread::sleep(Duration::from_millis(spec.start_delay_ms));
        }
    }
    if list
        .iter()
        .any(|s| matches!(s.child, Some(Proc::Adopted { .. })))
    {
        eval.event(
            now_ns(),
            "takeover",
            "supervisor",
            "adopted the services of a supervisor that died",
        );
    }
    write_state(&run_dir, &prefix, cell_start_ns, &list);

    let end_ns = duration_s.map(|d| t0 + (d * 1e9) as u64);
    let health_period = (1e9 / sup.health_hz.max(0.1)) as u64;
    let mut next_health = t0;
    let mut health = Health::zeroed();
    let mut tick = t0;
    let timeout_ns = sup.heartbeat_timeout_ms * 1_000_000;
    while !shutdown.requested() && end_ns.is_none_or(|e| now_ns() < e) {
        tick += 10_000_000;
        sleep_until_ns(tick);
        let now = now_ns();
        // evaluation streams, and heartbeats per channel
        let mut heard: Vec<&str> = Vec::new();
        while let Some(m) = stats_sub
            .receive()
            .map_err(|e| ipc_err(ROBOT_STATS, e).to_string())?
        {
            eval.on_stats(&m);
            heard.push(ROBOT_STATS);
        }
        while let Some(m) = truth_sub
            .receive()
            .map_err(|e| ipc_err(SIM_TRUTH, e).to_string())?
        {
            eval.on_truth(&m);
            heard.push(SIM_TRUTH);
        }
        while let Some(m) = residual_sub
            .receive()
            .map_err(|e| ipc_err(DYNAMICS_RESIDUAL, e).to_string())?
        {
            eval.on_residual(&m);
            heard.push(DYNAMICS_RESIDUAL);
        }
        while let Some(m) = status_sub
            .receive()
            .map_err(|e| ipc_err(CONTROL_STATUS, e).to_string())?
        {
            eval.on_status(&m, &reaction_name);
            heard.push(CONTROL_STATUS);
        }
        while let Some(f) = frames_sub
            .receive()
            .map_err(|e| ipc_err(CAMERA_DEPTH, e).to_string())?
        {
            eval.on_frame(f.user_header());
            heard.push(CAMERA_DEPTH);
        }
        while filtered_sub
            .receive()
            .map_err(|e| ipc_err(PERCEPTION_DEPTH, e).to_string())?
            .is_some()
        {
            heard.push(PERCEPTION_DEPTH);
        }
        while let Some(m) = repulsion_sub
            .receive()
            .map_err(|e| ipc_err(PERCEPTION_REPULSION, e).to_string())?
        {
            eval.on_repulsion(&m);
            heard.push(PERCEPTION_REPULSION);
        }
        for sv in list.iter_mut() {
            if sv
                .spec
                .heartbeat
                .as_deref()
                .is_some_and(|h| heard.contains(&h))
            {
                sv.last_heartbeat_ns = now;
            }
        }
        // reap and schedule restarts
        let mut changed = false;
        for sv in list.iter_mut() {
            if let Some(child) = sv.child.as_mut() {
                if let Some(detail) = child.try_exited() {
                    sv.child = None;
                    changed = true;
                    let _ = node.try_cleanup_dead_nodes();
                    if sv.spec.restart {
                        let at = sv.policy.exited(
                            now,
                            sup.restart_backoff_min_ms,
                            sup.restart_backoff_max_ms,
                            sup.stable_after_s,
                        );
                        sv.restart_at = Some(at);
                        eprintln!(
                            "phri-supervisor: {} {detail}; restarting in {} ms",
                            sv.name,
                            (at - now) / 1_000_000
                        );
                    } else {
                        eprintln!("phri-supervisor: {} {detail}", sv.name);
                    }
                    eval.event(now, "exit", &sv.name, detail);
                }
            }
        }
        // frozen services: alive, their dependencies heard from, but silent themselves
        let silent: Vec<(String, bool)> = list
            .iter()
            .map(|sv| {
                let limit = sv
                    .spec
                    .heartbeat_timeout_ms
                    .map_or(timeout_ns, |ms| ms * 1_000_000);
                (
                    sv.name.clone(),
                    sv.spec.heartbeat.is_some() && now.saturating_sub(sv.last_heartbeat_ns) > limit,
                )
            })
            .collect();
        for sv in list.iter_mut() {
            let deps_ok = sv
                .spec
                .depends_on
                .iter()
                .all(|d| silent.iter().any(|(n, s)| n == d && !*s));
            if !deps_ok {
                // its silence is explained by theirs: judge it afresh once they are back
                sv.last_heartbeat_ns = now;
            }
            let grace = now.saturating_sub(sv.started_ns) > 4 * timeout_ns.max(500_000_000);
            if let (Some(child), true) = (sv.child.as_ref(), deps_ok && grace) {
                if silent.iter().any(|(n, s)| *n == sv.name && *s) {
                    eprintln!(
                        "phri-supervisor: {} silent on {} for {} ms: frozen, killing it",
                        sv.name,
                        sv.spec.heartbeat.as_deref().unwrap_or("?"),
                        now.saturating_sub(sv.last_heartbeat_ns) / 1_000_000
                    );
                    eval.event(now, "frozen", &sv.name, "no heartbeat");
                    child.signal(libc::SIGKILL);
                    sv.last_heartbeat_ns = now;
                }
            }
        }
        for sv in list.iter_mut() {
            if sv.restart_at.is_some_and(|at| now >= at) {
                sv.restart_at = None;
                match spawn(&sv.name, &sv.spec) {
                    Ok(child) => {
                        eprintln!(
                            "phri-supervisor: restarted {} (pid {})",
                            sv.name,
                            child.id()
                        );
                        eval.event(
                            now,
                            "restart",
                            &sv.name,
                            format!("restart {}", sv.policy.restarts),
                        );
                        sv.child = Some(Proc::Child(child));
                        sv.policy.started(now);
                        sv.started_ns = now;
                        sv.last_heartbeat_ns = now;
                        changed = true;
                    }
                    Err(e) => {
                        eprintln!("phri-supervisor: {e}");
                        sv.restart_at = Some(sv.policy.exited(
                            now,
                            sup.restart_backoff_min_ms,
                            sup.restart_backoff_max_ms,
                            sup.stable_after_s,
                        ));
                    }
                }
            }
        }
        if changed {
            write_state(&run_dir, &prefix, cell_start_ns, &list);
        }
        if now >= next_health {
            next_health = now + health_period;
            health.seq += 1;
            health.stamp_ns = now;
            health.count = list.len() as u32;
            for (h, sv) in health.services.iter_mut().zip(&list) {
                h.name = [0; 32];
                let b = sv.name.as_bytes();
                h.name[..b.len().min(31)].copy_from_slice(&b[..b.len().min(31)]);
                h.pid = sv.child.as_ref().map_or(0, |c| c.pid() as i32);
                h.alive = sv.child.is_some() as u32;
                h.restarts = sv.policy.restarts;
                h.started_ns = sv.started_ns;
            }
            let _ = publish(&health_pub, SUPERVISOR_HEALTH, &health);
        }
    }
    let end = now_ns();
    let services_report: BTreeMap<String, ServiceReport> = list
        .iter()
        .map(|sv| {
            (
                sv.name.clone(),
                ServiceReport {
                    restarts: sv.policy.restarts,
                    alive_at_end: sv.child.is_some(),
                },
            )
        })
        .collect();
    // drain what arrived in the last period before stopping anything
    while let Ok(Some(m)) = truth_sub.receive() {
        eval.on_truth(&m);
    }
    while let Ok(Some(m)) = residual_sub.receive() {
        eval.on_residual(&m);
    }
    while let Ok(Some(m)) = status_sub.receive() {
        eval.on_status(&m, &reaction_name);
    }
    while let Ok(Some(m)) = stats_sub.receive() {
        eval.on_stats(&m);
    }
    let report = eval.report(end, &scenario.name, services_report);

    // ordered shutdown in start order: the robot first (it brakes the arm as it
    // exits), then what depends on it; SIGTERM, then SIGKILL after the grace period
    for sv in list.iter_mut() {
        if let Some(mut child) = sv.child.take() {
            child.signal(libc::SIGTERM);
            let deadline = now_ns() + sup.shutdown_grace_ms * 1_000_000;
            let mut killed = false;
            while child.try_exited().is_none() {
                if now_ns() > deadline + 2_000_000_000 {
                    eprintln!(
                        "phri-supervisor: {} (pid {}) does not end even after SIGKILL",
                        sv.name,
                        child.pid()
                    );
                    break;
                }
                if now_ns() > deadline && !killed {
                    eprintln!("phri-supervisor: {} ignored SIGTERM, killing it", sv.name);
                    child.signal(libc::SIGKILL);
                    killed = true;
                }
                std::thread::sleep(Duration::from_millis(5));
            }
        }
    }
    let _ = node.try_cleanup_dead_nodes();
    drop((
        health_pub,
        stats_sub,
        truth_sub,
        residual_sub,
        status_sub,
        frames_sub,
        filtered_sub,
        repulsion_sub,
    ));
    drop(node);
    match phri_ipc::remove_leftovers(&prefix) {
        Ok(0) => {}
        Ok(n) => eprintln!("phri-supervisor: removed {n} shared-memory files the run left"),
        Err(alive) => eprintln!("phri-supervisor: {alive} node(s) of prefix {prefix} still attached (a monitor or recorder?): the last one out cleans up"),
    }
    let _ = std::fs::remove_file(run_dir.join("state.json"));
    let _ = std::fs::remove_file(run_dir.join(STATE_FILE));
    if let Some(path) = args.get("--report") {
        let json = serde_json::to_string_pretty(&report).map_err(|e| e.to_string())?;
        std::fs::write(path, json + "\n").map_err(|e| format!("--report {path}: {e}"))?;
    }
    eprintln!(
        "phri-supervisor: {} done after {:.1} s: {} cycles, {} missed deadlines, latency p99 {:.0} µs, {} contacts, {} false detections",
        report.scenario, report.duration_s, report.torque_loop.cycles, report.torque_loop.missed_deadlines, report.torque_loop.latency_us.p99, report.contacts.len(), report.false_detections
    );
    Ok(())
}

/// Names of the robot model's collision objects (for contact reports).
fn phri_model_names(urdf: &Path) -> Vec<String> {
    phri_model::Model::from_urdf_file(urdf)
        .map(|m| m.collisions.iter().map(|c| c.link.clone()).collect())
        .unwrap_or_default()
}

/// Human body part names in the simulator's numbering.
fn part_names() -> Vec<String> {
    phri_sim::human::BodyPart::ALL
        .iter()
        .map(|p| p.name().to_string())
        .collect()
}
