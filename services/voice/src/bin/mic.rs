//! `phri-mic`: the microphone behind `audio/mic` (16 kHz mono 16-bit, 20 ms
//! chunks with capture times), and its figures on `audio/mic/status` (2 Hz
//! and at exit). `[mic] source = "alsa"` (or `--source alsa`): a real
//! microphone through ALSA (`phri_voice::capture`). `"sim"`: the stand-in
//! of `[audio]`: `source = "sim"`, the simulated room, background noise and
//! the scenario's `[[voice]]` recordings at their scenario times, paced by
//! the simulator's clock (`sim/world`); `"wav_dir"`: the recordings of a
//! directory in name order, paced by the wall clock.

use std::error::Error;
use std::path::Path;
use std::process::ExitCode;
use std::time::Duration;

use phri_config::{AudioSource, MicSource};
use phri_ipc::{
    AudioChunk, Zeroed, AUDIO_CHUNK_SAMPLES, AUDIO_MIC, AUDIO_MIC_STATUS, AUDIO_RATE_HZ, SIM_WORLD,
};
use phri_runtime::{now_ns, sleep_until_ns, ServiceContext};
use phri_voice::capture::Capture;
use phri_voice::mic::{due, Clip, MicFlags, MicStats, Playback, CHUNK_NS};
use phri_voice::wav;

/// Further behind than this, the mic skips ahead (a reader's queue holds 4 s) \[chunks\].
const MAX_BURST: u64 = 100;
/// A capture read waits this long for the device before the loop beats \[ms\].
const CAPTURE_WAIT_MS: u32 = 100;

fn main() -> ExitCode {
    phri_runtime::service::run("phri-mic", body)
}

