//! Solve times of phri-qp for a 7-joint safety filter: 16 and 32 rows, cold
//! and warm-started over a slowly changing sequence (1 ms periods, the
//! weight, nominal velocity and rows drifting at 0.5 Hz).
//!
//! `cargo run --release -p phri-qp --example qp-bench [-- STEPS]` (default
//! 20 000 periods per case). Prints p50 / p99 / p99.9 / max solve time
//! [µs] and the iterations (rows added or dropped) per solve. The maximum
//! is the scheduler's as much as the solver's unless the process runs at
//! real-time priority (`chrt -f 50 …`, REFERENCE §8).

#[path = "../tests/common/mod.rs"]
mod common;

use common::sequence::Sequence;
use phri_qp::{solve, Settings, Start, Workspace};
use rand::rngs::SmallRng;
use rand::SeedableRng;
use std::time::Instant;

const N: usize = 7;

fn percentile(sorted: &[f64], p: f64) -> f64 {
    let k = ((sorted.len() - 1) as f64 * p).round() as usize;
    sorted[k]
}

fn main() {
    let steps: usize = match std::env::args().nth(1).map(|s| s.parse()) {
        None => 20_000,
        Some(Ok(v)) if v > 0 => v,
        Some(_) => {
            eprintln!("usage: bench [STEPS]");
            std::process::exit(2);
        }
    };
    println!("phri-qp, n = {N}, {steps} periods per case, times in µs");
    println!(
        "{:>4} {:>5} {:>7} {:>7} {:>7} {:>8} {:>9} {:>8} {:>11}",
        "rows", "start", "p50", "p99", "p99.9", "max", "iter mean", "iter max", "active mean"
    );
    let mut rng = SmallRng::seed_from_u64(44);
    for m in [16, 32] {
        let seq = Sequence::new(&mut rng, N, m);
        for start in [Start::Cold, Start::Warm] {
            let mut ws = Workspace::new(N, m, Settings::default()).expect("workspace");
            let mut times = Vec::with_capacity(steps);
            let (mut it_sum, mut it_max, mut active) = (0usize, 0usize, 0usize);
            for k in 0..steps {
                let qp = seq.at(k);
                let p = qp.problem();
                let t0 = Instant::now();
                let sol = solve(&mut ws, &p, start);
                let dt = t0.elapsed().as_secs_f64() * 1e6;
                let sol = match sol {
                    Ok(s) => s,
                    Err(e) => {
                        eprintln!("period {k}: {e}");
                        std::process::exit(1);
                    }
                };
                times.push(dt);
                it_sum += sol.iterations;
                it_max = it_max.max(sol.iterations);
                active += sol.active.len();
            }
            times.sort_by(f64::total_cmp);
            println!(
                "{m:>4} {:>5} {:>7.2} {:>7.2} {:>7.2} {:>8.2} {:>9.2} {:>8} {:>11.2}",
                if start == Start::Cold { "cold" } else { "warm" },
                percentile(&times, 0.5),
                percentile(&times, 0.99),
                percentile(&times, 0.999),
                times[times.len() - 1],
                it_sum as f64 / steps as f64,
                it_max,
                active as f64 / steps as f64,
            );
        }
    }
}
