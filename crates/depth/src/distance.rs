//! Depth-space distances and repulsive vectors (paper Sect. V, eqs. 15-18;
//! Flacco et al. ICRA 2012; REFERENCE §3).
//!
//! For a point of interest `P` on the robot (base frame → camera frame
//! `(x_P, y_P, d_p)`, pixel `(p_x, p_y)`), the surveillance region is the cube of
//! side `2ρ` around `P`; only the pixels that can see it are visited.
//! For every valid pixel `O = (o_x, o_y, d_o)` of the window:
//!
//! - `d_o > d_p + ρ`: out of range, skipped;
//! - `d_o < d_p`: occlusion — the space behind `O` is unknown and may be
//!   occupied, the worst case lies at `P`'s own depth: `d_o := d_p`;
//! - distance vector in Cartesian camera coordinates (as coded by the
//!   implementations of the follow-up journal paper):
//!   `D = ((o_x − c_x) d_o/f_x − (p_x − c_x) d_p/f_x,
//!   (o_y − c_y) d_o/f_y − (p_y − c_y) d_p/f_y, d_o − d_p)`, pointing from `P` to `O`;
//! - `‖D‖ > ρ`: outside the region, skipped.
//!
//! Every remaining pixel contributes `V_C = v(‖D‖) (−D/‖D‖)` (pointing away from
//! the obstacle) with the magnitude (16) `v = V_max / (1 + exp((‖D‖ (2/ρ) − 1) α))`;
//! the repulsion (17)-(18) has the direction of their sum and the magnitude of
//! the nearest one, `v(‖D_min‖)`.
//!
//! The pixel window. REFERENCE §3 reads the cube's image as a square of
//! half-size `ρ f/(d_p − ρ)` around `(p_x, p_y)` (the near face seen on the
//! optical axis). Because every used point lies at depth `d_p ≤ d_o ≤ d_p + ρ`
//! (nearer pixels are moved to `d_p`), only the cube's back half can hold one,
//! so the window here is the exact bounding rectangle of that half box's image:
//! on the optical axis it is `ρ f/d_p` wide each side (about 35 % fewer pixels
//! at 2 m), and unlike the centred square it provably contains every pixel
//! with `‖D‖ ≤ ρ` also for points far off the axis (where the centred square
//! can miss a sliver near the image border). A point behind or very near the
//! camera gets the part of the image its region can reach, up to the whole.
//!
//! Points of interest on a link's axis carry the link radius `r`: they are
//! treated as spheres. Distances are measured from the sphere's surface,
//! `max(‖D‖ − r, 0)`, and the region grows with it (`ρ + r` in place of `ρ`
//! above), so that `ρ` is always the clearance at which repulsion starts. With
//! `r = 0` this is exactly the paper's rule.

use nalgebra::{Point3, Vector3};
use serde::{Deserialize, Serialize};

use crate::camera::{CameraPose, Intrinsics};
use crate::error::{check_frame, DepthError};
use crate::lanes::{self, Lanes};
use crate::shapes::camera_box_rect;

/// Parameters of the repulsive profile (16) (REFERENCE §3: α = 6, ρ = 0.4 m,
/// V_max = 0.21 m/s, labelled as the paper's values by a third party).
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct RepulsionParams {
    /// half side of the surveillance cube and distance where repulsion fades \[m\]
    pub rho: f64,
    /// largest repulsive speed, reached at zero distance \[m/s\]
    pub v_max: f64,
    /// shape factor of the sigmoid \[-\]
    pub alpha: f64,
}

impl Default for RepulsionParams {
    fn default() -> Self {
        Self {
            rho: 0.4,
            v_max: 0.21,
            alpha: 6.0,
        }
    }
}

impl RepulsionParams {
    /// Eq. (16): `v(d) = V_max / (1 + exp((d (2/ρ) − 1) α))` \[m/s\] for a
    /// distance `d` \[m\]: `V_max/(1 + e^−α)` at 0, `V_max/2` at `ρ/2`,
    /// `V_max/(1 + e^α)` at `ρ`.
    #[inline]
    pub fn magnitude(&self, distance: f64) -> f64 {
        self.v_max / (1.0 + ((distance * (2.0 / self.rho) - 1.0) * self.alpha).exp())
    }

    /// Checks `ρ > 0`, `V_max ≥ 0`, `α > 0`, all finite.
    pub fn validate(&self) -> Result<(), DepthError> {
        let ok = self.rho.is_finite()
            && self.rho > 0.0
            && self.v_max.is_finite()
            && self.v_max >= 0.0
            && self.alpha.is_finite()
            && self.alpha > 0.0;
        if ok {
            Ok(())
        } else {
            Err(DepthError::Parameter {
                what: "repulsion parameters",
                reason: format!("{self:?}: need rho > 0, v_max >= 0, alpha > 0, all finite"),
            })
        }
    }
}

/// A point of interest on the robot: a sphere around a point of a link's axis.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct PointOfInterest {
    /// centre, base frame \[m\]
    pub position: Point3<f64>,
    /// link radius around it \[m\], subtracted from every distance
    pub radius: f64,
}

