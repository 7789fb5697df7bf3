//! `[camera]`, `[perception]` and `[repulsion]`: the simulated depth camera,
//! depth ingestion and the repulsion workers with their control points.

use phri_depth::{CameraPose, Intrinsics, RenderOptions, RepulsionParams, SelfFilterParams};
use serde::{Deserialize, Serialize};

use crate::avoidance::AvoidanceLaw;
use crate::check::{finite, non_negative, positive, within};
use crate::error::Invalid;

/// Where a camera's frames come from (`[camera] source`).
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum CameraSource {
    /// the simulated camera rendering the simulated cell (`phri-camera`)
    #[default]
    Sim,
    /// a Kinect v1 through libfreenect (`phri-freenect`)
    Freenect,
    /// any ROS 2 depth camera: a `sensor_msgs/Image` and its `CameraInfo`
    /// (`phri-camera-ros2`)
    Ros2,
    /// a directory of recorded frames (`phri-camera`)
    Replay,
}

impl CameraSource {
    /// The name the configuration gives it.
    pub fn name(self) -> &'static str {
        match self {
            CameraSource::Sim => "sim",
            CameraSource::Freenect => "freenect",
            CameraSource::Ros2 => "ros2",
            CameraSource::Replay => "replay",
        }
    }

    /// The binary that serves a camera of this source.
    pub fn binary(self) -> &'static str {
        match self {
            CameraSource::Sim | CameraSource::Replay => "phri-camera",
            CameraSource::Freenect => "phri-freenect",
            CameraSource::Ros2 => "phri-camera-ros2",
        }
    }

    /// Every source, in the configuration's order.
    pub const ALL: [CameraSource; 4] = [
        CameraSource::Sim,
        CameraSource::Freenect,
        CameraSource::Ros2,
        CameraSource::Replay,
    ];
}

/// `[camera]`: one depth camera (simulated, a Kinect, a ROS 2 camera or a
/// recording), on `camera/depth` (`camera/I/depth` for `[[camera]]` entry I).
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct CameraConfig {
    /// where the frames come from
    pub source: CameraSource,
    /// frame rate \[Hz\] (the simulated camera's and a replay's; a real
    /// camera runs at its own)
    pub rate_hz: f64,
    /// capture → publish delay on top of rendering \[ms\] (a real sensor's latency)
    pub latency_ms: f64,
    /// the paper's set-up: 2 m from the base, 1.2 m high, looking at the robot;
    /// this is the camera's azimuth around the base \[rad\] (0 = on the x axis)
    pub azimuth_rad: f64,
    /// image size and pinhole parameters \[px\] (the simulated camera's and
    /// a replay's; a real camera gives its own)
    pub intrinsics: Intrinsics,
    /// sensor model (noise, range, edge drop-outs)
    pub render: RenderOptions,
    /// floor height \[m\] (absent: no floor)
    pub floor_z: Option<f64>,
    /// the table under the robot: box corners \[m\], base frame
    pub table_min: [f64; 3],
    /// the table's upper corner \[m\], base frame
    pub table_max: [f64; 3],
    /// a real camera's frame whose capture lies further in the past than
    /// this when it arrives is dropped (counted) \[s\]
    pub max_age_s: f64,
    /// `source = "freenect"`: the Kinect's index among libfreenect's devices
    pub device_index: u32,
    /// `source = "ros2"`: the `sensor_msgs/Image` topic (16UC1 or 32FC1)
    pub image_topic: String,
    /// `source = "ros2"`: its `sensor_msgs/CameraInfo` topic
    pub info_topic: String,
    /// `source = "replay"`: the directory of recorded frames (16-bit PNG,
    /// headerless little-endian 16-bit raw, or a fakenect recording)
    pub replay_dir: String,
    /// `source = "replay"`: start over after the last frame
    pub replay_loop: bool,
    /// `source = "replay"`: metres per sample unit of the recorded frames
    /// (0.001: millimetres; a fakenect recording is disparity, converted)
    pub depth_scale_m: f64,
}

impl CameraConfig {
    /// The camera's pose in the base frame.
    pub fn pose(&self) -> Result<CameraPose, Invalid> {
        CameraPose::paper_setup(self.azimuth_rad)
            .map_err(|e| Invalid::new("camera.azimuth_rad", e.to_string()))
    }

