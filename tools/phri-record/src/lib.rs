//! Shared parts of `phri-record`, `phri-replay` and `phri-plot`: message ↔ JSON
//! conversion, the MCAP conventions of a recording, a tiny line plotter, and
//! what `phri-plot` reads of a recording ([`series`]) and draws ([`figures`]),
//! and `phri-record`'s recorders, file and loop ([`recorder`]).

pub mod config;
pub mod figures;
pub mod foxglove;
pub mod json;
pub mod plot;
pub mod progress;
pub mod recorder;
pub mod series;
pub mod svg;
pub mod text;

use phri_ipc::{visit_named, Channel, ChannelVisitor, FrameChannel, Message};

/// MCAP profile written in the header (none of the well-known ones apply).
pub const PROFILE: &str = "";
/// Message encoding of every channel.
pub const ENCODING: &str = "json";
/// Name of the metadata record describing the recording.
pub const METADATA_NAME: &str = "phri-record";
/// Depth frames are downsampled by this factor per axis unless
/// `[record] frame_downsample` or `--frame-downsample` says otherwise.
pub const FRAME_DOWNSAMPLE: usize = 4;

/// Channels carrying depth frames (recorded downsampled, never replayed).
pub fn is_frame_channel(name: &str) -> bool {
    struct Frames(bool);
    impl ChannelVisitor for Frames {
        fn message<T: Message>(&mut self, _: Channel<T>) {}
        fn frames(&mut self, _: FrameChannel) {
            self.0 = true;
        }
    }
    let mut f = Frames(false);
    visit_named(name, &mut f);
    f.0
}

/// A recording that cannot be read.
#[derive(Debug, thiserror::Error)]
pub enum ReadError {
    #[error("cannot read '{path}': {source}")]
    Io {
        path: String,
        #[source]
        source: std::io::Error,
    },
    #[error("{path}: {source}")]
    Mcap {
        path: String,
        #[source]
        source: mcap::McapError,
    },
    /// a message of the recording is not JSON
    #[error("{path}: {topic} message {sequence}: {source}")]
    Json {
        path: String,
        topic: String,
        sequence: u32,
        #[source]
        source: serde_json::Error,
    },
}

impl ReadError {
    /// An MCAP error of the recording at `path`.
    pub fn mcap(path: &str) -> impl FnOnce(mcap::McapError) -> ReadError + '_ {
        move |source| ReadError::Mcap {
            path: path.to_string(),
            source,
        }
    }
}

/// Read a whole recording into memory.
pub fn read_file(path: &str) -> Result<Vec<u8>, ReadError> {
    std::fs::read(path).map_err(|source| ReadError::Io {
        path: path.to_string(),
        source,
    })
}
