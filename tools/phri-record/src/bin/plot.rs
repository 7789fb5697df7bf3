//! `phri-plot --file FILE.mcap --out DIR [--without FREE.mcap] [--format png|svg|both]`:
//! figures of a recording as PNG and SVG (`--format`, default both: each
//! figure's PNG where it always was, its SVG beside it), each with a title,
//! axis labels in SI units, tick values and a legend, the text in the
//! embedded DejaVu Sans (anti-aliased in the PNG, `<text>` in the SVG).
//! A progress bar on stderr while reading when stderr is a terminal; in a
//! pipe the output is what it always was.
//!
//! - `ee_trajectory.png` (like the paper's Fig. 7): end-effector x-y path
//!   (`control/status` `ee`), blue while the person is farther than the
//!   surveillance distance (0.4 m, `sim/truth` `min_distance`: the true
//!   person-robot distance, for evaluation), red while nearer;
//!   with `--without`, the path of a recording without the person (e.g.
//!   `free-motion`) underneath in grey
//! - `residual.png`: ‖r‖ over time (`dynamics/residual` `norm`), blue; the
//!   collision norm threshold from the recording's metadata (dashed red) when
//!   present; an orange vertical line where `flags & COLLISION` rises
//! - `min_distance.png`: `control/status` `min_distance` over time (non-finite skipped)
//! - with a collaboration in the recording (`collab/state` not idle):
//!   `collaboration.png` (the paper's Figs. 8 and 11): end-effector x, y, z
//!   (`control/status` `ee`) and the collaborative hand's (`collab/state`
//!   `hand`, while collaborating) against time, a grey line at each change of
//!   phase; `contact_force.png`: ‖F̂‖ (`collab/state`) and the true force of
//!   the collaborative hand (`sim/truth`, intended contacts of a hand)

use std::error::Error;
use std::path::PathBuf;
use std::process::ExitCode;
use std::time::{Duration, Instant};

use clap::Parser;

use phri_ipc::{
    residual_flags, BodyPart, COLLAB_STATE, CONTROL_STATUS, DYNAMICS_RESIDUAL, SIM_TRUTH,
};
use phri_record::plot::*;
use phri_record::progress::Progress;
use phri_record::{read_file, ReadError, METADATA_NAME};
use phri_runtime::cli::CompletionsCmd;
use serde_json::Value;

const BIN: &str = "phri-plot";

/// The command line.
#[derive(Parser, Debug)]
#[command(
    version = phri_runtime::cli::VERSION,
    about = "Draws the figures of a phri-record recording (MCAP) as PNG and SVG: end-effector path, momentum residual, minimum distance, and the collaboration's hand and contact force when the recording has a collaboration",
    args_conflicts_with_subcommands = true,
    subcommand_negates_reqs = true
)]
struct Cli {
    /// Recording to plot (MCAP written by phri-record)
    #[arg(long, value_name = "FILE.mcap", required = true)]
    file: Option<String>,
    /// Directory to write the figures into (created if missing)
    #[arg(long, value_name = "DIR", required = true)]
    out: Option<PathBuf>,
    /// A recording without the person (e.g. free-motion): its end-effector path drawn underneath in grey
    #[arg(long, value_name = "FREE.mcap")]
    without: Option<String>,
    /// Which files each figure is written as: NAME.png, NAME.svg, or both
    #[arg(long, value_enum, value_name = "FORMAT", default_value_t = Format::Both)]
    format: Format,
    #[command(subcommand)]
    completions: Option<CompletionsCmd>,
}
/// someone nearer than this to a control point counts as present \[m\] (ρ of eq. 16)
const NEAR_M: f64 = 0.4;
const GREEN: Rgb = [44, 160, 44];
const PURPLE: Rgb = [148, 103, 189];
const BROWN: Rgb = [140, 86, 75];
const W: usize = 900;
const H: usize = 600;

fn main() -> ExitCode {
    let cli: Cli = phri_runtime::cli::parse(BIN);
    if let Some(CompletionsCmd::Completions { shell }) = cli.completions {
        phri_runtime::cli::completions::<Cli>(BIN, shell);
        return ExitCode::SUCCESS;
    }
    phri_runtime::service::run(BIN, || body(cli).map_err(|e| e.to_string()))
}

fn num(v: &Value, k: &str) -> f64 {
    v.get(k).and_then(Value::as_f64).unwrap_or(f64::NAN)
}

