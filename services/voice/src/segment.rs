//! Utterances out of a continuous 16 kHz stream: an energy detector over
//! 10 ms frames against a tracked noise floor, as a pure step (samples and
//! their capture time in, finished utterances out). Its buffer is allocated
//! once, for the longest utterance.
//!
//! - the noise floor starts at the first frame's energy, follows quiet
//!   frames down at once and up slowly (`FLOOR_RISE_DB_PER_S`), not at
//!   all during speech, and ten times as fast after a too-long utterance
//!   (the noise itself may have risen: a machine started);
//! - a frame [`VoiceConfig::speech_db`] above the floor is speech; speech
//!   begins after [`VoiceConfig::onset_frames`] such frames in a row and ends
//!   after [`VoiceConfig::hangover_s`] without one (the gaps between words);
//! - an utterance is its speech and [`VoiceConfig::padding_s`] on either side;
//!   speech longer than [`VoiceConfig::max_utterance_s`] is cut off there
//!   (`TooLong`) and the rest, up to the next silence, ignored; shorter than
//!   [`VoiceConfig::min_utterance_s`] it is `TooShort`.

use phri_config::VoiceConfig;
use phri_ipc::AUDIO_RATE_HZ;

/// Samples per energy frame (10 ms).
pub const FRAME: usize = 160;
/// How fast the noise floor may rise [dB/s].
const FLOOR_RISE_DB_PER_S: f64 = 1.0;
/// The quietest frame energy counted [dBFS] (digital silence is −∞).
const MIN_DB: f64 = -90.0;
const NS_PER_SAMPLE: f64 = 1e9 / AUDIO_RATE_HZ as f64;

/// What became of a stretch of speech.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum SegmentKind {
    /// an utterance to decode
    Speech,
    /// speech shorter than [`VoiceConfig::min_utterance_s`]: not decoded
    TooShort,
    /// speech longer than [`VoiceConfig::max_utterance_s`], cut off there: not
    /// decoded
    TooLong,
}

/// A finished utterance; its audio is [`Segmenter::audio`] until the next push.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Segment {
    /// what became of the speech
    pub kind: SegmentKind,
    /// speech began / ended [ns, the stream's capture clock]
    pub start_ns: u64,
    /// speech ended, on the same clock \[ns\]
    pub end_ns: u64,
}

impl Segment {
    /// Speech duration \[s\].
    pub fn duration_s(&self) -> f64 {
        self.end_ns.saturating_sub(self.start_ns) as f64 * 1e-9
    }
}

#[derive(Clone, Copy, Debug, PartialEq)]
enum State {
    Quiet,
    /// speech frames in a row so far, from the frame starting at `start`
    Onset {
        frames: u32,
        start: usize,
        start_ns: u64,
    },
    /// in speech since `start_ns`; the last speech frame ended at `last_end`
    Speech {
        start: usize,
        start_ns: u64,
        last_end: usize,
        last_end_ns: u64,
    },
    /// after a too-long utterance: wait for a silence
    Discard {
        quiet_frames: u32,
    },
}

/// The energy detector: samples and their capture time in, finished
/// utterances out (see the module's docs).
pub struct Segmenter {
    speech_db: f64,
    onset_frames: u32,
    hangover_frames: u32,
    padding: usize,
    min_ns: u64,
    max_ns: u64,
    floor_db: Option<f64>,
    rise_per_frame: f64,
    /// samples since `buf[0]`, oldest first
    buf: Vec<i16>,
    /// the frame being filled, and its first sample's time
    frame: [i16; FRAME],
    frame_len: usize,
    frame_ns: u64,
    state: State,
    /// the finished utterance's audio
    out: Vec<i16>,
}

impl Segmenter {
    /// The longest utterance's audio \[samples\] (its buffers' size).
    pub fn capacity(cfg: &VoiceConfig) -> usize {
        let rate = AUDIO_RATE_HZ as f64;
        let padding = (cfg.padding_s * rate) as usize;
        ((cfg.max_utterance_s + cfg.hangover_s) * rate) as usize + 2 * padding + 4 * FRAME
    }

