//! Why the recogniser, a recording or the audio source could not be used.

use std::path::PathBuf;

use crate::ffi::PACKAGES;

#[derive(Debug, thiserror::Error)]
pub enum VoiceError {
    #[error("{name}: cannot load pocketsphinx ({message}); install Debian's packages: apt-get install {PACKAGES}")]
    Library { name: &'static str, message: String },
    #[error("{}: {what} not found; install Debian's packages: apt-get install {PACKAGES}", path.display())]
    Model { path: PathBuf, what: &'static str },
    #[error("pocketsphinx: {0}")]
    Decoder(String),
    #[error("{}: {message}", path.display())]
    Wav { path: PathBuf, message: String },
    #[error("{}: {source}", path.display())]
    Io {
        path: PathBuf,
        source: std::io::Error,
    },
}