fn body() -> Result<(), Box<dyn Error>> {
    let (ctx, flags) = ServiceContext::from_cli::<MicFlags>(
        "phri-mic",
        "mic",
        "The microphone behind audio/mic (16 kHz mono, 20 ms chunks), with its figures on audio/mic/status. [mic] source = \"alsa\" (or --source alsa) captures the ALSA device [mic] device (or --device): mono, resampled to 16 kHz; an overrun is counted, a device that disappears ends phri-mic (exit 2). \"sim\": the stand-in of [audio]: source = \"sim\" plays the scenario's [[voice]] lines (files under deploy/audio/) over background noise, on the simulator's clock; \"wav_dir\" replays [audio] wav_dir, paced by the wall clock.",
    )?;
    let mic = flags.apply(&ctx.config().mic)?;
    if mic.source == MicSource::Alsa {
        // the device is opened (and its format checked) by --check as well
        let capture = Capture::open(&mic.device)?;
        if ctx.checking() {
            return Ok(());
        }
        return alsa(&ctx, capture);
    }
    let cfg = ctx.config().audio.clone();
    let playback = match cfg.source {
        AudioSource::Sim => {
            let file = Path::new(&ctx.config().scenario.file);
            let mut clips = Vec::new();
            for line in &ctx.scenario().voice {
                let path = line.path(file);
                clips.push(Clip {
                    start: (line.t * AUDIO_RATE_HZ as f64).round() as u64,
                    samples: wav::read(&path)?,
                });
            }
            Playback::new(clips, cfg.noise_dbfs, cfg.seed)
        }
        AudioSource::WavDir => {
            let files = wav::list(Path::new(&cfg.wav_dir))?;
            let mut recordings = Vec::with_capacity(files.len());
            for f in &files {
                recordings.push(wav::read(f)?);
            }
            Playback::sequence(
                recordings,
                cfg.wav_gap_s,
                cfg.wav_loop,
                cfg.noise_dbfs,
                cfg.seed,
            )
        }
    };
    if ctx.checking() {
        return Ok(());
    }
    ctx.start_deadman()?;
    let node = ctx.node()?;
    let publisher = AUDIO_MIC.publisher(&node)?;
    let status = AUDIO_MIC_STATUS.publisher(&node)?;
    let mut stats = MicStats::new(MicSource::Sim, AUDIO_RATE_HZ);
    let mut beat = ctx.beat(&node)?;
    let mut chunk = AudioChunk::zeroed();
    chunk.rate_hz = AUDIO_RATE_HZ;
    chunk.samples = AUDIO_CHUNK_SAMPLES as u32;
    let mut publish = |k: u64, capture_ns: u64| -> Result<(), phri_ipc::IpcError> {
        chunk.seq += 1;
        chunk.capture_ns = capture_ns;
        playback.fill(k * AUDIO_CHUNK_SAMPLES as u64, &mut chunk.pcm);
        chunk.published_ns = now_ns();
        publisher.publish(&chunk)
    };
    let mut published = 0u64;
    let run: Result<(), Box<dyn Error>> = (|| {
        match cfg.source {
            AudioSource::Sim => {
                let dt_ns = (ctx.config().sim.dt_s * 1e9) as u64;
                let mut worlds = SIM_WORLD.latest_reader(&node)?;
                let mut next: Option<u64> = None;
                while !ctx.shutdown.requested() {
                    std::thread::sleep(Duration::from_millis(5));
                    beat.beat(now_ns());
                    if let Some(s) = stats.due(now_ns(), published, 0) {
                        status.publish(&s)?;
                    }
                    worlds.update()?;
                    let Some(w) = worlds.get() else { continue };
                    // scenario time: the simulator steps once per period from its epoch
                    let sim_ns = w.seq.saturating_sub(1) * dt_ns;
                    let now = now_ns();
                    let chunks = due(next, sim_ns, MAX_BURST);
                    next = Some(chunks.end);
                    for k in chunks {
                        // the chunk's first sample, on the wall clock
                        let ago = sim_ns - k * CHUNK_NS;
                        publish(k, now.saturating_sub(ago))?;
                        published += 1;
                    }
                }
            }
            AudioSource::WavDir => {
                let start = now_ns();
                let mut k = 0u64;
                while !ctx.shutdown.requested() {
                    let due_ns = start + (k + 1) * CHUNK_NS;
                    sleep_until_ns(due_ns);
                    beat.beat(now_ns());
                    if let Some(s) = stats.due(now_ns(), published, 0) {
                        status.publish(&s)?;
                    }
                    if now_ns() > due_ns + MAX_BURST * CHUNK_NS {
                        k = (now_ns() - start) / CHUNK_NS; // fell far behind: skip
                        continue;
                    }
                    publish(k, start + k * CHUNK_NS)?;
                    published += 1;
                    k += 1;
                }
            }
        }
        Ok(())
    })();
    status.publish(&stats.now(now_ns(), published, 0))?;
    run
}

/// A real microphone: chunks as the device delivers them.
fn alsa(ctx: &ServiceContext, mut capture: Capture) -> Result<(), Box<dyn Error>> {
    ctx.start_deadman()?;
    let node = ctx.node()?;
    let publisher = AUDIO_MIC.publisher(&node)?;
    let status = AUDIO_MIC_STATUS.publisher(&node)?;
    let mut stats = MicStats::new(MicSource::Alsa, capture.device_rate());
    let mut beat = ctx.beat(&node)?;
    tracing::info!(
        device = capture.device(),
        rate_hz = capture.device_rate(),
        channels = capture.channels(),
        format = capture.format().name(),
        "capturing"
    );
    let mut chunk = AudioChunk::zeroed();
    chunk.rate_hz = AUDIO_RATE_HZ;
    chunk.samples = AUDIO_CHUNK_SAMPLES as u32;
    let run: Result<(), Box<dyn Error>> = (|| {
        while !ctx.shutdown.requested() {
            beat.beat(now_ns());
            if let Some(capture_ns) = capture.next_chunk(&mut chunk.pcm, CAPTURE_WAIT_MS)? {
                chunk.seq += 1;
                chunk.capture_ns = capture_ns;
                chunk.published_ns = now_ns();
                publisher.publish(&chunk)?;
            }
            if let Some(s) = stats.due(now_ns(), chunk.seq, capture.overruns) {
                status.publish(&s)?;
            }
        }
        Ok(())
    })();
    status.publish(&stats.now(now_ns(), chunk.seq, capture.overruns))?;
    run
}
