//! `phri-voice`: voice commands. As a service: `audio/mic` → utterances →
//! `hri/request` (source `voice`) and `voice/utterance` (every utterance and
//! its verdict), gating `follow` on `perception/skeleton`. With
//! `--wav FILE...`: decode recordings and print one JSON line per utterance.

use std::error::Error;
use std::path::PathBuf;
use std::process::ExitCode;
use std::time::Duration;

use phri_ipc::{
    AudioChunk, CollabPart, Utterance, VoiceIntent, VoiceVerdict, Zeroed, AUDIO_CHUNK_SAMPLES,
    AUDIO_MIC, AUDIO_RATE_HZ, HRI_REQUEST, PERCEPTION_SKELETON, VOICE_UTTERANCE,
};
use phri_runtime::{now_ns, ServiceContext};
use phri_voice::{wav, Hands, Listener};

const ABOUT: &str = "Voice commands for the phri cell (pocketsphinx, offline): audio/mic → hri/request and voice/utterance";

const LONG_ABOUT: &str = "\
Voice commands for the phri cell (pocketsphinx, offline).

As a service: audio/mic → hri/request (source voice) and voice/utterance.
With --wav FILE...: decode recordings (16 kHz mono 16-bit WAV) and print one
JSON line per utterance: file, text (empty when refused), intent, score,
start_s, end_s, verdict (not_speech: no voicing, refused before decoding),
voiced_s (the longest voiced stretch), decode_ms; a file where nothing was
heard gets one line with verdict nothing_heard. Then a summary on stderr
(decoding cost against real time, utterances refused as not speech). The
hand gate is off: no scene to look at.

The grammar: follow [the] (right | left) hand | begin collaboration |
end collaboration | stop. Settings: [voice] in deploy/phri.toml.
Needs Debian's libpocketsphinx-dev and pocketsphinx-en-us.";

/// phri-voice's own flag.
#[derive(clap::Args, Debug)]
struct WavMode {
    /// Decode these recordings and print one JSON line per utterance instead of running the service
    #[arg(long, value_name = "FILE", num_args = 1..)]
    wav: Vec<PathBuf>,
}

fn main() -> ExitCode {
    let (flags, WavMode { wav }) =
        phri_runtime::cli::parse_service_with::<WavMode>("phri-voice", ABOUT, Some(LONG_ABOUT));
    if !wav.is_empty() {
        return match wav_mode(&flags, &wav) {
            Ok(()) => ExitCode::SUCCESS,
            Err(e) => {
                eprintln!("phri-voice: {e}");
                ExitCode::from(2)
            }
        };
    }
    phri_runtime::service::run("phri-voice", || body(flags))
}

