//! Why the recogniser, a recording or the audio source could not be used.

use std::path::PathBuf;

use crate::ffi::PACKAGES;

/// Why the recogniser or a recording could not be used.
#[derive(Debug, thiserror::Error)]
pub enum VoiceError {
    /// pocketsphinx's libraries, or one of their functions, could not be loaded
    #[error("{name}: cannot load pocketsphinx ({message}); install Debian's packages: apt-get install {PACKAGES}")]
    Library {
        /// the library file or the function
        name: &'static str,
        /// the loader's error
        message: String,
    },
    /// a file of the model is missing
    #[error("{}: {what} not found; install Debian's packages: apt-get install {PACKAGES}", path.display())]
    Model {
        /// the configured path
        path: PathBuf,
        /// which file: `acoustic model` or `dictionary`
        what: &'static str,
    },
    /// pocketsphinx refused an argument, a word, the grammar or a call: what failed
    #[error("pocketsphinx: {0}")]
    Decoder(String),
    /// a recording refused (not a WAV file, not 16 kHz mono 16-bit PCM, damaged),
    /// or a directory without one
    #[error("{}: {message}", path.display())]
    Wav {
        /// the file or directory
        path: PathBuf,
        /// what is wrong with it
        message: String,
    },
    /// a file or directory could not be read
    #[error("{}: {source}", path.display())]
    Io {
        /// the file or directory
        path: PathBuf,
        /// the system's error
        source: std::io::Error,
    },
}
