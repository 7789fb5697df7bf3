//! A repulsion worker: for its control points, at the frame's joint state, the
//! depth-space distance and repulsive vector (eqs. 15-18), and the
//! `perception/repulsion` message that carries them. In a cell of several
//! cameras each camera's answer is a lower bound of the true distance only
//! over the space that camera watches: a worker then bounds it by the view
//! too ([`Worker::bounded_by`], [`phri_depth::fusion`]) and caps it by the
//! nearest surface any camera saw ([`SeenSurfaces`], [`Worker::respond_among`]),
//! and the controller takes, per point, the largest of the fresh cameras'
//! bounds.

use nalgebra::{Point3, Vector3};
use phri_config::{Invalid, RepulsionConfig};
use phri_depth::{
    capped_by_surface, fuse, CameraView, DepthError, DepthSpaceDistance, PointOfInterest,
    RepulsionParams, SeenSurface,
};
use phri_ipc::{FrameHeader, PointRepulsion, RepulsionResult, Zeroed, MAX_POINTS_PER_WORKER};
use phri_model::{Data, Model, ModelError};

use crate::camera::{header_camera, HeaderError};
use crate::surfaces::SeenSurfaces;

/// Why a worker could not be built or could not answer a frame.
#[derive(Debug, thiserror::Error)]
pub enum RepulsionError {
    /// an invalid `[repulsion]` section
    #[error(transparent)]
    Config(#[from] Invalid),
    /// the worker index is not below `repulsion.workers`
    #[error("repulsion.workers = {workers}: worker {worker} does not exist")]
    NoSuchWorker {
        /// the worker index asked for
        worker: u32,
        /// workers configured
        workers: u32,
    },
    /// a control point names a link the model does not have
    #[error("repulsion.points[{index}] ({name}): unknown link '{link}'")]
    UnknownLink {
        /// index of the point in `repulsion.points`
        index: usize,
        /// the point's name
        name: String,
        /// the link it names
        link: String,
    },
    /// `repulsion.params` refused by the depth-space distance
    #[error("repulsion.params: {0}")]
    Params(#[source] DepthError),
    /// the frame's joint state is not one of this model
    #[error("frame {seq}: joint state of {got} joints, the model has {model}")]
    Dof {
        /// the frame's sequence number
        seq: u64,
        /// joints of the state in the frame's header
        got: u32,
        /// joints of the model
        model: usize,
    },
    /// the frame header's camera fields describe no camera
    #[error("frame {seq}: {source}")]
    Camera {
        /// the frame's sequence number
        seq: u64,
        /// what is wrong with the header
        source: HeaderError,
    },
    /// the depth-space distance refused the camera or the frame
    #[error("frame {seq}: {source}")]
    Depth {
        /// the frame's sequence number
        seq: u64,
        /// its error
        source: DepthError,
    },
    /// the control points could not be placed at the frame's joint state
    /// (kinematics)
    #[error("frame {seq}: {source}")]
    Model {
        /// the frame's sequence number
        seq: u64,
        /// the kinematics error
        source: ModelError,
    },
}

/// One worker's state; `step` allocates nothing after the first frame.
pub struct Worker {
    model: Model,
    data: Data,
    params: RepulsionParams,
    /// (point index, frame id, point in the link frame [m], radius [m])
    points: Vec<(usize, usize, Vector3<f64>, f64)>,
    distance: Option<(u64, DepthSpaceDistance)>,
    /// the space its camera watches, when the cell has several cameras
    view: Option<CameraView>,
    out: [PointRepulsion; MAX_POINTS_PER_WORKER],
    msg: RepulsionResult,
    /// place the control points but scan nothing ([`Worker::set_positions_only`])
    positions_only: bool,
}

impl Worker {
    /// Worker `worker` of `[repulsion]` (validated here): the points `i` with
    /// `i mod workers = worker`.
    pub fn new(model: Model, cfg: &RepulsionConfig, worker: u32) -> Result<Worker, RepulsionError> {
        cfg.validate()?;
        if worker >= cfg.workers {
            return Err(RepulsionError::NoSuchWorker {
                worker,
                workers: cfg.workers,
            });
        }
        let mut points = Vec::new();
        for i in cfg.points_of(worker) {
            let p = &cfg.points[i];
            let frame = model
                .frame_id(&p.link)
                .map_err(|_| RepulsionError::UnknownLink {
                    index: i,
                    name: p.name.clone(),
                    link: p.link.clone(),
                })?;
            points.push((i, frame, Vector3::from(p.xyz), p.radius));
        }
        cfg.params.validate().map_err(RepulsionError::Params)?;
        let mut msg = RepulsionResult::zeroed();
        msg.worker = worker;
        msg.workers = cfg.workers;
        Ok(Worker {
            data: Data::new(&model),
            params: cfg.params,
            points,
            distance: None,
            view: None,
            out: [PointRepulsion::default(); MAX_POINTS_PER_WORKER],
            msg,
            model,
            positions_only: false,
        })
    }

    /// With `on`, each answer places the control points at the frame's
    /// joint state and scans nothing: every point inactive, at ρ (a
    /// lock-step cell whose distances are replaced by the simulator's truth
    /// renders its frames for the tracker and ingestion, and spends nothing
    /// on scans it would throw away).
    pub fn set_positions_only(&mut self, on: bool) {
        self.positions_only = on;
    }

    /// This worker's answers bounded by what `camera` watches (space outside
    /// its view or range counts as occupied): each camera's distance is then
    /// a lower bound of the truth, so the largest over cameras is one too.
    /// For cells of several cameras; one camera's answers stay the paper's.
    pub fn bounded_by(mut self, camera: &phri_config::CameraConfig) -> Result<Worker, Invalid> {
        let view = CameraView::new(
            &camera.intrinsics,
            camera.pose()?,
            camera.render.min_range_m,
            camera.render.max_range_m,
        )
        .map_err(|e| Invalid::new("camera", e.to_string()))?;
        self.view = Some(view);
        Ok(self)
    }

    /// Control points this worker answers for.
    pub fn n_points(&self) -> usize {
        self.points.len()
    }

    /// Results for `frame` (filtered depths \[mm\], with the joint state in
    /// its header), one per control point of this worker: the point and the
    /// closest obstacle [m, base frame], their distance \[m\] and the repulsive
    /// velocity V_Call [m/s, base frame].
    pub fn step(
        &mut self,
        header: &FrameHeader,
        frame: &[u16],
    ) -> Result<&[PointRepulsion], RepulsionError> {
        self.answer(header, frame, None)
    }

    /// [`Worker::step`] for camera `camera` of several, sharing `seen` with
    /// this worker's answers for the others: the surfaces this frame shows
    /// are recorded there, and each bound is capped by the nearest surface
    /// any camera saw from the point in frames captured near this one
    /// ([`capped_by_surface`]): where another camera saw a surface nearer
    /// than this one's bound, the answer is that surface's. Only for a
    /// worker [`Worker::bounded_by`] its camera; otherwise as
    /// [`Worker::step`].
    pub fn step_among(
        &mut self,
        header: &FrameHeader,
        frame: &[u16],
        camera: usize,
        seen: &mut SeenSurfaces,
    ) -> Result<&[PointRepulsion], RepulsionError> {
        self.answer(header, frame, Some((camera, seen)))
    }

    fn answer(
        &mut self,
        header: &FrameHeader,
        frame: &[u16],
        mut among: Option<(usize, &mut SeenSurfaces)>,
    ) -> Result<&[PointRepulsion], RepulsionError> {
        let n = self.model.nv();
        let seq = header.seq;
        if header.dof as usize != n || n > header.q.len() {
            return Err(RepulsionError::Dof {
                seq,
                got: header.dof,
                model: n,
            });
        }
        let key = header.width as u64
            ^ header.fx.to_bits()
            ^ header.pose_t[0].to_bits().rotate_left(7)
            ^ header.pose_t[2].to_bits().rotate_left(13);
        if self.distance.as_ref().is_none_or(|(k, _)| *k != key) {
            let (k, pose) =
                header_camera(header).map_err(|source| RepulsionError::Camera { seq, source })?;
            self.distance = Some((
                key,
                DepthSpaceDistance::new(k, pose, self.params, header.depth_scale)
                    .map_err(|source| RepulsionError::Depth { seq, source })?,
            ));
        }
        phri_model::forward_kinematics(&self.model, &mut self.data, &header.q[..n])
            .map_err(|source| RepulsionError::Model { seq, source })?;
        let Some((_, dist)) = self.distance.as_ref() else {
            return Ok(&self.out[..0]);
        };
        for (k, (slot, &(index, frame_id, xyz, radius))) in
            self.out.iter_mut().zip(&self.points).enumerate()
        {
            let p = phri_model::frame_placement(&self.model, &self.data, frame_id).apply(&xyz);
            if self.positions_only {
                *slot = PointRepulsion {
                    point: index as u32,
                    min_distance: self.params.rho,
                    position: [p.x, p.y, p.z],
                    ..PointRepulsion::default()
                };
                continue;
            }
            let poi = PointOfInterest::new(Point3::from(p), radius);
            let mut r = dist
                .repulsion(frame, &poi)
                .map_err(|source| RepulsionError::Depth { seq, source })?;
            if let Some(view) = self.view.as_ref() {
                let mut bound = view.bound(&poi, &r, self.params.rho);
                if let Some((camera, seen)) = among.as_mut() {
                    let own = r.surface_point.map(|point| SeenSurface {
                        clearance: r.surface_distance,
                        point,
                    });
                    seen.record(*camera, header.capture_ns, k, own);
                    let nearest = seen.nearest(k, header.capture_ns);
                    (bound, r) = capped_by_surface(bound, &r, &poi, nearest, &self.params);
                }
                r = fuse([(bound, &r)], &self.params).repulsion;
            }
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

    /// [`Worker::step`] as this worker's `perception/repulsion` message: its
    /// results, the frame's sequence and capture times, the worker's index
    /// and the configured worker count, and `seq` counting the results. The
    /// caller sets `compute_ns` and `published_ns` (the service: its clock
    /// when it publishes) before sending.
    pub fn respond(
        &mut self,
        header: &FrameHeader,
        frame: &[u16],
    ) -> Result<&mut RepulsionResult, RepulsionError> {
        let n = self.step(header, frame)?.len();
        Ok(self.message(header, n))
    }

    /// [`Worker::respond`] with [`Worker::step_among`]'s answers when the
    /// cell shares its cameras' surfaces (`seen`), as [`Worker::respond`]
    /// without.
    pub fn respond_among(
        &mut self,
        header: &FrameHeader,
        frame: &[u16],
        camera: usize,
        seen: Option<&mut SeenSurfaces>,
    ) -> Result<&mut RepulsionResult, RepulsionError> {
        let n = self.answer(header, frame, seen.map(|s| (camera, s)))?.len();
        Ok(self.message(header, n))
    }

    fn message(&mut self, header: &FrameHeader, n: usize) -> &mut RepulsionResult {
        let m = &mut self.msg;
        m.n_points = n as u32;
        m.points[..n].copy_from_slice(&self.out[..n]);
        m.seq += 1;
        m.frame_seq = header.seq;
        m.capture_ns = header.capture_ns;
        m.frame_capture_wall_ns = header.capture_wall_ns;
        m.compute_ns = 0;
        m.published_ns = 0;
        m
    }
}
