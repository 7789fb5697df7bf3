//! `phri-residual --urdf FILE --log LOG.csv [--ki K] [--dt S] [--config phri.toml]`
//! (`phri-residual completions bash|zsh|fish`: a shell completion script)
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
use std::path::PathBuf;
use std::process::ExitCode;

use clap::Parser;

use phri_config::{Loaded, PerJoint, ResidualConfig};
use phri_estimation::ResidualObserver;
use phri_runtime::cli::CompletionsCmd;

const BIN: &str = "phri-residual";

/// The command line.
#[derive(Parser, Debug)]
#[command(
    version = phri_runtime::cli::VERSION,
    about = "Runs the momentum residual observer offline over a recorded log (CSV in, `t,r1..rn` CSV out)",
    long_about = "Runs the residual observer of phri-estimation (the one the dynamics service runs) over a recorded log, \
to tune thresholds and gains on data from a real arm. The log's header is `t,q1..qn,tau1..taun` (joint order as \
phri-model prints it; t [s], q [rad], tau the applied joint torque [Nm]); stdout gets `t,r1..rn` (r [Nm]).",
    args_conflicts_with_subcommands = true,
    subcommand_negates_reqs = true,
    args_override_self = true
)]
struct Cli {
    /// Robot model (URDF) the log was recorded with
    #[arg(long, value_name = "FILE", required = true)]
    urdf: Option<String>,
    /// Recorded log: CSV `t,q1..qn,tau1..taun` (t \[s\], q \[rad\], tau \[Nm\])
    #[arg(long, value_name = "LOG.csv", required = true)]
    log: Option<String>,
    /// Observer gain K_I on every joint [1/s] (default: the configuration's `dynamics.gain`)
    #[arg(long, value_name = "K", allow_negative_numbers = true, value_parser = positive)]
    ki: Option<f64>,
    /// Integrate with this fixed period \[s\] instead of the log's t column
    #[arg(long, value_name = "S", allow_negative_numbers = true, value_parser = positive)]
    dt: Option<f64>,
    /// phri configuration to take `[dynamics]` from (friction model, thresholds); without it no friction is compensated
    #[arg(long, value_name = "phri.toml")]
    config: Option<PathBuf>,
    #[command(subcommand)]
    completions: Option<CompletionsCmd>,
}

/// A positive, finite number.
fn positive(v: &str) -> Result<f64, String> {
    match v.trim().parse::<f64>() {
        Ok(x) if x.is_finite() && x > 0.0 => Ok(x),
        _ => Err("must be a positive number".into()),
    }
}

fn main() -> ExitCode {
    let cli: Cli = phri_runtime::cli::parse(BIN);
    if let Some(CompletionsCmd::Completions { shell }) = cli.completions {
        phri_runtime::cli::completions::<Cli>(BIN, shell);
        return ExitCode::SUCCESS;
    }
    phri_runtime::service::run(BIN, || body(cli))
}

fn body(cli: Cli) -> Result<(), Box<dyn Error>> {
    // clap requires both unless a subcommand is given
    let (Some(urdf), Some(log)) = (cli.urdf.as_deref(), cli.log.as_deref()) else {
        return Err("--urdf and --log are required".into());
    };
    let model = phri_model::Model::from_urdf_file(urdf).map_err(|e| e.to_string())?;
    let n = model.nv();
    let mut cfg = match &cli.config {
        Some(path) => {
            Loaded::load(path, None, &[])
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
    if let Some(ki) = cli.ki {
        cfg.gain = PerJoint::All(ki);
    }
    let dt = cli.dt;
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

#[cfg(test)]
mod tests {
    use clap::CommandFactory;

    /// clap's own consistency checks (names, conflicts, positionals), which
    /// release builds skip at run time.
    #[test]
    fn the_command_is_consistent() {
        super::Cli::command().debug_assert();
    }
}
