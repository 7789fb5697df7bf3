//! A slowly changing sequence of problems, as a 1 kHz safety filter sees:
//! the weight, the nominal velocity and the rows drift a little each period.

use super::{random_spd, uniform, Qp};
use rand::rngs::SmallRng;
use rand::Rng;

/// The sequence's fixed parts; `at(k)` is period k's problem (1 ms apart).
pub struct Sequence {
    pub n: usize,
    h0: Vec<f64>,
    h1: Vec<f64>,
    c0: Vec<f64>,
    c1: Vec<f64>,
    d0: Vec<f64>,
    phase: Vec<f64>,
    amp: Vec<f64>,
}

impl Sequence {
    pub fn new(rng: &mut SmallRng, n: usize, m: usize) -> Self {
        Self {
            n,
            h0: random_spd(rng, n),
            h1: random_spd(rng, n),
            c0: uniform(rng, m * n, 1.0),
            c1: uniform(rng, m * n, 1.0),
            // x = 0 (standing still) always satisfies the rows
            d0: (0..m).map(|_| rng.gen_range(0.05..0.5)).collect(),
            phase: uniform(rng, n + m, 3.0),
            amp: (0..n).map(|_| rng.gen_range(0.5..2.0)).collect(),
        }
    }

    pub fn at(&self, k: usize) -> Qp {
        let n = self.n;
        let m = self.d0.len();
        let t = k as f64 * 1e-3;
        let w = 2.0 * std::f64::consts::PI * 0.5; // 0.5 Hz drift
        let s = 0.5 + 0.5 * (w * t).sin();
        let h: Vec<f64> = self
            .h0
            .iter()
            .zip(&self.h1)
            .map(|(a, b)| a + 0.3 * s * b)
            .collect();
        let xnom: Vec<f64> = (0..n)
            .map(|i| self.amp[i] * (w * t + self.phase[i]).sin())
            .collect();
        let g = (0..n)
            .map(|i| -(0..n).map(|j| h[i * n + j] * xnom[j]).sum::<f64>())
            .collect();
        let c = self
            .c0
            .iter()
            .zip(&self.c1)
            .enumerate()
            .map(|(idx, (a, b))| a + 0.2 * (w * t + self.phase[n + idx / n]).sin() * b)
            .collect();
        let d = (0..m)
            .map(|i| self.d0[i] * (1.0 + 0.5 * (w * t + self.phase[n + i]).cos()))
            .collect();
        Qp {
            n,
            h,
            g,
            c,
            d,
            bounds: None,
        }
    }
}
