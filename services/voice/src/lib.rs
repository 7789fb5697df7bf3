//! Voice commands (paper Sect. VI-A): offline recognition of a small
//! command grammar, as a step: `audio/mic` chunks and the tracked hands in,
//! an [`Utterance`] (every one heard, with its verdict) and at most one
//! [`HriRequest`] out. `main.rs` wires the channels; `phri-voice --wav`
//! runs the same segmenter and recogniser over files.
//!
//! The verdict, in order: speech too short or too long; no voicing (noise,
//! a rattle: [`voicing`], refused before decoding); no command in the
//! grammar; a command scoring below `[voice] min_score`; `follow` for a hand
//! the body tracker does not see (the gate that blocks a closed grammar's
//! false accepts: "follow the red band" is heard as "follow the right
//! hand"). `stop` is accepted in any state and whatever the hands, on a
//! lower score (`[voice] min_stop_score`): a protective stop, which
//! complements and never replaces the robot's emergency stop.

#![deny(missing_docs)]

pub mod bursts;
pub mod capture;
pub mod error;
pub mod ffi;
pub mod mic;
pub mod recognizer;
pub mod resample;
pub mod segment;
pub mod voicing;
pub mod wav;

use phri_config::VoiceConfig;
use phri_ipc::{
    AudioChunk, CollabPart, HriRequest, RequestKind, RequestSource, Skeleton, Utterance,
    VoiceVerdict, Zeroed,
};

pub use error::VoiceError;
pub use recognizer::{Decoded, Recognizer};
pub use segment::{Segment, SegmentKind, Segmenter};
pub use voicing::{Voicing, VoicingMeter};

/// The best-tracked person showing each hand.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct Hands {
    /// (person, confidence) of the right / left hand
    pub right: Option<(u32, f64)>,
    /// the same for the left hand
    pub left: Option<(u32, f64)>,
}

impl Hands {
    /// Both hands of someone, fully confident (`phri-voice --wav`: no scene to gate on).
    pub const ANYONE: Hands = Hands {
        right: Some((u32::MAX, 1.0)),
        left: Some((u32::MAX, 1.0)),
    };

    /// The hands of `skeleton`, or none when it is older than `max_age_ns` at `now_ns`.
    pub fn of(skeleton: Option<&Skeleton>, now_ns: u64, max_age_ns: u64) -> Hands {
        let mut hands = Hands::default();
        let Some(sk) = skeleton else { return hands };
        if now_ns.saturating_sub(sk.published_ns) > max_age_ns {
            return hands;
        }
        let n = (sk.n_people as usize).min(sk.people.len());
        for p in sk.people[..n].iter().filter(|p| p.tracked != 0) {
            for (part, slot) in [
                (CollabPart::RightHand, &mut hands.right),
                (CollabPart::LeftHand, &mut hands.left),
            ] {
                let Some(j) = part.joint() else { continue };
                let c = p.confidence[j as usize];
                if c.is_finite() && slot.is_none_or(|(_, best)| c > best) {
                    *slot = Some((p.id, c));
                }
            }
        }
        hands
    }

    fn get(&self, part: CollabPart) -> Option<(u32, f64)> {
        match part {
            CollabPart::RightHand => self.right,
            CollabPart::LeftHand => self.left,
            CollabPart::None => None,
        }
    }
}

/// The verdict on a decoded utterance, and the person a `follow` names.
pub fn judge(d: &Decoded, hands: &Hands, cfg: &VoiceConfig) -> (VoiceVerdict, u32) {
    let Some((kind, part)) = d.intent.request() else {
        return (VoiceVerdict::NoMatch, u32::MAX);
    };
    if kind == RequestKind::Stop {
        // in any state, whatever the hands: a protective stop
        let v = if d.score >= cfg.min_stop_score {
            VoiceVerdict::Accepted
        } else {
            VoiceVerdict::LowScore
        };
        return (v, u32::MAX);
    }
    if !(d.score >= cfg.min_score) {
        return (VoiceVerdict::LowScore, u32::MAX);
    }
    if kind == RequestKind::Follow {
        return match hands.get(part) {
            Some((person, c)) if c >= cfg.min_hand_confidence => (VoiceVerdict::Accepted, person),
            _ => (VoiceVerdict::HandNotTracked, u32::MAX),
        };
    }
    (VoiceVerdict::Accepted, u32::MAX)
}

