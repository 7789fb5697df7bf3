//! The simulated depth camera: renders the world (human capsules, the arm at
//! its true joints, the table and the floor) into a millimetre depth frame
//! and stamps it; and the camera fields a frame header carries.

use nalgebra::{Isometry3, Matrix3, Point3, Rotation3, Translation3, UnitQuaternion};
use phri_config::{CameraConfig, Invalid};
use phri_depth::{Aabb, CameraPose, Capsule, DepthError, Intrinsics, Renderer};
use phri_ipc::{FrameHeader, WorldState, Zeroed};
use phri_model::{Data, Model, ModelError};

use crate::robot::robot_capsules;

/// Depth unit of every frame of this pipeline \[m\]: millimetres.
pub const DEPTH_SCALE_M: f64 = phri_depth::png::MILLIMETRE_SCALE_M;

/// Why the camera could not be built or could not render a frame.
#[derive(Debug, thiserror::Error)]
pub enum CameraError {
    /// an invalid `[camera]` section (or its pose)
    #[error(transparent)]
    Config(#[from] Invalid),
    /// the renderer refused the intrinsics, pose or sensor model
    #[error("camera: {0}")]
    Renderer(#[source] DepthError),
    /// rendering a frame failed
    #[error("camera: {0}")]
    Render(#[source] DepthError),
    /// the arm could not be placed at the world's joint positions (kinematics)
    #[error("camera: {0}")]
    Model(#[from] ModelError),
}

/// A frame header whose camera fields do not describe a camera.
#[derive(Clone, Debug, PartialEq, thiserror::Error)]
pub enum HeaderError {
    /// the intrinsics describe no camera (size, focal lengths, principal point)
    #[error(transparent)]
    Intrinsics(DepthError),
    /// an entry of the pose is NaN or infinite
    #[error("camera pose not finite")]
    PoseNotFinite,
    /// the pose's rotation is not orthonormal
    #[error("camera rotation is not orthonormal")]
    NotOrthonormal,
}

/// Camera state; `step` allocates nothing after the first frame.
pub struct CameraSim {
    model: Model,
    data: Data,
    renderer: Renderer,
    intrinsics: Intrinsics,
    pose: CameraPose,
    table: [Aabb; 1],
    floor_z: Option<f64>,
    capsules: Vec<Capsule>,
    robot: Vec<Capsule>,
    seq: u64,
}

impl CameraSim {
    /// The camera of `[camera]` (validated here) watching `model`.
    pub fn new(model: Model, cfg: &CameraConfig) -> Result<CameraSim, CameraError> {
        cfg.validate()?;
        let pose = cfg.pose()?;
        let renderer =
            Renderer::new(cfg.intrinsics, pose, cfg.render).map_err(CameraError::Renderer)?;
        let table = Aabb::new(Point3::from(cfg.table_min), Point3::from(cfg.table_max));
        Ok(CameraSim {
            data: Data::new(&model),
            renderer,
            intrinsics: cfg.intrinsics,
            pose,
            table: [table],
            floor_z: cfg.floor_z,
            capsules: Vec::with_capacity(64),
            robot: Vec::with_capacity(32),
            seq: 0,
            model,
        })
    }

    /// The camera's pose in the robot base frame.
    pub fn pose(&self) -> CameraPose {
        self.pose
    }

    /// Number of pixels of a frame.
    pub fn pixels(&self) -> usize {
        self.intrinsics.pixel_count()
    }

    /// Capture `world` into `out` (`pixels()` depths \[mm\], row-major) and
    /// write its whole `header`: the next frame number, intrinsics and pose
    /// ([`fill_camera_header`]), the capture time (the world's stamp [ns,
    /// robot clock]), `capture_wall_ns` [ns, CLOCK_MONOTONIC] as given (the
    /// lock-step cell passes its robot time) and the valid pixels.
    /// `published_ns` stays 0: the publisher sets it when it sends.
    ///
    /// The arm is drawn only when `world` carries the model's joint count.
    pub fn step(
        &mut self,
        world: &WorldState,
        capture_wall_ns: u64,
        out: &mut [u16],
        header: &mut FrameHeader,
    ) -> Result<(), CameraError> {
        let n = (world.dof as usize).min(self.model.nv());
        self.capsules.clear();
        if n == self.model.nv() {
            phri_model::forward_kinematics(&self.model, &mut self.data, &world.q[..n])?;
            robot_capsules(&self.model, &self.data, 0.0, &mut self.robot);
            self.capsules.extend_from_slice(&self.robot);
        }
        for h in world
            .human
            .iter()
            .take((world.n_human as usize).min(world.human.len()))
        {
            let c = Capsule::new(Point3::from(h.a), Point3::from(h.b), h.radius);
            if c.is_valid() {
                self.capsules.push(c);
            }
        }
        self.renderer
            .render(&self.capsules, &self.table, self.floor_z, out)
            .map_err(CameraError::Render)?;
        self.seq += 1;
        *header = FrameHeader::zeroed();
        fill_camera_header(header, self.seq, &self.intrinsics, &self.pose);
        header.capture_ns = world.stamp_ns;
        header.capture_wall_ns = capture_wall_ns;
        header.valid_pixels = out.iter().filter(|&&d| d > 0).count() as u32;
        Ok(())
    }
}

/// Camera fields of a frame header: frame number `seq`, intrinsics \[px\], the
/// camera pose in the base frame, millimetre depths.
pub fn fill_camera_header(h: &mut FrameHeader, seq: u64, k: &Intrinsics, pose: &CameraPose) {
    h.seq = seq;
    h.width = k.width;
    h.height = k.height;
    h.fx = k.fx;
    h.fy = k.fy;
    h.cx = k.cx;
    h.cy = k.cy;
    h.depth_scale = DEPTH_SCALE_M;
    let iso = pose.base_from_camera();
    let r = iso.rotation.to_rotation_matrix();
    for i in 0..3 {
        for j in 0..3 {
            h.pose_r[3 * i + j] = r[(i, j)];
        }
        h.pose_t[i] = iso.translation.vector[i];
    }
}

/// Intrinsics and pose carried by a frame header.
pub fn header_camera(h: &FrameHeader) -> Result<(Intrinsics, CameraPose), HeaderError> {
    let k = Intrinsics {
        width: h.width,
        height: h.height,
        fx: h.fx,
        fy: h.fy,
        cx: h.cx,
        cy: h.cy,
    };
    k.validate().map_err(HeaderError::Intrinsics)?;
    if h.pose_r
        .iter()
        .chain(h.pose_t.iter())
        .any(|x| !x.is_finite())
    {
        return Err(HeaderError::PoseNotFinite);
    }
    let m = Matrix3::from_row_slice(&h.pose_r);
    if (m * m.transpose() - Matrix3::identity()).amax() > 1e-6 {
        return Err(HeaderError::NotOrthonormal);
    }
    let rot = UnitQuaternion::from_rotation_matrix(&Rotation3::from_matrix_unchecked(m));
    let iso = Isometry3::from_parts(
        Translation3::new(h.pose_t[0], h.pose_t[1], h.pose_t[2]),
        rot,
    );
    Ok((k, CameraPose::from_isometry(iso)))
}

#[cfg(test)]
mod tests {
    use super::*;
    use phri_config::Loaded;

    #[test]
    fn a_header_round_trips_its_camera_and_bad_ones_are_refused() {
        let pose = CameraPose::paper_setup(0.6).unwrap();
        let k = Loaded::defaults().config.camera.intrinsics;
        let mut h = FrameHeader::zeroed();
        fill_camera_header(&mut h, 3, &k, &pose);
        let (k2, p2) = header_camera(&h).unwrap();
        assert_eq!(k2, k);
        let (a, b) = (pose.base_from_camera(), p2.base_from_camera());
        assert!((a.translation.vector - b.translation.vector).norm() < 1e-12);
        assert!(a.rotation.angle_to(&b.rotation) < 1e-9);
        let mut bad = h;
        bad.pose_t[1] = f64::NAN;
        assert_eq!(header_camera(&bad).unwrap_err(), HeaderError::PoseNotFinite);
        let mut bad = h;
        bad.pose_r[0] = 2.0;
        assert_eq!(
            header_camera(&bad).unwrap_err(),
            HeaderError::NotOrthonormal
        );
        let mut bad = h;
        bad.width = 0;
        assert!(matches!(
            header_camera(&bad),
            Err(HeaderError::Intrinsics(_))
        ));
    }

    #[test]
    fn a_capture_is_stamped_with_the_world_and_the_callers_clock() {
        let loaded = Loaded::defaults();
        let mut cam = CameraSim::new(loaded.model().unwrap(), &loaded.config.camera).unwrap();
        let mut world = WorldState::zeroed();
        world.stamp_ns = 123_000_000;
        world.dof = 7;
        let mut frame = vec![0u16; cam.pixels()];
        let mut h = FrameHeader::zeroed();
        h.published_ns = 99; // overwritten: the header is the capture's own
        cam.step(&world, 456, &mut frame, &mut h).unwrap();
        assert_eq!(
            (h.seq, h.capture_ns, h.capture_wall_ns, h.published_ns),
            (1, 123_000_000, 456, 0)
        );
        assert_eq!(h.depth_scale, DEPTH_SCALE_M);
        assert_eq!(
            h.valid_pixels as usize,
            frame.iter().filter(|&&d| d > 0).count()
        );
        assert!(
            h.valid_pixels > 0,
            "the arm, the table and the floor are in view"
        );
        cam.step(&world, 457, &mut frame, &mut h).unwrap();
        assert_eq!(h.seq, 2);
        let mut bad = loaded.config.camera.clone();
        bad.rate_hz = 0.0;
        assert!(matches!(
            CameraSim::new(loaded.model().unwrap(), &bad),
            Err(CameraError::Config(_))
        ));
    }
}
