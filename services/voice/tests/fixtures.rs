//! Recognition on the committed fixtures (tests/fixtures/voice: espeak-ng
//! speech, 3 voices × 2 speeds, clean and with white noise at 20, 13 and
//! 7 dB SNR, and out-of-grammar sentences), through the service's own
//! segmenter and recogniser. Issue 12's figures:
//! - ≥ 90 % of clean commands recognised exactly, none as another command
//!   than `stop`; ≥ 80 % at 13 dB;
//! - no speech is taken for noise (issue 26's voicing check): no fixture,
//!   down to 7 dB SNR, is refused as `not_speech`;
//! - out-of-grammar speech never starts a collaboration, the hand gate
//!   included: no out-of-grammar sentence passes as `begin` (the ungated
//!   start), and the `follow`s that pass the score are refused unless the
//!   named hand is tracked.
//!
//! Needs Debian's `libpocketsphinx-dev` and `pocketsphinx-en-us` (the
//! README's test command installs them); without them this test fails.

use std::path::{Path, PathBuf};

use phri_ipc::{AudioChunk, VoiceIntent, VoiceVerdict, Zeroed, AUDIO_CHUNK_SAMPLES, AUDIO_RATE_HZ};
use phri_voice::{wav, Hands, Listener};

fn fixtures() -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR")).join("../../tests/fixtures/voice")
}

#[derive(serde::Deserialize)]
struct Manifest {
    utterances: Vec<Entry>,
}

#[derive(serde::Deserialize)]
struct Entry {
    file: String,
    text: String,
    intent: String,
    snr_db: Option<f64>,
    in_grammar: bool,
}

/// Every utterance of a file: (intent heard, verdict).
fn hear(listener: &mut Listener, file: &Path, hands: &Hands) -> Vec<(VoiceIntent, VoiceVerdict)> {
    let audio = wav::read(file).unwrap_or_else(|e| panic!("{e}"));
    let mut chunk = AudioChunk::zeroed();
    chunk.rate_hz = AUDIO_RATE_HZ;
    let mut out = Vec::new();
    let mut take = |h: Option<phri_voice::Heard>| {
        if let Some(h) = h {
            let u = h.utterance;
            out.push((
                VoiceIntent::try_from(u.intent).unwrap(),
                VoiceVerdict::try_from(u.verdict).unwrap(),
            ));
        }
    };
    for (k, s) in audio.chunks(AUDIO_CHUNK_SAMPLES).enumerate() {
        chunk.seq = k as u64 + 1;
        chunk.capture_ns = (k * AUDIO_CHUNK_SAMPLES) as u64 * 62_500;
        chunk.samples = s.len() as u32;
        chunk.pcm[..s.len()].copy_from_slice(s);
        take(listener.step(&chunk, hands, || 0).unwrap());
    }
    take(listener.finish(hands, || 0).unwrap());
    out
}

#[test]
fn commands_are_recognised_and_out_of_grammar_speech_never_starts_a_collaboration() {
    let dir = fixtures();
    let manifest: Manifest = serde_json::from_str(
        &std::fs::read_to_string(dir.join("manifest.json"))
            .expect("tests/fixtures/voice/manifest.json"),
    )
    .expect("manifest.json");
    let cfg = phri_config::Config::defaults().voice;
    let mut listener = Listener::new(&cfg).unwrap_or_else(|e| panic!("{e}"));
    let nobody = Hands::default();
    // per SNR (None: clean): (exact, total)
    let mut exact: std::collections::BTreeMap<Option<i64>, (usize, usize)> = Default::default();
    let mut confused = Vec::new();
    let mut not_speech = Vec::new();
    let mut oog_begin = Vec::new();
    let mut oog_follow_scored = Vec::new();
    let mut oog_started_gated = Vec::new();
    for e in &manifest.utterances {
        let file = dir.join(&e.file);
        let heard = hear(&mut listener, &file, &Hands::ANYONE);
        if heard.iter().any(|(_, v)| *v == VoiceVerdict::NotSpeech) {
            not_speech.push(e.file.clone());
        }
        let accepted: Vec<VoiceIntent> = heard
            .iter()
            .filter(|(_, v)| *v == VoiceVerdict::Accepted)
            .map(|(i, _)| *i)
            .collect();
        if e.in_grammar {
            let slot = exact.entry(e.snr_db.map(|s| s as i64)).or_default();
            slot.1 += 1;
            if accepted.len() == 1 && accepted[0].name() == e.intent {
                slot.0 += 1;
            }
            if e.snr_db.is_none()
                && accepted
                    .iter()
                    .any(|i| i.name() != e.intent && *i != VoiceIntent::Stop)
            {
                confused.push((e.file.clone(), accepted.clone()));
            }
        } else {
            if accepted.contains(&VoiceIntent::Begin) {
                oog_begin.push(e.file.clone());
            }
            if accepted.iter().any(|i| {
                matches!(
                    i,
                    VoiceIntent::FollowRightHand | VoiceIntent::FollowLeftHand
                )
            }) {
                oog_follow_scored.push(format!("{} ({})", e.file, e.text));
            }
            // the same speech where the named hand is not tracked: the gate
            let gated = hear(&mut listener, &file, &nobody);
            if gated.iter().any(|(i, v)| {
                *v == VoiceVerdict::Accepted
                    && matches!(
                        i,
                        VoiceIntent::FollowRightHand | VoiceIntent::FollowLeftHand
                    )
            }) {
                oog_started_gated.push(e.file.clone());
            }
        }
    }
    let rate = |snr: Option<i64>| {
        let (ok, n) = exact[&snr];
        ok as f64 / n as f64
    };
    for (snr, (ok, n)) in &exact {
        let label = snr.map_or("clean".to_string(), |s| format!("{s} dB"));
        println!("{label}: {ok}/{n} recognised exactly");
    }
    println!(
        "out of grammar: {} passed as begin, {} passed the score as follow (refused by the gate unless that hand is tracked): {:?}",
        oog_begin.len(),
        oog_follow_scored.len(),
        oog_follow_scored
    );
    assert!(
        not_speech.is_empty(),
        "speech refused as not speech: {not_speech:?}"
    );
    assert!(rate(None) >= 0.9, "clean: {:.0} %", 100.0 * rate(None));
    assert!(
        rate(Some(13)) >= 0.8,
        "13 dB: {:.0} %",
        100.0 * rate(Some(13))
    );
    assert!(
        confused.is_empty(),
        "clean commands heard as another: {confused:?}"
    );
    assert!(
        oog_begin.is_empty(),
        "out-of-grammar speech passed as begin: {oog_begin:?}"
    );
    assert!(
        oog_started_gated.is_empty(),
        "the gate let through: {oog_started_gated:?}"
    );
}