/// A decoder score as a confidence in [0, 1]: 0.5 at `min_score`, a
/// logistic of width 2 score units.
pub fn confidence(score: f64, min_score: f64) -> f64 {
    1.0 / (1.0 + (-(score - min_score) / 2.0).exp())
}

/// What one utterance came to.
#[derive(Clone, Copy, Debug)]
pub struct Heard {
    /// the utterance, with its verdict
    pub utterance: Utterance,
    /// the request to publish (accepted utterances)
    pub request: Option<HriRequest>,
}

/// The recogniser's step: segmenter, voicing, decoder, verdict.
pub struct Listener {
    cfg: VoiceConfig,
    segmenter: Segmenter,
    voicing: VoicingMeter,
    recognizer: Recognizer,
    utterances: u64,
    requests: u64,
    /// utterances refused as not speech (no voicing)
    pub not_speech: u64,
    /// the last utterance's voicing (none when it was not analysed)
    pub last_voicing: Option<Voicing>,
    /// audio decoded and the time it took \[s\]
    pub audio_s: f64,
    /// the time decoding took \[s\], the voicing analysis included
    pub decode_s: f64,
}

impl Listener {
    /// The segmenter, voicing meter and recogniser of `cfg`; fails when
    /// pocketsphinx or its model cannot be loaded.
    pub fn new(cfg: &VoiceConfig) -> Result<Listener, VoiceError> {
        Ok(Listener {
            cfg: cfg.clone(),
            segmenter: Segmenter::new(cfg),
            voicing: VoicingMeter::with_capacity(Segmenter::capacity(cfg)),
            recognizer: Recognizer::new(cfg)?,
            utterances: 0,
            requests: 0,
            not_speech: 0,
            last_voicing: None,
            audio_s: 0.0,
            decode_s: 0.0,
        })
    }

    /// Number the next utterance and request after `seq` (a restarted
    /// recogniser starts after its predecessor's numbers: readers tell
    /// requests apart by source and number).
    pub fn number_after(&mut self, seq: u64) {
        self.utterances = seq;
        self.requests = seq;
    }

    /// Feed one chunk; `hands` is the scene when it arrives, `clock` the
    /// CLOCK_MONOTONIC time \[ns\] (read after decoding: the verdict's time).
    pub fn step(
        &mut self,
        chunk: &AudioChunk,
        hands: &Hands,
        clock: impl Fn() -> u64,
    ) -> Result<Option<Heard>, VoiceError> {
        let n = (chunk.samples as usize).min(chunk.pcm.len());
        match self.segmenter.push(&chunk.pcm[..n], chunk.capture_ns) {
            Some(seg) => self.heard(seg, hands, clock).map(Some),
            None => Ok(None),
        }
    }

    /// The stream ended: speech in progress is an utterance.
    pub fn finish(
        &mut self,
        hands: &Hands,
        clock: impl Fn() -> u64,
    ) -> Result<Option<Heard>, VoiceError> {
        match self.segmenter.finish() {
            Some(seg) => self.heard(seg, hands, clock).map(Some),
            None => Ok(None),
        }
    }

