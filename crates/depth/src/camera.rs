//! Pinhole depth camera: intrinsics, the camera's pose in the robot base frame,
//! projection and back-projection (REFERENCE §3 and §6).
//!
//! Frames. The *base frame* is the robot base (x forward, z up, metres). The
//! *camera frame* has its origin at the optical centre, z forward along the
//! optical axis, x to the right of the image and y down. Pixel coordinates
//! `(p_x, p_y)` have their origin at the centre of the top-left pixel, `p_x`
//! growing to the right (columns) and `p_y` downwards (rows). Depth is the
//! camera-frame `z` coordinate (not the distance along the ray), as Kinect-class
//! sensors report it.

use nalgebra::{Isometry3, Point3, Rotation3, Translation3, UnitQuaternion, Vector3};
use serde::{Deserialize, Serialize};

use crate::error::DepthError;

/// Radial distance of the camera from the robot base in the paper's set-up \[m\].
pub const PAPER_CAMERA_RADIUS_M: f64 = 2.0;
/// Height of the camera above the robot base in the paper's set-up \[m\].
pub const PAPER_CAMERA_HEIGHT_M: f64 = 1.2;
/// Default azimuth of the camera around the base z axis \[rad\] (front-left of the robot).
pub const PAPER_CAMERA_AZIMUTH_RAD: f64 = 0.6;
/// Point the default camera looks at, base frame \[m\] (the middle of the arm's workspace).
pub const PAPER_CAMERA_TARGET_M: [f64; 3] = [0.3, 0.0, 0.4];

/// Pinhole intrinsics of a depth camera; focal lengths and principal point in pixels.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct Intrinsics {
    /// image width \[px\] (columns)
    pub width: u32,
    /// image height \[px\] (rows)
    pub height: u32,
    /// focal length along x \[px\]
    pub fx: f64,
    /// focal length along y \[px\]
    pub fy: f64,
    /// principal point, column \[px\]
    pub cx: f64,
    /// principal point, row \[px\]
    pub cy: f64,
}

impl Default for Intrinsics {
    /// The Kinect v1 at 640×480: f = 525 px, c = (319.5, 239.5) (REFERENCE §6).
    fn default() -> Self {
        Self::KINECT
    }
}

/// A projected point: pixel coordinates and depth.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct PixelDepth {
    /// column coordinate \[px\] (may lie outside the image)
    pub px: f64,
    /// row coordinate \[px\] (may lie outside the image)
    pub py: f64,
    /// depth = camera-frame z \[m\]
    pub depth: f64,
}

impl Intrinsics {
    /// The Kinect v1 at 640×480: f = 525 px, c = (319.5, 239.5).
    pub const KINECT: Intrinsics = Intrinsics {
        width: 640,
        height: 480,
        fx: 525.0,
        fy: 525.0,
        cx: 319.5,
        cy: 239.5,
    };

    /// The Kinect v1's nominal intrinsics at 640×480 that the real frames
    /// of `../shared/data/kinect-person/` are read with (their README):
    /// f = 580 px, c = (320, 240).
    pub const KINECT_NOMINAL: Intrinsics = Intrinsics {
        width: 640,
        height: 480,
        fx: 580.0,
        fy: 580.0,
        cx: 320.0,
        cy: 240.0,
    };

    /// Checks sizes (non-zero, at most 2^15 per side) and that the focal
    /// lengths are positive and the principal point finite.
    pub fn validate(&self) -> Result<(), DepthError> {
        if self.width == 0 || self.height == 0 || self.width > 32768 || self.height > 32768 {
            return Err(DepthError::Intrinsics(format!(
                "image size {}x{} must be between 1 and 32768 per side",
                self.width, self.height
            )));
        }
        if !(self.fx.is_finite() && self.fx > 0.0 && self.fy.is_finite() && self.fy > 0.0) {
            return Err(DepthError::Intrinsics(format!(
                "focal lengths fx = {}, fy = {} must be positive and finite",
                self.fx, self.fy
            )));
        }
        if !(self.cx.is_finite() && self.cy.is_finite()) {
            return Err(DepthError::Intrinsics(format!(
                "principal point ({}, {}) must be finite",
                self.cx, self.cy
            )));
        }
        Ok(())
    }

