//! Every tunable of the tracker in one place, with its default, unit and
//! reason. Lengths are metres, times seconds, frames the camera's optical
//! frame (x right, y down, z forward).

use serde::{Deserialize, Serialize};

use crate::error::TrackError;
use crate::floor::FloorMode;

/// Configuration of a [`crate::Tracker`]; [`TrackerConfig::default`] documents the defaults.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
#[serde(default, deny_unknown_fields)]
pub struct TrackerConfig {
    /// metres per unit of the depth frame (default 0.001: millimetres)
    pub depth_scale_m: f64,

    // --- the downsampled surface ---
    /// one sample every `grid_step_px` pixels in each direction (default 6: a
    /// 107×80 grid at 640×480, about 1 cm per cell at 1 m, 3 cm at 3 m)
    pub grid_step_px: u32,
    /// readings nearer than this are ignored \[m\] (default 0.4, the Kinect's near limit)
    pub min_depth_m: f64,
    /// readings farther than this are ignored \[m\] (default 4.5)
    pub max_depth_m: f64,
    /// the world's up direction in the camera frame (unit vector; default
    /// `[0, -1, 0]`: an upright camera, image up = world up)
    pub up_camera: [f64; 3],

    // --- segmentation ---
    /// depth continuity: two neighbouring cells join when their depths differ by
    /// at most `join_base_m + join_cell_slope · cell + join_sigmas · σ_z(z)`,
    /// `cell` = the cell's width at that depth \[m\], σ_z the Kinect noise (REFERENCE §6).
    /// Default 0.03 m
    pub join_base_m: f64,
    /// see `join_base_m`; default 4 (a surface seen at up to ~75° from its normal stays joined)
    pub join_cell_slope: f64,
    /// see `join_base_m`; default 3
    pub join_sigmas: f64,
    /// with a learned background, foreground = nearer than the background by
    /// more than `bg_margin_m + bg_margin_sigmas · σ_z(z_bg)` \[m\] (default 0.05)
    pub bg_margin_m: f64,
    /// see `bg_margin_m`; default 4
    pub bg_margin_sigmas: f64,
    /// the floor: none, a given plane, or fitted by RANSAC every frame
    /// (default [`FloorMode::Ransac`]: a camera in a room sees the floor, which
    /// would join everyone standing on it into one component)
    pub floor: FloorMode,
    /// cells within this height above the floor plane (or below it) are removed \[m\] (default 0.06)
    pub floor_margin_m: f64,
    /// a person's visible surface covers at least this area \[m²\] (default 0.04: a head and shoulders)
    pub person_min_area_m2: f64,
    /// a person's extent along up is at least this \[m\] (default 0.3)
    pub person_min_height_m: f64,
    /// a person's extent across (perpendicular to up and the view) is at least this \[m\] (default 0.2)
    pub person_min_width_m: f64,
    /// ... and at most this along up \[m\] (default 2.4)
    pub person_max_height_m: f64,
    /// ... and at most this across \[m\] (default 2.6: arms spread)
    pub person_max_width_m: f64,
    /// a component whose points lie within this RMS distance of a plane is a
    /// wall, a door or a table, not a person \[m\] (default 0.015)
    pub planar_max_rms_m: f64,
    /// a person has at least this many grid cells (default 30)
    pub person_min_cells: usize,
    /// a second body whose centre lies within this distance across the floor
    /// of a larger one is a piece of it, cut by something in front (default 0.4 m)
    pub fragment_m: f64,

    // --- geodesic extrema ---
    /// accumulative geodesic extrema per person (default 8: head, hands, feet,
    /// elbows and the corners where the image's border cuts the body)
    pub extrema: usize,
    /// an extremum is at least this far (geodesic) from the centre and from the extrema before it \[m\] (default 0.12)
    pub min_extremum_m: f64,