    /// Range checks of every field, the source's own keys, the pose, the
    /// intrinsics and the sensor model.
    pub fn validate(&self) -> Result<(), Invalid> {
        within("camera", "rate_hz", self.rate_hz, 1e-3, 1000.0)?;
        within("camera", "max_age_s", self.max_age_s, 1e-3, 10.0)?;
        if self.device_index > 63 {
            return Err(Invalid::new(
                "camera.device_index",
                format!("{} is not a device index in 0..=63", self.device_index),
            ));
        }
        if self.source == CameraSource::Replay && self.replay_dir.trim().is_empty() {
            return Err(Invalid::new(
                "camera.replay_dir",
                "source = \"replay\" needs a directory",
            ));
        }
        if self.source == CameraSource::Ros2 {
            for (k, t) in [
                ("image_topic", &self.image_topic),
                ("info_topic", &self.info_topic),
            ] {
                if !valid_topic(t) {
                    return Err(Invalid::new(
                        format!("camera.{k}"),
                        format!("'{t}' is not a ROS 2 topic name (letters, digits, _ and /)"),
                    ));
                }
            }
        }
        within("camera", "depth_scale_m", self.depth_scale_m, 1e-6, 1.0)?;
        within("camera", "latency_ms", self.latency_ms, 0.0, 10_000.0)?;
        self.pose()?;
        let i = &self.intrinsics;
        if !(1..=4096).contains(&i.width) || !(1..=4096).contains(&i.height) {
            return Err(Invalid::new(
                "camera.intrinsics",
                format!("{}×{} is not an image size in 1..=4096", i.width, i.height),
            ));
        }
        positive("camera.intrinsics", "fx", i.fx)?;
        positive("camera.intrinsics", "fy", i.fy)?;
        finite("camera.intrinsics", "cx", &[i.cx, i.cy])?;
        self.render
            .validate()
            .map_err(|e| Invalid::new("camera.render", e.to_string()))?;
        if let Some(z) = self.floor_z {
            finite("camera", "floor_z", &[z])?;
        }
        finite("camera", "table_min", &self.table_min)?;
        finite("camera", "table_max", &self.table_max)?;
        Ok(())
    }
}

/// A ROS 2 topic name as phri accepts it: 1-256 characters of letters,
/// digits, `_` and `/`, not starting with a digit, no empty segment.
pub fn valid_topic(t: &str) -> bool {
    let body = t.strip_prefix('/').unwrap_or(t);
    !body.is_empty()
        && t.len() <= 256
        && !body.starts_with(|c: char| c.is_ascii_digit())
        && body.split('/').all(|seg| {
            !seg.is_empty() && seg.chars().all(|c| c.is_ascii_alphanumeric() || c == '_')
        })
}

/// Where ingestion takes its frames from (`[perception] source`): kept
/// so that older configurations load; `png` is a replay camera
/// (`[camera] source = "replay"`), which the loader turns it into.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum DepthSource {
    /// the `camera/depth` channel (a camera driver or the simulated camera)
    Camera,
    /// a directory of 16-bit PNG depth images, replayed in name order
    Png,
}

/// `[perception]`: depth ingestion.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct IngestConfig {
    /// where the frames come from (`png`: the older way to replay)
    pub source: DepthSource,
    /// with `source = "png"`: the directory, its files replayed in name order
    pub png_dir: String,
    /// metres per PNG sample unit (0.001: millimetres; TUM RGB-D uses 0.0002)
    pub png_depth_scale: f64,
    /// replay rate \[Hz\]
    pub png_rate_hz: f64,
    /// start over at the end of the directory
    pub png_loop: bool,
    /// self-filter: margin added to the robot's capsules and depth tolerance
    pub self_filter: SelfFilterParams,
    /// the joint state used must lie within this of the frame's capture time \[ms\]
    pub max_state_gap_ms: f64,
    /// frames older than this when they arrive are refused \[ms\]
    pub max_frame_age_ms: f64,
}

