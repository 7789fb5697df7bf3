//! Issue 26, item 6: "a rattle is not a word". Noise bursts with a varying
//! envelope (white noise and clatters, [`phri_voice::bursts`], seeded) fed
//! in 20 ms chunks through the service's own step (segmenter, voicing,
//! decoder, verdict) are refused before decoding (`not_speech`): at most 1
//! of 30 may become a command, at speech-like, quieter and louder levels,
//! over digital silence and over a room's noise. Before the voicing check
//! 12 of the 30 speech-like bursts over a room were `stop`.
//!
//! Needs Debian's `libpocketsphinx-dev` and `pocketsphinx-en-us`, as
//! `tests/fixtures.rs`.

use phri_ipc::{AudioChunk, VoiceVerdict, Zeroed, AUDIO_CHUNK_SAMPLES, AUDIO_RATE_HZ};
use phri_voice::{bursts, Hands, Listener};

/// The set's seed (`examples/noise-bursts.rs` writes the same files).
const SEED: u64 = 26;

/// The verdicts of everything heard in `audio`, and the commands among them.
fn hear(listener: &mut Listener, audio: &[i16]) -> (Vec<VoiceVerdict>, usize) {
    let mut chunk = AudioChunk::zeroed();
    chunk.rate_hz = AUDIO_RATE_HZ;
    let mut verdicts = Vec::new();
    let mut commands = 0;
    let mut take = |h: Option<phri_voice::Heard>| {
        if let Some(h) = h {
            verdicts.push(VoiceVerdict::try_from(h.utterance.verdict).unwrap());
            commands += h.request.is_some() as usize;
        }
    };
    for (k, s) in audio.chunks(AUDIO_CHUNK_SAMPLES).enumerate() {
        chunk.seq = k as u64 + 1;
        chunk.capture_ns = (k * AUDIO_CHUNK_SAMPLES) as u64 * 62_500;
        chunk.samples = s.len() as u32;
        chunk.pcm[..s.len()].copy_from_slice(s);
        take(listener.step(&chunk, &Hands::ANYONE, || 0).unwrap());
    }
    take(listener.finish(&Hands::ANYONE, || 0).unwrap());
    (verdicts, commands)
}

#[test]
fn noise_bursts_are_refused_as_not_speech_at_any_level() {
    let cfg = phri_config::Config::defaults().voice;
    let mut listener = Listener::new(&cfg).unwrap_or_else(|e| panic!("{e}"));
    for level in [-40.0, -28.0, -16.0] {
        for (background, db) in [("silence", None), ("room", Some(-60.0))] {
            let mut commands = 0;
            let mut not_speech = 0;
            let mut heard = 0;
            for k in 0..30 {
                let audio = bursts::recording(SEED, k, level, db, 0.3);
                let (verdicts, c) = hear(&mut listener, &audio);
                commands += (c > 0) as usize;
                heard += !verdicts.is_empty() as usize;
                not_speech += verdicts
                    .iter()
                    .filter(|v| **v == VoiceVerdict::NotSpeech)
                    .count();
            }
            println!(
                "{level} dBFS over {background}: {heard}/30 heard, {not_speech} not speech, {commands} commands"
            );
            assert!(
                commands <= 1,
                "{level} dBFS over {background}: {commands} of 30 noise bursts became commands"
            );
            assert!(heard >= 25, "the segmenter hears the bursts: {heard}");
        }
    }
    assert!(listener.not_speech >= 150, "{}", listener.not_speech);
}

#[test]
fn a_command_after_the_noise_is_still_heard() {
    let cfg = phri_config::Config::defaults().voice;
    let mut listener = Listener::new(&cfg).unwrap_or_else(|e| panic!("{e}"));
    let fixtures =
        std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("../../tests/fixtures/voice");
    // a burst, a second of quiet, then "stop", in one stream
    let mut audio = bursts::recording(SEED, 0, -28.0, None, 1.0);
    audio.extend(phri_voice::wav::read(&fixtures.join("stop_en-us_140.wav")).unwrap());
    let (verdicts, commands) = hear(&mut listener, &audio);
    assert_eq!(
        verdicts,
        [VoiceVerdict::NotSpeech, VoiceVerdict::Accepted],
        "{verdicts:?}"
    );
    assert_eq!(commands, 1);
}
