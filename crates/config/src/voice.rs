//! `[voice]` (the recogniser `phri-voice`) and `[audio]` (the source on
//! `audio/mic`, `phri-mic`).

use serde::{Deserialize, Serialize};

use crate::check::{non_negative, positive, within};
use crate::error::Invalid;

/// `[voice]`: offline command recognition (pocketsphinx, JSGF grammar).
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct VoiceConfig {
    /// acoustic model directory (Debian's `pocketsphinx-en-us`)
    pub acoustic_model: String,
    /// pronunciation dictionary
    pub dictionary: String,
    /// a command's score (acoustic log-likelihood per frame against a free
    /// phone loop) must reach this, else the utterance is refused (`low_score`)
    pub min_score: f64,
    /// `stop` needs less: a false stop is safe, a missed one is not (this
    /// complements, never replaces, the emergency stop)
    pub min_stop_score: f64,
    /// speech shorter than this is refused (`too_short`) \[s\]
    pub min_utterance_s: f64,
    /// speech longer than this is refused (`too_long`) \[s\]
    pub max_utterance_s: f64,
    /// a 10 ms frame this far above the noise floor is speech \[dB\]
    pub speech_db: f64,
    /// speech begins after this many speech frames in a row [10 ms frames]
    pub onset_frames: u32,
    /// this long below the threshold ends the utterance \[s\]
    pub hangover_s: f64,
    /// an utterance needs a voiced stretch (periodic at a pitch of
    /// 60-400 Hz) at least this long, else it is refused before decoding
    /// (`not_speech`: noise, a rattle) \[s\]; 0 turns the check off
    pub min_voiced_s: f64,
    /// audio kept before the onset and after the end, for the decoder \[s\]
    pub padding_s: f64,
    /// `follow` needs the named hand tracked at least this confidently (the gate)
    pub min_hand_confidence: f64,
    /// a skeleton older than this tracks nothing \[ms\]
    pub skeleton_max_age_ms: f64,
}

impl VoiceConfig {
    /// Range checks of every field, and of the pairs that must agree
    /// (`min_stop_score` ≤ `min_score`, `min_utterance_s` below
    /// `max_utterance_s`).
    pub fn validate(&self) -> Result<(), Invalid> {
        const S: &str = "voice";
        if !self.min_score.is_finite() {
            return Err(Invalid::new("voice.min_score", "not a finite number"));
        }
        if !(self.min_stop_score.is_finite() && self.min_stop_score <= self.min_score) {
            return Err(Invalid::new(
                "voice.min_stop_score",
                "must be a finite number no greater than min_score",
            ));
        }
        positive(S, "min_utterance_s", self.min_utterance_s)?;
        positive(S, "max_utterance_s", self.max_utterance_s)?;
        if self.min_utterance_s >= self.max_utterance_s {
            return Err(Invalid::new(
                "voice.min_utterance_s",
                "must be below max_utterance_s",
            ));
        }
        if self.max_utterance_s > 30.0 {
            return Err(Invalid::new("voice.max_utterance_s", "at most 30 s"));
        }
        within(S, "speech_db", self.speech_db, 1.0, 60.0)?;
        if !(1..=50).contains(&self.onset_frames) {
            return Err(Invalid::new("voice.onset_frames", "not in 1..=50"));
        }
        // the segmenter's buffer holds an utterance and its hangover: bounded
        within(S, "hangover_s", self.hangover_s, 0.01, 5.0)?;
        within(S, "min_voiced_s", self.min_voiced_s, 0.0, 1.0)?;
        within(S, "padding_s", self.padding_s, 0.0, 2.0)?;
        within(S, "min_hand_confidence", self.min_hand_confidence, 0.0, 1.0)?;
        within(
            S,
            "skeleton_max_age_ms",
            self.skeleton_max_age_ms,
            1.0,
            60_000.0,
        )?;
        Ok(())
    }
}

/// Where `audio/mic`'s audio comes from.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum AudioSource {
    /// the simulated cell: background noise and the scenario's `[[voice]]` lines
    Sim,
    /// recordings: the WAV files of `wav_dir`, in name order
    WavDir,
}

/// `[audio]`: the microphone stand-in `phri-mic`.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct AudioConfig {
    /// the simulated room or recordings
    pub source: AudioSource,
    /// with `source = "wav_dir"`: 16 kHz mono 16-bit WAV files, played in name order
    pub wav_dir: String,
    /// silence between two files \[s\]
    pub wav_gap_s: f64,
    /// start again after the last file
    pub wav_loop: bool,
    /// background noise of the simulated room [dBFS RMS] (a quiet room's
    /// microphone: about −60)
    pub noise_dbfs: f64,
    /// noise seed
    pub seed: u64,
}

impl AudioConfig {
    /// Range checks of every field; `wav_dir` given when it is the source.
    pub fn validate(&self) -> Result<(), Invalid> {
        const S: &str = "audio";
        if self.source == AudioSource::WavDir && self.wav_dir.trim().is_empty() {
            return Err(Invalid::new(
                "audio.wav_dir",
                "source = \"wav_dir\" needs a directory",
            ));
        }
        non_negative(S, "wav_gap_s", self.wav_gap_s)?;
        within(S, "noise_dbfs", self.noise_dbfs, -120.0, -10.0)?;
        Ok(())
    }
}

/// Where `phri-mic` takes its sound from (`[mic] source`).
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum MicSource {
    /// the stand-in of `[audio]` (the simulated room or recordings)
    #[default]
    Sim,
    /// a real microphone through ALSA
    Alsa,
}

impl MicSource {
    /// The name in `[mic] source`: `sim` or `alsa`.
    pub fn name(self) -> &'static str {
        match self {
            MicSource::Sim => "sim",
            MicSource::Alsa => "alsa",
        }
    }
}

/// `[mic]`: the microphone behind `audio/mic`.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct MicConfig {
    /// the stand-in of `[audio]` or a real microphone
    pub source: MicSource,
    /// `source = "alsa"`: the ALSA capture device (`arecord -L` lists them)
    pub device: String,
}

impl MicConfig {
    /// `device` names an ALSA device: 1-256 printable characters.
    pub fn validate(&self) -> Result<(), Invalid> {
        let d = self.device.trim();
        if d.is_empty() || d.len() > 256 || d.chars().any(|c| c.is_control()) {
            return Err(Invalid::new(
                "mic.device",
                "must name an ALSA device (1-256 printable characters, e.g. \"default\", \"hw:1,0\")",
            ));
        }
        Ok(())
    }
}
