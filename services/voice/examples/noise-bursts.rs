//! Write issue 26's noise probe as WAV files (16 kHz mono 16 bit, as the
//! voice fixtures): 30 bursts of 0.6 s ([`phri_voice::bursts`]) with 0.3 s
//! of background either side, at three levels (RMS over the burst: −40,
//! −28 (speech-like: the fixtures' speech), −16 dBFS), over digital silence and a −60 dBFS
//! room; then feed them to `phri-voice --wav`:
//!
//! ```text
//! cargo run --release -p phri-voice --example noise-bursts -- /tmp/bursts
//! target/release/phri-voice --wav /tmp/bursts/l28_room_*.wav
//! ```

use std::path::PathBuf;
use std::process::ExitCode;

use phri_voice::bursts::{kind_of, recording};

/// The set's seed (the test uses the same).
const SEED: u64 = 26;

fn main() -> ExitCode {
    let Some(dir) = std::env::args_os().nth(1).map(PathBuf::from) else {
        eprintln!("usage: noise-bursts OUT_DIR [BURSTS_PER_SET (30)]");
        return ExitCode::from(2);
    };
    let count = match std::env::args().nth(2).map(|a| a.parse::<usize>()) {
        None => 30,
        Some(Ok(n)) => n,
        Some(Err(e)) => {
            eprintln!("noise-bursts: BURSTS_PER_SET: {e}");
            return ExitCode::from(2);
        }
    };
    if let Err(e) = std::fs::create_dir_all(&dir) {
        eprintln!("noise-bursts: {}: {e}", dir.display());
        return ExitCode::from(2);
    }
    let spec = hound::WavSpec {
        channels: 1,
        sample_rate: phri_ipc::AUDIO_RATE_HZ,
        bits_per_sample: 16,
        sample_format: hound::SampleFormat::Int,
    };
    let mut n = 0;
    for level in [-40.0, -28.0, -16.0] {
        for (bg_name, bg) in [("silence", None), ("room", Some(-60.0))] {
            for k in 0..count {
                let audio = recording(SEED, k, level, bg, 0.3);
                let path = dir.join(format!(
                    "l{:02}_{bg_name}_{k:03}_{}.wav",
                    -level as i32,
                    kind_of(k).name()
                ));
                let written = hound::WavWriter::create(&path, spec).and_then(|mut w| {
                    audio.iter().try_for_each(|&s| w.write_sample(s))?;
                    w.finalize()
                });
                if let Err(e) = written {
                    eprintln!("noise-bursts: {}: {e}", path.display());
                    return ExitCode::from(2);
                }
                n += 1;
            }
        }
    }
    eprintln!("noise-bursts: {n} files in {}", dir.display());
    ExitCode::SUCCESS
}
