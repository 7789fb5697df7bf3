//! The WAV-directory source through the real processes: `phri-mic` replays
//! recordings on `audio/mic` (wall clock), `phri-voice` hears them, gates
//! `follow` on the (absent) skeleton and publishes `stop` on `hri/request`
//! with the utterance's end; every utterance is a `voice/utterance`.

use std::process::{Child, Command, Stdio};
use std::time::{Duration, Instant};

use phri_ipc::{Queue, RequestKind, VoiceIntent, VoiceVerdict, HRI_REQUEST, VOICE_UTTERANCE};

#[path = "../../../tests/support/workspace.rs"]
mod workspace;
use workspace::repo;

fn start(bin: &str, prefix: &str, sets: &[String]) -> Child {
    let mut cmd = Command::new(bin);
    cmd.current_dir(repo())
        .arg("--config")
        .arg(repo().join("deploy/phri.toml"))
        .args(["--prefix", prefix]);
    for s in sets {
        cmd.arg("--set").arg(s);
    }
    cmd.stdout(Stdio::null())
        .stderr(Stdio::inherit())
        .spawn()
        .unwrap()
}

fn stop(mut c: Child) {
    let _ = Command::new("kill")
        .args(["-TERM", &c.id().to_string()])
        .status();
    let _ = c.wait();
}

#[test]
fn recordings_replayed_on_audio_mic_are_heard_gated_and_requested() {
    let prefix = format!("tv{}wav_", std::process::id());
    let dir = std::env::temp_dir().join(format!("phri-voice-wavdir-{}", std::process::id()));
    let _ = std::fs::remove_dir_all(&dir);
    std::fs::create_dir_all(&dir).unwrap();
    let fixtures = repo().join("tests/fixtures/voice");
    // name order: the follow first, then the stop
    std::fs::copy(
        fixtures.join("follow-the-left-hand_en-us_140.wav"),
        dir.join("1.wav"),
    )
    .unwrap();
    std::fs::copy(fixtures.join("stop_en-us_140.wav"), dir.join("2.wav")).unwrap();
    std::fs::write(dir.join("notes.txt"), "not audio").unwrap();
    let node = phri_ipc::node("wav-dir-test", &prefix).unwrap();
    let utterances = VOICE_UTTERANCE.subscriber(&node, Queue::Drain).unwrap();
    let requests = HRI_REQUEST.subscriber(&node, Queue::Drain).unwrap();
    let voice = start(env!("CARGO_BIN_EXE_phri-voice"), &prefix, &[]);
    // the recogniser subscribes before the first word is played
    std::thread::sleep(Duration::from_millis(1500));
    let mic = start(
        env!("CARGO_BIN_EXE_phri-mic"),
        &prefix,
        &[
            "audio.source=\"wav_dir\"".into(),
            format!("audio.wav_dir=\"{}\"", dir.display()),
            "audio.wav_gap_s=1.0".into(),
        ],
    );
    let mut heard = Vec::new();
    let mut asked = Vec::new();
    let deadline = Instant::now() + Duration::from_secs(20);
    while heard.len() < 2 && Instant::now() < deadline {
        std::thread::sleep(Duration::from_millis(50));
        utterances.drain(|u| heard.push(*u)).unwrap();
        requests.drain(|r| asked.push(*r)).unwrap();
    }
    std::thread::sleep(Duration::from_millis(200));
    requests.drain(|r| asked.push(*r)).unwrap();
    stop(mic);
    stop(voice);
    drop((utterances, requests, node));
    let _ = phri_ipc::remove_leftovers(&prefix);
    let _ = std::fs::remove_dir_all(&dir);
    let summary: Vec<(&str, &str)> = heard
        .iter()
        .map(|u| {
            (
                VoiceIntent::name_of(u.intent),
                VoiceVerdict::name_of(u.verdict),
            )
        })
        .collect();
    assert_eq!(
        summary,
        [
            ("follow_left_hand", "hand_not_tracked"),
            ("stop", "accepted")
        ],
        "no skeleton here: the follow is gated, the stop goes through"
    );
    assert_eq!(asked.len(), 1, "{asked:?}");
    let r = asked[0];
    assert_eq!(r.kind, RequestKind::Stop as u32);
    assert_eq!(r.seq, heard[1].request_seq);
    assert_eq!(r.utterance_end_ns, heard[1].end_ns);
    let latency_ms = r.stamp_ns.saturating_sub(r.utterance_end_ns) as f64 * 1e-6;
    assert!(latency_ms > 0.0 && latency_ms < 1000.0, "{latency_ms} ms");
    // the speech is where the files put it: 1 s of gap, 0.3 s of silence in the file
    let d = heard[1].end_ns.saturating_sub(heard[1].start_ns) as f64 * 1e-9;
    assert!(d > 0.2 && d < 1.2, "stop lasted {d} s");
}
