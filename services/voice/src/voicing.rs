//! Is it a voice? Every command has a vowel, and a vowel is voiced: the
//! vocal folds make it periodic at the speaker's pitch (60-400 Hz) for
//! 80 ms and more. Noise is not: white noise, a blast of air, a rattle or a
//! clatter of impulses at random times. An utterance without such a stretch
//! of voicing is refused before it is decoded (`not_speech`): the closed
//! grammar would otherwise map a noise burst onto its nearest command, most
//! often `stop` (its /s/, /t/ and /p/ are noise themselves).
//!
//! Per 10 ms frame of the utterance:
//! 1. low-pass at 1 kHz and decimate to 4 kHz: a voice's periodicity is
//!    carried by its harmonics below 1 kHz, and white noise keeps only an
//!    eighth of its power there (the band's SNR is about 9 dB better);
//! 2. the normalised cross-correlation of a 20 ms window with itself shifted
//!    by each lag of the pitch range ([`MIN_PITCH_HZ`]..[`MAX_PITCH_HZ`]):
//!    about 1 for a periodic frame, about 0.3 for band-limited noise;
//! 3. the frame is voiced when that peak reaches [`VOICED_CORRELATION`],
//!    beats every shorter lag (the resonances a clatter rings with correlate
//!    there too; a voice's half period does not) and its band energy is within
//!    [`LOUD_DB`] of the utterance's loudest frame.
//!
//! An utterance is speech when its longest run of voiced frames lasts at
//! least `[voice] min_voiced_s`. Measured on the committed fixtures and
//! 2 400 generated noise bursts ([`crate::bursts`]): every command's longest
//! run is 120 ms or more, down to 7 dB SNR; a burst's is at most 60 ms but
//! for 2 (70 and 100 ms, clatters whose clicks happen to fall a pitch
//! period apart).
//!
//! Cost: about 1 M multiply-adds per second of audio; on the fixtures
//! 0.0012× real time, under 2 ms per utterance on a loaded machine where
//! the decoder took 0.17× (under 1 % of the decode), and what is refused is
//! never decoded. Its scratch buffer is allocated once, for the longest
//! utterance: the check itself allocates nothing.

use phri_ipc::AUDIO_RATE_HZ;

/// The analysis rate \[Hz\] (16 kHz decimated by `DECIMATE`).
pub const RATE_HZ: usize = 4000;
const DECIMATE: usize = AUDIO_RATE_HZ as usize / RATE_HZ;
/// Frame hop: 10 ms at [`RATE_HZ`].
pub const HOP: usize = RATE_HZ / 100;
/// Correlation window: 20 ms at [`RATE_HZ`] (a longer one loses a falling
/// pitch: espeak's "stop" falls from 102 to 77 Hz in 110 ms).
pub const WINDOW: usize = 80;
/// The pitch range searched \[Hz\].
pub const MIN_PITCH_HZ: f64 = 60.0;
/// The top of the pitch range searched \[Hz\].
pub const MAX_PITCH_HZ: f64 = 400.0;
const MIN_LAG: usize = (RATE_HZ as f64 / MAX_PITCH_HZ) as usize;
const MAX_LAG: usize = (RATE_HZ as f64 / MIN_PITCH_HZ) as usize + 1;
/// The shortest lag looked at for a periodicity above the pitch range
/// (1.33 kHz at [`RATE_HZ`]).
const MIN_TONE_LAG: usize = 3;
/// A frame whose correlation peak reaches this is periodic.
pub const VOICED_CORRELATION: f64 = 0.5;
/// Only frames within this of the utterance's loudest count \[dB\].
pub const LOUD_DB: f64 = 25.0;
/// The low-pass: windowed sinc (Hamming), cut-off 1 kHz at 16 kHz.
const TAPS: usize = 63;

/// What the voicing analysis found in an utterance.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct Voicing {
    /// frames analysed (10 ms)
    pub frames: u32,
    /// voiced frames
    pub voiced: u32,
    /// the longest run of voiced frames
    pub longest_run: u32,
}

impl Voicing {
    /// The longest voiced stretch \[s\].
    pub fn longest_s(&self) -> f64 {
        self.longest_run as f64 * HOP as f64 / RATE_HZ as f64
    }

    /// Voiced long enough to be speech: a run of at least `min_voiced_s` \[s\]
    /// (0: everything is).
    pub fn is_speech(&self, min_voiced_s: f64) -> bool {
        self.longest_s() + 1e-9 >= min_voiced_s
    }
}