    /// A segmenter with the thresholds and durations of `cfg`, its buffers
    /// allocated for the longest utterance.
    pub fn new(cfg: &VoiceConfig) -> Segmenter {
        let rate = AUDIO_RATE_HZ as f64;
        let padding = (cfg.padding_s * rate) as usize;
        let hangover_frames = ((cfg.hangover_s * rate) as usize).div_ceil(FRAME).max(1) as u32;
        let capacity = Segmenter::capacity(cfg);
        Segmenter {
            speech_db: cfg.speech_db,
            onset_frames: cfg.onset_frames.max(1),
            hangover_frames,
            padding,
            min_ns: (cfg.min_utterance_s * 1e9) as u64,
            max_ns: (cfg.max_utterance_s * 1e9) as u64,
            floor_db: None,
            rise_per_frame: FLOOR_RISE_DB_PER_S * FRAME as f64 / rate,
            buf: Vec::with_capacity(capacity),
            frame: [0; FRAME],
            frame_len: 0,
            frame_ns: 0,
            state: State::Quiet,
            out: Vec::with_capacity(capacity),
        }
    }

    /// The audio of the segment last returned.
    pub fn audio(&self) -> &[i16] {
        &self.out
    }

    /// The tracked noise floor \[dBFS\] (none before the first frame).
    pub fn floor_db(&self) -> Option<f64> {
        self.floor_db
    }

    /// Feed `samples` whose first was captured at `capture_ns`; a finished
    /// utterance, if one ended in them (the rest of them is kept).
    pub fn push(&mut self, samples: &[i16], capture_ns: u64) -> Option<Segment> {
        let mut done = None;
        for (i, &s) in samples.iter().enumerate() {
            if self.frame_len == 0 {
                self.frame_ns = capture_ns + (i as f64 * NS_PER_SAMPLE) as u64;
            }
            self.frame[self.frame_len] = s;
            self.frame_len += 1;
            if self.frame_len == FRAME {
                self.frame_len = 0;
                if let Some(seg) = self.on_frame() {
                    done = Some(seg);
                }
            }
        }
        done
    }

    /// The stream ended (end of a file): speech in progress ends here.
    pub fn finish(&mut self) -> Option<Segment> {
        let seg = match self.state {
            State::Speech {
                start, start_ns, ..
            } => {
                let end = self.buf.len();
                let end_ns = self.frame_ns + (self.frame_len as f64 * NS_PER_SAMPLE) as u64;
                Some(self.emit(start, start_ns, end, end_ns))
            }
            _ => None,
        };
        self.state = State::Quiet;
        self.buf.clear();
        self.frame_len = 0;
        self.floor_db = None; // the next stream has its own noise
        seg
    }

