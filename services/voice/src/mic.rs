//! The microphone stand-in's audio, as a pure function of the sample index:
//! background noise (seeded) with recordings mixed in where a schedule puts
//! them. `phri-mic` cuts it into `audio/mic` chunks, paced by the simulated
//! clock (a scenario's `[[voice]]` lines) or the wall clock (a WAV directory).
//! Also `phri-mic`'s flags and its `audio/mic/status` figures (whatever the
//! source; a real microphone is [`crate::capture`]).

use phri_config::{Invalid, MicConfig, MicSource};
use phri_ipc::{MicStatus, Zeroed, AUDIO_RATE_HZ};

/// Duration of one `audio/mic` chunk \[ns\].
pub const CHUNK_NS: u64 =
    phri_ipc::AUDIO_CHUNK_SAMPLES as u64 * 1_000_000_000 / AUDIO_RATE_HZ as u64;

/// The chunks to publish at `now_ns` (time since the stream's sample 0
/// \[ns\]): every chunk wholly captured by then from `next` on, or, for a
/// source that has published nothing yet (`None`) or fell more than
/// `max_burst` chunks behind, none (it starts over from the present).
pub fn due(next: Option<u64>, now_ns: u64, max_burst: u64) -> std::ops::Range<u64> {
    let captured = now_ns / CHUNK_NS;
    match next {
        Some(k) if captured.saturating_sub(k) <= max_burst => k..captured.max(k),
        _ => captured..captured,
    }
}

/// `--source`'s values.
#[derive(clap::ValueEnum, Clone, Copy, Debug, PartialEq, Eq)]
pub enum SourceFlag {
    /// the stand-in of `[audio]` (the simulated room, or recordings)
    Sim,
    /// a real microphone through ALSA
    Alsa,
}

/// `phri-mic`'s own flags: they override `[mic]`.
#[derive(clap::Args, Debug, Clone, Default, PartialEq)]
pub struct MicFlags {
    /// Where the sound comes from (overrides \[mic\] source): sim, the stand-in
    /// of \[audio\]; alsa, a real microphone (mono, resampled to 16 kHz)
    #[arg(long, value_enum, value_name = "SOURCE")]
    pub source: Option<SourceFlag>,
    /// The ALSA capture device with --source alsa (overrides \[mic\] device;
    /// `arecord -L` lists them: "default", "hw:1,0", "plughw:1,0")
    #[arg(long, value_name = "NAME")]
    pub device: Option<String>,
}

impl MicFlags {
    /// `[mic]` with the flags applied, checked.
    pub fn apply(&self, mic: &MicConfig) -> Result<MicConfig, Invalid> {
        let mut m = mic.clone();
        match self.source {
            Some(SourceFlag::Sim) => m.source = MicSource::Sim,
            Some(SourceFlag::Alsa) => m.source = MicSource::Alsa,
            None => {}
        }
        if let Some(d) = &self.device {
            m.device = d.clone();
        }
        m.validate().map_err(|e| match self.device {
            Some(_) => Invalid::new("--device", e.reason),
            None => e,
        })?;
        Ok(m)
    }
}

/// `audio/mic/status`: the microphone's figures, 2 Hz and at exit.
#[derive(Clone, Debug)]
pub struct MicStats {
    /// the last message (source and device rate set once, the rest per message)
    pub status: MicStatus,
    next_ns: u64,
}

/// Between two `audio/mic/status` messages \[ns\].
pub const STATUS_PERIOD_NS: u64 = 500_000_000;

impl MicStats {
    /// Figures of `source` at `device_rate_hz` \[Hz\]; the first message is due at
    /// once.
    pub fn new(source: MicSource, device_rate_hz: u32) -> MicStats {
        let mut status = MicStatus::zeroed();
        status.source = match source {
            MicSource::Sim => 0,
            MicSource::Alsa => 1,
        };
        status.device_rate_hz = device_rate_hz;
        MicStats { status, next_ns: 0 }
    }

    /// The message to publish at `now_ns`, if one is due (the first at once).
    pub fn due(&mut self, now_ns: u64, chunks: u64, overruns: u64) -> Option<MicStatus> {
        if now_ns < self.next_ns {
            return None;
        }
        self.next_ns = now_ns + STATUS_PERIOD_NS;
        Some(self.now(now_ns, chunks, overruns))
    }

    /// The message at `now_ns` whatever the period (at exit).
    pub fn now(&mut self, now_ns: u64, chunks: u64, overruns: u64) -> MicStatus {
        self.status.seq += 1;
        self.status.stamp_ns = now_ns;
        self.status.chunks = chunks;
        self.status.overruns = overruns;
        self.status
    }
}

/// A recording and the sample it starts at.
#[derive(Clone, Debug)]
pub struct Clip {
    /// the sample it begins at (16 kHz, from the stream's start)
    pub start: u64,
    /// the recording, 16 kHz mono
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
    fn the_flags_override_mic_and_status_is_2hz() {
        let cfg = phri_config::Config::defaults().mic;
        let f = MicFlags {
            source: Some(SourceFlag::Alsa),
            device: Some("hw:1,0".into()),
        };
        let m = f.apply(&cfg).unwrap();
        assert_eq!((m.source, m.device.as_str()), (MicSource::Alsa, "hw:1,0"));
        assert_eq!(MicFlags::default().apply(&cfg).unwrap(), cfg);
        let bad = MicFlags {
            source: None,
            device: Some(String::new()),
        };
        assert!(bad
            .apply(&cfg)
            .unwrap_err()
            .to_string()
            .contains("--device"));
        let mut s = MicStats::new(MicSource::Alsa, 44_100);
        let a = s.due(1_000, 0, 0).unwrap();
        assert_eq!((a.seq, a.source, a.device_rate_hz), (1, 1, 44_100));
        assert!(s.due(400_000_000, 5, 0).is_none());
        let b = s.due(500_001_000, 25, 1).unwrap();
        assert_eq!((b.seq, b.chunks, b.overruns), (2, 25, 1));
        assert_eq!(s.now(600_000_000, 30, 1).seq, 3);
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
