//! `[camera]`, `[perception]` and `[repulsion]` sections of `deploy/phri.toml`.

use phri_depth::{CameraPose, Intrinsics, RenderOptions, RepulsionParams, SelfFilterParams};
use serde::Deserialize;

/// The simulated depth camera.
#[derive(Clone, Debug, Deserialize)]
#[serde(default, deny_unknown_fields)]
pub struct CameraConfig {
    /// frame rate [Hz]
    pub rate_hz: f64,
    /// capture → publish delay on top of rendering [ms] (a real sensor's latency)
    pub latency_ms: f64,
    /// the paper's set-up: 2 m from the base, 1.2 m high, looking at the
    /// robot; this is the camera's azimuth around the base [rad] (0 = on the x axis)
    pub azimuth_rad: f64,
    pub intrinsics: Intrinsics,
    /// sensor model (noise, range, edge drop-outs)
    pub render: RenderOptions,
    /// floor height [m] (none: no floor)
    pub floor_z: Option<f64>,
    /// the table under the robot: box corners [m], base frame
    pub table_min: [f64; 3],
    pub table_max: [f64; 3],
}

impl Default for CameraConfig {
    fn default() -> Self {
        CameraConfig {
            rate_hz: 30.0,
            latency_ms: 15.0,
            azimuth_rad: 0.6,
            intrinsics: Intrinsics::default(),
            render: RenderOptions::default(),
            floor_z: Some(-0.8),
            table_min: [-0.25, -0.25, -0.8],
            table_max: [0.25, 0.25, 0.0],
        }
    }
}

impl CameraConfig {
    pub fn pose(&self) -> Result<CameraPose, String> {
        CameraPose::paper_setup(self.azimuth_rad).map_err(|e| format!("[camera] azimuth_rad: {e}"))
    }
}

/// Depth ingestion.
#[derive(Clone, Debug, Deserialize)]
#[serde(default, deny_unknown_fields)]
pub struct IngestConfig {
    /// `camera` (the `camera/depth` channel) or `png` (a directory of 16-bit PNG depth images)
    pub source: String,
    /// with `source = "png"`: the directory, its files replayed in name order
    pub png_dir: String,
    /// metres per PNG sample unit (0.001: millimetres; TUM RGB-D uses 0.0002)
    pub png_depth_scale: f64,
    /// replay rate [Hz]
    pub png_rate_hz: f64,
    /// start over at the end of the directory
    pub png_loop: bool,
    /// self-filter: margin added to the robot's capsules and depth tolerance
    pub self_filter: SelfFilterParams,
    /// the joint state used must lie within this of the frame's capture time [ms]
    pub max_state_gap_ms: f64,
    /// frames older than this when they arrive are refused [ms]
    pub max_frame_age_ms: f64,
}

impl Default for IngestConfig {
    fn default() -> Self {
        IngestConfig {
            source: "camera".into(),
            png_dir: String::new(),
            png_depth_scale: 0.001,
            png_rate_hz: 30.0,
            png_loop: true,
            self_filter: SelfFilterParams::default(),
            max_state_gap_ms: 20.0,
            max_frame_age_ms: 200.0,
        }
    }
}

/// One control point: a point fixed on a link, with the link's radius.
#[derive(Clone, Debug, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct PointConfig {
    pub name: String,
    pub link: String,
    /// position in the link frame [m]
    pub xyz: [f64; 3],
    /// radius of the link around the point [m] (subtracted from distances)
    pub radius: f64,
}

/// Repulsion workers and their control points.
#[derive(Clone, Debug, Deserialize)]
#[serde(default, deny_unknown_fields)]
pub struct RepulsionConfig {
    /// worker processes; point i belongs to worker i mod workers
    pub workers: u32,
    /// eq. 16 parameters (ρ [m], V_max [m/s], α)
    pub params: RepulsionParams,
    /// control points; the first is the end effector (eq. 19), the others shape velocity bounds (eq. 20)
    pub points: Vec<PointConfig>,
}

impl Default for RepulsionConfig {
    fn default() -> Self {
        let p = |name: &str, link: &str, xyz: [f64; 3], radius: f64| PointConfig {
            name: name.into(),
            link: link.into(),
            xyz,
            radius,
        };
        RepulsionConfig {
            workers: 4,
            params: RepulsionParams::default(),
            points: vec![
                p("end_effector", "lwr_flange", [0.0, 0.0, 0.0], 0.05),
                p("wrist", "lwr_link_6", [0.0, 0.0, 0.0], 0.07),
                p("forearm_high", "lwr_link_5", [0.0, 0.0, 0.35], 0.065),
                p("forearm_low", "lwr_link_5", [0.0, 0.0, 0.20], 0.065),
                p("elbow_out", "lwr_link_4", [0.0, -0.10, 0.0], 0.07),
                p("elbow", "lwr_link_4", [0.0, 0.0, 0.0], 0.07),
                p("upper_arm_high", "lwr_link_3", [0.0, 0.0, 0.30], 0.07),
                p("upper_arm_low", "lwr_link_3", [0.0, 0.0, 0.15], 0.07),
            ],
        }
    }
}

impl RepulsionConfig {
    /// Indices of the points worker `w` owns.
    pub fn points_of(&self, w: u32) -> Vec<usize> {
        (0..self.points.len())
            .filter(|i| *i as u32 % self.workers.max(1) == w)
            .collect()
    }
}
