//! Non-speech probes, deterministic from a seed: bursts of noise with a
//! varying envelope, the sounds a cell makes that an energy detector takes
//! for speech (a rattle, a dropped tool, a blast of air). Issue 26's probe
//! and the test that keeps noise from becoming a command use these.
//!
//! A burst is [`BURST_S`] of
//! - white noise, or
//! - a clatter: impulses at random times (20-80 per second), each a click
//!   and a damped resonance (1-6 kHz, 2-12 ms),
//!
//! shaped by a random attack (5-150 ms) and decay (50-400 ms) and a
//! gain that takes a random walk in 10 ms steps (σ 3 dB a step, between
//! −20 and 0 dB: the syllable-like ups and downs that made 22 of 30 such
//! bursts `stop` before issue 26), scaled so its RMS over the burst is the
//! level asked for \[dBFS\].

use std::f64::consts::PI;

use phri_ipc::AUDIO_RATE_HZ;

/// A burst's length \[s\].
pub const BURST_S: f64 = 0.6;

/// What a burst is made of.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum BurstKind {
    /// white noise
    White,
    /// impulses at random times, each a click and a damped resonance
    Clatter,
}

impl BurstKind {
    /// The kind's name: `white` or `clatter`.
    pub fn name(self) -> &'static str {
        match self {
            BurstKind::White => "white",
            BurstKind::Clatter => "clatter",
        }
    }
}

/// The kind of the `k`-th burst of a set: one in four is a clatter.
pub fn kind_of(k: usize) -> BurstKind {
    if k % 4 == 3 {
        BurstKind::Clatter
    } else {
        BurstKind::White
    }
}

/// A small deterministic generator (SplitMix64): the same seed, the same bursts.
#[derive(Clone, Debug)]
pub struct Rng(u64);

impl Rng {
    /// A generator seeded with `seed`.
    pub fn new(seed: u64) -> Rng {
        Rng(seed)
    }

    /// The next value, uniform over all of `u64`.
    pub fn next_u64(&mut self) -> u64 {
        self.0 = self.0.wrapping_add(0x9E37_79B9_7F4A_7C15);
        let mut z = self.0;
        z = (z ^ (z >> 30)).wrapping_mul(0xBF58_476D_1CE4_E5B9);
        z = (z ^ (z >> 27)).wrapping_mul(0x94D0_49BB_1331_11EB);
        z ^ (z >> 31)
    }

    /// Uniform in [0, 1).
    pub fn uniform(&mut self) -> f64 {
        (self.next_u64() >> 11) as f64 / (1u64 << 53) as f64
    }

    /// Uniform in [lo, hi).
    pub fn range(&mut self, lo: f64, hi: f64) -> f64 {
        lo + (hi - lo) * self.uniform()
    }

    /// Standard normal (Box-Muller).
    pub fn normal(&mut self) -> f64 {
        let u = self.uniform().max(1e-300);
        let v = self.uniform();
        (-2.0 * u.ln()).sqrt() * (2.0 * PI * v).cos()
    }
}

