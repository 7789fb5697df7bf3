//! Recordings: 16 kHz mono 16-bit PCM WAV files (what `audio/mic` carries).

use std::path::{Path, PathBuf};

use phri_ipc::AUDIO_RATE_HZ;

use crate::error::VoiceError;

/// Read a whole WAV file; anything but 16 kHz mono 16-bit PCM is refused, naming the file.
pub fn read(path: &Path) -> Result<Vec<i16>, VoiceError> {
    let bad = |message: String| VoiceError::Wav {
        path: path.to_path_buf(),
        message,
    };
    let mut reader = hound::WavReader::open(path).map_err(|e| match e {
        hound::Error::IoError(source) => VoiceError::Io {
            path: path.to_path_buf(),
            source,
        },
        e => bad(format!("not a WAV file: {e}")),
    })?;
    let spec = reader.spec();
    if spec.channels != 1
        || spec.sample_rate != AUDIO_RATE_HZ
        || spec.bits_per_sample != 16
        || spec.sample_format != hound::SampleFormat::Int
    {
        return Err(bad(format!(
            "{} Hz, {} channel(s), {} bit {:?}: phri needs {AUDIO_RATE_HZ} Hz mono 16-bit PCM (sox IN -r 16000 -c 1 -b 16 OUT.wav)",
            spec.sample_rate, spec.channels, spec.bits_per_sample, spec.sample_format
        )));
    }
    reader
        .samples::<i16>()
        .collect::<Result<Vec<i16>, _>>()
        .map_err(|e| bad(format!("damaged audio data: {e}")))
}

/// The `.wav` files of `dir`, in name order.
pub fn list(dir: &Path) -> Result<Vec<PathBuf>, VoiceError> {
    let io = |source| VoiceError::Io {
        path: dir.to_path_buf(),
        source,
    };
    let mut files: Vec<PathBuf> = std::fs::read_dir(dir)
        .map_err(io)?
        .filter_map(|e| e.ok().map(|e| e.path()))
        .filter(|p| p.extension().is_some_and(|e| e.eq_ignore_ascii_case("wav")))
        .collect();
    files.sort();
    if files.is_empty() {
        return Err(VoiceError::Wav {
            path: dir.to_path_buf(),
            message: "holds no .wav file".into(),
        });
    }
    Ok(files)
}
