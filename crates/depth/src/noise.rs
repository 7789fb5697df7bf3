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

/// Number of entries of the normal table (a power of two).
const TABLE_BITS: u32 = 16;
const TABLE_SIZE: usize = 1 << TABLE_BITS;

/// Seeded generator of standard-normal samples: a table of 65 536 Box-Muller
/// samples drawn once, indexed by 16-bit slices of a fast PRNG. Deterministic
/// for a seed; four samples per 64-bit draw, no allocation after construction.
#[derive(Debug, Clone)]
pub(crate) struct NormalSource {
    table: Vec<f32>,
    rng: SmallRng,
    bits: u64,
    left: u32,
}

impl NormalSource {
    pub fn new(seed: u64) -> Self {
        // the table depends on a fixed seed only: reseeding changes the sequence
        let mut table_rng = SmallRng::seed_from_u64(0x5eed_7ab1e_u64);
        let mut table = Vec::with_capacity(TABLE_SIZE);
        while table.len() < TABLE_SIZE {
            // u1 in (0, 1], u2 in [0, 1)
            let u1 = ((table_rng.next_u64() >> 11) as f64 + 1.0) / (1u64 << 53) as f64;
            let u2 = (table_rng.next_u64() >> 11) as f64 / (1u64 << 53) as f64;
            let r = (-2.0 * u1.ln()).sqrt();
            let phi = std::f64::consts::TAU * u2;
            table.push((r * phi.cos()) as f32);
            table.push((r * phi.sin()) as f32);
        }
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

    /// 16 fresh random bits.
    #[inline(always)]
    fn next_16(&mut self) -> usize {
        if self.left == 0 {
            self.bits = self.rng.next_u64();
            self.left = 4;
        }
        let i = (self.bits & 0xffff) as usize;
        self.bits >>= TABLE_BITS;
        self.left -= 1;
        i
    }

    /// One standard-normal sample.
    #[inline(always)]
    pub fn normal(&mut self) -> f64 {
        let i = self.next_16();
        f64::from(self.table[i & (TABLE_SIZE - 1)])
    }

    /// `true` with probability `p` (resolution 2⁻¹⁶).
    #[inline(always)]
    pub fn bernoulli(&mut self, p: f64) -> bool {
        (self.next_16() as f64) < p * TABLE_SIZE as f64
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
    fn sigma_matches_nguyen() {
        assert!((sigma_z(0.4) - 0.0012).abs() < 1e-15);
        assert!((sigma_z(2.4) - (0.0012 + 0.0019 * 4.0)).abs() < 1e-15);
    }
}