/// One burst of `kind`, [`BURST_S`] long, its RMS `level_dbfs`, from `seed`.
pub fn burst(kind: BurstKind, seed: u64, level_dbfs: f64) -> Vec<i16> {
    let rate = AUDIO_RATE_HZ as f64;
    let n = (BURST_S * rate) as usize;
    let mut rng = Rng::new(seed);
    let mut x = vec![0.0f64; n];
    match kind {
        BurstKind::White => x.iter_mut().for_each(|s| *s = rng.normal()),
        BurstKind::Clatter => {
            let per_s = rng.range(20.0, 80.0);
            let mut t = 0.0;
            loop {
                // exponential gaps: a Poisson train, no period to find
                t += -rng.uniform().max(1e-12).ln() / per_s;
                let i0 = (t * rate) as usize;
                if i0 >= n {
                    break;
                }
                let amp = rng.range(0.3, 1.0);
                let f = rng.range(1000.0, 6000.0);
                let tau = rng.range(0.002, 0.012) * rate;
                let phase = rng.range(0.0, 2.0 * PI);
                x[i0] += amp * 3.0 * if rng.uniform() < 0.5 { -1.0 } else { 1.0 };
                let len = ((6.0 * tau) as usize).min(n - i0);
                for (j, s) in x[i0..i0 + len].iter_mut().enumerate() {
                    let j = j as f64;
                    *s += amp * (-j / tau).exp() * (2.0 * PI * f * j / rate + phase).sin();
                }
            }
        }
    }
    let attack = rng.range(0.005, 0.15) * rate;
    let decay = rng.range(0.05, 0.4) * rate;
    let step = AUDIO_RATE_HZ as usize / 100;
    let mut gain_db = 0.0f64;
    for (i, s) in x.iter_mut().enumerate() {
        if i % step == 0 {
            gain_db = (gain_db + 3.0 * rng.normal()).clamp(-20.0, 0.0);
        }
        let t = i as f64;
        let rise = (t / attack).min(1.0);
        let fall = ((n as f64 - t) / decay).min(1.0);
        *s *= rise * fall * 10f64.powf(gain_db / 20.0);
    }
    let rms = (x.iter().map(|s| s * s).sum::<f64>() / n as f64).sqrt();
    let gain = 32768.0 * 10f64.powf(level_dbfs / 20.0) / rms.max(1e-12);
    x.iter()
        .map(|s| (s * gain).round().clamp(-32768.0, 32767.0) as i16)
        .collect()
}

/// A probe recording: `pad_s` of background, the `k`-th burst of the set
/// `seed` at `level_dbfs`, `pad_s` of background; the background is
/// digital silence, or white noise at `background_dbfs` (a room).
pub fn recording(
    seed: u64,
    k: usize,
    level_dbfs: f64,
    background_dbfs: Option<f64>,
    pad_s: f64,
) -> Vec<i16> {
    let rate = AUDIO_RATE_HZ as f64;
    let pad = (pad_s * rate) as usize;
    let b = burst(
        kind_of(k),
        seed.wrapping_mul(1_000_003).wrapping_add(k as u64),
        level_dbfs,
    );
    let mut out = vec![0i16; pad];
    out.extend_from_slice(&b);
    out.extend(std::iter::repeat_n(0i16, pad));
    if let Some(db) = background_dbfs {
        let sigma = 32768.0 * 10f64.powf(db / 20.0);
        let mut rng = Rng::new(seed ^ 0xB4C6_0000 ^ k as u64);
        for s in out.iter_mut() {
            let v = *s as f64 + sigma * rng.normal();
            *s = v.round().clamp(-32768.0, 32767.0) as i16;
        }
    }
    out
}

#[cfg(test)]
mod tests {
    use super::*;

    fn rms_db(x: &[i16]) -> f64 {
        let p = x.iter().map(|&s| (s as f64).powi(2)).sum::<f64>() / x.len() as f64;
        10.0 * (p / (32768.0 * 32768.0)).log10()
    }

    #[test]
    fn a_burst_is_deterministic_at_its_level() {
        for kind in [BurstKind::White, BurstKind::Clatter] {
            let a = burst(kind, 7, -22.0);
            assert_eq!(a, burst(kind, 7, -22.0));
            assert_ne!(a, burst(kind, 8, -22.0));
            assert_eq!(a.len(), 9600);
            // within a clatter's clipped peaks
            assert!((rms_db(&a) + 22.0).abs() < 0.5, "{}", rms_db(&a));
        }
        let r = recording(1, 3, -22.0, Some(-60.0), 0.3);
        assert_eq!(r.len(), 9600 + 2 * 4800);
        assert!((rms_db(&r[..4800]) + 60.0).abs() < 0.5);
    }
}