    fn on_frame(&mut self) -> Option<Segment> {
        let energy = self
            .frame
            .iter()
            .map(|&s| (s as f64) * (s as f64))
            .sum::<f64>()
            / FRAME as f64;
        let db = (10.0 * (energy / (32768.0 * 32768.0)).log10()).max(MIN_DB);
        let floor = *self.floor_db.get_or_insert(db);
        let speech = db >= floor + self.speech_db;
        let rise = match self.state {
            // after a too-long utterance, the noise itself may have risen:
            // the floor follows whatever it hears, ten times as fast
            State::Discard { .. } => 10.0 * self.rise_per_frame,
            State::Speech { .. } => 0.0,
            _ if speech => 0.0,
            _ => self.rise_per_frame,
        };
        if db < floor && !speech {
            self.floor_db = Some(db);
        } else if rise > 0.0 {
            self.floor_db = Some((floor + rise).min(db));
        }
        // the buffer always holds at least one padding of history
        if self.buf.len() + FRAME > self.buf.capacity() {
            self.state = State::Quiet;
        }
        if matches!(self.state, State::Quiet | State::Discard { .. })
            && self.buf.len() > self.padding
        {
            let drop = self.buf.len() - self.padding;
            self.buf.drain(..drop);
        }
        let frame_start = self.buf.len();
        let frame_ns = self.frame_ns;
        self.buf.extend_from_slice(&self.frame);
        let frame_end = frame_start + FRAME;
        let frame_end_ns = frame_ns + (FRAME as f64 * NS_PER_SAMPLE) as u64;
        match self.state {
            State::Quiet => {
                if speech {
                    self.state = State::Onset {
                        frames: 1,
                        start: frame_start,
                        start_ns: frame_ns,
                    };
                    self.check_onset(frame_end, frame_end_ns);
                }
                None
            }
            State::Onset {
                frames,
                start,
                start_ns,
            } => {
                if speech {
                    self.state = State::Onset {
                        frames: frames + 1,
                        start,
                        start_ns,
                    };
                    self.check_onset(frame_end, frame_end_ns);
                } else {
                    self.state = State::Quiet;
                }
                None
            }
            State::Speech {
                start,
                start_ns,
                last_end,
                last_end_ns,
            } => {
                let (last_end, last_end_ns) = if speech {
                    (frame_end, frame_end_ns)
                } else {
                    (last_end, last_end_ns)
                };
                if last_end_ns.saturating_sub(start_ns) > self.max_ns {
                    let end = start
                        + ((self.max_ns as f64 / NS_PER_SAMPLE) as usize)
                            .min(self.buf.len() - start);
                    let seg = self.emit_kind(
                        SegmentKind::TooLong,
                        start,
                        start_ns,
                        end,
                        start_ns + self.max_ns,
                    );
                    self.state = State::Discard { quiet_frames: 0 };
                    return Some(seg);
                }
                let quiet = ((frame_end - last_end) / FRAME) as u32;
                if quiet >= self.hangover_frames {
                    let seg = self.emit(start, start_ns, last_end, last_end_ns);
                    self.state = State::Quiet;
                    return Some(seg);
                }
                self.state = State::Speech {
                    start,
                    start_ns,
                    last_end,
                    last_end_ns,
                };
                None
            }
            State::Discard { quiet_frames } => {
                let quiet_frames = if speech { 0 } else { quiet_frames + 1 };
                self.state = if quiet_frames >= self.hangover_frames {
                    State::Quiet
                } else {
                    State::Discard { quiet_frames }
                };
                None
            }
        }
    }

    fn check_onset(&mut self, frame_end: usize, frame_end_ns: u64) {
        if let State::Onset {
            frames,
            start,
            start_ns,
        } = self.state
        {
            if frames >= self.onset_frames {
                self.state = State::Speech {
                    start,
                    start_ns,
                    last_end: frame_end,
                    last_end_ns: frame_end_ns,
                };
            }
        }
    }

    fn emit(&mut self, start: usize, start_ns: u64, end: usize, end_ns: u64) -> Segment {
        let kind = if end_ns.saturating_sub(start_ns) < self.min_ns {
            SegmentKind::TooShort
        } else {
            SegmentKind::Speech
        };
        self.emit_kind(kind, start, start_ns, end, end_ns)
    }