fn body(cli: Cli) -> Result<(), Box<dyn Error>> {
    // clap requires both unless a subcommand is given
    let (Some(file), Some(out)) = (cli.file.as_deref(), cli.out.clone()) else {
        return Err("--file and --out are required".into());
    };
    let format = cli.format;
    let buf = read_file(file)?;

    // the collision threshold from the recording's metadata; the message count
    let mut threshold: Option<f64> = None;
    let summary = mcap::Summary::read(&buf).map_err(ReadError::mcap(file))?;
    let total = summary
        .as_ref()
        .and_then(|s| s.stats.as_ref())
        .map(|s| s.message_count);
    if let Some(summary) = summary {
        for idx in &summary.metadata_indexes {
            if idx.name == METADATA_NAME {
                let m = mcap::read::metadata(&buf, idx).map_err(ReadError::mcap(file))?;
                threshold = m
                    .metadata
                    .get("collision_norm_threshold")
                    .and_then(|s| s.parse().ok());
            }
        }
    }

    let (mut ee, mut dist, mut norm) = (Vec::new(), Vec::new(), Vec::new());
    let mut rises = Vec::new();
    // collaboration: end effector and hand x, y, z over time, phase changes,
    // estimated and true contact force
    let mut ee_t: [Vec<(f64, f64)>; 3] = Default::default();
    let mut hand_t: [Vec<(f64, f64)>; 3] = Default::default();
    let mut phase_changes: Vec<(f64, String)> = Vec::new();
    let (mut f_est, mut f_true) = (Vec::new(), Vec::new());
    let mut collaborated = false;
    let mut prev_collision = false;
    // true distance person ↔ arm, newest (infinite: no person)
    let mut person_m = f64::INFINITY;
    let mut t0: Option<u64> = None;
    let t_start = Instant::now();
    let mut next_report = t_start + Duration::from_secs(1);
    let mut n = 0u64;
    let progress = Progress::new(BIN, total, "messages");
    let stream = mcap::MessageStream::new(&buf).map_err(ReadError::mcap(file))?;
    for m in stream {
        let m = m.map_err(ReadError::mcap(file))?;
        n += 1;
        progress.inc(1);
        if !progress.shown() && Instant::now() >= next_report {
            next_report += Duration::from_secs(1);
            eprintln!("phri-plot: {n} messages read");
        }
        let topic = m.channel.topic.as_str();
        if topic != CONTROL_STATUS.name
            && topic != DYNAMICS_RESIDUAL.name
            && topic != SIM_TRUTH.name
            && topic != COLLAB_STATE.name
        {
            continue;
        }
        let v: Value = serde_json::from_slice(&m.data).map_err(|source| ReadError::Json {
            path: file.to_string(),
            topic: topic.to_string(),
            sequence: m.sequence,
            source,
        })?;
        let t0 = *t0.get_or_insert(m.log_time);
        let t = (m.log_time as f64 - t0 as f64) * 1e-9;
        if topic == COLLAB_STATE.name {
            let phase = v.get("phase").and_then(Value::as_str).unwrap_or("idle");
            if phase_changes.last().is_none_or(|(_, p)| p != phase) {
                phase_changes.push((t, phase.to_string()));
            }
            if phase != "idle" {
                collaborated = true;
                if let Some(h) = v.get("hand").and_then(Value::as_array) {
                    for (i, series) in hand_t.iter_mut().enumerate() {
                        if let Some(x) = h.get(i).and_then(Value::as_f64) {
                            series.push((t, x));
                        }
                    }
                }
                let f = v["forces"][0]["force"].as_array().map(|f| {
                    f.iter()
                        .filter_map(Value::as_f64)
                        .map(|x| x * x)
                        .sum::<f64>()
                        .sqrt()
                });
                if let Some(f) = f {
                    f_est.push((t, f));
                }
            }
            continue;
        }
        if topic == SIM_TRUTH.name {
            person_m = num(&v, "min_distance");
            if collaborated {
                let hands = [BodyPart::HandRight as i64, BodyPart::HandLeft as i64];
                let mut sum = [0.0; 3];
                for c in v["contacts"].as_array().into_iter().flatten() {
                    let intended = c["intended"].as_bool().unwrap_or(false);
                    let hand = c["human_part"].as_i64().is_some_and(|p| hands.contains(&p));
                    if intended && hand {
                        for (k, x) in c["force"].as_array().into_iter().flatten().enumerate() {
                            if k < 3 {
                                sum[k] += x.as_f64().unwrap_or(0.0);
                            }
                        }
                    }
                }
                f_true.push((
                    t,
                    (sum[0] * sum[0] + sum[1] * sum[1] + sum[2] * sum[2]).sqrt(),
                ));
            }
        } else if topic == CONTROL_STATUS.name {
            if let Some(p) = v.get("ee").and_then(Value::as_array) {
                for (i, series) in ee_t.iter_mut().enumerate() {
                    if let Some(x) = p.get(i).and_then(Value::as_f64) {
                        series.push((t, x));
                    }
                }
            }
            let d = num(&v, "min_distance");
            if let Some(p) = v.get("ee").and_then(Value::as_array) {
                let c = |i: usize| p.get(i).and_then(Value::as_f64).unwrap_or(f64::NAN);
                ee.push((c(0), c(1), person_m < NEAR_M));
            }
            if d.is_finite() {
                dist.push((t, d));
            }
        } else {
            norm.push((t, num(&v, "norm")));
            let flags = v.get("flags").and_then(Value::as_u64).unwrap_or(0) as u32;
            let c = flags & residual_flags::COLLISION != 0;
            if c && !prev_collision {
                rises.push(t);
            }
            prev_collision = c;
        }
    }
    progress.finish();
    if ee.is_empty() && norm.is_empty() {
        return Err(format!(
            "{file}: no {} or {} messages",
            CONTROL_STATUS.name, DYNAMICS_RESIDUAL.name
        )
        .into());
    }
    std::fs::create_dir_all(&out).map_err(|e| format!("cannot create '{}': {e}", out.display()))?;

    // the same path without the person, if given
    let without: Vec<(f64, f64)> = match cli.without.as_deref() {
        Some(f) => ee_path(f)?,
        None => Vec::new(),
    };

    // (a) end-effector path, equal scale on both axes
    let mut c = Figure::new(W, H);
    let xs = || ee.iter().map(|p| p.0).chain(without.iter().map(|p| p.0));
    let ys = || ee.iter().map(|p| p.1).chain(without.iter().map(|p| p.1));
    if let (Some(xr), Some(yr)) = (range(xs()), range(ys())) {
        let probe = Axes::new(&c, xr, yr);
        let (pw, ph) = (
            (probe.right - probe.left) as f64,
            (probe.bottom - probe.top) as f64,
        );
        let scale = ((xr.1 - xr.0) / pw).max((yr.1 - yr.0) / ph);
        let (cx, cy) = ((xr.0 + xr.1) / 2.0, (yr.0 + yr.1) / 2.0);
        let a = Axes::new(
            &c,
            (cx - scale * pw / 2.0, cx + scale * pw / 2.0),
            (cy - scale * ph / 2.0, cy + scale * ph / 2.0),
        );
        a.draw(&mut c);
        a.label(&mut c, "end-effector path", "x [m]", "y [m]");
        let mut legend = vec![
            (BLUE, "person farther than 0.4 m"),
            (RED, "person within 0.4 m"),
        ];
        if !without.is_empty() {
            legend.push((GREY, "without the person"));
        }
        a.legend(&mut c, &legend);
        a.polyline(&mut c, &without, GREY);
        // contiguous runs of the same presence, each in its colour
        let mut run: Vec<(f64, f64)> = Vec::new();
        let mut near = false;
        for &(x, y, n) in &ee {
            if n != near && !run.is_empty() {
                a.polyline(&mut c, &run, if near { RED } else { BLUE });
                let last = run[run.len() - 1];
                run.clear();
                run.push(last);
            }
            near = n;
            run.push((x, y));
        }
        a.polyline(&mut c, &run, if near { RED } else { BLUE });
    }
    c.save(&out, "ee_trajectory", format)?;

    // (b) residual norm over time
    let mut c = Figure::new(W, H);
    if let (Some(xr), Some(yr)) = (
        range(norm.iter().map(|p| p.0)),
        range(norm.iter().map(|p| p.1).chain(threshold).chain([0.0])),
    ) {
        let a = Axes::new(&c, xr, yr);
        a.draw(&mut c);
        a.label(&mut c, "momentum residual", "t [s]", "‖r‖ [Nm]");
        let mut legend = vec![(BLUE, "‖r‖")];
        if threshold.is_some() {
            legend.push((RED, "threshold"));
        }
        if !rises.is_empty() {
            legend.push((ORANGE, "collision detected"));
        }
        a.legend(&mut c, &legend);
        for &t in &rises {
            a.vline(&mut c, t, ORANGE);
        }
        if let Some(th) = threshold {
            a.hline(&mut c, th, RED);
        }
        a.polyline(&mut c, &norm, BLUE);
    }
    c.save(&out, "residual", format)?;

    // (c) minimum distance over time
    let mut c = Figure::new(W, H);
    if let (Some(xr), Some(yr)) = (
        range(dist.iter().map(|p| p.0)),
        range(dist.iter().map(|p| p.1).chain([0.0])),
    ) {
        let a = Axes::new(&c, xr, yr);
        a.draw(&mut c);
        a.label(
            &mut c,
            "minimum distance, depth space",
            "t [s]",
            "distance [m]",
        );
        a.polyline(&mut c, &dist, BLUE);
    }
    c.save(&out, "min_distance", format)?;

    if collaborated {
        // (d) Figs. 8/11: end effector (solid colours) and hand (darker) x, y, z
        let mut c = Figure::new(W, H);
        let all = || ee_t.iter().chain(hand_t.iter()).flatten();
        if let (Some(xr), Some(yr)) = (range(all().map(|p| p.0)), range(all().map(|p| p.1))) {
            let a = Axes::new(&c, xr, yr);
            a.draw(&mut c);
            a.label(
                &mut c,
                "end effector and collaborative hand",
                "t [s]",
                "position [m]",
            );
            a.legend(
                &mut c,
                &[
                    (BLUE, "end effector x"),
                    (RED, "end effector y"),
                    (ORANGE, "end effector z"),
                    (GREEN, "hand x"),
                    (PURPLE, "hand y"),
                    (BROWN, "hand z"),
                    (GREY, "change of phase"),
                ],
            );
            for (t, _) in &phase_changes[1.min(phase_changes.len())..] {
                a.vline(&mut c, *t, GREY);
            }
            for (series, col) in ee_t.iter().zip([BLUE, RED, ORANGE]) {
                a.polyline(&mut c, series, col);
            }
            // the hand only while collaborating: one line per stretch
            for (series, col) in hand_t.iter().zip([GREEN, PURPLE, BROWN]) {
                for run in series.chunk_by(|p, q| q.0 - p.0 < 0.2) {
                    a.polyline(&mut c, run, col);
                }
            }
        }
        c.save(&out, "collaboration", format)?;
        // (e) estimated against true contact force
        let mut c = Figure::new(W, H);
        let all = || f_est.iter().chain(f_true.iter());
        if let (Some(xr), Some(yr)) = (
            range(all().map(|p| p.0)),
            range(all().map(|p| p.1).chain([0.0])),
        ) {
            let a = Axes::new(&c, xr, yr);
            a.draw(&mut c);
            a.label(
                &mut c,
                "contact force of the collaborative hand",
                "t [s]",
                "force [N]",
            );
            a.legend(
                &mut c,
                &[(RED, "true (simulator)"), (BLUE, "estimated (eqs. 21-22)")],
            );
            a.polyline(&mut c, &f_true, RED);
            for run in f_est.chunk_by(|p, q| q.0 - p.0 < 0.2) {
                a.polyline(&mut c, run, BLUE);
            }
        }
        c.save(&out, "contact_force", format)?;
    }
    eprintln!(
        "phri-plot: {n} messages; {} ee points, {} residuals ({} collision onsets, threshold {}), {} distances -> {}",
        ee.len(),
        norm.len(),
        rises.len(),
        threshold.map_or("none".into(), |t| format!("{t} Nm")),
        dist.len(),
        out.display()
    );
    Ok(())
}

/// The end-effector x-y path of a recording's `control/status`.
fn ee_path(file: &str) -> Result<Vec<(f64, f64)>, Box<dyn Error>> {
    let buf = read_file(file)?;
    let mut out = Vec::new();
    for m in mcap::MessageStream::new(&buf).map_err(ReadError::mcap(file))? {
        let m = m.map_err(ReadError::mcap(file))?;
        if m.channel.topic != CONTROL_STATUS.name {
            continue;
        }
        let v: Value = serde_json::from_slice(&m.data).map_err(|source| ReadError::Json {
            path: file.to_string(),
            topic: CONTROL_STATUS.name.to_string(),
            sequence: m.sequence,
            source,
        })?;
        if let Some(p) = v.get("ee").and_then(Value::as_array) {
            let c = |i: usize| p.get(i).and_then(Value::as_f64).unwrap_or(f64::NAN);
            out.push((c(0), c(1)));
        }
    }
    if out.is_empty() {
        return Err(format!("{file}: no {} messages", CONTROL_STATUS.name).into());
    }
    Ok(out)
}
