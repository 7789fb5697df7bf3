//! A cell of the bench's own (its own iceoryx2 prefix and report), and
//! `phri-bench cell`: one run of a scenario with the machine's floor
//! measured beside it ([`crate::floor`]), printed as a table of what the
//! run cost and how the torque loop and perception kept their pace.

use std::error::Error;
use std::path::{Path, PathBuf};
use std::process::{Child, Command, Stdio};

use serde_json::{json, Value};

/// A supervisor started for a bench, with its own prefix and report.
pub struct BenchCell {
    child: Child,
    pub prefix: String,
    report: PathBuf,
}

impl BenchCell {
    /// `scenario` for `duration_s` with `config` (default: the checkout's
    /// deploy/phri.toml) and `sets` (`section.key=value`).
    pub fn start(
        config: Option<&Path>,
        scenario: &str,
        duration_s: f64,
        sets: &[String],
    ) -> Result<BenchCell, Box<dyn Error>> {
        let exe_dir = std::env::current_exe()?
            .parent()
            .map(PathBuf::from)
            .unwrap_or_default();
        let config = config.map_or_else(|| exe_dir.join("../../deploy/phri.toml"), PathBuf::from);
        let prefix = format!("bench{}_", std::process::id());
        let report = std::env::temp_dir().join(format!("phri-bench-{prefix}.json"));
        let mut cmd = Command::new(exe_dir.join("phri-supervisor"));
        cmd.arg("--config")
            .arg(&config)
            .arg("--scenario")
            .arg(scenario)
            .arg("--duration")
            .arg(duration_s.to_string())
            .arg("--prefix")
            .arg(&prefix)
            .arg("--report")
            .arg(&report);
        for s in sets {
            cmd.arg("--set").arg(s);
        }
        let child = cmd
            .stdout(Stdio::null())
            .stderr(Stdio::null())
            .spawn()
            .map_err(|e| format!("cannot start phri-supervisor: {e}"))?;
        Ok(BenchCell {
            child,
            prefix,
            report,
        })
    }

    /// Wait for the run's end; its report.
    pub fn finish(mut self) -> Result<Value, Box<dyn Error>> {
        let st = self.child.wait()?;
        if let Err(alive) = phri_ipc::remove_leftovers(&self.prefix) {
            eprintln!(
                "phri-bench: {alive} node(s) of {} still attached: their shared memory stays",
                self.prefix
            );
        }
        if !st.success() {
            return Err(format!("phri-supervisor failed: {st}").into());
        }
        let text = std::fs::read_to_string(&self.report)
            .map_err(|e| format!("{}: {e}", self.report.display()))?;
        let _ = std::fs::remove_file(&self.report);
        Ok(serde_json::from_str(&text)?)
    }
}

/// One run's figures from its `report` and the `floor` beside it (JSON).
pub fn figures(scenario: &str, report: &Value, floor: &Value) -> Value {
    let tl = &report["torque_loop"];
    let cycles = tl["cycles"].as_u64().unwrap_or(0);
    // start-up's braked wait, while the services start, and the shutdown
    // are not the run's (the floor is measured from 1.5 s on, until the end)
    let startup_overruns = tl["startup_overruns"].as_u64().unwrap_or(0);
    let shutdown_overruns = tl["shutdown_overruns"].as_u64().unwrap_or(0);
    let overruns = tl["overruns"]
        .as_u64()
        .unwrap_or(0)
        .saturating_sub(startup_overruns + shutdown_overruns);
    let cameras: Vec<Value> = report["perception"]["cameras"]
        .as_array()
        .map(|cs| {
            cs.iter()
                .map(|c| {
                    json!({
                        "camera": c["camera"],
                        "capture_to_repulsion_ms": c["frame_to_repulsion_ms"],
                        "arrival_to_repulsion_ms": c["arrival_to_repulsion_ms"],
                    })
                })
                .collect()
        })
        .unwrap_or_default();
    // the services and the supervisor that runs them
    let cores: f64 = report["cpu"]
        .as_object()
        .map(|m| m.values().filter_map(|c| c["share"].as_f64()).sum())
        .unwrap_or(0.0)
        + report["supervisor_cpu"]["share"].as_f64().unwrap_or(0.0);
    json!({
        "scenario": scenario,
        "summary": report["summary"],
        "cpu": report["cpu"],
        "supervisor_cpu": report["supervisor_cpu"],
        "cell_cores": cores,
        "torque_loop": {
            "cycles": cycles,
            "cycles_expected": tl["cycles_expected"],
            "cycles_short": tl["cycles_short"],
            "overruns": overruns,
            "startup_overruns": startup_overruns,
            "shutdown_overruns": shutdown_overruns,
            "overrun_share": if cycles > 0 { overruns as f64 / cycles as f64 } else { 0.0 },
            "missed_deadlines": tl["missed_deadlines"],
            "latency_us": tl["latency_us"],
            "braked_after_start_up": tl["braked_cycles"].as_u64().unwrap_or(0)
                .saturating_sub(tl["startup_braked_cycles"].as_u64().unwrap_or(0)),
        },
        "perception": cameras,
        "floor": floor,
    })
}

