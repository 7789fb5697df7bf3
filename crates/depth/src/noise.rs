//! Kinect v1 axial depth noise (Nguyen, Izadi, Lovell 2012; REFERENCE §6) and a
//! fast, seeded source of standard-normal samples for the renderer.

use rand::rngs::SmallRng;
use rand::{RngCore, SeedableRng};

/// Standard deviation \[m\] of the measured depth at depth `z` \[m\]:
/// `σ_z(z) = 0.0012 + 0.0019 (z − 0.4)²` (Nguyen et al. 2012, valid for
/// about 0.5-4.5 m).
#[inline]
pub fn sigma_z(z: f64) -> f64 {
    let e = z - 0.4;
    0.0012 + 0.0019 * e * e
}

/// The normal table has `2^TABLE_BITS` entries; one 64-bit draw gives 5 indices.
const TABLE_BITS: u32 = 12;
const TABLE_SIZE: usize = 1 << TABLE_BITS;
const TABLE_MASK: u64 = (1 << TABLE_BITS) - 1;
const DRAWS_PER_U64: u32 = 64 / TABLE_BITS;

/// Inverse of the standard normal CDF (Acklam's rational approximation,
/// relative error below 1.2e-9) for `p` in (0, 1).
pub(crate) fn inverse_normal_cdf(p: f64) -> f64 {
    const A: [f64; 6] = [
        -3.969_683_028_665_376e1,
        2.209_460_984_245_205e2,
        -2.759_285_104_469_687e2,
        1.383_577_518_672_69e2,
        -3.066_479_806_614_716e1,
        2.506_628_277_459_239,
    ];
    const B: [f64; 5] = [
        -5.447_609_879_822_406e1,
        1.615_858_368_580_409e2,
        -1.556_989_798_598_866e2,
        6.680_131_188_771_972e1,
        -1.328_068_155_288_572e1,
    ];
    const C: [f64; 6] = [
        -7.784_894_002_430_293e-3,
        -3.223_964_580_411_365e-1,
        -2.400_758_277_161_838,
        -2.549_732_539_343_734,
        4.374_664_141_464_968,
        2.938_163_982_698_783,
    ];
    const D: [f64; 4] = [
        7.784_695_709_041_462e-3,
        3.224_671_290_700_398e-1,
        2.445_134_137_142_996,
        3.754_408_661_907_416,
    ];
    const P_LOW: f64 = 0.02425;
    let tail = |q: f64| {
        (((((C[0] * q + C[1]) * q + C[2]) * q + C[3]) * q + C[4]) * q + C[5])
            / ((((D[0] * q + D[1]) * q + D[2]) * q + D[3]) * q + 1.0)
    };
    if p < P_LOW {
        tail((-2.0 * p.ln()).sqrt())
    } else if p > 1.0 - P_LOW {
        -tail((-2.0 * (1.0 - p).ln()).sqrt())
    } else {
        let q = p - 0.5;
        let r = q * q;
        (((((A[0] * r + A[1]) * r + A[2]) * r + A[3]) * r + A[4]) * r + A[5]) * q
            / (((((B[0] * r + B[1]) * r + B[2]) * r + B[3]) * r + B[4]) * r + 1.0)
    }
}

/// Seeded generator of standard-normal samples for per-pixel noise: a table of
/// the 4096 quantiles `Φ⁻¹((i + ½)/4096)` of N(0, 1) (small enough to stay in
/// the L1 cache; tails truncated at ±3.5σ), indexed by 12-bit slices of a fast
/// PRNG. Deterministic for a seed; five samples per 64-bit draw; no allocation
/// after construction.
#[derive(Debug, Clone)]
pub(crate) struct NormalSource {
    table: Vec<f32>,
    rng: SmallRng,
    bits: u64,
    left: u32,
}

impl NormalSource {
    pub fn new(seed: u64) -> Self {
        let table = (0..TABLE_SIZE)
            .map(|i| inverse_normal_cdf((i as f64 + 0.5) / TABLE_SIZE as f64) as f32)
            .collect();
        Self {
            table,
            rng: SmallRng::seed_from_u64(seed),
            bits: 0,
            left: 0,
        }
    }

    /// Restarts the sequence from `seed`.
    pub fn reseed(&mut self, seed: u64) {
        self.rng = SmallRng::seed_from_u64(seed);
        self.left = 0;
    }

    /// `TABLE_BITS` fresh random bits.
    #[inline(always)]
    fn next_index(&mut self) -> usize {
        if self.left == 0 {
            self.bits = self.rng.next_u64();
            self.left = DRAWS_PER_U64;
        }
        let i = (self.bits & TABLE_MASK) as usize;
        self.bits >>= TABLE_BITS;
        self.left -= 1;
        i
    }

    /// One standard-normal sample.
    #[inline(always)]
    pub fn normal(&mut self) -> f64 {
        let i = self.next_index();
        f64::from(self.table[i & (TABLE_SIZE - 1)])
    }

    /// `true` with probability `p`, rounded to a multiple of 1/4096.
    #[inline(always)]
    pub fn bernoulli(&mut self, p: f64) -> bool {
        (self.next_index() as f64) < p * TABLE_SIZE as f64
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn table_is_standard_normal() {
        let mut n = NormalSource::new(1);
        let count = 200_000;
        let (mut s, mut s2) = (0.0, 0.0);
        for _ in 0..count {
            let x = n.normal();
            s += x;
            s2 += x * x;
        }
        let mean = s / count as f64;
        let var = s2 / count as f64 - mean * mean;
        assert!(mean.abs() < 0.02, "mean {mean}");
        assert!((var - 1.0).abs() < 0.03, "variance {var}");
    }

    #[test]
    fn same_seed_same_sequence() {
        let mut a = NormalSource::new(7);
        let mut b = NormalSource::new(7);
        for _ in 0..100 {
            assert_eq!(a.normal(), b.normal());
        }
        b.reseed(8);
        let differs = (0..100).any(|_| a.normal() != b.normal());
        assert!(differs);
    }

    #[test]
    fn inverse_cdf_matches_known_quantiles() {
        assert!(inverse_normal_cdf(0.5).abs() < 1e-12);
        assert!((inverse_normal_cdf(0.975) - 1.959_963_984_540_054).abs() < 1e-8);
        assert!((inverse_normal_cdf(0.001) + 3.090_232_306_167_813_5).abs() < 1e-8);
    }

    #[test]
    fn bernoulli_rate() {
        let mut n = NormalSource::new(3);
        let hits = (0..100_000).filter(|_| n.bernoulli(0.25)).count();
        assert!((hits as f64 / 1e5 - 0.25).abs() < 0.01, "{hits}");
    }

    #[test]
    fn sigma_matches_nguyen() {
        assert!((sigma_z(0.4) - 0.0012).abs() < 1e-15);
        assert!((sigma_z(2.4) - (0.0012 + 0.0019 * 4.0)).abs() < 1e-15);
    }
}
