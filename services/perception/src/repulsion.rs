//! A repulsion worker: for its control points, at the frame's joint state, the
//! depth-space distance and repulsive vector (eqs. 15-18).

use nalgebra::{Point3, Vector3};
use phri_depth::{DepthSpaceDistance, PointOfInterest, RepulsionParams};
use phri_ipc::{FrameHeader, PointRepulsion, MAX_POINTS_PER_WORKER};
use phri_model::{Data, Model};

use crate::camera::header_camera;
use crate::config::RepulsionConfig;

/// One worker's state; `step` allocates nothing after the first frame.
pub struct Worker {
    model: Model,
    data: Data,
    params: RepulsionParams,
    /// (point index, frame id, point in the link frame, radius)
    points: Vec<(usize, usize, Vector3<f64>, f64)>,
    distance: Option<(u64, DepthSpaceDistance)>,
    out: [PointRepulsion; MAX_POINTS_PER_WORKER],
}

impl Worker {
    pub fn new(model: Model, cfg: &RepulsionConfig, worker: u32) -> Result<Worker, String> {
        if cfg.workers == 0 || worker >= cfg.workers {
            return Err(format!(
                "[repulsion] workers = {}: worker {worker} does not exist",
                cfg.workers
            ));
        }
        let mine = cfg.points_of(worker);
        if mine.len() > MAX_POINTS_PER_WORKER {
            return Err(format!(
                "[repulsion]: worker {worker} would own {} points, at most {MAX_POINTS_PER_WORKER}",
                mine.len()
            ));
        }
        let mut points = Vec::new();
        for i in mine {
            let p = &cfg.points[i];
            let frame = model.frame_id(&p.link).map_err(|_| {
                format!(
                    "[repulsion] points[{i}] ({}): unknown link '{}'",
                    p.name, p.link
                )
            })?;
            if !(p.radius >= 0.0) || p.xyz.iter().any(|x| !x.is_finite()) {
                return Err(format!(
                    "[repulsion] points[{i}] ({}): position and radius must be finite, radius ≥ 0",
                    p.name
                ));
            }
            points.push((i, frame, Vector3::from(p.xyz), p.radius));
        }
        cfg.params
            .validate()
            .map_err(|e| format!("[repulsion] params: {e}"))?;
        Ok(Worker {
            data: Data::new(&model),
            params: cfg.params,
            points,
            distance: None,
            out: [PointRepulsion::default(); MAX_POINTS_PER_WORKER],
            model,
        })
    }

    pub fn n_points(&self) -> usize {
        self.points.len()
    }

    /// Results for `frame` (filtered, with the joint state in its header).
    pub fn step(
        &mut self,
        header: &FrameHeader,
        frame: &[u16],
    ) -> Result<&[PointRepulsion], String> {
        let n = self.model.nv();
        if header.dof as usize != n {
            return Err(format!(
                "frame {}: joint state of {} joints, the model has {n}",
                header.seq, header.dof
            ));
        }
        let key = header.width as u64
            ^ header.fx.to_bits()
            ^ header.pose_t[0].to_bits().rotate_left(7)
            ^ header.pose_t[2].to_bits().rotate_left(13);
        if self.distance.as_ref().is_none_or(|(k, _)| *k != key) {
            let (k, pose) = header_camera(header)?;
            self.distance = Some((
                key,
                DepthSpaceDistance::new(k, pose, self.params, header.depth_scale)
                    .map_err(|e| e.to_string())?,
            ));
        }
        phri_model::forward_kinematics(&self.model, &mut self.data, &header.q[..n])
            .map_err(|e| e.to_string())?;
        let Some((_, dist)) = self.distance.as_ref() else {
            return Ok(&self.out[..0]);
        };
        for (slot, &(index, frame_id, xyz, radius)) in self.out.iter_mut().zip(&self.points) {
            let p = phri_model::frame_placement(&self.model, &self.data, frame_id).apply(&xyz);
            let r = dist
                .repulsion(frame, &PointOfInterest::new(Point3::from(p), radius))
                .map_err(|e| e.to_string())?;
            *slot = PointRepulsion {
                point: index as u32,
                active: r.obstacle_point.is_some() as u32,
                v_call: [r.v_call.x, r.v_call.y, r.v_call.z],
                min_distance: r.min_distance,
                obstacle: r.obstacle_point.map_or([0.0; 3], |o| [o.x, o.y, o.z]),
                position: [p.x, p.y, p.z],
            };
        }
        Ok(&self.out[..self.points.len()])
    }
}
