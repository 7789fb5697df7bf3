//! `phri-model bench`: median nanoseconds per call of each algorithm.

use std::hint::black_box;
use std::time::Instant;

use std::path::PathBuf;

use phri_model::{Data, Model};
use rand::{Rng, SeedableRng};
use serde_json::json;

use crate::inspect::load;

/// `phri-model bench`'s arguments.
#[derive(clap::Args, Debug)]
pub(crate) struct BenchArgs {
    /// Robot description (URDF)
    #[arg(value_name = "ROBOT.urdf")]
    urdf: PathBuf,
    /// Timed batches, each on a new random state (at most 100000)
    #[arg(long, value_name = "N", default_value_t = 500, value_parser = parse_samples)]
    samples: usize,
}

/// A positive sample count of at most [`MAX_SAMPLES`].
fn parse_samples(s: &str) -> Result<usize, String> {
    match s.parse::<usize>() {
        Ok(n) if n > MAX_SAMPLES => Err(format!("{n} is more than {MAX_SAMPLES}")),
        Ok(n) if n > 0 => Ok(n),
        _ => Err(format!("'{s}' is not a positive integer")),
    }
}

/// Calls per timed batch; the median is taken over batches, each on a new random state.
const CALLS_PER_BATCH: usize = 200;
/// Most `--samples` accepted: the random states are kept in memory (two
/// vectors per sample) and each sample costs 8 × [`CALLS_PER_BATCH`] calls, so
/// 100 000 samples already take minutes.
pub(crate) const MAX_SAMPLES: usize = 100_000;

fn random_state(model: &Model, rng: &mut impl Rng) -> (Vec<f64>, Vec<f64>) {
    let q = model
        .actuated()
        .iter()
        .map(|j| {
            let (lo, hi) = if j.lower.is_finite() && j.upper.is_finite() && j.upper > j.lower {
                (j.lower, j.upper)
            } else {
                (-3.0, 3.0)
            };
            rng.gen_range(lo..=hi)
        })
        .collect();
    let qd = (0..model.nv()).map(|_| rng.gen_range(-2.0..2.0)).collect();
    (q, qd)
}

fn median_ns(
    samples: usize,
    model: &Model,
    data: &mut Data,
    seed: u64,
    mut f: impl FnMut(&Model, &mut Data, &[f64], &[f64]),
) -> f64 {
    let mut rng = rand::rngs::SmallRng::seed_from_u64(seed);
    let states: Vec<(Vec<f64>, Vec<f64>)> = (0..samples)
        .map(|_| random_state(model, &mut rng))
        .collect();
    // warm-up
    for (q, qd) in states.iter().take(50) {
        for _ in 0..CALLS_PER_BATCH {
            f(model, data, black_box(q), black_box(qd));
        }
    }
    let mut per_call: Vec<f64> = states
        .iter()
        .map(|(q, qd)| {
            let t = Instant::now();
            for _ in 0..CALLS_PER_BATCH {
                f(model, data, black_box(q), black_box(qd));
            }
            t.elapsed().as_nanos() as f64 / CALLS_PER_BATCH as f64
        })
        .collect();
    per_call.sort_by(f64::total_cmp);
    per_call[per_call.len() / 2]
}

pub(crate) fn run(args: &BenchArgs) -> Result<String, String> {
    let samples = args.samples;
    let model = load(&args.urdf)?;
    let mut data = Data::new(&model);
    let mut jac = Data::jacobian_buffer(&model);
    let last = model.frames.len() - 1;
    let n = model.nv();
    let zero = vec![0.0; n];
    // every call below has checked lengths, so the results are discarded with black_box
    let fk = median_ns(samples, &model, &mut data, 1, |m, d, q, _| {
        black_box(phri_model::forward_kinematics(m, d, q).is_ok());
    });
    let jacobian = median_ns(samples, &model, &mut data, 2, |m, d, q, _| {
        black_box(phri_model::forward_kinematics(m, d, q).is_ok());
        black_box(
            phri_model::point_jacobian(
                m,
                d,
                last,
                &nalgebra::Vector3::new(0.0, 0.0, 0.05),
                &mut jac,
            )
            .is_ok(),
        );
    });
    let crba = median_ns(samples, &model, &mut data, 3, |m, d, q, _| {
        black_box(phri_model::crba(m, d, q).is_ok());
    });
    let rnea = median_ns(samples, &model, &mut data, 4, |m, d, q, qd| {
        black_box(phri_model::rnea(m, d, q, qd, qd).is_ok());
    });
    let gravity = median_ns(samples, &model, &mut data, 5, |m, d, q, _| {
        black_box(phri_model::gravity(m, d, q).is_ok());
    });
    let coriolis = median_ns(samples, &model, &mut data, 6, |m, d, q, qd| {
        black_box(phri_model::coriolis_matrix(m, d, q, qd).is_ok());
    });
    let residual = median_ns(samples, &model, &mut data, 7, |m, d, q, qd| {
        black_box(phri_model::residual_terms(m, d, q, qd).is_ok());
    });
    let fd = median_ns(samples, &model, &mut data, 8, |m, d, q, qd| {
        black_box(phri_model::forward_dynamics(m, d, q, qd, &zero).is_ok());
    });
    // what the controller computed per period before the one pass: CRBA,
    // gravity, RNEA and the end effector's kinematics, each from scratch
    let separate = median_ns(samples, &model, &mut data, 9, |m, d, q, qd| {
        black_box(phri_model::crba(m, d, q).is_ok());
        black_box(phri_model::gravity(m, d, q).is_ok());
        black_box(phri_model::rnea(m, d, q, qd, &zero).is_ok());
        black_box(phri_model::forward_kinematics(m, d, q).is_ok());
        black_box(phri_model::frame_placement(m, d, last));
    });
    let all = median_ns(samples, &model, &mut data, 9, |m, d, q, qd| {
        black_box(phri_model::all_terms(m, d, q, qd).is_ok());
        black_box(phri_model::frame_placement(m, d, last));
    });
    let out = json!({
        "robot": model.name,
        "dof": n,
        "samples": samples,
        "calls_per_sample": CALLS_PER_BATCH,
        "fk_ns": fk,
        "jacobian_ns": jacobian,
        "crba_ns": crba,
        "rnea_ns": rnea,
        "gravity_ns": gravity,
        "coriolis_ns": coriolis,
        "residual_terms_ns": residual,
        "forward_dynamics_ns": fd,
        "terms_separately_ns": separate,
        "all_terms_ns": all,
    });
    Ok(out.to_string())
}
