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

/// The normal table has `2^TABLE_BITS` entries.
const TABLE_BITS: u32 = 12;
pub(crate) const TABLE_SIZE: usize = 1 << TABLE_BITS;
const TABLE_MASK: u64 = (1 << TABLE_BITS) - 1;

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

/// Seeded source of standard-normal samples for per-pixel noise: a table of
/// the 4096 quantiles `Φ⁻¹((i + ½)/4096)` of N(0, 1) (small enough to stay in
/// the L1 cache; tails truncated at ±3.67σ), indexed by [`pixel_bits`] of a
/// key per frame from a fast PRNG. Deterministic for a seed; no allocation
/// after construction.
#[derive(Debug, Clone)]
pub(crate) struct NormalSource {
    table: Box<[f32; TABLE_SIZE]>,
    rng: SmallRng,
}

impl NormalSource {
    pub fn new(seed: u64) -> Self {
        let mut table = Box::new([0.0f32; TABLE_SIZE]);
        for (i, t) in table.iter_mut().enumerate() {
            *t = inverse_normal_cdf((i as f64 + 0.5) / TABLE_SIZE as f64) as f32;
        }
        Self {
            table,
            rng: SmallRng::seed_from_u64(seed),
        }
    }

    /// Restarts the sequence from `seed`.
    pub fn reseed(&mut self, seed: u64) {
        self.rng = SmallRng::seed_from_u64(seed);
    }

    /// A fresh key for one frame's [`pixel_bits`].
    pub fn frame_key(&mut self) -> u32 {
        self.rng.next_u32()
    }

    /// The quantiles: `table()[i]` is `Φ⁻¹((i + ½)/4096)`.
    pub fn table(&self) -> &[f32; TABLE_SIZE] {
        &self.table
    }
}

/// Random bits of pixel `index` of the frame whose key is `key`: a
/// bijective 32-bit mix (MurmurHash3's finaliser), so that every pixel draws
/// its own noise independently of the others (in vector lanes, unlike a
/// sequential generator). The low [`TABLE_BITS`] index the normal table
/// ([`NormalSource::table`]), the next [`TABLE_BITS`] a drop-out.
#[inline(always)]
pub(crate) fn pixel_bits(key: u32, index: u32) -> u32 {
    let mut x = index ^ key;
    x ^= x >> 16;
    x = x.wrapping_mul(0x85eb_ca6b);
    x ^= x >> 13;
    x = x.wrapping_mul(0xc2b2_ae35);
    x ^ (x >> 16)
}

/// The table index in [`pixel_bits`]' bits.
#[inline(always)]
pub(crate) fn normal_index(bits: u32) -> usize {
    (bits & TABLE_MASK as u32) as usize
}

/// Whether [`pixel_bits`]' bits draw an event of probability `p` (rounded
/// to a multiple of 1/4096).
#[inline(always)]
pub(crate) fn draws(bits: u32, p: f64) -> bool {
    f64::from((bits >> TABLE_BITS) & TABLE_MASK as u32) < p * TABLE_SIZE as f64
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn table_is_standard_normal() {
        let n = NormalSource::new(1);
        let c = TABLE_SIZE as f64;
        let s: f64 = n.table().iter().map(|&x| f64::from(x)).sum();
        let s2: f64 = n.table().iter().map(|&x| f64::from(x).powi(2)).sum();
        let (mean, var) = (s / c, s2 / c - (s / c).powi(2));
        assert!(mean.abs() < 1e-6, "mean {mean}");
        assert!((var - 1.0).abs() < 0.01, "variance {var}");
        // truncated at the outermost quantiles, ±3.67σ
        let most = n.table().iter().fold(0.0f32, |m, x| m.max(x.abs()));
        assert!((3.6..3.7).contains(&most), "{most}");
    }

    #[test]
    fn pixel_bits_draw_standard_normals_and_events_independently() {
        let n = NormalSource::new(3);
        let (key_a, key_b) = (0x1234_5678, 0x9abc_def0);
        let count = 307_200u32;
        let (mut s, mut s2, mut cross, mut events, mut same) = (0.0, 0.0, 0.0, 0u32, 0u32);
        for i in 0..count {
            let a = pixel_bits(key_a, i);
            let b = pixel_bits(key_b, i);
            let x = f64::from(n.table()[normal_index(a)]);
            let y = f64::from(n.table()[normal_index(b)]);
            let next = f64::from(n.table()[normal_index(pixel_bits(key_a, i + 1))]);
            s += x;
            s2 += x * x;
            cross += x * next + x * y;
            events += u32::from(draws(a, 0.5));
            same += u32::from(normal_index(a) == normal_index(b));
        }
        let c = f64::from(count);
        assert!((s / c).abs() < 0.01, "mean {}", s / c);
        assert!((s2 / c - 1.0).abs() < 0.02, "variance {}", s2 / c);
        // neighbours and the frames' keys uncorrelated
        assert!((cross / c).abs() < 0.02, "correlation {}", cross / c);
        assert!((f64::from(events) / c - 0.5).abs() < 0.005);
        assert!(f64::from(same) / c < 2.0 / 4096.0);
    }

    #[test]
    fn same_seed_same_sequence() {
        let mut a = NormalSource::new(7);
        let mut b = NormalSource::new(7);
        for _ in 0..100 {
            assert_eq!(a.frame_key(), b.frame_key());
        }
        b.reseed(8);
        let differs = (0..100).any(|_| a.frame_key() != b.frame_key());
        assert!(differs);
    }

    #[test]
    fn inverse_cdf_matches_known_quantiles() {
        assert!(inverse_normal_cdf(0.5).abs() < 1e-12);
        assert!((inverse_normal_cdf(0.975) - 1.959_963_984_540_054).abs() < 1e-8);
        assert!((inverse_normal_cdf(0.001) + 3.090_232_306_167_813_5).abs() < 1e-8);
    }

    #[test]
    fn draw_rate() {
        let hits = (0..100_000u32)
            .filter(|&i| draws(pixel_bits(0x5eed, i), 0.25))
            .count();
        assert!((hits as f64 / 1e5 - 0.25).abs() < 0.01, "{hits}");
        assert!(!(0..10_000u32).any(|i| draws(pixel_bits(1, i), 0.0)));
        assert!((0..10_000u32).all(|i| draws(pixel_bits(1, i), 1.0)));
    }

    #[test]
    fn sigma_matches_nguyen() {
        assert!((sigma_z(0.4) - 0.0012).abs() < 1e-15);
        assert!((sigma_z(2.4) - (0.0012 + 0.0019 * 4.0)).abs() < 1e-15);
    }
}
