//! `phri-residual --urdf FILE --log LOG.csv [--ki K] [--dt S] [--config phri.toml]`
//!
//! Runs the residual observer of `phri-estimation` (the one the dynamics
//! service runs) over a recorded log, so that thresholds and gains can be
//! tuned on data from a real arm. The log's
//! header is `t,q1..qn,tau1..taun` (joint order as `phri-model` prints it,
//! t in seconds, q in rad, tau the applied joint torque in Nm); the output on
//! stdout is `t,r1..rn`. `--dt S` integrates with a fixed period instead of
//! the t column; `--config` takes `[dynamics]` (friction model, thresholds)
//! from a phri configuration file, otherwise no friction is compensated.

use std::error::Error;
use std::io::{BufRead, BufReader, BufWriter, Write};
use std::process::ExitCode;

use phri_config::{Loaded, PerJoint, ResidualConfig};
use phri_estimation::ResidualObserver;
use phri_runtime::Args;

const USAGE: &str =
    "usage: phri-residual --urdf FILE --log LOG.csv [--ki K] [--dt S] [--config phri.toml]";

fn main() -> ExitCode {
    phri_runtime::service::run("phri-residual", body)
}

fn body() -> Result<(), Box<dyn Error>> {
    let args = Args::parse(
        std::env::args().skip(1),
        &["--urdf", "--log", "--ki", "--dt", "--config"],
        &["--help"],
    )?;
    if args.has("--help") {
        println!("{USAGE}");
        return Ok(());
    }
    let urdf = args
        .get("--urdf")
        .ok_or(format!("--urdf is required\n{USAGE}"))?;
    let log = args
        .get("--log")
        .ok_or(format!("--log is required\n{USAGE}"))?;
    let model = phri_model::Model::from_urdf_file(urdf).map_err(|e| e.to_string())?;
    let n = model.nv();
    let mut cfg = match args.get("--config") {
        Some(path) => {
            Loaded::load(std::path::Path::new(path), None, &[])
                .map_err(|e| e.to_string())?
                .config
                .dynamics
        }
        None => ResidualConfig {
            viscous_friction: PerJoint::All(0.0),
            coulomb_friction: PerJoint::All(0.0),
            ..Loaded::defaults().config.dynamics
        },
    };
    if let Some(ki) = args.parse_value::<f64>("--ki")? {
        if !(ki.is_finite() && ki > 0.0) {
            return Err(format!("--ki: {ki} must be positive").into());
        }
        cfg.gain = PerJoint::All(ki);
    }
    let dt = args.parse_value::<f64>("--dt")?;
    if dt.is_some_and(|d| !(d.is_finite() && d > 0.0)) {
        return Err("--dt: must be positive".into());
    }
    if let Some(d) = dt {
        // a fixed period: never treat a sample as a gap
        cfg.max_gap_s = cfg.max_gap_s.max(2.0 * d);
    }
    let mut observer = ResidualObserver::new(model, &cfg).map_err(|e| e.to_string())?;

    let file = std::fs::File::open(log).map_err(|e| format!("{log}: {e}"))?;
    let mut lines = BufReader::new(file).lines();
    let header = lines
        .next()
        .ok_or(format!("{log}: empty file"))?
        .map_err(|e| format!("{log}: {e}"))?;
    let cols: Vec<&str> = header.trim().split(',').map(str::trim).collect();
    let expected: Vec<String> = std::iter::once("t".to_string())
        .chain((1..=n).map(|i| format!("q{i}")))
        .chain((1..=n).map(|i| format!("tau{i}")))
        .collect();
    if cols != expected {
        return Err(format!(
            "{log}:1: header must be '{}' for this {n}-joint robot, got '{}'",
            expected.join(","),
            header.trim()
        )
        .into());
    }
    let out = std::io::stdout();
    let mut out = BufWriter::new(out.lock());
    let w = |e: std::io::Error| format!("stdout: {e}");
    writeln!(
        out,
        "t,{}",
        (1..=n)
            .map(|i| format!("r{i}"))
            .collect::<Vec<_>>()
            .join(",")
    )
    .map_err(w)?;
    let mut row = vec![0.0; 1 + 2 * n];
    let mut last_t = f64::NEG_INFINITY;
    for (k, line) in lines.enumerate() {
        let lineno = k + 2;
        let line = line.map_err(|e| format!("{log}:{lineno}: {e}"))?;
        if line.trim().is_empty() {
            continue;
        }
        let mut count = 0;
        for (i, cell) in line.split(',').enumerate() {
            if i >= row.len() {
                return Err(format!("{log}:{lineno}: more than {} columns", row.len()).into());
            }
            let v: f64 = cell.trim().parse().map_err(|_| {
                format!(
                    "{log}:{lineno}: column '{}': '{}' is not a number",
                    expected[i],
                    cell.trim()
                )
            })?;
            if !v.is_finite() {
                return Err(format!(
                    "{log}:{lineno}: column '{}': not a finite number",
                    expected[i]
                )
                .into());
            }
            row[i] = v;
            count += 1;
        }
        if count != row.len() {
            return Err(format!(
                "{log}:{lineno}: expected {} columns, got {count}",
                row.len()
            )
            .into());
        }
        let t_log = row[0];
        if dt.is_none() && t_log <= last_t {
            return Err(format!("{log}:{lineno}: t = {t_log} does not increase").into());
        }
        last_t = t_log;
        let t = dt.map_or(t_log, |d| k as f64 * d);
        let r = observer
            .step(t, &row[1..1 + n], &row[1 + n..], None)
            .map_err(|e| format!("{log}:{lineno}: {e}"))?;
        write!(out, "{t_log}").map_err(w)?;
        for x in r.r {
            write!(out, ",{x}").map_err(w)?;
        }
        writeln!(out).map_err(w)?;
    }
    out.flush().map_err(w)?;
    Ok(())
}
