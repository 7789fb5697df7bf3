//! The avoidance stage: a behaviour's Cartesian reference of the end
//! effector becomes the joint reference. Under perception (paper Sect. V)
//! the end effector's repulsive vector adds to its task velocity (eq. 19),
//! every other control point shapes the joint velocity bounds (eq. 20) and
//! SNS solves the task within them and the joint-limit bounds; without
//! perception, CLIK with a null-space posture.

use nalgebra::{Matrix6xX, Vector3};
use phri_config::{ControlConfig, PointConfig};
use phri_model::{Data, Model, ModelError};

use crate::avoidance::Avoidance;
use crate::clik::{Clik, ClikGains};
use crate::error::ControlError;
use crate::inputs::PerceptionView;
use crate::modes::CartesianRef;
use crate::reference::JointReference;

/// Failures met while resolving, counted (each leaves the fail-safe it always had).
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub struct Faults {
    /// model calls refused (kinematics, Jacobians)
    pub model: u64,
    /// avoidance or SNS refusals (dimensions, inconsistent bounds, non-finite values)
    pub avoidance: u64,
}

/// CLIK, the avoidance with its SNS solver, and the control points,
/// preallocated for one robot.
pub struct Resolver {
    clik: Clik,
    avoidance: Avoidance,
    /// control points: (link frame, point in it \[m\]); 0 is the end effector
    points: Vec<(usize, Vector3<f64>)>,
    jac_ee: Matrix6xX<f64>,
    jac_point: Matrix6xX<f64>,
    /// low-passed repulsive vectors per control point [m/s], base frame
    v_call_filtered: Vec<Vector3<f64>>,
    /// task scale of the last SNS solution
    task_scale: f64,
}

impl Resolver {
    /// For the end effector `ee_frame` of `model`.
    pub fn new(model: &Model, ee_frame: usize, cfg: &ControlConfig) -> Resolver {
        Resolver {
            clik: Clik::new(model, ee_frame),
            avoidance: Avoidance::new(model, cfg.avoidance_params),
            points: Vec::new(),
            jac_ee: Data::jacobian_buffer(model),
            jac_point: Data::jacobian_buffer(model),
            v_call_filtered: Vec::new(),
            task_scale: 1.0,
        }
    }

    /// The control points of the repulsion workers, in their configured
    /// order (the first is the end effector); an unknown link names its key.
    pub fn set_control_points(
        &mut self,
        model: &Model,
        points: &[PointConfig],
    ) -> Result<(), ControlError> {
        self.points = points
            .iter()
            .enumerate()
            .map(|(i, p)| {
                let f = model
                    .frame_id(&p.link)
                    .map_err(|_| ControlError::UnknownLink {
                        key: format!("repulsion.points[{i}].link"),
                        link: p.link.clone(),
                    })?;
                Ok((f, Vector3::from(p.xyz)))
            })
            .collect::<Result<_, ControlError>>()?;
        self.v_call_filtered = vec![Vector3::zeros(); points.len()];
        Ok(())
    }

    /// Position of the end effector at `q` \[m\], base frame.
    pub fn ee_position(
        &self,
        model: &Model,
        data: &mut Data,
        q: &[f64],
    ) -> Result<Vector3<f64>, ModelError> {
        self.clik.position(model, data, q)
    }

    /// Task scale of the last SNS solution (1 without perception).
    pub fn task_scale(&self) -> f64 {
        self.task_scale
    }

    /// Without perception: CLIK moves `q_ref` after `c`, writes `qd_ref`.
    #[allow(clippy::too_many_arguments)]
    pub fn clik(
        &mut self,
        model: &Model,
        data: &mut Data,
        reference: &mut JointReference,
        c: &CartesianRef,
        dt: f64,
        cfg: &ControlConfig,
        posture: &[f64],
        vmax: &[f64],
    ) -> Faults {
        let gains = ClikGains {
            clik: cfg.clik_gain,
            posture: cfg.posture_gain,
            damping: cfg.damping,
        };
        let step = self.clik.step(
            model,
            data,
            &mut reference.q_ref,
            &c.x_d,
            &c.xd_d,
            dt,
            gains,
            posture,
            vmax,
        );
        let model_errors = u64::from(step.is_err());
        reference.qd_ref.copy_from_slice(self.clik.velocity());
        Faults {
            model: model_errors,
            avoidance: 0,
        }
    }

