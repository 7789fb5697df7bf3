//! `[camera]`, `[perception]` and `[repulsion]`: the simulated depth camera,
//! depth ingestion and the repulsion workers with their control points.

use phri_depth::{CameraPose, Intrinsics, RenderOptions, RepulsionParams, SelfFilterParams};
use serde::{Deserialize, Serialize};

use crate::check::{finite, non_negative, positive, within};
use crate::error::Invalid;

/// `[camera]`: the simulated depth camera.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct CameraConfig {
    /// frame rate [Hz]
    pub rate_hz: f64,
    /// capture → publish delay on top of rendering [ms] (a real sensor's latency)
    pub latency_ms: f64,
    /// the paper's set-up: 2 m from the base, 1.2 m high, looking at the robot;
    /// this is the camera's azimuth around the base [rad] (0 = on the x axis)
    pub azimuth_rad: f64,
    pub intrinsics: Intrinsics,
    /// sensor model (noise, range, edge drop-outs)
    pub render: RenderOptions,
    /// floor height [m] (absent: no floor)
    pub floor_z: Option<f64>,
    /// the table under the robot: box corners [m], base frame
    pub table_min: [f64; 3],
    pub table_max: [f64; 3],
}

impl CameraConfig {
    /// The camera's pose in the base frame.
    pub fn pose(&self) -> Result<CameraPose, Invalid> {
        CameraPose::paper_setup(self.azimuth_rad)
            .map_err(|e| Invalid::new("camera.azimuth_rad", e.to_string()))
    }

    pub fn validate(&self) -> Result<(), Invalid> {
        within("camera", "rate_hz", self.rate_hz, 1e-3, 1000.0)?;
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

/// Where ingestion takes its frames from.
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
    pub source: DepthSource,
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

impl IngestConfig {
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
    pub name: String,
    pub link: String,
    /// position in the link frame [m]
    pub xyz: [f64; 3],
    /// radius of the link around the point [m] (subtracted from distances)
    pub radius: f64,
}

/// `[repulsion]`: the repulsion workers and their control points.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct RepulsionConfig {
    /// worker processes; point i belongs to worker i mod workers
    pub workers: u32,
    /// eq. 16 parameters (ρ [m], V_max [m/s], α)
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
