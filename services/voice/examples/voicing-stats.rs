//! Tuning: the voicing measure of every utterance the segmenter finds in
//! the WAV files given, one line each (file, segment kind, longest voiced
//! run, voiced frames, frames); with FRAMES=1 in the environment a second
//! line per utterance gives every frame as correlation/faster/pitch@dB.
//!
//! ```text
//! cargo run --release -p phri-voice --example voicing-stats -- tests/fixtures/voice/*.wav
//! ```

use phri_voice::voicing::VoicingMeter;
use phri_voice::{wav, SegmentKind, Segmenter};

fn main() {
    let cfg = phri_config::Config::defaults().voice;
    let mut seg = Segmenter::new(&cfg);
    let mut meter = VoicingMeter::with_capacity(16000 * 5);
    let verbose = std::env::var_os("FRAMES").is_some();
    let (mut audio_s, mut took_s, mut n) = (0.0, 0.0, 0usize);
    for f in std::env::args().skip(1) {
        let Ok(audio) = wav::read(std::path::Path::new(&f)) else {
            eprintln!("{f}: unreadable");
            continue;
        };
        let mut show = |s: phri_voice::Segment, a: &[i16]| {
            let t0 = std::time::Instant::now();
            let v = meter.measure(a);
            took_s += t0.elapsed().as_secs_f64();
            audio_s += a.len() as f64 / 16000.0;
            n += 1;
            let mut peaks = Vec::new();
            meter.measure_frames(a, |f| peaks.push(*f));
            println!(
                "{} {:?} {} {} {}",
                f.rsplit('/').next().unwrap_or(&f),
                s.kind,
                v.longest_run,
                v.voiced,
                v.frames,
            );
            if verbose {
                let p: Vec<String> = peaks
                    .iter()
                    .map(|f| {
                        format!(
                            "{:.2}/{:.2}/{:.0}@{:.0}",
                            f.correlation, f.faster, f.pitch_hz, f.db
                        )
                    })
                    .collect();
                println!("  {}", p.join(" "));
            }
        };
        for (k, c) in audio.chunks(320).enumerate() {
            if let Some(s) = seg.push(c, k as u64 * 20_000_000) {
                if s.kind == SegmentKind::Speech {
                    show(s, seg.audio());
                }
            }
        }
        if let Some(s) = seg.finish() {
            if s.kind == SegmentKind::Speech {
                show(s, seg.audio());
            }
        }
    }
    eprintln!(
        "{n} utterance(s), {audio_s:.1} s of audio analysed in {:.1} ms ({:.4}× real time, {:.2} ms per utterance)",
        took_s * 1e3,
        took_s / audio_s.max(1e-9),
        took_s * 1e3 / n.max(1) as f64
    );
}