impl PointOfInterest {
    /// A point of interest at `position` (base frame \[m\]) with `radius` \[m\].
    pub fn new(position: Point3<f64>, radius: f64) -> Self {
        Self { position, radius }
    }
}

/// Result of the depth-space computation for one point of interest.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Repulsion {
    /// repulsive vector `V_Call(P)` of eq. (17), base frame \[m/s\]; zero when no
    /// obstacle pixel lies in the region (or the contributions cancel exactly)
    pub v_call: Vector3<f64>,
    /// `max(‖D_min‖ − radius, 0)` \[m\]: clearance between the point's sphere and
    /// the nearest obstacle point; `INFINITY` when the region holds none
    pub min_distance: f64,
    /// `‖D_min‖` \[m\], from the point itself; `INFINITY` when the region holds none
    pub center_distance: f64,
    /// the obstacle point `O_min` of eq. (18) in the base frame \[m\], at the depth
    /// used for the distance (`d_p` when it was occluded)
    pub obstacle_point: Option<Point3<f64>>,
    /// number of pixels in the surveillance region (the `O ∈ S` of eq. 17)
    pub pixels_considered: usize,
    /// clearance between the point's sphere and the nearest surface the
    /// camera saw, every pixel at its own depth (no occlusion rule) \[m\]:
    /// observed surfaces are real, so this bounds the true clearance from
    /// above (to the sensor's noise) where `min_distance` bounds it from
    /// below. Pixels of the scan's window only (the region's back half as
    /// the image shows it: surfaces up to about ρ away); `INFINITY` when
    /// none lies there
    pub surface_distance: f64,
    /// that surface point, base frame \[m\]; `None` with no pixel
    pub surface_point: Option<Point3<f64>>,
}

impl Repulsion {
    /// No obstacle in the region.
    pub const NONE: Repulsion = Repulsion {
        v_call: Vector3::new(0.0, 0.0, 0.0),
        min_distance: f64::INFINITY,
        center_distance: f64::INFINITY,
        obstacle_point: None,
        pixels_considered: 0,
        surface_distance: f64::INFINITY,
        surface_point: None,
    };
}

impl Default for Repulsion {
    fn default() -> Self {
        Self::NONE
    }
}

/// Inclusive pixel window: columns `u0..=u1`, rows `v0..=v1`.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct PixelWindow {
    /// first column \[px\]
    pub u0: usize,
    /// last column \[px\], `≥ u0`
    pub u1: usize,
    /// first row \[px\]
    pub v0: usize,
    /// last row \[px\], `≥ v0`
    pub v1: usize,
}

impl PixelWindow {
    /// Number of pixels.
    pub fn len(&self) -> usize {
        (self.u1 + 1 - self.u0) * (self.v1 + 1 - self.v0)
    }

    /// Always `false`: a window holds at least one pixel.
    pub fn is_empty(&self) -> bool {
        false
    }
}

/// Depth-space distance and repulsion for one camera: intrinsics, pose, the
/// repulsive profile and per-column/per-row back-projection factors.
#[derive(Debug, Clone)]
pub struct DepthSpaceDistance {
    intrinsics: Intrinsics,
    pose: CameraPose,
    params: RepulsionParams,
    depth_scale_m: f64,
    /// `(u − c_x)/f_x` per column
    xn: Vec<f64>,
    /// `(v − c_y)/f_y` per row
    yn: Vec<f64>,
    /// the vector width of the scan this CPU runs
    lanes: Lanes,
}

impl DepthSpaceDistance {
    /// For frames of `intrinsics` at `pose` whose values are in units of
    /// `depth_scale_m` metres (0.001 for millimetres).
    pub fn new(
        intrinsics: Intrinsics,
        pose: CameraPose,
        params: RepulsionParams,
        depth_scale_m: f64,
    ) -> Result<Self, DepthError> {
        intrinsics.validate()?;
        params.validate()?;
        if !(depth_scale_m.is_finite() && depth_scale_m > 0.0) {
            return Err(DepthError::Parameter {
                what: "depth scale",
                reason: format!("{depth_scale_m} m per unit must be positive and finite"),
            });
        }
        Ok(Self {
            intrinsics,
            pose,
            params,
            depth_scale_m,
            xn: intrinsics.column_factors(),
            yn: intrinsics.row_factors(),
            lanes: Lanes::detect(),
        })
    }

    /// Repulsion parameters.
    pub fn params(&self) -> &RepulsionParams {
        &self.params
    }

    /// Moves the camera.
    pub fn set_pose(&mut self, pose: CameraPose) {
        self.pose = pose;
    }

    /// The pixel window of the surveillance region of `point`, or `None` if it
    /// lies outside the image.
    pub fn window(&self, point: &PointOfInterest) -> Option<PixelWindow> {
        let p = self.pose.to_camera(&point.position);
        self.window_camera(&p, self.params.rho + point.radius)
    }

