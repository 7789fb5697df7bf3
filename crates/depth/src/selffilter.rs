//! Removing the robot's own pixels from a depth frame (REFERENCE §3: the robot
//! sees itself and must not repel itself).
//!
//! Each robot capsule is inflated by a margin. A pixel belongs to the robot if
//! its ray crosses an inflated capsule and its measured depth lies in that
//! capsule's entry/exit depth interval along the ray, widened on both sides by
//! a depth tolerance `tol(d) = depth_tolerance_m + noise_sigmas · σ_z(d)`. Such
//! pixels are set to 0 (no reading). Only pixels inside each capsule's
//! projected bounding rectangle are visited.
//!
//! Why this catches every robot pixel: a surface point of the true capsule lies
//! at least `margin` behind the inflated capsule's entry along any ray (the
//! distance along a ray is at least the distance between the two surfaces), so
//! a reading is kept only if its noise exceeds `margin + tol(d)`.

use serde::{Deserialize, Serialize};

use crate::camera::{CameraPose, Intrinsics};
use crate::error::{check_frame, DepthError};
use crate::noise::sigma_z;
use crate::render::NEAR_M;
use crate::shapes::{Capsule, RayCapsule};

/// Parameters of the self-filter.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct SelfFilterParams {
    /// radius added to every robot capsule \[m\] (covers model error, joint-state latency)
    pub margin_m: f64,
    /// constant depth tolerance on both ends of the ray interval \[m\]
    pub depth_tolerance_m: f64,
    /// extra depth tolerance in multiples of the sensor noise `σ_z(d)`
    pub noise_sigmas: f64,
    /// metres per unit of the frame (0.001: millimetres)
    pub depth_scale_m: f64,
}

impl Default for SelfFilterParams {
    /// 3 cm margin, 2 cm + 3σ depth tolerance, millimetre frames.
    fn default() -> Self {
        Self {
            margin_m: 0.03,
            depth_tolerance_m: 0.02,
            noise_sigmas: 3.0,
            depth_scale_m: 0.001,
        }
    }
}

impl SelfFilterParams {
    /// Checks that every value is finite and ≥ 0 (scale > 0).
    pub fn validate(&self) -> Result<(), DepthError> {
        let ok = self.margin_m.is_finite()
            && self.margin_m >= 0.0
            && self.depth_tolerance_m.is_finite()
            && self.depth_tolerance_m >= 0.0
            && self.noise_sigmas.is_finite()
            && self.noise_sigmas >= 0.0
            && self.depth_scale_m.is_finite()
            && self.depth_scale_m > 0.0;
        if ok {
            Ok(())
        } else {
            Err(DepthError::Parameter {
                what: "self-filter",
                reason: format!("{self:?}: values must be finite and >= 0, scale > 0"),
            })
        }
    }
}

/// Removes the pixels of the robot's own (inflated) collision capsules from
/// depth frames of one camera.
#[derive(Debug, Clone)]
pub struct SelfFilter {
    intrinsics: Intrinsics,
    pose: CameraPose,
    params: SelfFilterParams,
    xn: Vec<f64>,
    yn: Vec<f64>,
}

impl SelfFilter {
    /// A filter for `intrinsics` at `pose`; precomputes the per-column and
    /// per-row ray factors.
    pub fn new(
        intrinsics: Intrinsics,
        pose: CameraPose,
        params: SelfFilterParams,
    ) -> Result<Self, DepthError> {
        intrinsics.validate()?;
        params.validate()?;
        Ok(Self {
            intrinsics,
            pose,
            params,
            xn: intrinsics.column_factors(),
            yn: intrinsics.row_factors(),
        })
    }

    /// Parameters.
    pub fn params(&self) -> &SelfFilterParams {
        &self.params
    }

    /// Moves the camera.
    pub fn set_pose(&mut self, pose: CameraPose) {
        self.pose = pose;
    }

    /// Sets to 0 every pixel of `frame` (`width × height`, units of
    /// `depth_scale_m`) that lies on one of `robot_capsules` (base frame, at the
    /// joint state of the frame's time) inflated by the margin, within the depth
    /// tolerance. Returns the number of pixels removed. Allocates nothing.
    pub fn apply(
        &mut self,
        robot_capsules: &[Capsule],
        frame: &mut [u16],
    ) -> Result<usize, DepthError> {
        check_frame(
            "self-filter frame",
            self.intrinsics.width,
            self.intrinsics.height,
            frame.len(),
        )?;
        for (index, c) in robot_capsules.iter().enumerate() {
            if !c.is_valid() {
                return Err(DepthError::Primitive {
                    what: "robot capsule",
                    index,
                    reason: "endpoints and radius must be finite, radius >= 0",
                });
            }
        }
        let p = self.params;
        let w = self.intrinsics.width as usize;
        let mut removed = 0;
        for capsule in robot_capsules {
            let rc = RayCapsule::new(capsule, &self.pose, p.margin_m);
            let (z_min, z_max) = rc.depth_range();
            let Some(rect) = rc.pixel_rect(&self.intrinsics, NEAR_M) else {
                continue;
            };
            for v in rect.v0..=rect.v1 {
                let y = self.yn[v];
                let row = &mut frame[v * w..(v + 1) * w];
                for u in rect.u0..=rect.u1 {
                    let raw = row[u];
                    if raw == 0 {
                        continue;
                    }
                    let d = f64::from(raw) * p.depth_scale_m;
                    let tol = p.depth_tolerance_m + p.noise_sigmas * sigma_z(d);
                    if d < z_min - tol || d > z_max + tol {
                        continue;
                    }
                    if let Some((t_in, t_out)) = rc.interval(self.xn[u], y) {
                        if d >= t_in - tol && d <= t_out + tol {
                            row[u] = 0;
                            removed += 1;
                        }
                    }
                }
            }
        }
        Ok(removed)
    }
}
