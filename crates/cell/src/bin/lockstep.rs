//! `phri-lockstep`: run a scenario with the whole cell in one process, in
//! lock-step (deterministic, faster than real time), and print what happened
//! as JSON. With several `--offset` values (or `--sweep FROM,TO,STEP`) it runs
//! once per offset of the person's script against the robot's cycle.
//!
//!   phri-lockstep --scenario coexistence [--duration S] [--config deploy/phri.toml]
//!                 [--set section.key=value ...] [--offset S ...] [--sweep FROM,TO,STEP]
//!                 [--latency-ms MS] [--outage perception|dynamics:FROM:TO ...] [--no-perception]

use std::path::PathBuf;
use std::process::ExitCode;

use phri_cell::{load, Cell, CellOptions};

const USAGE: &str = "usage: phri-lockstep --scenario NAME|FILE [--duration S] [--config FILE] [--set k=v ...] [--offset S ...] [--sweep FROM,TO,STEP] [--latency-ms MS] [--outage perception|dynamics:FROM:TO ...] [--no-perception]";

fn main() -> ExitCode {
    match run() {
        Ok(()) => ExitCode::SUCCESS,
        Err(e) => {
            eprintln!("phri-lockstep: {e}");
            ExitCode::from(2)
        }
    }
}

fn run() -> Result<(), String> {
    let args = phri_runtime::args::Args::parse(
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
    )?;
    if args.has("--help") {
        println!("{USAGE}");
        return Ok(());
    }
    let config = PathBuf::from(args.get("--config").unwrap_or("deploy/phri.toml"));
    let name = args
        .get("--scenario")
        .ok_or_else(|| format!("--scenario is required\n{USAGE}"))?;
    let scenario = if name.ends_with(".toml") {
        PathBuf::from(name)
    } else {
        config
            .parent()
            .unwrap_or(std::path::Path::new("."))
            .join("scenarios")
            .join(format!("{name}.toml"))
    };
    let sets = args.all("--set");
    let (table, scen, model) = load(&config, &scenario, &sets).map_err(|e| e.to_string())?;
    let duration = args
        .parse_value::<f64>("--duration")?
        .unwrap_or(scen.duration_s);
    if !(duration > 0.0 && duration.is_finite()) {
        return Err(format!(
            "--duration: must be a positive number of seconds, got {duration}"
        ));
    }
    let mut offsets = Vec::new();
    for o in args.all("--offset") {
        offsets.push(
            o.parse::<f64>()
                .map_err(|_| format!("--offset: not a number: {o}"))?,
        );
    }
    if let Some(s) = args.get("--sweep") {
        let v: Vec<f64> = s
            .split(',')
            .map(|x| x.trim().parse::<f64>())
            .collect::<Result<_, _>>()
            .map_err(|_| format!("--sweep: expected FROM,TO,STEP, got {s}"))?;
        if v.len() != 3 || !(v[2] > 0.0) || v[1] < v[0] {
            return Err(format!(
                "--sweep: expected FROM,TO,STEP with STEP > 0 and TO ≥ FROM, got {s}"
            ));
        }
        let mut x = v[0];
        while x <= v[1] + 1e-9 {
            offsets.push(x);
            x += v[2];
        }
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
    let periods = (duration / 1e-3).round() as u64;
    let mut runs = Vec::new();
    let mut total = 0usize;
    for (i, &offset) in offsets.iter().enumerate() {
        opts.human_time_offset_s = offset;
        let mut cell = Cell::new(&table, &scen, model.clone(), &opts).map_err(|e| e.to_string())?;
        for _ in 0..periods {
            cell.tick().map_err(|e| e.to_string())?;
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
        "scenario": scen.name,
        "duration_s": duration,
        "perception_latency_ms": opts.perception_latency_ms,
        "unintended_contacts": total,
        "runs": runs,
    });
    println!(
        "{}",
        serde_json::to_string_pretty(&out).map_err(|e| e.to_string())?
    );
    Ok(())
}