/// One frame of the analysis (for tuning).
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct Frame {
    /// the correlation peak over the pitch range, and its pitch \[Hz\]
    pub correlation: f64,
    /// the pitch of that peak \[Hz\]
    pub pitch_hz: f64,
    /// the best correlation at a shorter lag (above the pitch range)
    pub faster: f64,
    /// band energy against the utterance's loudest frame \[dB\]
    pub db: f64,
    /// the frame counts as voiced (periodic, no shorter lag beats it, loud enough)
    pub voiced: bool,
}

/// The voicing analysis and its scratch buffer.
pub struct VoicingMeter {
    taps: [f32; TAPS],
    /// the utterance low-passed and decimated to [`RATE_HZ`]
    band: Vec<f32>,
}

impl VoicingMeter {
    /// A meter for utterances up to `samples` long (16 kHz) without allocating.
    pub fn with_capacity(samples: usize) -> VoicingMeter {
        let mut taps = [0f32; TAPS];
        let fc = 1000.0 / AUDIO_RATE_HZ as f64;
        let mid = (TAPS / 2) as f64;
        let pi = std::f64::consts::PI;
        let mut weights = [0f64; TAPS];
        for (i, w) in weights.iter_mut().enumerate() {
            let k = i as f64 - mid;
            let sinc = if k == 0.0 {
                2.0 * fc
            } else {
                (2.0 * pi * fc * k).sin() / (pi * k)
            };
            *w = sinc * (0.54 - 0.46 * (2.0 * pi * i as f64 / (TAPS - 1) as f64).cos());
        }
        let sum: f64 = weights.iter().sum();
        for (t, w) in taps.iter_mut().zip(weights) {
            *t = (w / sum) as f32;
        }
        VoicingMeter {
            taps,
            band: Vec::with_capacity(samples / DECIMATE + 1),
        }
    }

    /// Analyse `audio` (16 kHz mono).
    pub fn measure(&mut self, audio: &[i16]) -> Voicing {
        self.measure_frames(audio, |_| {})
    }

    /// As [`VoicingMeter::measure`], showing `each` every frame.
    pub fn measure_frames(&mut self, audio: &[i16], each: impl FnMut(&Frame)) -> Voicing {
        self.low_pass(audio);
        voicing(&self.band, each)
    }

    fn low_pass(&mut self, audio: &[i16]) {
        self.band.clear();
        let half = TAPS / 2;
        for i in (0..audio.len()).step_by(DECIMATE) {
            // zero outside the utterance
            let from = i.saturating_sub(half);
            let to = (i + half + 1).min(audio.len());
            let skip = (from + half) - i;
            let acc: f32 = self.taps[skip..]
                .iter()
                .zip(&audio[from..to])
                .map(|(&t, &s)| t * s as f32)
                .sum();
            self.band.push(acc);
        }
    }
}

