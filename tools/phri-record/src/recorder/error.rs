//! Why `phri-record` could not start or stopped writing.

use phri_ipc::IpcError;

/// A recording refused or broken; each message names the flag or the file.
#[derive(Debug, thiserror::Error)]
pub enum RecordError {
    /// a flag (or its `[record]` key) out of range: `--flag: why`
    #[error("{0}")]
    Flag(String),
    /// `--config` unreadable or invalid
    #[error("--config {path}: {message}")]
    Config { path: String, message: String },
    #[error("no cell running under prefix '{prefix}' (no live iceoryx2 node)")]
    NoCell { prefix: String },
    #[error("--out: cannot create '{path}': {source}")]
    Create {
        path: String,
        #[source]
        source: std::io::Error,
    },
    #[error("mcap: {0}")]
    Mcap(#[from] mcap::McapError),
    /// a scene message that did not encode
    #[error("{topic}: {message}")]
    Scene { topic: String, message: String },
    #[error(transparent)]
    Ipc(#[from] IpcError),
}