    /// The task under avoidance (paper Sect. V): the end effector's repulsive
    /// velocity adds to its task velocity (eq. 19); every other control point
    /// shapes the joint velocity bounds (eq. 20); SNS solves the task within
    /// them and the joint-limit bounds. Moves `q_ref`, writes `qd_ref`.
    /// `perception`: fresh results (`None`: stale, no repulsion).
    #[allow(clippy::too_many_arguments)]
    pub fn avoid(
        &mut self,
        model: &Model,
        data: &mut Data,
        reference: &mut JointReference,
        c: &CartesianRef,
        dt: f64,
        cfg: &ControlConfig,
        perception: Option<PerceptionView<'_>>,
    ) -> Faults {
        let mut faults = Faults::default();
        let ee = self.clik.frame();
        let kinematics =
            phri_model::forward_kinematics(model, data, &reference.q_ref).and_then(|_| {
                phri_model::point_jacobian(model, data, ee, &Vector3::zeros(), &mut self.jac_ee)
            });
        if kinematics.is_err() {
            faults.model += 1;
            reference.qd_ref.fill(0.0);
            return faults;
        }
        if self.avoidance.begin(&reference.q_ref).is_err() {
            faults.avoidance += 1;
            reference.qd_ref.fill(0.0);
            return faults;
        }
        let x = phri_model::frame_placement(model, data, ee).p;
        // position feedback capped below the repulsion's V_max
        let mut fb = (c.x_d - x) * cfg.clik_gain;
        let cap = cfg.feedback_max_speed;
        if fb.norm() > cap {
            fb *= cap / fb.norm();
        }
        let xdot_task = c.xd_d + fb;
        let mut v_ee = Vector3::zeros();
        let alpha = if cfg.repulsion_filter_s > 0.0 {
            1.0 - (-dt / cfg.repulsion_filter_s).exp()
        } else {
            1.0
        };
        if let Some(v) = perception {
            for (k, &(frame, xyz)) in self.points.iter().enumerate() {
                let Some(p) = v.points.get(k) else { break };
                let margin = match c.collab_touching {
                    true => BEHIND_MARGIN_CONTACT_M,
                    false => BEHIND_MARGIN_M,
                };
                let behind_the_hand =
                    k == 0 && c.collab_hand.is_some_and(|h| behind(&h, p, margin));
                let target = if p.active == 0 || behind_the_hand {
                    Vector3::zeros()
                } else {
                    Vector3::from(p.v_call)
                };
                let Some(f) = self.v_call_filtered.get_mut(k) else {
                    break;
                };
                *f += (target - *f) * alpha;
                let v_call = *f;
                if v_call.norm() < 1e-6 {
                    continue;
                }
                if k == 0 {
                    v_ee = v_call;
                } else if phri_model::point_jacobian(model, data, frame, &xyz, &mut self.jac_point)
                    .is_err()
                {
                    faults.model += 1;
                } else if self.avoidance.add_point(&self.jac_point, v_call).is_err() {
                    faults.avoidance += 1;
                }
            }
        }
        // slew-limited towards the SNS solution (which stays within the bounds
        // it was computed for; the limit only delays reaching it)
        let dv = cfg.reference_accel_limit * dt;
        match self
            .avoidance
            .solve(&self.jac_ee, &xdot_task, &v_ee, c.speed_scale)
        {
            Ok(out) => {
                self.task_scale = out.scale;
                for (r, &target) in reference.qd_ref.iter_mut().zip(out.qd) {
                    *r += (target - *r).clamp(-dv, dv);
                }
            }
            Err(_) => {
                faults.avoidance += 1;
                self.task_scale = 0.0;
                for r in reference.qd_ref.iter_mut() {
                    *r -= r.clamp(-dv, dv);
                }
            }
        }
        for (q, v) in reference.q_ref.iter_mut().zip(&reference.qd_ref) {
            *q += v * dt;
        }
        faults
    }
}

/// Margin by which an obstacle must lie beyond the collaborative hand's
/// centre to be "behind" it \[m\]: less than the hand's radius, so that the
/// hand's own near surface, were it not masked, still repels the end effector.
const BEHIND_MARGIN_M: f64 = 0.02;
/// The margin while the end effector touches the hand \[m\]: more than the
/// hand's radius; what lies about as deep as the hand then is the hand
/// itself (where the tracker misplaced the mask) and the mask's edge, and
/// its repulsion would only shake the contact.
const BEHIND_MARGIN_CONTACT_M: f64 = 0.05;

/// The obstacle of `p` lies behind the collaborative hand `h` as seen from
/// the control point: farther along the direction to the hand than the hand,
/// less a margin (the person's body behind the hand the robot is asked to
/// touch; a hand crossing in between is nearer and still repels).
fn behind(h: &Vector3<f64>, p: &phri_ipc::PointRepulsion, margin: f64) -> bool {
    let (o, x) = (Vector3::from(p.obstacle), Vector3::from(p.position));
    let to_hand = h - x;
    let d = to_hand.norm();
    if d < 1e-6 || !o.iter().chain(x.iter()).all(|v| v.is_finite()) {
        return false;
    }
    (o - x).dot(&to_hand) / d >= d - margin
}
