//! `phri-voice --wav`: one JSON line per utterance, clear errors on bad input.

use std::path::{Path, PathBuf};
use std::process::Command;

fn fixture(name: &str) -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR"))
        .join("../../tests/fixtures/voice")
        .join(name)
}

fn voice(args: &[&str]) -> std::process::Output {
    Command::new(env!("CARGO_BIN_EXE_phri-voice"))
        .args(args)
        .current_dir(Path::new(env!("CARGO_MANIFEST_DIR")).join("../.."))
        .output()
        .expect("phri-voice runs")
}

#[test]
fn wav_files_print_one_json_line_per_utterance_and_the_cost() {
    let command = fixture("follow-the-left-hand_en-us_140.wav");
    let other = fixture("what-time-is-it_en-us_140.wav");
    let out = voice(&["--wav", command.to_str().unwrap(), other.to_str().unwrap()]);
    let stderr = String::from_utf8_lossy(&out.stderr);
    assert!(out.status.success(), "{stderr}");
    let lines: Vec<serde_json::Value> = String::from_utf8_lossy(&out.stdout)
        .lines()
        .map(|l| serde_json::from_str(l).expect("a JSON line"))
        .collect();
    assert_eq!(lines.len(), 2, "{lines:?}");
    let first = &lines[0];
    for key in ["file", "text", "intent", "score", "start_s", "end_s"] {
        assert!(first.get(key).is_some(), "{key} missing: {first}");
    }
    assert_eq!(first["text"], "follow the left hand");
    assert_eq!(first["intent"], "follow_left_hand");
    // the speech starts after the file's 0.3 s of silence and ends before its end
    let (s, e) = (
        first["start_s"].as_f64().unwrap(),
        first["end_s"].as_f64().unwrap(),
    );
    assert!(s > 0.2 && s < 0.5 && e > s + 0.8 && e < 2.6, "{first}");
    assert!(stderr.contains("× real time"), "{stderr}");
    assert!(first["voiced_s"].as_f64().unwrap() >= 0.1, "{first}");
}

fn write_wav(path: &Path, samples: &[i16]) {
    let spec = hound::WavSpec {
        channels: 1,
        sample_rate: 16_000,
        bits_per_sample: 16,
        sample_format: hound::SampleFormat::Int,
    };
    let mut w = hound::WavWriter::create(path, spec).unwrap();
    for &s in samples {
        w.write_sample(s).unwrap();
    }
    w.finalize().unwrap();
}

#[test]
fn noise_is_not_speech_and_silence_is_nothing_heard_each_file_with_its_verdict() {
    let dir = std::env::temp_dir().join(format!("phri-voice-noise-{}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    let noise = dir.join("burst.wav");
    write_wav(
        &noise,
        &phri_voice::bursts::recording(26, 1, -28.0, Some(-60.0), 0.3),
    );
    let silence = dir.join("silence.wav");
    write_wav(&silence, &[0; 16_000]);
    let out = voice(&["--wav", noise.to_str().unwrap(), silence.to_str().unwrap()]);
    let stderr = String::from_utf8_lossy(&out.stderr);
    assert!(out.status.success(), "{stderr}");
    let lines: Vec<serde_json::Value> = String::from_utf8_lossy(&out.stdout)
        .lines()
        .map(|l| serde_json::from_str(l).expect("a JSON line"))
        .collect();
    assert_eq!(lines.len(), 2, "{lines:?}");
    assert_eq!(lines[0]["verdict"], "not_speech", "{}", lines[0]);
    assert_eq!(lines[0]["text"], "");
    assert!(
        lines[0]["voiced_s"].as_f64().unwrap() < 0.08,
        "{}",
        lines[0]
    );
    assert_eq!(lines[1]["verdict"], "nothing_heard", "{}", lines[1]);
    assert!(stderr.contains("1 refused as not speech"), "{stderr}");
    let _ = std::fs::remove_dir_all(&dir);
}

#[test]
fn bad_files_are_refused_naming_them() {
    let dir = std::env::temp_dir().join(format!("phri-voice-cli-{}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    let junk = dir.join("junk.wav");
    std::fs::write(&junk, b"RIFF\x10\x00\x00\x00WAVEnot really").unwrap();
    let out = voice(&["--wav", junk.to_str().unwrap()]);
    let err = String::from_utf8_lossy(&out.stderr);
    assert_eq!(out.status.code(), Some(2), "{err}");
    assert!(
        err.contains("junk.wav") && err.lines().count() == 1,
        "{err}"
    );
    // 44.1 kHz stereo: refused with the conversion to use
    let stereo = dir.join("stereo.wav");
    let spec = hound::WavSpec {
        channels: 2,
        sample_rate: 44_100,
        bits_per_sample: 16,
        sample_format: hound::SampleFormat::Int,
    };
    let mut w = hound::WavWriter::create(&stereo, spec).unwrap();
    for _ in 0..1000 {
        w.write_sample(0i16).unwrap();
    }
    w.finalize().unwrap();
    let out = voice(&["--wav", stereo.to_str().unwrap()]);
    let err = String::from_utf8_lossy(&out.stderr);
    assert_eq!(out.status.code(), Some(2), "{err}");
    assert!(
        err.contains("stereo.wav") && err.contains("16000 Hz mono"),
        "{err}"
    );
    // a header that promises more audio than the file holds
    let cut = dir.join("cut.wav");
    let mut bytes = std::fs::read(fixture("stop_en-us_140.wav")).unwrap();
    bytes.truncate(bytes.len() / 2 + 1);
    std::fs::write(&cut, &bytes).unwrap();
    let out = voice(&["--wav", cut.to_str().unwrap()]);
    let err = String::from_utf8_lossy(&out.stderr);
    assert_eq!(out.status.code(), Some(2), "{err}");
    assert!(err.contains("cut.wav") && err.lines().count() == 1, "{err}");
    let out = voice(&["--wav", dir.join("missing.wav").to_str().unwrap()]);
    assert_eq!(out.status.code(), Some(2));
    assert!(String::from_utf8_lossy(&out.stderr).contains("missing.wav"));
    let out = voice(&["--wav"]);
    assert_eq!(out.status.code(), Some(2));
    let _ = std::fs::remove_dir_all(&dir);
}