    fn heard(
        &mut self,
        seg: Segment,
        hands: &Hands,
        clock: impl Fn() -> u64,
    ) -> Result<Heard, VoiceError> {
        self.utterances += 1;
        let mut u = Utterance::zeroed();
        u.seq = self.utterances;
        u.start_ns = seg.start_ns;
        u.end_ns = seg.end_ns;
        self.last_voicing = None;
        // the voicing analysis is on the way to a request: timed with the decode
        let t0 = std::time::Instant::now();
        let verdict = match seg.kind {
            SegmentKind::TooShort => Some(VoiceVerdict::TooShort),
            SegmentKind::TooLong => Some(VoiceVerdict::TooLong),
            SegmentKind::Speech if self.cfg.min_voiced_s > 0.0 => {
                // noise is refused before the closed grammar can name it
                let v = self.voicing.measure(self.segmenter.audio());
                self.last_voicing = Some(v);
                if v.is_speech(self.cfg.min_voiced_s) {
                    None
                } else {
                    self.not_speech += 1;
                    Some(VoiceVerdict::NotSpeech)
                }
            }
            SegmentKind::Speech => None,
        };
        let mut request = None;
        u.verdict = match verdict {
            Some(v) => {
                u.decode_ms = t0.elapsed().as_secs_f64() * 1e3;
                v as u32
            }
            None => {
                let audio = self.segmenter.audio();
                let audio_s = audio.len() as f64 / phri_ipc::AUDIO_RATE_HZ as f64;
                let d = self.recognizer.decode(audio)?;
                let took = t0.elapsed().as_secs_f64();
                self.audio_s += audio_s;
                self.decode_s += took;
                u.decode_ms = took * 1e3;
                u.score = d.score;
                u.intent = d.intent as u32;
                u.text = phri_ipc::json::to_c_str(&d.text);
                let (v, person) = judge(&d, hands, &self.cfg);
                if v == VoiceVerdict::Accepted {
                    if let Some((kind, part)) = d.intent.request() {
                        self.requests += 1;
                        let mut r = HriRequest::zeroed();
                        r.seq = self.requests;
                        r.utterance_end_ns = seg.end_ns;
                        r.source = RequestSource::Voice as u32;
                        r.kind = kind as u32;
                        r.part = part as u32;
                        r.person = person;
                        r.confidence = confidence(d.score, self.cfg.min_score);
                        r.score = d.score;
                        r.text = u.text;
                        u.request_seq = r.seq;
                        request = Some(r);
                    }
                }
                v as u32
            }
        };
        let now = clock();
        u.decoded_ns = now;
        if let Some(r) = request.as_mut() {
            r.stamp_ns = now;
        }
        Ok(Heard {
            utterance: u,
            request,
        })
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use phri_ipc::VoiceIntent;

    fn decoded(intent: VoiceIntent, score: f64) -> Decoded {
        Decoded {
            text: "x".into(),
            intent,
            score,
            frames: 100,
        }
    }

    #[test]
    fn the_verdict_order_stop_always_follow_gated_by_the_hand() {
        let cfg = phri_config::Config::defaults().voice;
        let left_only = Hands {
            right: Some((1, 0.0)),
            left: Some((1, 0.9)),
        };
        let j = |i, s| judge(&decoded(i, s), &left_only, &cfg).0;
        assert_eq!(
            j(VoiceIntent::Stop, cfg.min_score - 0.1),
            VoiceVerdict::Accepted
        );
        assert_eq!(
            j(VoiceIntent::Stop, cfg.min_stop_score - 0.1),
            VoiceVerdict::LowScore
        );
        assert_eq!(j(VoiceIntent::FollowLeftHand, 5.0), VoiceVerdict::Accepted);
        assert_eq!(
            j(VoiceIntent::FollowRightHand, 5.0),
            VoiceVerdict::HandNotTracked
        );
        assert_eq!(
            j(VoiceIntent::FollowLeftHand, cfg.min_score - 0.1),
            VoiceVerdict::LowScore
        );
        assert_eq!(j(VoiceIntent::Begin, 5.0), VoiceVerdict::Accepted);
        assert_eq!(j(VoiceIntent::None, 5.0), VoiceVerdict::NoMatch);
        assert_eq!(
            judge(&decoded(VoiceIntent::FollowLeftHand, 5.0), &left_only, &cfg).1,
            1
        );
        assert!((confidence(cfg.min_score, cfg.min_score) - 0.5).abs() < 1e-12);
    }
}
