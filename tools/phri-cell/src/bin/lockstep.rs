//! `phri-lockstep`: run a scenario with the whole cell in one process, in
//! lock-step (deterministic, faster than real time), and print what happened
//! as JSON. With several `--offset` values (or `--sweep FROM,TO,STEP`) it runs
//! once per offset of the person's script against the robot's cycle.
//!
//!   phri-lockstep --scenario coexistence [--duration S] [--config deploy/phri.toml]
//!                 [--set section.key=value ...] [--offset S ...] [--sweep FROM,TO,STEP]
//!                 [--latency-ms MS] [--outage perception|dynamics|control:FROM:TO ...]
//!                 [--no-perception]

use std::error::Error;
use std::path::PathBuf;
use std::process::ExitCode;

use phri_cell::{Cell, CellOptions};
use phri_config::Loaded;
use phri_runtime::Args;

const USAGE: &str = "usage: phri-lockstep --scenario NAME|FILE [--duration S] [--config FILE] [--set k=v ...] [--offset S ...] [--sweep FROM,TO,STEP] [--latency-ms MS] [--outage perception|dynamics|control:FROM:TO ...] [--no-perception]";

fn main() -> ExitCode {
    phri_runtime::service::run("phri-lockstep", body)
}

/// `FROM,TO,STEP` as the offsets it spans.
fn sweep(s: &str) -> Result<Vec<f64>, String> {
    let v: Vec<f64> = s
        .split(',')
        .map(|x| x.trim().parse::<f64>())
        .collect::<Result<_, _>>()
        .map_err(|_| format!("--sweep: expected FROM,TO,STEP, got {s}"))?;
    if v.len() != 3 || !v.iter().all(|x| x.is_finite()) || !(v[2] > 0.0) || v[1] < v[0] {
        return Err(format!(
            "--sweep: expected FROM,TO,STEP with STEP > 0 and TO ≥ FROM, got {s}"
        ));
    }
    let steps = ((v[1] - v[0]) / v[2] + 1e-9).floor() as usize;
    if steps > 10_000 {
        return Err(format!("--sweep: {} runs, at most 10001", steps + 1));
    }
    Ok((0..=steps).map(|k| v[0] + k as f64 * v[2]).collect())
}

fn body() -> Result<(), Box<dyn Error>> {
    let args = Args::parse(
        std::env::args().skip(1),
        &[
            "--scenario",
            "--duration",
            "--config",
            "--set",
            "--offset",
            "--sweep",
            "--latency-ms",
            "--outage",
        ],
        &["--no-perception", "--help"],
    )
    .map_err(|e| format!("{e}; {USAGE}"))?;
    if args.has("--help") {
        println!("{USAGE}");
        return Ok(());
    }
    let config = PathBuf::from(args.get("--config").unwrap_or("deploy/phri.toml"));
    let name = args
        .get("--scenario")
        .ok_or_else(|| format!("--scenario is required; {USAGE}"))?;
    let loaded = Loaded::load(&config, Some(name), &args.all("--set"))?;
    let model = loaded.model()?;
    let duration = args
        .parse_value::<f64>("--duration")?
        .unwrap_or(loaded.scenario.duration_s);
    if !(duration > 0.0 && duration.is_finite()) {
        return Err(
            format!("--duration: must be a positive number of seconds, got {duration}").into(),
        );
    }
    let mut offsets = Vec::new();
    for o in args.all("--offset") {
        let x = o
            .parse::<f64>()
            .ok()
            .filter(|x| x.is_finite())
            .ok_or_else(|| format!("--offset: not a number: {o}"))?;
        offsets.push(x);
    }
    if let Some(s) = args.get("--sweep") {
        offsets.extend(sweep(s)?);
    }
    if offsets.is_empty() {
        offsets.push(0.0);
    }
    let mut opts = CellOptions {
        perception: !args.has("--no-perception"),
        ..CellOptions::default()
    };
    for o in args.all("--outage") {
        opts.outages.push(o.parse()?);
    }
    if let Some(l) = args.parse_value::<f64>("--latency-ms")? {
        opts.perception_latency_ms = l;
    }
    let periods = (duration / loaded.config.sim.dt_s).round() as u64;
    let mut runs = Vec::new();
    let mut total = 0usize;
    for (i, &offset) in offsets.iter().enumerate() {
        opts.human_time_offset_s = offset;
        let mut cell = Cell::new(&loaded, model.clone(), &opts)?;
        for _ in 0..periods {
            cell.tick()?;
        }
        let s = cell.summary();
        eprintln!(
            "[{}/{}] offset {offset:+.2} s: {} unintended contacts, closest {:.3} m, {} waypoints, {} detections",
            i + 1,
            offsets.len(),
            s.unintended_contacts,
            s.min_distance_m,
            s.waypoints,
            s.detections
        );
        total += s.unintended_contacts;
        runs.push(serde_json::json!({"offset_s": offset, "summary": s}));
    }
    let out = serde_json::json!({
        "scenario": loaded.scenario.name,
        "duration_s": duration,
        "perception_latency_ms": opts.perception_latency_ms,
        "unintended_contacts": total,
        "runs": runs,
    });
    println!("{}", serde_json::to_string_pretty(&out)?);
    Ok(())
}