/// `--wav FILE... [--config FILE] [--set k=v]...`
fn wav_mode(
    flags: &phri_runtime::cli::ServiceFlags,
    files: &[PathBuf],
) -> Result<(), Box<dyn Error>> {
    let config = &flags.config;
    let sets: Vec<&str> = flags.set.iter().map(String::as_str).collect();
    let loaded = if config.exists() {
        phri_config::Loaded::load(config, None, &sets)?
    } else {
        phri_config::Loaded::load_text("", config, None, &sets)?
    };
    let cfg = &loaded.config.voice;
    let mut listener = Listener::new(cfg)?;
    let mut latencies = Vec::new();
    let mut utterances = 0usize;
    for file in files {
        let audio = wav::read(file)?;
        let mut chunk = AudioChunk::zeroed();
        chunk.rate_hz = AUDIO_RATE_HZ;
        let before = utterances;
        let mut emit = |h: phri_voice::Heard, voicing: Option<phri_voice::Voicing>| {
            utterances += 1;
            latencies.push(h.utterance.decode_ms);
            println!("{}", line(file, &h.utterance, voicing));
        };
        for (k, samples) in audio.chunks(AUDIO_CHUNK_SAMPLES).enumerate() {
            chunk.seq = k as u64 + 1;
            chunk.capture_ns =
                (k * AUDIO_CHUNK_SAMPLES) as u64 * 1_000_000_000 / AUDIO_RATE_HZ as u64;
            chunk.samples = samples.len() as u32;
            chunk.pcm[..samples.len()].copy_from_slice(samples);
            if let Some(h) = listener.step(&chunk, &Hands::ANYONE, now_ns)? {
                emit(h, listener.last_voicing);
            }
        }
        if let Some(h) = listener.finish(&Hands::ANYONE, now_ns)? {
            emit(h, listener.last_voicing);
        }
        if utterances == before {
            println!(
                "{}",
                serde_json::json!({
                    "file": file.display().to_string(),
                    "text": "",
                    "intent": "none",
                    "verdict": "nothing_heard",
                })
            );
        }
    }
    latencies.sort_by(f64::total_cmp);
    let pct = |p: f64| {
        latencies
            .get(((latencies.len().max(1) - 1) as f64 * p).round() as usize)
            .copied()
            .unwrap_or(0.0)
    };
    eprintln!(
        "phri-voice: {} file(s), {utterances} utterance(s), {} refused as not speech: decoded {:.1} s of audio in {:.3} s = {:.3}× real time; decode p50 {:.0} ms, max {:.0} ms",
        files.len(),
        listener.not_speech,
        listener.audio_s,
        listener.decode_s,
        listener.decode_s / listener.audio_s.max(1e-9),
        pct(0.5),
        pct(1.0),
    );
    Ok(())
}

fn line(file: &std::path::Path, u: &Utterance, voicing: Option<phri_voice::Voicing>) -> String {
    let verdict = VoiceVerdict::try_from(u.verdict).unwrap_or(VoiceVerdict::NoMatch);
    let text = if verdict == VoiceVerdict::Accepted || verdict == VoiceVerdict::HandNotTracked {
        phri_ipc::json::c_str(&u.text)
    } else {
        String::new()
    };
    serde_json::json!({
        "file": file.display().to_string(),
        "text": text,
        "intent": VoiceIntent::name_of(u.intent),
        "heard": phri_ipc::json::c_str(&u.text),
        "score": (u.score * 100.0).round() / 100.0,
        "start_s": (u.start_ns as f64 * 1e-6).round() / 1e3,
        "end_s": (u.end_ns as f64 * 1e-6).round() / 1e3,
        "verdict": verdict.name(),
        "voiced_s": voicing.map(|v| (v.longest_s() * 100.0).round() / 100.0),
        "decode_ms": (u.decode_ms * 10.0).round() / 10.0,
    })
    .to_string()
}

