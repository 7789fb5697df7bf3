//! Shared parts of `phri-record`, `phri-replay` and `phri-plot`: message ↔ JSON
//! conversion, the MCAP conventions of a recording, and a tiny line plotter.

pub mod config;
pub mod foxglove;
pub mod json;
pub mod plot;
pub mod text;

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
    name == phri_ipc::CAMERA_DEPTH || name == phri_ipc::PERCEPTION_DEPTH
}

/// Read a whole recording into memory.
pub fn read_file(path: &str) -> Result<Vec<u8>, String> {
    std::fs::read(path).map_err(|e| format!("cannot read '{path}': {e}"))
}