    // --- skeleton ---
    /// the head extremum lies at least this far above the body's centre \[m\] (default 0.1)
    pub head_min_above_m: f64,
    /// ... and at most this far from the body's vertical axis \[m\] (default 0.3)
    pub head_max_lateral_m: f64,
    /// the head joint is the mean of the surface within this geodesic distance of the head's extremum \[m\] (default 0.2)
    pub head_cap_m: f64,
    /// the hand joint is the mean of the surface within this geodesic distance of the hand's extremum \[m\] (default 0.08)
    pub hand_cap_m: f64,
    /// a hand is at least this far (geodesic) from the head's extremum \[m\]
    /// (default 0.45; Skeltrack uses 0.55)
    pub hand_min_from_head_m: f64,
    /// a hand is at most this far below the head's extremum \[m\] (default 1.1:
    /// a hanging hand is ~0.9 m below the top of the head, the legs farther)
    pub hand_max_below_head_m: f64,
    /// a foot is at least this far below the head's extremum \[m\] (default 1.0)
    pub foot_min_below_head_m: f64,
    /// the neck is on the geodesic path from the head's extremum to the centre, this far from the extremum \[m\] (default 0.24)
    pub neck_from_head_m: f64,
    /// shoulders: the outermost surface points this far below the top of the head \[m\] (default 0.28)
    pub shoulder_below_head_m: f64,
    /// ... at most this far to the side of the neck \[m\] (default 0.2)
    pub shoulder_max_lateral_m: f64,
    /// surface joints are reported this far behind the surface along the view ray, toward the body's axis \[m\]:
    /// head (default 0.03), hands (0.02), the rest (0.06)
    pub head_inset_m: f64,
    /// see `head_inset_m`
    pub hand_inset_m: f64,
    /// see `head_inset_m`
    pub body_inset_m: f64,

    // --- tracking ---
    /// a detection continues a track when its centre lies within this of the
    /// track's prediction \[m\] (default 0.6)
    pub gate_m: f64,
    /// the gate grows by this speed while a person is hidden \[m/s\] (default 1.5)
    pub gate_growth_mps: f64,
    /// a hidden person keeps its id this long \[s\] (default 1.0)
    pub max_hidden_s: f64,
    /// one-euro filter of the joints: cut-off at rest \[Hz\] (default 2.0)
    pub filter_min_cutoff_hz: f64,
    /// one-euro filter: cut-off growth per m/s of joint speed (default 4: a hand moving at
    /// 1 m/s lags ~3 cm)
    pub filter_beta: f64,
    /// one-euro filter: cut-off of the speed estimate \[Hz\] (default 1.0)
    pub filter_d_cutoff_hz: f64,
    /// a joint that moves farther than this between frames restarts its filter
    /// (a re-detection, or motion faster than 1.5 m/s at 30 Hz) \[m\] (default 0.05)
    pub filter_snap_m: f64,
}

impl Default for TrackerConfig {
    fn default() -> Self {
        Self {
            depth_scale_m: 0.001,
            grid_step_px: 6,
            min_depth_m: 0.4,
            max_depth_m: 4.5,
            up_camera: [0.0, -1.0, 0.0],
            join_base_m: 0.03,
            join_cell_slope: 4.0,
            join_sigmas: 3.0,
            bg_margin_m: 0.05,
            bg_margin_sigmas: 4.0,
            floor: FloorMode::Ransac,
            floor_margin_m: 0.06,
            person_min_area_m2: 0.04,
            person_min_height_m: 0.3,
            person_min_width_m: 0.2,
            person_max_height_m: 2.4,
            person_max_width_m: 2.6,
            planar_max_rms_m: 0.015,
            person_min_cells: 30,
            fragment_m: 0.4,
            extrema: 8,
            min_extremum_m: 0.12,
            head_min_above_m: 0.1,
            head_max_lateral_m: 0.3,
            head_cap_m: 0.2,
            hand_cap_m: 0.08,
            hand_min_from_head_m: 0.45,
            hand_max_below_head_m: 1.1,
            foot_min_below_head_m: 1.0,
            neck_from_head_m: 0.24,
            shoulder_below_head_m: 0.28,
            shoulder_max_lateral_m: 0.2,
            head_inset_m: 0.03,
            hand_inset_m: 0.02,
            body_inset_m: 0.06,
            gate_m: 0.6,
            gate_growth_mps: 1.5,
            max_hidden_s: 1.0,
            filter_min_cutoff_hz: 2.0,
            filter_beta: 4.0,
            filter_d_cutoff_hz: 1.0,
            filter_snap_m: 0.05,
        }
    }
}