/// Frame by frame over a band-limited signal at [`RATE_HZ`].
fn voicing(band: &[f32], mut each: impl FnMut(&Frame)) -> Voicing {
    let span = WINDOW + MAX_LAG;
    let mut v = Voicing::default();
    if band.len() < span {
        return v;
    }
    let frames = (band.len() - span) / HOP + 1;
    v.frames = frames as u32;
    let energy = |x: &[f32]| x.iter().map(|&s| s as f64 * s as f64).sum::<f64>();
    let loudest = (0..frames)
        .map(|k| energy(&band[k * HOP..k * HOP + WINDOW]))
        .fold(0.0, f64::max);
    if !(loudest > 0.0) {
        return v;
    }
    let mut run = 0u32;
    for k in 0..frames {
        let x = &band[k * HOP..k * HOP + span];
        let e0 = energy(&x[..WINDOW]);
        let mut f = Frame {
            db: 10.0 * (e0 / loudest).max(1e-30).log10(),
            ..Frame::default()
        };
        if f.db >= -LOUD_DB {
            // the shifted window's energy, updated lag by lag
            let mut e1 = energy(&x[MIN_TONE_LAG..MIN_TONE_LAG + WINDOW]);
            for lag in MIN_TONE_LAG..=MAX_LAG {
                if lag > MIN_TONE_LAG {
                    let (out, inn) = (x[lag - 1] as f64, x[lag + WINDOW - 1] as f64);
                    e1 += inn * inn - out * out;
                }
                let c: f64 = x[..WINDOW]
                    .iter()
                    .zip(&x[lag..lag + WINDOW])
                    .map(|(&a, &b)| a as f64 * b as f64)
                    .sum();
                let d = (e0 * e1.max(0.0)).sqrt();
                let r = if d > 0.0 { c / d } else { 0.0 };
                if lag < MIN_LAG {
                    f.faster = f.faster.max(r);
                } else if r > f.correlation {
                    f.correlation = r;
                    f.pitch_hz = RATE_HZ as f64 / lag as f64;
                }
            }
            f.voiced = f.correlation >= VOICED_CORRELATION && f.correlation > f.faster;
        }
        each(&f);
        if f.voiced {
            v.voiced += 1;
            run += 1;
            v.longest_run = v.longest_run.max(run);
        } else {
            run = 0;
        }
    }
    v
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::bursts::{burst, BurstKind, Rng};
    use std::f64::consts::PI;

    /// `secs` of a vowel-like voice: harmonics of `f0` [Hz] under two
    /// formants (F1 700 Hz, F2 1200 Hz), with a slow vibrato, at `amp`.
    fn vowel(secs: f64, f0: f64, amp: f64) -> Vec<i16> {
        let n = (secs * 16000.0) as usize;
        let formant = |f: f64, fc: f64, bw: f64| 1.0 / (1.0 + ((f - fc) / bw).powi(2));
        let mut phase = 0.0;
        let raw: Vec<f64> = (0..n)
            .map(|i| {
                let t = i as f64 / 16000.0;
                let f = f0 * (1.0 + 0.03 * (2.0 * PI * 5.0 * t).sin());
                phase += 2.0 * PI * f / 16000.0;
                (1..40)
                    .map(|h| {
                        let fh = h as f64 * f;
                        let g = (formant(fh, 700.0, 120.0) + 0.5 * formant(fh, 1200.0, 150.0))
                            / h as f64;
                        g * (h as f64 * phase).sin()
                    })
                    .sum()
            })
            .collect();
        let peak = raw.iter().fold(0.0f64, |m, s| m.max(s.abs()));
        raw.iter().map(|s| (amp * s / peak) as i16).collect()
    }

    fn measure(a: &[i16]) -> Voicing {
        VoicingMeter::with_capacity(a.len()).measure(a)
    }

    #[test]
    fn a_vowel_is_voiced_at_any_pitch_and_level() {
        for f0 in [85.0, 120.0, 210.0, 320.0] {
            for amp in [300.0, 8000.0] {
                let mut best = 0.0f64;
                let v = VoicingMeter::with_capacity(0)
                    .measure_frames(&vowel(0.3, f0, amp), |f| best = best.max(f.correlation));
                assert!(v.is_speech(0.08), "{f0} Hz at {amp}: {v:?}");
                assert!(v.voiced + 2 >= v.frames, "{f0} Hz at {amp}: {v:?}");
                assert!(best > 0.9, "{f0} Hz: {best}");
            }
        }
    }

    #[test]
    fn a_vowel_in_white_noise_at_7_db_snr_is_still_voiced() {
        let clean = vowel(0.3, 120.0, 8000.0);
        let p = clean.iter().map(|&s| (s as f64).powi(2)).sum::<f64>() / clean.len() as f64;
        let sigma = (p / 10f64.powf(0.7)).sqrt();
        let mut rng = Rng::new(3);
        let noisy: Vec<i16> = clean
            .iter()
            .map(|&s| (s as f64 + sigma * rng.normal()) as i16)
            .collect();
        assert!(measure(&noisy).is_speech(0.08), "{:?}", measure(&noisy));
    }

    #[test]
    fn white_noise_clatter_and_clicks_are_not_voiced() {
        for seed in 0..20 {
            for kind in [BurstKind::White, BurstKind::Clatter] {
                let v = measure(&burst(kind, seed, -20.0));
                assert!(!v.is_speech(0.08), "{kind:?} {seed}: {v:?}");
            }
        }
        // a click every 130 ms (a rattle of loose parts), and single clicks
        let mut clicks = vec![0i16; 16000];
        for k in (0..16000).step_by(2080) {
            clicks[k] = 20000;
            clicks[k + 1] = -15000;
        }
        assert!(!measure(&clicks).is_speech(0.08), "{:?}", measure(&clicks));
        // digital silence, and too little audio to analyse
        assert_eq!(measure(&[0; 8000]).voiced, 0);
        assert_eq!(measure(&[100; 10]), Voicing::default());
        assert!(measure(&[]).is_speech(0.0), "0 s: the gate is off");
    }
}
