//! The microphone stand-in's audio, as a pure function of the sample index:
//! background noise (seeded) with recordings mixed in where a schedule puts
//! them. `phri-mic` cuts it into `audio/mic` chunks, paced by the simulated
//! clock (a scenario's `[[voice]]` lines) or the wall clock (a WAV directory).

use phri_ipc::AUDIO_RATE_HZ;

/// Duration of one `audio/mic` chunk [ns].
pub const CHUNK_NS: u64 =
    phri_ipc::AUDIO_CHUNK_SAMPLES as u64 * 1_000_000_000 / AUDIO_RATE_HZ as u64;

/// The chunks to publish at `now_ns` (time since the stream's sample 0
/// [ns]): every chunk wholly captured by then from `next` on, or, for a
/// source that has published nothing yet (`None`) or fell more than
/// `max_burst` chunks behind, none (it starts over from the present).
pub fn due(next: Option<u64>, now_ns: u64, max_burst: u64) -> std::ops::Range<u64> {
    let captured = now_ns / CHUNK_NS;
    match next {
        Some(k) if captured.saturating_sub(k) <= max_burst => k..captured.max(k),
        _ => captured..captured,
    }
}

/// A recording and the sample it starts at.
#[derive(Clone, Debug)]
pub struct Clip {
    pub start: u64,
    pub samples: Vec<i16>,
}

/// Noise plus clips.
#[derive(Clone, Debug)]
pub struct Playback {
    clips: Vec<Clip>,
    /// noise RMS [full-scale units]
    noise_rms: f64,
    seed: u64,
    /// samples of one pass (0: no repeat)
    period: u64,
}

/// splitmix64: a sample's noise depends on its index alone.
fn hash(mut x: u64) -> u64 {
    x = x.wrapping_add(0x9E37_79B9_7F4A_7C15);
    x = (x ^ (x >> 30)).wrapping_mul(0xBF58_476D_1CE4_E5B9);
    x = (x ^ (x >> 27)).wrapping_mul(0x94D0_49BB_1331_11EB);
    x ^ (x >> 31)
}

impl Playback {
    /// `clips` sorted by start; `noise_dbfs`: the noise's RMS level.
    pub fn new(mut clips: Vec<Clip>, noise_dbfs: f64, seed: u64) -> Playback {
        clips.sort_by_key(|c| c.start);
        Playback {
            clips,
            noise_rms: 32768.0 * 10f64.powf(noise_dbfs / 20.0),
            seed,
            period: 0,
        }
    }

    /// Recordings one after the other from sample 0, `gap_s` of silence
    /// before each; with `repeat` the whole plays again and again.
    pub fn sequence(
        recordings: Vec<Vec<i16>>,
        gap_s: f64,
        repeat: bool,
        noise_dbfs: f64,
        seed: u64,
    ) -> Playback {
        let gap = (gap_s * AUDIO_RATE_HZ as f64) as u64;
        let mut at = 0u64;
        let mut clips = Vec::with_capacity(recordings.len());
        for samples in recordings {
            at += gap;
            let len = samples.len() as u64;
            clips.push(Clip { start: at, samples });
            at += len;
        }
        let mut p = Playback::new(clips, noise_dbfs, seed);
        if repeat {
            p.period = at + gap;
        }
        p
    }

    /// The sample after the last clip (0: none).
    pub fn end(&self) -> u64 {
        self.clips
            .iter()
            .map(|c| c.start + c.samples.len() as u64)
            .max()
            .unwrap_or(0)
    }

    /// Samples `first..first + out.len()` into `out`.
    pub fn fill(&self, first: u64, out: &mut [i16]) {
        for (i, o) in out.iter_mut().enumerate() {
            let n = first + i as u64;
            // uniform noise of the given RMS: amplitude √3·rms
            let u = (hash(n ^ self.seed.rotate_left(32)) >> 11) as f64 / (1u64 << 53) as f64;
            let mut x = (2.0 * u - 1.0) * 3f64.sqrt() * self.noise_rms;
            let local = if self.period > 0 { n % self.period } else { n };
            for c in &self.clips {
                if local < c.start {
                    break;
                }
                if let Some(&s) = c.samples.get((local - c.start) as usize) {
                    x += s as f64;
                }
            }
            *o = x.round().clamp(-32768.0, 32767.0) as i16;
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn clips_play_at_their_sample_over_noise_of_the_given_level() {
        let p = Playback::new(
            vec![Clip {
                start: 1000,
                samples: vec![10_000; 500],
            }],
            -40.0,
            3,
        );
        let mut out = vec![0i16; 4000];
        p.fill(0, &mut out);
        let rms = |s: &[i16]| {
            (s.iter().map(|&x| (x as f64).powi(2)).sum::<f64>() / s.len() as f64).sqrt()
        };
        let noise = rms(&out[..1000]);
        assert!((noise / 327.68 - 1.0).abs() < 0.1, "noise rms {noise}");
        assert!(out[1000..1500]
            .iter()
            .all(|&x| (x as i32 - 10_000).abs() < 700));
        // the same samples whatever the chunking
        let mut a = vec![0i16; 320];
        p.fill(1200, &mut a);
        assert_eq!(&a[..], &out[1200..1520]);
    }

    #[test]
    fn chunks_are_due_once_captured_and_a_long_stall_starts_over() {
        assert_eq!(due(None, 95_000_000, 100), 4..4);
        assert_eq!(due(Some(4), 95_000_000, 100), 4..4);
        assert_eq!(due(Some(4), 100_000_000, 100), 4..5);
        assert_eq!(due(Some(4), 10 * 1_000_000_000, 100), 500..500);
        assert_eq!(due(Some(9), 100_000_000, 100), 9..9);
    }

    #[test]
    fn a_sequence_repeats_after_its_last_gap() {
        let p = Playback::sequence(
            vec![vec![1000; 100], vec![2000; 100]],
            0.01,
            true,
            -120.0,
            0,
        );
        // gap 160, clip, gap 160, clip, final gap: period 680
        let mut out = vec![0i16; 1400];
        p.fill(0, &mut out);
        assert_eq!(out[160], 1000);
        assert_eq!(out[420], 2000);
        assert_eq!(out[680 + 160], 1000);
        assert_eq!(p.end(), 520);
    }
}
