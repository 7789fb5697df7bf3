//! Warm starts: the same answer as a cold start, in fewer iterations on a
//! slowly changing sequence; a wrong hint is harmless.

mod common;

use common::sequence::Sequence;
use common::{kkt, random_feasible};
use phri_qp::{solve, Settings, Start, Workspace};
use rand::rngs::SmallRng;
use rand::SeedableRng;

#[test]
fn warm_equals_cold_in_fewer_iterations() {
    let mut rng = SmallRng::seed_from_u64(1000);
    for m in [16, 32] {
        let seq = Sequence::new(&mut rng, 7, m);
        let mut cold = Workspace::new(7, m, Settings::default()).expect("workspace");
        let mut warm = Workspace::new(7, m, Settings::default()).expect("workspace");
        let (mut it_cold, mut it_warm, mut active) = (0, 0, 0);
        for k in 0..3000 {
            let qp = seq.at(k);
            let a = solve(&mut cold, &qp.problem(), Start::Cold).expect("cold");
            it_cold += a.iterations;
            active += a.active.len();
            let x_cold = a.x.to_vec();
            let b = solve(&mut warm, &qp.problem(), Start::Warm).expect("warm");
            it_warm += b.iterations;
            let dx = x_cold
                .iter()
                .zip(b.x)
                .fold(0.0f64, |a, (u, v)| a.max((u - v).abs()));
            assert!(
                dx < 1e-9,
                "m {m} period {k}: warm and cold differ by {dx:e}"
            );
            let (p, d, _, s) = kkt(&qp, b.x, b.lambda);
            assert!(
                p < 1e-8 && d <= 0.0 && s < 1e-8,
                "m {m} period {k}: KKT {p:e} {d:e} {s:e}"
            );
        }
        eprintln!(
            "m {m}: cold {it_cold} iterations, warm {it_warm}, mean active {}",
            active as f64 / 3000.0
        );
        assert!(
            active > 3000,
            "the sequence should keep rows active (mean {})",
            active as f64 / 3000.0
        );
        assert!(
            2 * it_warm < it_cold,
            "m {m}: warm {it_warm} vs cold {it_cold} iterations"
        );
    }
}

#[test]
fn a_wrong_hint_still_gives_the_optimum() {
    let mut rng = SmallRng::seed_from_u64(2000);
    let mut ws = Workspace::new(7, 32, Settings::default()).expect("workspace");
    let mut reference = Workspace::new(7, 32, Settings::default()).expect("workspace");
    for case in 0..1000 {
        let qp = random_feasible(&mut rng, 7, 32);
        // hints from another problem, out-of-range rows and repeats
        let hint: Vec<usize> = (0..7).map(|i| (case * 7 + i * 5) % 40).collect();
        ws.set_hint(&hint);
        let x_ref = solve(&mut reference, &qp.problem(), Start::Cold)
            .expect("cold")
            .x
            .to_vec();
        let sol = solve(&mut ws, &qp.problem(), Start::Warm).expect("warm");
        let dx = x_ref
            .iter()
            .zip(sol.x)
            .fold(0.0f64, |a, (u, v)| a.max((u - v).abs()));
        assert!(dx < 1e-8, "case {case}: {dx:e}");
    }
}

#[test]
fn hint_is_the_last_active_set() {
    let mut rng = SmallRng::seed_from_u64(3000);
    let mut ws = Workspace::new(7, 16, Settings::default()).expect("workspace");
    let qp = random_feasible(&mut rng, 7, 16);
    let active = solve(&mut ws, &qp.problem(), Start::Cold)
        .expect("solve")
        .active
        .to_vec();
    assert_eq!(ws.hint(), active.as_slice());
    let again = solve(&mut ws, &qp.problem(), Start::Warm).expect("solve");
    assert_eq!(
        again.iterations, 0,
        "the same problem warm-started needs no search"
    );
    assert_eq!(again.warm_rows, active.len());
    ws.clear_hint();
    assert!(ws.hint().is_empty());
}