    fn emit_kind(
        &mut self,
        kind: SegmentKind,
        start: usize,
        start_ns: u64,
        end: usize,
        end_ns: u64,
    ) -> Segment {
        let from = start.saturating_sub(self.padding);
        let to = (end + self.padding).min(self.buf.len());
        self.out.clear();
        self.out.extend_from_slice(&self.buf[from..to.max(from)]);
        // what follows the utterance stays as the next one's history
        let keep_from = to.saturating_sub(self.padding);
        self.buf.drain(..keep_from);
        Segment {
            kind,
            start_ns,
            end_ns,
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn cfg() -> VoiceConfig {
        phri_config::Config::defaults().voice
    }

    /// `secs` of a 300 Hz tone at `amp`, or noise-like quiet at ±`amp`.
    fn tone(secs: f64, amp: f64) -> Vec<i16> {
        let n = (secs * 16000.0) as usize;
        (0..n)
            .map(|i| (amp * (i as f64 * 2.0 * std::f64::consts::PI * 300.0 / 16000.0).sin()) as i16)
            .collect()
    }

    fn run(seg: &mut Segmenter, audio: &[i16]) -> Vec<(Segment, usize)> {
        let mut out = Vec::new();
        for (k, chunk) in audio.chunks(320).enumerate() {
            if let Some(s) = seg.push(chunk, k as u64 * 20_000_000) {
                out.push((s, seg.audio().len()));
            }
        }
        if let Some(s) = seg.finish() {
            out.push((s, seg.audio().len()));
        }
        out
    }

    #[test]
    fn one_utterance_between_silences_with_its_times_and_padding() {
        let c = cfg();
        let mut audio = tone(1.0, 30.0);
        audio.extend(tone(1.2, 8000.0));
        audio.extend(tone(1.5, 30.0));
        let mut seg = Segmenter::new(&c);
        let out = run(&mut seg, &audio);
        assert_eq!(out.len(), 1, "{out:?}");
        let (s, len) = out[0];
        assert_eq!(s.kind, SegmentKind::Speech);
        assert!((s.start_ns as f64 * 1e-9 - 1.0).abs() < 0.02, "{s:?}");
        assert!((s.end_ns as f64 * 1e-9 - 2.2).abs() < 0.02, "{s:?}");
        let expected = ((1.2 + 2.0 * c.padding_s) * 16000.0) as usize;
        assert!(len.abs_diff(expected) <= 2 * FRAME, "{len} vs {expected}");
    }

    #[test]
    fn a_gap_between_words_shorter_than_the_hangover_is_one_utterance() {
        let mut audio = tone(0.5, 30.0);
        audio.extend(tone(0.4, 8000.0));
        audio.extend(tone(0.3, 30.0));
        audio.extend(tone(0.4, 8000.0));
        audio.extend(tone(1.0, 30.0));
        let out = run(&mut Segmenter::new(&cfg()), &audio);
        assert_eq!(out.len(), 1, "{out:?}");
        assert!((out[0].0.duration_s() - 1.1).abs() < 0.03);
    }

    #[test]
    fn clicks_are_too_short_and_monologues_too_long() {
        let c = cfg();
        let mut audio = tone(0.5, 30.0);
        audio.extend(tone(0.1, 8000.0));
        audio.extend(tone(1.0, 30.0));
        audio.extend(tone(c.max_utterance_s + 2.0, 8000.0));
        audio.extend(tone(1.0, 30.0));
        audio.extend(tone(1.0, 8000.0));
        audio.extend(tone(1.0, 30.0));
        let kinds: Vec<SegmentKind> = run(&mut Segmenter::new(&c), &audio)
            .iter()
            .map(|(s, _)| s.kind)
            .collect();
        assert_eq!(
            kinds,
            [
                SegmentKind::TooShort,
                SegmentKind::TooLong,
                SegmentKind::Speech
            ]
        );
    }

    #[test]
    fn digital_silence_and_a_loud_room_both_work() {
        let mut audio = vec![0i16; 16000];
        audio.extend(tone(1.0, 8000.0));
        audio.extend(vec![0i16; 16000]);
        assert_eq!(run(&mut Segmenter::new(&cfg()), &audio).len(), 1);
        // a steady hum 40 dB louder: the floor follows it, speech still stands out
        let mut audio = tone(3.0, 300.0);
        audio.extend(tone(1.0, 12000.0));
        audio.extend(tone(2.0, 300.0));
        let out = run(&mut Segmenter::new(&cfg()), &audio);
        assert_eq!(out.len(), 1, "{out:?}");
    }

    #[test]
    fn a_lasting_rise_of_the_noise_is_one_too_long_utterance_then_the_floor() {
        let c = cfg();
        // a quiet room, then a machine 30 dB louder that keeps running, then a word over it
        let mut audio = tone(1.0, 30.0);
        audio.extend(tone(c.max_utterance_s + 8.0, 1000.0));
        audio.extend(tone(1.0, 30_000.0));
        audio.extend(tone(1.0, 1000.0));
        let kinds: Vec<SegmentKind> = run(&mut Segmenter::new(&c), &audio)
            .iter()
            .map(|(s, _)| s.kind)
            .collect();
        assert_eq!(kinds, [SegmentKind::TooLong, SegmentKind::Speech]);
    }
}
