//! `[record]`: what `phri-record` keeps of the depth frames and how it compresses.

use serde::{Deserialize, Serialize};

use crate::error::Invalid;

/// MCAP chunk compression.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum Compression {
    /// Zstandard
    Zstd,
    /// LZ4
    Lz4,
    /// uncompressed chunks
    None,
}

impl Compression {
    /// The name in `[record] compression`: `zstd`, `lz4` or `none`.
    pub fn name(self) -> &'static str {
        match self {
            Compression::Zstd => "zstd",
            Compression::Lz4 => "lz4",
            Compression::None => "none",
        }
    }
}

impl std::str::FromStr for Compression {
    type Err = Invalid;
    fn from_str(s: &str) -> Result<Compression, Invalid> {
        match s {
            "zstd" => Ok(Compression::Zstd),
            "lz4" => Ok(Compression::Lz4),
            "none" => Ok(Compression::None),
            other => Err(Invalid::new(
                "compression",
                format!("'{other}': expected zstd, lz4 or none"),
            )),
        }
    }
}

/// `[record]` (command-line flags override it).
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct RecordConfig {
    /// record every N-th received depth frame (≥ 1)
    pub frame_every: u64,
    /// keep one pixel in N per axis (1 = full resolution, 1..=16)
    pub frame_downsample: usize,
    /// MCAP chunk compression
    pub compression: Compression,
}

impl RecordConfig {
    /// `frame_every` at least 1, `frame_downsample` in 1..=16.
    pub fn validate(&self) -> Result<(), Invalid> {
        if self.frame_every == 0 {
            return Err(Invalid::new("record.frame_every", "must be at least 1"));
        }
        if !(1..=16).contains(&self.frame_downsample) {
            return Err(Invalid::new(
                "record.frame_downsample",
                format!("{} is not in 1..=16", self.frame_downsample),
            ));
        }
        Ok(())
    }
}
