//! `--camera I`: which of the `[[camera]]` entries a per-camera service
//! (camera, ingestion) serves, and that camera's channels.

use phri_config::{CameraConfig, Config, Invalid};
use phri_ipc::CameraChannels;

/// The per-camera services' own flag.
#[derive(clap::Args, Debug, Clone, Copy, Default, PartialEq)]
pub struct CameraFlag {
    /// Index of the camera in `[[camera]]` this process serves (0: the first,
    /// on `camera/depth`; I ≥ 1 on `camera/I/depth`, …)
    #[arg(long, value_name = "I", default_value_t = 0)]
    pub camera: usize,
}

impl CameraFlag {
    /// The camera's configuration and channels; an index past the
    /// configured cameras is an error naming the flag.
    pub fn resolve<'a>(
        &self,
        config: &'a Config,
    ) -> Result<(&'a CameraConfig, &'static CameraChannels), Invalid> {
        let i = self.camera;
        match (config.cameras.get(i), phri_ipc::camera(i)) {
            (Some(c), Some(ch)) => Ok((c, ch)),
            _ => Err(Invalid::new(
                "--camera",
                format!(
                    "{i}: [[camera]] lists {} camera(s), numbered from 0",
                    config.cameras.len()
                ),
            )),
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_camera_past_the_list_is_refused_by_the_flag() {
        let cfg = Config::defaults();
        let (c, ch) = CameraFlag { camera: 0 }.resolve(&cfg).unwrap();
        assert_eq!(c, &cfg.camera);
        assert_eq!(ch.depth.name, "camera/depth");
        let e = CameraFlag { camera: 1 }.resolve(&cfg).unwrap_err();
        assert!(e.to_string().contains("--camera"), "{e}");
    }
}