impl IngestConfig {
    /// Range checks of every field, the self-filter's included.
    pub fn validate(&self) -> Result<(), Invalid> {
        const S: &str = "perception";
        if self.source == DepthSource::Png && self.png_dir.is_empty() {
            return Err(Invalid::new(
                "perception.png_dir",
                "source = \"png\" needs a directory",
            ));
        }
        positive(S, "png_depth_scale", self.png_depth_scale)?;
        within(S, "png_rate_hz", self.png_rate_hz, 1e-3, 1000.0)?;
        positive(S, "max_state_gap_ms", self.max_state_gap_ms)?;
        positive(S, "max_frame_age_ms", self.max_frame_age_ms)?;
        let f = &self.self_filter;
        const F: &str = "perception.self_filter";
        non_negative(F, "margin_m", f.margin_m)?;
        non_negative(F, "depth_tolerance_m", f.depth_tolerance_m)?;
        non_negative(F, "noise_sigmas", f.noise_sigmas)?;
        positive(F, "depth_scale_m", f.depth_scale_m)?;
        Ok(())
    }
}

/// One control point: a point fixed on a link, with the link's radius.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct PointConfig {
    /// the point's name (`end_effector`, `wrist`, …)
    pub name: String,
    /// the link the point is fixed on
    pub link: String,
    /// position in the link frame \[m\]
    pub xyz: [f64; 3],
    /// radius of the link around the point \[m\] (subtracted from distances)
    pub radius: f64,
    /// the one avoidance law this point serves (`[avoidance] law`); absent:
    /// both. A point of the other law is dropped when the configuration is
    /// typed, so that no worker, controller or report sees it
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub law: Option<AvoidanceLaw>,
}

/// `[repulsion]`: the repulsion workers and their control points.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct RepulsionConfig {
    /// worker processes; point i belongs to worker i mod workers
    pub workers: u32,
    /// eq. 16 parameters (ρ \[m\], V_max [m/s], α)
    pub params: RepulsionParams,
    /// control points; the first is the end effector (eq. 19), the others shape velocity bounds (eq. 20)
    pub points: Vec<PointConfig>,
    /// with several cameras, whose repulsive direction a fused point takes
    pub fused_direction: FusedDirection,
}

/// With several cameras, the direction of a point's fused repulsion
/// (`[repulsion] fused_direction`); its distance is always the largest of
/// the fresh cameras' bounds, and its magnitude that distance's (eq. 16).
#[derive(Clone, Copy, Debug, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum FusedDirection {
    /// the first camera's direction whenever it is fresh and sees an
    /// obstacle near the point; otherwise the camera's that gives the distance
    First,
    /// always the camera's that gives the distance
    Largest,
}

impl RepulsionConfig {
    /// Indices of the points worker `w` owns.
    pub fn points_of(&self, w: u32) -> Vec<usize> {
        (0..self.points.len())
            .filter(|i| *i as u32 % self.workers.max(1) == w)
            .collect()
    }

    /// The control points as (link, point in the link frame).
    pub fn point_links(&self) -> Vec<(String, [f64; 3])> {
        self.points
            .iter()
            .map(|p| (p.link.clone(), p.xyz))
            .collect()
    }

    /// Range checks: 1-16 workers, no more points per worker than a message
    /// carries, positive eq. 16 parameters, finite points.
    pub fn validate(&self) -> Result<(), Invalid> {
        if !(1..=16).contains(&self.workers) {
            return Err(Invalid::new(
                "repulsion.workers",
                format!("{} is not in 1..=16", self.workers),
            ));
        }
        let per_worker = self.points.len().div_ceil(self.workers as usize);
        if per_worker > phri_ipc::MAX_POINTS_PER_WORKER {
            return Err(Invalid::new(
                "repulsion.points",
                format!(
                    "{} points on {} workers: at most {} per worker",
                    self.points.len(),
                    self.workers,
                    phri_ipc::MAX_POINTS_PER_WORKER
                ),
            ));
        }
        const P: &str = "repulsion.params";
        positive(P, "rho", self.params.rho)?;
        positive(P, "v_max", self.params.v_max)?;
        positive(P, "alpha", self.params.alpha)?;
        for (i, p) in self.points.iter().enumerate() {
            let k = format!("repulsion.points[{i}]");
            finite(&k, "xyz", &p.xyz)?;
            non_negative(&k, "radius", p.radius)?;
        }
        Ok(())
    }
}