    /// Number of pixels of a frame, `width * height`.
    pub fn pixel_count(&self) -> usize {
        self.width as usize * self.height as usize
    }

    /// Projects a camera-frame point \[m\]: `p_x = f_x x/z + c_x`,
    /// `p_y = f_y y/z + c_y`, depth `z`. `None` if the point is not in front of
    /// the camera (`z <= 0`) or not finite.
    pub fn project(&self, p_camera: &Point3<f64>) -> Option<PixelDepth> {
        let z = p_camera.z;
        if z <= 0.0 || !z.is_finite() || !p_camera.x.is_finite() || !p_camera.y.is_finite() {
            return None;
        }
        Some(PixelDepth {
            px: self.fx * p_camera.x / z + self.cx,
            py: self.fy * p_camera.y / z + self.cy,
            depth: z,
        })
    }

    /// Back-projects pixel coordinates \[px\] and a depth \[m\] to the camera frame:
    /// `x = (p_x − c_x) d / f_x`, `y = (p_y − c_y) d / f_y`, `z = d`.
    pub fn back_project(&self, px: f64, py: f64, depth: f64) -> Point3<f64> {
        Point3::new(
            (px - self.cx) * depth / self.fx,
            (py - self.cy) * depth / self.fy,
            depth,
        )
    }

    /// Camera-frame direction of the ray through `(px, py)`, scaled so that its
    /// z component is 1: the point at depth `d` on the ray is `d · ray(px, py)`.
    pub fn ray(&self, px: f64, py: f64) -> Vector3<f64> {
        Vector3::new((px - self.cx) / self.fx, (py - self.cy) / self.fy, 1.0)
    }

    /// Per-column factors `(u − c_x)/f_x` for u = 0..width (camera x per metre of depth).
    pub fn column_factors(&self) -> Vec<f64> {
        (0..self.width)
            .map(|u| (f64::from(u) - self.cx) / self.fx)
            .collect()
    }

    /// Per-row factors `(v − c_y)/f_y` for v = 0..height (camera y per metre of depth).
    pub fn row_factors(&self) -> Vec<f64> {
        (0..self.height)
            .map(|v| (f64::from(v) - self.cy) / self.fy)
            .collect()
    }
}

/// Rigid transform from the camera frame to the robot base frame
/// (`p_base = R p_camera + t`, `t` = optical centre in the base frame).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct CameraPose {
    base_from_camera: Isometry3<f64>,
}

impl Default for CameraPose {
    /// The paper's set-up, [`CameraPose::paper_default`].
    fn default() -> Self {
        Self::paper_default()
    }
}

impl CameraPose {
    /// A pose from the camera-to-base transform.
    pub fn from_isometry(base_from_camera: Isometry3<f64>) -> Self {
        Self { base_from_camera }
    }

    /// The camera at `eye` looking at `target` (base frame, metres), with the
    /// image's "up" (camera −y) as close to `up` as possible. Camera axes in
    /// the base frame: `z = (target − eye)/‖·‖`, `x = z × up / ‖·‖`, `y = z × x`.
    /// Fails if a point is not finite, `eye == target`, or `up` is zero or
    /// parallel to the viewing direction.
    pub fn look_at(
        eye: &Point3<f64>,
        target: &Point3<f64>,
        up: &Vector3<f64>,
    ) -> Result<Self, DepthError> {
        let mut coordinates = eye.iter().chain(target.iter()).chain(up.iter());
        if !coordinates.all(|c| c.is_finite()) {
            return Err(DepthError::Pose(
                "look_at: eye, target and up must be finite".into(),
            ));
        }
        let forward = target - eye;
        let distance = forward.norm();
        if distance < 1e-9 {
            return Err(DepthError::Pose("look_at: eye and target coincide".into()));
        }
        let z = forward / distance;
        let side = z.cross(up);
        let side_norm = side.norm();
        if side_norm < 1e-9 * up.norm().max(1e-300) || up.norm() < 1e-12 {
            return Err(DepthError::Pose(
                "look_at: up is zero or parallel to the viewing direction".into(),
            ));
        }
        let x = side / side_norm;
        let y = z.cross(&x);
        let rotation = Rotation3::from_basis_unchecked(&[x, y, z]);
        Ok(Self {
            base_from_camera: Isometry3::from_parts(
                Translation3::from(eye.coords),
                UnitQuaternion::from_rotation_matrix(&rotation),
            ),
        })
    }

