//! The `[record]` section of a cell configuration (`deploy/phri.toml`):
//! what `phri-record` keeps of the depth frames and how it compresses.
//! Command-line flags override it.

use serde::Deserialize;

use crate::FRAME_DOWNSAMPLE;

/// `[record]`: every key optional.
#[derive(Clone, Debug, PartialEq, Deserialize)]
#[serde(default, deny_unknown_fields)]
pub struct RecordConfig {
    /// record every N-th received depth frame (≥ 1)
    pub frame_every: u64,
    /// keep one pixel in N per axis (1 = full resolution, 1..=16)
    pub frame_downsample: usize,
    /// MCAP chunk compression: `zstd`, `lz4` or `none`
    pub compression: String,
}

impl Default for RecordConfig {
    fn default() -> Self {
        RecordConfig {
            frame_every: 10,
            frame_downsample: FRAME_DOWNSAMPLE,
            compression: "zstd".into(),
        }
    }
}

/// A recording's settings from a configuration file: `[record]` and
/// `dynamics.collision_norm_threshold` \[Nm\] (for the residual plot).
pub fn from_file(path: &str) -> Result<(RecordConfig, Option<f64>), String> {
    let text = std::fs::read_to_string(path).map_err(|e| format!("cannot read '{path}': {e}"))?;
    from_str(&text).map_err(|e| format!("{path}: {e}"))
}

/// As [`from_file`], from the file's text.
pub fn from_str(text: &str) -> Result<(RecordConfig, Option<f64>), String> {
    let t: toml::Table = text.parse().map_err(|e| format!("{e}"))?;
    let cfg = match t.get("record") {
        Some(v) => v
            .clone()
            .try_into::<RecordConfig>()
            .map_err(|e| format!("[record]: {e}"))?,
        None => RecordConfig::default(),
    };
    let threshold = t
        .get("dynamics")
        .and_then(|d| d.get("collision_norm_threshold"))
        .and_then(|x| x.as_float().or_else(|| x.as_integer().map(|i| i as f64)));
    Ok((cfg, threshold))
}

impl RecordConfig {
    /// The settings' own limits, naming the key at fault.
    pub fn validate(&self) -> Result<(), String> {
        if self.frame_every == 0 {
            return Err("frame_every must be at least 1".into());
        }
        if !(1..=16).contains(&self.frame_downsample) {
            return Err(format!(
                "frame_downsample {}: expected 1 to 16",
                self.frame_downsample
            ));
        }
        self.mcap_compression().map(|_| ())
    }

    /// The MCAP compression named by `compression`.
    pub fn mcap_compression(&self) -> Result<Option<mcap::Compression>, String> {
        match self.compression.as_str() {
            "zstd" => Ok(Some(mcap::Compression::Zstd)),
            "lz4" => Ok(Some(mcap::Compression::Lz4)),
            "none" => Ok(None),
            other => Err(format!("compression '{other}': expected zstd, lz4 or none")),
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn the_deploy_file_gives_the_defaults() {
        let text = std::fs::read_to_string(concat!(
            env!("CARGO_MANIFEST_DIR"),
            "/../../deploy/phri.toml"
        ))
        .unwrap();
        let (cfg, threshold) = from_str(&text).unwrap();
        assert_eq!(cfg, RecordConfig::default());
        assert_eq!(threshold, Some(12.0));
    }

    #[test]
    fn bad_settings_name_their_key() {
        let e = from_str("[record]\nframe_evry = 3\n").unwrap_err();
        assert!(e.contains("[record]") && e.contains("frame_evry"), "{e}");
        let (cfg, _) = from_str("[record]\nframe_downsample = 0\n").unwrap();
        assert!(cfg.validate().unwrap_err().contains("frame_downsample"));
        let (cfg, _) = from_str("[record]\ncompression = \"gzip\"\n").unwrap();
        assert!(cfg.validate().unwrap_err().contains("'gzip'"));
        let (cfg, _) = from_str("[record]\nframe_every = 0\n").unwrap();
        assert!(cfg.validate().unwrap_err().contains("frame_every"));
        let (cfg, t) = from_str("[record]\ncompression = \"none\"\nframe_every = 1\n").unwrap();
        assert_eq!((cfg.frame_every, t), (1, None));
        assert!(cfg.mcap_compression().unwrap().is_none());
    }
}
