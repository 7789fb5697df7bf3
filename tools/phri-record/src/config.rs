//! What `phri-record` takes from a cell configuration: its `[record]`
//! section (phri-config; the flags override it) and the residual's collision
//! norm threshold `dynamics.collision_norm_threshold` \[Nm\] for the plots.

use std::path::Path;

pub use phri_config::{Compression, RecordConfig};
use phri_config::{Config, ConfigError, Loaded};

/// `[record]` and the collision norm threshold of the configuration at `path`
/// (merged over the defaults and checked, as every phri process reads it).
pub fn from_file(path: &str) -> Result<(RecordConfig, Option<f64>), ConfigError> {
    let l = Loaded::load(Path::new(path), None, &[])?;
    Ok((
        l.config.record,
        Some(l.config.dynamics.collision_norm_threshold),
    ))
}

/// The recorder's settings without a configuration file: the defaults.
pub fn defaults() -> RecordConfig {
    Config::defaults().record
}

/// The MCAP compression of `c`.
pub fn mcap_compression(c: Compression) -> Option<mcap::Compression> {
    match c {
        Compression::Zstd => Some(mcap::Compression::Zstd),
        Compression::Lz4 => Some(mcap::Compression::Lz4),
        Compression::None => None,
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn the_deploy_file_gives_the_defaults() {
        let (cfg, threshold) = from_file(concat!(
            env!("CARGO_MANIFEST_DIR"),
            "/../../deploy/phri.toml"
        ))
        .unwrap();
        assert_eq!(cfg, defaults());
        assert_eq!(cfg.frame_downsample, crate::FRAME_DOWNSAMPLE);
        assert_eq!(cfg.compression, Compression::Zstd);
        assert_eq!(threshold, Some(12.0));
    }

    #[test]
    fn bad_settings_name_their_key() {
        let dir = std::env::temp_dir().join(format!("phri-record-cfg-{}", std::process::id()));
        std::fs::create_dir_all(&dir).unwrap();
        let write = |text: &str| {
            let p = dir.join("c.toml");
            std::fs::write(&p, text).unwrap();
            from_file(p.to_str().unwrap())
                .map(|_| ())
                .unwrap_err()
                .to_string()
        };
        let e = write("[record]\nframe_evry = 3\n");
        assert!(e.contains("record.frame_evry"), "{e}");
        let e = write("[record]\nframe_downsample = 0\n");
        assert!(e.contains("record.frame_downsample"), "{e}");
        let e = write("[record]\ncompression = \"gzip\"\n");
        assert!(
            e.contains("record.compression") && e.contains("gzip"),
            "{e}"
        );
        let e = write("[record]\nframe_every = 0\n");
        assert!(e.contains("record.frame_every"), "{e}");
        std::fs::remove_dir_all(&dir).ok();
        assert!(mcap_compression("none".parse::<Compression>().unwrap()).is_none());
        assert!("gzip".parse::<Compression>().is_err());
    }
}