impl TrackerConfig {
    /// Checks every value's range.
    pub fn validate(&self) -> Result<(), TrackError> {
        let bad =
            |what: &str, v: f64| Err(TrackError::Config(format!("{what} = {v} is out of range")));
        if !(1..=64).contains(&self.grid_step_px) {
            return bad("grid_step_px", f64::from(self.grid_step_px));
        }
        if !(self.min_depth_m.is_finite()
            && self.max_depth_m.is_finite()
            && self.min_depth_m >= 0.0
            && self.min_depth_m < self.max_depth_m)
        {
            return bad("min_depth_m/max_depth_m", self.min_depth_m);
        }
        let n = self.up_camera.iter().map(|c| c * c).sum::<f64>().sqrt();
        if !(n.is_finite() && n > 1e-6) {
            return bad("|up_camera|", n);
        }
        if !(self.depth_scale_m.is_finite() && self.depth_scale_m > 0.0) {
            return bad("depth_scale_m", self.depth_scale_m);
        }
        let non_negative = [
            ("join_base_m", self.join_base_m),
            ("join_cell_slope", self.join_cell_slope),
            ("join_sigmas", self.join_sigmas),
            ("bg_margin_m", self.bg_margin_m),
            ("bg_margin_sigmas", self.bg_margin_sigmas),
            ("floor_margin_m", self.floor_margin_m),
            ("person_min_area_m2", self.person_min_area_m2),
            ("person_min_height_m", self.person_min_height_m),
            ("person_min_width_m", self.person_min_width_m),
            ("planar_max_rms_m", self.planar_max_rms_m),
            ("fragment_m", self.fragment_m),
            ("min_extremum_m", self.min_extremum_m),
            ("head_min_above_m", self.head_min_above_m),
            ("head_max_lateral_m", self.head_max_lateral_m),
            ("head_cap_m", self.head_cap_m),
            ("hand_cap_m", self.hand_cap_m),
            ("hand_min_from_head_m", self.hand_min_from_head_m),
            ("hand_max_below_head_m", self.hand_max_below_head_m),
            ("foot_min_below_head_m", self.foot_min_below_head_m),
            ("neck_from_head_m", self.neck_from_head_m),
            ("shoulder_below_head_m", self.shoulder_below_head_m),
            ("shoulder_max_lateral_m", self.shoulder_max_lateral_m),
            ("head_inset_m", self.head_inset_m),
            ("hand_inset_m", self.hand_inset_m),
            ("body_inset_m", self.body_inset_m),
            ("gate_m", self.gate_m),
            ("gate_growth_mps", self.gate_growth_mps),
            ("max_hidden_s", self.max_hidden_s),
            ("filter_beta", self.filter_beta),
            ("filter_snap_m", self.filter_snap_m),
        ];
        for (what, v) in non_negative {
            if !(v.is_finite() && v >= 0.0) {
                return bad(what, v);
            }
        }
        for (what, v) in [
            ("person_max_height_m", self.person_max_height_m),
            ("person_max_width_m", self.person_max_width_m),
            ("filter_min_cutoff_hz", self.filter_min_cutoff_hz),
            ("filter_d_cutoff_hz", self.filter_d_cutoff_hz),
        ] {
            if !(v.is_finite() && v > 0.0) {
                return bad(what, v);
            }
        }
        if !(1..=16).contains(&self.extrema) {
            return bad("extrema", self.extrema as f64);
        }
        self.floor.validate()?;
        Ok(())
    }

    /// The unit up vector in the camera frame.
    pub fn up(&self) -> [f64; 3] {
        let [x, y, z] = self.up_camera;
        let n = (x * x + y * y + z * z).sqrt().max(1e-12);
        [x / n, y / n, z / n]
    }
}
