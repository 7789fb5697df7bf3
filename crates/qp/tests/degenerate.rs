//! Degenerate and badly scaled rows: many rows through one vertex,
//! duplicated and rescaled rows, row norms over six decades. KKT checked
//! directly; a warm start from each answer's own active set agrees.

mod common;

use common::{kkt, random_feasible};
use phri_qp::{solve, Settings, Start, Workspace};
use rand::rngs::SmallRng;
use rand::{Rng, SeedableRng};

const N: usize = 7;
const M: usize = 24;

#[test]
fn degenerate_rows() {
    let mut rng = SmallRng::seed_from_u64(5);
    let mut cold = Workspace::new(N, 2 * M, Settings::default()).expect("workspace");
    let mut warm = Workspace::new(N, 2 * M, Settings::default()).expect("workspace");
    for case in 0..3000 {
        let mut qp = random_feasible(&mut rng, N, M);
        match case % 3 {
            0 => {
                // every row through one point: a vertex with 24 tight rows
                let xf: Vec<f64> = (0..N).map(|_| rng.gen_range(-1.0..1.0)).collect();
                for i in 0..M {
                    qp.d[i] = (0..N).map(|k| qp.c[i * N + k] * xf[k]).sum();
                }
            }
            1 => {
                // every row twice, the copy rescaled
                let (c0, d0) = (qp.c.clone(), qp.d.clone());
                for i in 0..M {
                    let s = rng.gen_range(0.5..2.0);
                    qp.c.extend(c0[i * N..(i + 1) * N].iter().map(|v| v * s));
                    qp.d.push(d0[i] * s);
                }
            }
            _ => {
                for i in 0..M {
                    let s = 10f64.powf(rng.gen_range(-3.0..3.0));
                    qp.c[i * N..(i + 1) * N].iter_mut().for_each(|v| *v *= s);
                    qp.d[i] *= s;
                }
            }
        }
        let sol = solve(&mut cold, &qp.problem(), Start::Cold)
            .unwrap_or_else(|e| panic!("case {case}: {e}"));
        let (p, d, c, s) = kkt(&qp, sol.x, sol.lambda);
        let scale = 1.0 + qp.g.iter().fold(0.0f64, |a, v| a.max(v.abs()));
        assert!(
            p <= 1e-8 && d <= 0.0,
            "case {case}: primal {p:e} dual {d:e}"
        );
        assert!(
            c <= 1e-8 * scale && s <= 1e-8 * scale,
            "case {case}: comp {c:e} stat {s:e}"
        );
        let x = sol.x.to_vec();
        warm.set_hint(sol.active);
        let again = solve(&mut warm, &qp.problem(), Start::Warm).expect("warm");
        let dx = x
            .iter()
            .zip(again.x)
            .fold(0.0f64, |a, (u, v)| a.max((u - v).abs()));
        assert!(dx < 1e-9, "case {case}: warm differs by {dx:e}");
    }
}
