//! The simulated depth camera: renders the world (human capsules, the arm at
//! its true joints, the table and the floor) into a millimetre depth frame.

use nalgebra::Point3;
use phri_depth::{Aabb, CameraPose, Capsule, Intrinsics, Renderer};
use phri_ipc::{FrameHeader, WorldState};
use phri_model::{Data, Model};

use crate::config::CameraConfig;
use crate::robot::robot_capsules;

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
    pub fn new(model: Model, cfg: &CameraConfig) -> Result<CameraSim, String> {
        let pose = cfg.pose()?;
        let renderer = Renderer::new(cfg.intrinsics, pose, cfg.render)
            .map_err(|e| format!("[camera]: {e}"))?;
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

    /// Number of pixels of a frame.
    pub fn pixels(&self) -> usize {
        self.intrinsics.pixel_count()
    }

    /// Render `world` into `out`; fill `header` (times are the caller's).
    pub fn step(
        &mut self,
        world: &WorldState,
        out: &mut [u16],
        header: &mut FrameHeader,
    ) -> Result<(), String> {
        let n = (world.dof as usize).min(self.model.nv());
        self.capsules.clear();
        if n == self.model.nv() {
            phri_model::forward_kinematics(&self.model, &mut self.data, &world.q[..n])
                .map_err(|e| e.to_string())?;
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
            .map_err(|e| e.to_string())?;
        self.seq += 1;
        fill_camera_header(header, self.seq, &self.intrinsics, &self.pose);
        header.valid_pixels = out.iter().filter(|&&d| d > 0).count() as u32;
        Ok(())
    }
}

/// Camera fields of a frame header: sequence, intrinsics, pose, millimetres.
pub fn fill_camera_header(h: &mut FrameHeader, seq: u64, k: &Intrinsics, pose: &CameraPose) {
    h.seq = seq;
    h.width = k.width;
    h.height = k.height;
    h.fx = k.fx;
    h.fy = k.fy;
    h.cx = k.cx;
    h.cy = k.cy;
    h.depth_scale = 0.001;
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
pub fn header_camera(h: &FrameHeader) -> Result<(Intrinsics, CameraPose), String> {
    let k = Intrinsics {
        width: h.width,
        height: h.height,
        fx: h.fx,
        fy: h.fy,
        cx: h.cx,
        cy: h.cy,
    };
    k.validate().map_err(|e| format!("frame {}: {e}", h.seq))?;
    if h.pose_r
        .iter()
        .chain(h.pose_t.iter())
        .any(|x| !x.is_finite())
    {
        return Err(format!("frame {}: camera pose not finite", h.seq));
    }
    let m = nalgebra::Matrix3::from_row_slice(&h.pose_r);
    if (m * m.transpose() - nalgebra::Matrix3::identity()).amax() > 1e-6 {
        return Err(format!(
            "frame {}: camera rotation is not orthonormal",
            h.seq
        ));
    }
    let rot = nalgebra::UnitQuaternion::from_rotation_matrix(
        &nalgebra::Rotation3::from_matrix_unchecked(m),
    );
    let iso = nalgebra::Isometry3::from_parts(
        nalgebra::Translation3::new(h.pose_t[0], h.pose_t[1], h.pose_t[2]),
        rot,
    );
    Ok((k, CameraPose::from_isometry(iso)))
}