    /// The paper's set-up (REFERENCE §6) at azimuth `azimuth` \[rad\] around the
    /// base z axis: eye = (2 cos a, 2 sin a, 1.2) m, looking at
    /// (0.3, 0.0, 0.4) m, image up = base +z.
    pub fn paper_setup(azimuth: f64) -> Result<Self, DepthError> {
        let eye = Point3::new(
            PAPER_CAMERA_RADIUS_M * azimuth.cos(),
            PAPER_CAMERA_RADIUS_M * azimuth.sin(),
            PAPER_CAMERA_HEIGHT_M,
        );
        let [tx, ty, tz] = PAPER_CAMERA_TARGET_M;
        Self::look_at(&eye, &Point3::new(tx, ty, tz), &Vector3::z())
    }

    /// [`CameraPose::paper_setup`] at the default azimuth 0.6 rad (front-left
    /// of the robot, whose x axis points forward).
    pub fn paper_default() -> Self {
        let eye = Point3::new(
            PAPER_CAMERA_RADIUS_M * PAPER_CAMERA_AZIMUTH_RAD.cos(),
            PAPER_CAMERA_RADIUS_M * PAPER_CAMERA_AZIMUTH_RAD.sin(),
            PAPER_CAMERA_HEIGHT_M,
        );
        let [tx, ty, tz] = PAPER_CAMERA_TARGET_M;
        let target = Point3::new(tx, ty, tz);
        // the construction above is never degenerate (eye ≠ target, the view is
        // not vertical); fall back to the explicit frame for completeness
        Self::look_at(&eye, &target, &Vector3::z()).unwrap_or(Self {
            base_from_camera: Isometry3::translation(eye.x, eye.y, eye.z),
        })
    }

    /// The camera-to-base transform.
    pub fn base_from_camera(&self) -> &Isometry3<f64> {
        &self.base_from_camera
    }

    /// Optical centre in the base frame \[m\].
    pub fn position(&self) -> Point3<f64> {
        Point3::from(self.base_from_camera.translation.vector)
    }

    /// Rotation matrix whose columns are the camera axes in the base frame.
    pub fn rotation(&self) -> Rotation3<f64> {
        self.base_from_camera.rotation.to_rotation_matrix()
    }

    /// Base-frame point → camera frame.
    pub fn to_camera(&self, p_base: &Point3<f64>) -> Point3<f64> {
        self.base_from_camera.inverse_transform_point(p_base)
    }

    /// Camera-frame point → base frame.
    pub fn to_base(&self, p_camera: &Point3<f64>) -> Point3<f64> {
        self.base_from_camera.transform_point(p_camera)
    }

    /// Base-frame vector → camera frame (rotation only).
    pub fn vector_to_camera(&self, v_base: &Vector3<f64>) -> Vector3<f64> {
        self.base_from_camera.inverse_transform_vector(v_base)
    }

    /// Camera-frame vector → base frame (rotation only).
    pub fn vector_to_base(&self, v_camera: &Vector3<f64>) -> Vector3<f64> {
        self.base_from_camera.transform_vector(v_camera)
    }

    /// Projects a base-frame point \[m\] with `intrinsics`; `None` if it is not
    /// in front of the camera.
    pub fn project(&self, intrinsics: &Intrinsics, p_base: &Point3<f64>) -> Option<PixelDepth> {
        intrinsics.project(&self.to_camera(p_base))
    }

    /// Back-projects pixel coordinates \[px\] and depth \[m\] to the base frame.
    pub fn back_project(
        &self,
        intrinsics: &Intrinsics,
        px: f64,
        py: f64,
        depth: f64,
    ) -> Point3<f64> {
        self.to_base(&intrinsics.back_project(px, py, depth))
    }
}