    /// Exact projection of the back half `[x_P ± r] × [y_P ± r] × [d_p, d_p + r]`
    /// of the surveillance cube (`r` = ρ + radius), clipped to depths a pixel
    /// can hold; `None` if it misses the image.
    fn window_camera(&self, p: &Point3<f64>, reach: f64) -> Option<PixelWindow> {
        let lo = Vector3::new(p.x - reach, p.y - reach, p.z);
        let hi = Vector3::new(p.x + reach, p.y + reach, p.z + reach);
        let rect = camera_box_rect(&self.intrinsics, &lo, &hi, self.depth_scale_m)?;
        Some(PixelWindow {
            u0: rect.u0,
            u1: rect.u1,
            v0: rect.v0,
            v1: rect.v1,
        })
    }

    /// Eqs. (15)-(18) for one point of interest on a frame (`width × height`,
    /// row-major, units of the depth scale, 0 = no reading) from which the
    /// robot's own pixels have been removed. Allocates nothing.
    pub fn repulsion(
        &self,
        frame: &[u16],
        point: &PointOfInterest,
    ) -> Result<Repulsion, DepthError> {
        check_frame(
            "distance frame",
            self.intrinsics.width,
            self.intrinsics.height,
            frame.len(),
        )?;
        self.repulsion_unchecked(frame, point, 0)
    }

    /// [`DepthSpaceDistance::repulsion`] for every point, into `out` (same length).
    pub fn repulsions(
        &self,
        frame: &[u16],
        points: &[PointOfInterest],
        out: &mut [Repulsion],
    ) -> Result<(), DepthError> {
        check_frame(
            "distance frame",
            self.intrinsics.width,
            self.intrinsics.height,
            frame.len(),
        )?;
        if out.len() != points.len() {
            return Err(DepthError::Count {
                what: "repulsion output",
                expected: points.len(),
                got: out.len(),
            });
        }
        for (index, (p, o)) in points.iter().zip(out.iter_mut()).enumerate() {
            *o = self.repulsion_unchecked(frame, p, index)?;
        }
        Ok(())
    }

    fn repulsion_unchecked(
        &self,
        frame: &[u16],
        point: &PointOfInterest,
        index: usize,
    ) -> Result<Repulsion, DepthError> {
        let finite = point.position.iter().all(|c| c.is_finite());
        if !finite || !point.radius.is_finite() || point.radius < 0.0 {
            return Err(DepthError::PointOfInterest { index });
        }
        let prm = self.params;
        let radius = point.radius;
        let reach = prm.rho + radius;
        let reach2 = reach * reach;
        let p = self.pose.to_camera(&point.position);
        let Some(win) = self.window_camera(&p, reach) else {
            return Ok(Repulsion::NONE);
        };
        let d_p = p.z;
        let d_far = d_p + reach;
        let scale = self.depth_scale_m;
        let w = self.intrinsics.width as usize;

        // a run of pixels all invalid or beyond `d_far` by more than a unit
        // is skipped whole (one vectorised minimum per run): exactly the
        // pixels the region test would skip, most of a window's background
        let raw_far = match d_far / scale + 1.0 {
            f if f >= 0.0 && f < f64::from(u16::MAX - 1) => f.floor() as u16 + 1,
            f if f < 0.0 => 0,
            _ => u16::MAX,
        };
        let lp = lanes::Point {
            x: p.x,
            y: p.y,
            d_p,
            d_far,
            reach2,
            radius,
            scale,
            v_max: prm.v_max,
            two_over_rho: 2.0 / prm.rho,
            alpha: prm.alpha,
        };
        let window = lanes::Window {
            frame,
            width: w,
            u0: win.u0,
            v0: win.v0,
            v1: win.v1,
            xs: &self.xn[win.u0..=win.u1],
            yn: &self.yn,
            raw_far,
        };
        let mut sums = lanes::Sums::new();
        lanes::scan(self.lanes, &lp, &window, &mut sums);
        let lanes::Nearest {
            count,
            best2,
            best,
            surface2,
            surface,
        } = sums.nearest();
        let sum = sums.total();
        if count == 0 {
            return Ok(Repulsion::NONE);
        }
        let center_distance = best2.sqrt();
        let min_distance = (center_distance - radius).max(0.0);
        let sum_norm = sum.norm();
        let v_cam = if sum_norm > 0.0 {
            sum * (prm.magnitude(min_distance) / sum_norm)
        } else {
            Vector3::zeros()
        };
        let (bu, bv, bd) = best;
        let o_cam = Point3::new(self.xn[bu] * bd, self.yn[bv] * bd, bd);
        Ok(Repulsion {
            v_call: self.pose.vector_to_base(&v_cam),
            min_distance,
            center_distance,
            obstacle_point: Some(self.pose.to_base(&o_cam)),
            pixels_considered: count,
            surface_distance: (surface2.sqrt() - radius).max(0.0),
            surface_point: surface2.is_finite().then(|| {
                let (su, sv) = surface;
                let sd = f64::from(frame[sv * w + su]) * scale;
                self.pose
                    .to_base(&Point3::new(self.xn[su] * sd, self.yn[sv] * sd, sd))
            }),
        })
    }
}