/// `figures` as a readable table.
pub fn table(f: &Value) -> String {
    let mut out = String::new();
    let num = |v: &Value| v.as_f64().map_or("–".to_string(), |x| format!("{x:.2}"));
    let pct = |v: &Value| {
        v.as_f64()
            .map_or("–".to_string(), |x| format!("{:.1} %", 100.0 * x))
    };
    out += &format!(
        "scenario {}: {}\n",
        f["scenario"].as_str().unwrap_or(""),
        f["summary"].as_str().unwrap_or("")
    );
    out += "service             CPU share  budget\n";
    if let Some(m) = f["cpu"].as_object() {
        for (name, c) in m {
            out += &format!(
                "{name:<20}{:>9}  {:>6}\n",
                pct(&c["share"]),
                pct(&c["budget"])
            );
        }
    }
    out += &format!(
        "{:<20}{:>9}\n",
        "(the supervisor)",
        pct(&f["supervisor_cpu"]["share"])
    );
    out += &format!(
        "{:<20}{:>9} cores (the services and the supervisor)\n",
        "the cell",
        num(&f["cell_cores"])
    );
    let tl = &f["torque_loop"];
    let fl = &f["floor"];
    out += &format!(
        "torque loop: {} cycles of {} ({} short), {} missed deadlines, {} braked after start-up\n",
        tl["cycles"],
        tl["cycles_expected"],
        tl["cycles_short"],
        tl["missed_deadlines"],
        tl["braked_after_start_up"]
    );
    out += &format!(
        "  wake-ups over half a period late: robot {} ({}; {} more in start-up's braked wait, {} in the shutdown), floor {} ({})\n",
        tl["overruns"],
        pct(&tl["overrun_share"]),
        tl["startup_overruns"],
        tl["shutdown_overruns"],
        fl["late_over_half_period"],
        pct(&fl["late_share"])
    );
    out += &format!(
        "  state → command p50/p99/max {} / {} / {} µs; floor's wake-up latency p50/p99/max {} / {} / {} µs\n",
        num(&tl["latency_us"]["p50"]), num(&tl["latency_us"]["p99"]), num(&tl["latency_us"]["max"]),
        num(&fl["latency_us"]["p50"]), num(&fl["latency_us"]["p99"]), num(&fl["latency_us"]["max"]),
    );
    if let Some(cs) = f["perception"].as_array() {
        for c in cs {
            out += &format!(
                "camera {}: capture → repulsion p50/p99 {} / {} ms, arrival → repulsion p50/p99 {} / {} ms\n",
                c["camera"],
                num(&c["capture_to_repulsion_ms"]["p50"]), num(&c["capture_to_repulsion_ms"]["p99"]),
                num(&c["arrival_to_repulsion_ms"]["p50"]), num(&c["arrival_to_repulsion_ms"]["p99"]),
            );
        }
    }
    out
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn the_figures_take_the_report_s_pace_cpu_and_perception_beside_the_floor() {
        let report = json!({
            "summary": "degraded (robot loop behind: 600 overruns, 1 % of periods)",
            "cpu": {"sim": {"cpu_s": 7.0, "share": 0.12, "budget": 0.3},
                    "camera": {"cpu_s": 5.0, "share": 0.08, "budget": 0.2}},
            "supervisor_cpu": {"cpu_s": 1.2, "share": 0.02, "budget": null},
            "torque_loop": {"cycles": 59_000, "cycles_expected": 59_700, "cycles_short": 700,
                            "overruns": 602, "missed_deadlines": 0, "braked_cycles": 230,
                            "startup_braked_cycles": 200, "startup_overruns": 10,
                            "shutdown_overruns": 2,
                            "latency_us": {"p50": 100.0, "p99": 300.0, "max": 5000.0}},
            "perception": {"cameras": [{"camera": 0,
                "frame_to_repulsion_ms": {"p50": 4.0, "p99": 7.0},
                "arrival_to_repulsion_ms": {"p50": 1.3, "p99": 2.5}}]},
        });
        let floor = json!({"late_over_half_period": 610, "late_share": 0.0102,
                           "latency_us": {"p50": 45.0, "p99": 800.0, "max": 9000.0}});
        let f = figures("coexistence", &report, &floor);
        // the services and the supervisor
        assert!((f["cell_cores"].as_f64().unwrap() - 0.22).abs() < 1e-9);
        assert_eq!(f["torque_loop"]["braked_after_start_up"], 30);
        assert!((f["torque_loop"]["overrun_share"].as_f64().unwrap() - 0.01).abs() < 1e-9);
        assert_eq!(f["perception"][0]["capture_to_repulsion_ms"]["p99"], 7.0);
        let t = table(&f);
        for needle in [
            "scenario coexistence: degraded",
            "sim                    12.0 %  30.0 %",
            "(the supervisor)        2.0 %",
            "the cell                 0.22 cores",
            "59000 cycles of 59700 (700 short)",
            "robot 590 (1.0 %; 10 more in start-up's braked wait, 2 in the shutdown), floor 610 (1.0 %)",
            "300.00 / 5000.00 µs; floor's wake-up latency p50/p99/max 45.00 / 800.00",
            "capture → repulsion p50/p99 4.00 / 7.00 ms",
        ] {
            assert!(t.contains(needle), "'{needle}' missing from\n{t}");
        }
    }
}
