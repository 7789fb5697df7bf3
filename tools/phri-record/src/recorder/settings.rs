//! What a recording keeps: `[record]` of `--config` (else the defaults), the
//! flags over it, and the configuration the 3-D scene is drawn from.

use std::path::{Path, PathBuf};

use phri_viz::{Pipeline, Rates};

use super::channels::Viz;
use super::RecordError;
use crate::config::{self, RecordConfig};

/// Rates of the 3-D scene in a recording: the scene as phri-viz serves it by default.
pub const SCENE_RATES: Rates = Rates {
    scene_hz: 30.0,
    joints_hz: 250.0,
    // both set from [record] frame_downsample
    depth_downsample: 4,
    cloud_downsample: 4,
};

/// The flags that shape a recording, as `phri-record` takes them (its
/// command line flattens them in).
#[derive(clap::Args, Clone, Debug, Default)]
pub struct Flags {
    /// Stop after this long \[s\] (default: on Ctrl-C)
    #[arg(long, value_name = "S")]
    pub seconds: Option<f64>,
    /// Keep every N-th depth frame \[default: [record\] frame_every, 10]
    #[arg(long, value_name = "N")]
    pub frame_every: Option<u64>,
    /// Keep one depth pixel in K per axis \[default: [record\] frame_downsample, 4]
    #[arg(long, value_name = "K")]
    pub frame_downsample: Option<usize>,
    /// Chunk compression: zstd, lz4 or none \[default: [record\] compression, zstd]
    #[arg(long, value_name = "zstd|lz4|none")]
    pub compression: Option<String>,
    /// Cell configuration: \[record\], the robot model, the collision threshold and the cameras (a further camera's channels, `camera/1/depth`, …, are recorded too)
    #[arg(long, value_name = "FILE")]
    pub config: Option<PathBuf>,
    /// Collision norm threshold written into the metadata for phri-plot \[Nm\] [default: the configuration's]
    #[arg(long, value_name = "NM", allow_negative_numbers = true)]
    pub threshold: Option<f64>,
}

/// The flags resolved against the configuration.
pub struct Settings {
    /// `[record]` with the flags over it, validated
    pub rc: RecordConfig,
    /// collision norm threshold \[Nm\]: `--threshold`, else the configuration's
    pub threshold: Option<f64>,
    /// the cell's configuration (the scene's robot model, thresholds, cameras)
    pub loaded: phri_config::Loaded,
    /// stop after this long \[s\], > 0
    pub seconds: Option<f64>,
}

impl Settings {
    /// Resolves `flags`, each refusal naming its flag.
    pub fn resolve(flags: &Flags) -> Result<Settings, RecordError> {
        if flags.seconds.is_some_and(|s| !(s > 0.0 && s.is_finite())) {
            return Err(RecordError::Flag("--seconds must be positive".into()));
        }
        let config_path = flags.config.as_ref().map(|p| p.display().to_string());
        let config_err = |p: &str, e: &dyn std::fmt::Display| RecordError::Config {
            path: p.to_string(),
            message: e.to_string(),
        };
        let (rc, mut threshold) = match &config_path {
            Some(p) => config::from_file(p).map_err(|e| config_err(p, &e))?,
            None => (config::defaults(), None),
        };
        let rc = with_flags(rc, flags)?;
        if let Some(t) = flags.threshold {
            threshold = Some(t);
        }
        // the scene's robot model, thresholds and control points: the configuration's
        let loaded = match &config_path {
            Some(p) => {
                phri_config::Loaded::load(Path::new(p), None, &[]).map_err(|e| config_err(p, &e))?
            }
            None => phri_config::Loaded::defaults(),
        };
        Ok(Settings {
            rc,
            threshold,
            loaded,
            seconds: flags.seconds,
        })
    }

    /// The scene's rates: [`SCENE_RATES`] with the depth downsampled as the frames.
    pub fn rates(&self) -> Rates {
        Rates {
            depth_downsample: self.rc.frame_downsample,
            cloud_downsample: self.rc.frame_downsample,
            ..SCENE_RATES
        }
    }

    /// The 3-D scene, or none (with a warning on stderr, from `bin`) when
    /// the configuration's model does not make one: the channels are still
    /// worth recording.
    pub fn viz(&self, bin: &str) -> Viz {
        let pipeline = match Pipeline::from_config(&self.loaded, self.rates()) {
            Ok(p) => Some(p),
            Err(e) => {
                eprintln!("{bin}: warning: no 3-D scene in the recording: {e}");
                None
            }
        };
        Viz {
            pipeline,
            out: Vec::new(),
        }
    }
}

/// `rc` with the flags over it, validated; a key's refusal names its flag
/// (`record.frame_every` → `--frame-every`).
fn with_flags(mut rc: RecordConfig, flags: &Flags) -> Result<RecordConfig, RecordError> {
    if let Some(v) = flags.frame_every {
        rc.frame_every = v;
    }
    if let Some(v) = flags.frame_downsample {
        rc.frame_downsample = v;
    }
    if let Some(v) = &flags.compression {
        rc.compression = v.parse().map_err(|e: phri_config::Invalid| {
            RecordError::Flag(format!("--compression {}", e.reason))
        })?;
    }
    rc.validate().map_err(|e| {
        let flag = e.key.trim_start_matches("record.").replace('_', "-");
        RecordError::Flag(format!("--{flag}: {}", e.reason))
    })?;
    Ok(rc)
}

#[cfg(test)]
mod tests {
    use super::*;

    fn refusal(flags: Flags) -> String {
        match Settings::resolve(&flags) {
            Ok(_) => panic!("{flags:?} accepted"),
            Err(e) => e.to_string(),
        }
    }

    #[test]
    fn flags_override_the_defaults() {
        let s = Settings::resolve(&Flags {
            frame_every: Some(3),
            frame_downsample: Some(2),
            compression: Some("lz4".into()),
            threshold: Some(7.5),
            ..Flags::default()
        })
        .unwrap();
        assert_eq!((s.rc.frame_every, s.rc.frame_downsample), (3, 2));
        assert_eq!(s.rc.compression.name(), "lz4");
        assert_eq!(s.threshold, Some(7.5));
        assert_eq!(s.rates().cloud_downsample, 2);
    }

    #[test]
    fn each_refusal_names_its_flag() {
        let seconds = refusal(Flags {
            seconds: Some(0.0),
            ..Flags::default()
        });
        assert_eq!(seconds, "--seconds must be positive");
        let every = refusal(Flags {
            frame_every: Some(0),
            ..Flags::default()
        });
        assert!(every.starts_with("--frame-every: "), "{every}");
        let compression = refusal(Flags {
            compression: Some("gzip".into()),
            ..Flags::default()
        });
        assert!(compression.starts_with("--compression "), "{compression}");
        let config = refusal(Flags {
            config: Some("/nonexistent/phri.toml".into()),
            ..Flags::default()
        });
        assert!(
            config.starts_with("--config /nonexistent/phri.toml: "),
            "{config}"
        );
    }
}