fn body(flags: phri_runtime::cli::ServiceFlags) -> Result<(), Box<dyn Error>> {
    let ctx = ServiceContext::from_flags("voice", flags)?;
    let cfg = ctx.config().voice.clone();
    let mut listener = Listener::new(&cfg)?;
    // numbers that grow across restarts: microseconds of CLOCK_MONOTONIC
    listener.number_after(now_ns() / 1_000);
    if ctx.checking() {
        return Ok(());
    }
    // audio only from the microphone the supervisor started (counted on audit/inputs)
    let owners = ctx.watch_inputs();
    ctx.start_deadman()?;
    let node = ctx.node()?;
    let audio = AUDIO_MIC.waking_subscriber(&node, phri_ipc::Queue::Drain)?;
    let mut skeletons = PERCEPTION_SKELETON.latest_reader(&node)?;
    let requests = HRI_REQUEST.publisher(&node)?;
    let utterances = VOICE_UTTERANCE.publisher(&node)?;
    let mut beat = ctx.beat(&node)?;
    let max_age_ns = (cfg.skeleton_max_age_ms * 1e6) as u64;
    let mut last_seq = 0u64;
    let mut lost = 0u64;
    let mut refused = 0u64;
    let mut latencies: Vec<f64> = Vec::new();
    while !ctx.shutdown.requested() {
        // a wait ended early (a signal, a failed wake-up) is one more poll
        let _ = audio.wait(Duration::from_millis(100));
        beat.beat(now_ns());
        let mut heard = Vec::new();
        let mut failure = None;
        skeletons.update()?;
        let hands = Hands::of(skeletons.get(), now_ns(), max_age_ns);
        audio.drain_from(|pid, chunk| {
            if !owners.admit(phri_ipc::Owned::AUDIO_MIC, pid).accepted() {
                return;
            }
            if last_seq != 0 && chunk.seq > last_seq + 1 {
                lost += chunk.seq - last_seq - 1;
            }
            last_seq = chunk.seq;
            if chunk.rate_hz != AUDIO_RATE_HZ || chunk.samples as usize > AUDIO_CHUNK_SAMPLES {
                // another rate, or more samples than a chunk holds: refused whole
                if refused == 0 {
                    tracing::warn!(
                        "{}: refusing chunk {} ({} Hz, {} samples): phri needs {AUDIO_RATE_HZ} Hz, at most {AUDIO_CHUNK_SAMPLES} samples",
                        AUDIO_MIC.name, chunk.seq, chunk.rate_hz, chunk.samples
                    );
                }
                refused += 1;
                return;
            }
            match listener.step(chunk, &hands, now_ns) {
                Ok(Some(h)) => heard.push(h),
                Ok(None) => {}
                Err(e) => failure = Some(e),
            }
        })?;
        if let Some(e) = failure {
            return Err(e.into());
        }
        for h in heard {
            if let Some(r) = h.request {
                requests.publish(&r)?;
                latencies.push(r.stamp_ns.saturating_sub(r.utterance_end_ns) as f64 * 1e-6);
            }
            utterances.publish(&h.utterance)?;
            tracing::info!("{}", describe(&h.utterance));
        }
    }
    latencies.sort_by(f64::total_cmp);
    let not_speech = listener.not_speech;
    if listener.audio_s <= 0.0 {
        tracing::info!("no speech heard ({not_speech} utterance(s) refused as not speech); {lost} audio chunk(s) lost, {refused} refused");
        return Ok(());
    }
    tracing::info!(
        "decoding cost {:.3}× real time ({:.1} s of utterances in {:.2} s); utterance end → request p50 {:.0} ms, max {:.0} ms over {} request(s); {not_speech} utterance(s) refused as not speech; {lost} audio chunk(s) lost, {refused} refused",
        listener.decode_s / listener.audio_s.max(1e-9),
        listener.audio_s,
        listener.decode_s,
        latencies.get(latencies.len() / 2).copied().unwrap_or(0.0),
        latencies.last().copied().unwrap_or(0.0),
        latencies.len(),
    );
    Ok(())
}

fn describe(u: &Utterance) -> String {
    let verdict = VoiceVerdict::name_of(u.verdict);
    if u.verdict == VoiceVerdict::NotSpeech as u32 {
        return format!(
            "heard {:.2} s of sound without voicing (noise, a rattle): not decoded: {verdict}",
            u.end_ns.saturating_sub(u.start_ns) as f64 * 1e-9
        );
    }
    let text = phri_ipc::json::c_str(&u.text);
    let what = match VoiceIntent::try_from(u.intent)
        .ok()
        .and_then(VoiceIntent::request)
    {
        Some((kind, part)) if part != CollabPart::None => {
            format!("{} {}", kind.name(), part.name())
        }
        Some((kind, _)) => kind.name().to_string(),
        None => "nothing".into(),
    };
    format!(
        "heard '{text}' ({:.2} s, score {:.1}, decoded in {:.0} ms): {what}: {verdict}",
        u.end_ns.saturating_sub(u.start_ns) as f64 * 1e-9,
        u.score,
        u.decode_ms
    )
}
