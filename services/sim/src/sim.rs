//! The simulated arm: torque in, quantized joint positions out, one control
//! period per [`Simulator::step`].
//!
//! Each period is split into `substeps` sub-steps of length `h`, integrated
//! with velocity Verlet (half kick, drift, half kick), contacts evaluated at
//! the drifted position:
//!
//! - joint torque `τ = τ_m + τ_f + J_cᵀ F`: the motor torque `τ_m` (the command
//!   clamped to the effort limits plus noise, held over the period, or when
//!   braking `g(q) − sat(b q̇)`), friction `τ_f = −(f_v q̇ + f_c tanh(q̇ / v_s))`
//!   and the contact forces `F` at their points on the robot;
//! - `q̈ = M⁻¹ (τ − C q̇ − g)` by [`phri_model::forward_dynamics`];
//! - each half kick takes the dissipative torques (friction, brake) at the new
//!   velocity, written `−D q̇` with secant coefficients `D ≥ 0`:
//!   `(M + ½h D) Δq̇ = ½h M q̈`. This is unconditionally stable, so the stiff
//!   smoothed Coulomb friction and the brakes cannot chatter on light distal
//!   links, and a saturated brake never reverses the motion;
//! - the closing half kick is predicted once and redone with the forces at
//!   the predicted velocity (Coriolis and friction depend on it), which keeps
//!   the scheme second order;
//! - drift `q += h q̇` with inelastic end stops at the position limits, then
//!   the contacts at the new position (their damping uses the change of
//!   penetration over the sub-step).
//!
//! Three forward-dynamics calls per sub-step. The energy error is second
//! order: below 0.01 % of the kinetic energy for a limp arm (no end stops)
//! falling freely for 1 s at the default 4 × 0.25 ms. Contacts are stable up
//! to `h √(k/m) < 2`: 0.25 ms covers the head's 150 kN/m against 0.1 kg of
//! effective mass.

use nalgebra::{DMatrix, DVector, Vector3};
use phri_model::spatial::Force;
use phri_model::{forward_dynamics, forward_kinematics, gravity, Data, Model, Placement, Shape};
use rand::rngs::SmallRng;
use rand::{Rng, SeedableRng};

use crate::config::SimConfig;
use crate::contact::{capsule_distance, contact_force_magnitude};
use crate::error::SimError;
use crate::human::{BodyPart, Human, HumanCapsule, HumanScript};

/// Largest number of joints the simulator accepts.
pub const MAX_JOINTS: usize = 12;
/// Largest number of contacts reported in [`Truth::contacts`] (the deepest
/// ones; every contact acts on the robot regardless).
pub const MAX_CONTACTS: usize = 8;
/// Human–robot capsule pairs whose bounding spheres are farther apart than
/// this \[m\] are not measured in intermediate sub-steps: neither body moves
/// 5 cm in a sub-step.
const CULL_MARGIN: f64 = 0.05;

/// What the robot's sensors report after a step.
#[derive(Clone, Debug, PartialEq)]
pub struct Measurement {
    /// simulation time at the end of the step \[s\]
    pub t_s: f64,
    /// joint positions \[rad\], quantized to the encoder resolution
    pub q: Vec<f64>,
    /// the torque the drives applied [N·m]: the command clamped to the effort
    /// limits, or while braking the brake torque (mean over the period);
    /// neither includes the torque noise or friction
    pub tau_applied: Vec<f64>,
    /// wrist force/torque sensor (only with `ft_sensor`): external force \[N\]
    /// then moment [N·m] on the last link, base-frame axes, moment about the
    /// last joint's link frame origin
    pub wrench: Option<[f64; 6]>,
}

/// One contact between the human and a robot capsule (ground truth).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct ContactTruth {
    /// index into `model.collisions` of the robot capsule (link name via
    /// [`Simulator::collision_link`])
    pub collision: usize,
    /// the human body part
    pub part: BodyPart,
    /// contact with a collaborative part (intended)
    pub intended: bool,
    /// force on the robot \[N\], base frame
    pub force: Vector3<f64>,
    /// application point on the robot capsule's surface \[m\], base frame
    pub point: Vector3<f64>,
    /// penetration depth \[m\] (> 0)
    pub depth: f64,
}

impl ContactTruth {
    /// Name of the robot link touched (`model` is the simulator's, see [`Simulator::model`]).
    pub fn link<'m>(&self, model: &'m Model) -> &'m str {
        model
            .collisions
            .get(self.collision)
            .map_or("", |c| c.link.as_str())
    }
}

/// Ground truth after a step, for evaluation only (a controller must not read it).
#[derive(Clone, Debug, PartialEq)]
pub struct Truth {
    /// simulation time \[s\]
    pub t_s: f64,
    /// joint positions \[rad\] and velocities [rad/s], unquantized
    pub q: Vec<f64>,
    pub qd: Vec<f64>,
    /// external joint torque `Σ J_cᵀ F` of every contact at the current state [N·m]
    pub tau_ext: Vec<f64>,
    /// torque the motors or brakes really applied (noise included), mean over the last period [N·m]
    pub tau_motor: Vec<f64>,
    /// friction torque, mean over the last period [N·m]
    pub tau_friction: Vec<f64>,
    /// the deepest contacts at the current state (at most [`MAX_CONTACTS`])
    pub contacts: Vec<ContactTruth>,
    /// number of penetrating human–robot capsule pairs (may exceed `contacts.len()`)
    pub contact_pairs: usize,
    /// smallest surface distance between any human and robot capsule \[m\],
    /// negative when penetrating; +∞ without a human
    pub min_distance: f64,
    /// sub-steps whose dynamics failed (left the state unchanged); 0 in a sane run
    pub faults: u64,
}

/// A robot collision primitive as a capsule, with its current pose.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct RobotCapsule {
    /// index into `model.collisions`
    pub collision: usize,
    /// body (joint index) it rides on, `None` for the base
    pub body: Option<usize>,
    /// axis endpoints \[m\], base frame, at the current state
    pub a: Vector3<f64>,
    pub b: Vector3<f64>,
    /// \[m\]
    pub radius: f64,
    /// shape frame in the body frame and half length \[m\] of the axis along its z
    placement: Placement,
    half_length: f64,
    /// centre \[m\] (base frame) and radius \[m\] of a sphere around the capsule
    centre: Vector3<f64>,
    bound_radius: f64,
}

/// Capsule (radius, half length) standing in for a collision primitive:
/// capsules and spheres exactly, a cylinder by the capsule of the same
/// radius and axis, a box by a capsule along its longest axis that contains
/// its cross-section. Returns the rotation to put the capsule axis on z.
fn as_capsule(shape: &Shape) -> (f64, f64, nalgebra::Matrix3<f64>) {
    let id = nalgebra::Matrix3::identity();
    match *shape {
        Shape::Capsule {
            radius,
            half_length,
        }
        | Shape::Cylinder {
            radius,
            half_length,
        } => (radius, half_length, id),
        Shape::Sphere { radius } => (radius, 0.0, id),
        Shape::Box { half_extents: e } => {
            // permutation putting the longest axis on z
            let (x, y, z) = (Vector3::x(), Vector3::y(), Vector3::z());
            if e.z >= e.x && e.z >= e.y {
                (e.x.hypot(e.y), e.z, id)
            } else if e.x >= e.y {
                (
                    e.y.hypot(e.z),
                    e.x,
                    nalgebra::Matrix3::from_columns(&[y, z, x]),
                )
            } else {
                (
                    e.z.hypot(e.x),
                    e.y,
                    nalgebra::Matrix3::from_columns(&[z, x, y]),
                )
            }
        }
    }
}

/// The simulated cell: one arm and at most one scripted human. Cloning gives
/// an independent copy (same state, same noise sequence from here on).
#[derive(Clone)]
pub struct Simulator {
    model: Model,
    data: Data,
    cfg: SimConfig,
    n: usize,
    h: f64,
    // per-joint parameters
    effort: Vec<f64>,
    viscous: Vec<f64>,
    coulomb: Vec<f64>,
    brake_max: Vec<f64>,
    // world
    human: Option<Human>,
    collaborative: [bool; BodyPart::ALL.len()],
    robot: Vec<RobotCapsule>,
    rng: SmallRng,
    /// added to the simulation time to get the human script's time [s]
    human_time_offset: f64,
    // state
    t: f64,
    q: Vec<f64>,
    qd: Vec<f64>,
    // per-period and per-substep buffers
    tau_cmd: Vec<f64>,
    noise: Vec<f64>,
    tau_motor: Vec<f64>,
    tau: Vec<f64>,
    /// secant coefficients of friction and brake torque `−D q̇` [N·m·s/rad]
    damp_friction: Vec<f64>,
    damp_brake: Vec<f64>,
    /// velocity the kick evaluates forces at, and the velocity it produces [rad/s]
    v_eval: Vec<f64>,
    v_new: Vec<f64>,
    rhs: DVector<f64>,
    lhs: DMatrix<f64>,
    /// signed distances of every (human capsule, robot capsule) pair at the previous evaluation
    prev_distance: Vec<f64>,
    wrench: [f64; 6],
    meas: Measurement,
    truth: Truth,
}

impl Simulator {
    /// Build a simulator. `human` is the scripted human (none: an empty cell),
    /// contacts with `collaborative_parts` are marked intended, and `seed`
    /// seeds the torque noise (`None`: `cfg.seed`). The arm starts at
    /// `cfg.q0` at rest, at time 0.
    pub fn new(
        model: Model,
        cfg: SimConfig,
        human: Option<HumanScript>,
        collaborative_parts: &[BodyPart],
        seed: Option<u64>,
    ) -> Result<Simulator, SimError> {
        let n = model.nv();
        if n > MAX_JOINTS {
            return Err(SimError::TooManyJoints { n, max: MAX_JOINTS });
        }
        cfg.validate()?;
        let viscous = cfg.viscous_friction.resolve(n, "viscous_friction")?;
        let coulomb = cfg.coulomb_friction.resolve(n, "coulomb_friction")?;
        let brake_max = cfg.brake_torque_max.resolve(n, "brake_torque_max")?;
        if cfg.q0.len() != n {
            return Err(SimError::Config {
                field: "q0",
                reason: format!("has {} values, the model has {n} joints", cfg.q0.len()),
            });
        }
        for (i, (x, j)) in cfg.q0.iter().zip(&model.joints).enumerate() {
            if !(x.is_finite() && *x >= j.lower && *x <= j.upper) {
                return Err(SimError::Config {
                    field: "q0",
                    reason: format!(
                        "joint {i} ('{}'): {x} rad is outside the limits [{}, {}]",
                        j.name, j.lower, j.upper
                    ),
                });
            }
        }
        let robot = model
            .collisions
            .iter()
            .enumerate()
            .map(|(collision, c)| {
                let (radius, half_length, rot) = as_capsule(&c.shape);
                let placement = c.placement.compose(&Placement {
                    r: rot,
                    p: Vector3::zeros(),
                });
                RobotCapsule {
                    collision,
                    body: c.body,
                    a: Vector3::zeros(),
                    b: Vector3::zeros(),
                    radius,
                    placement,
                    half_length,
                    centre: Vector3::zeros(),
                    bound_radius: half_length + radius,
                }
            })
            .collect::<Vec<_>>();
        let mut collaborative = [false; BodyPart::ALL.len()];
        for p in collaborative_parts {
            collaborative[*p as usize] = true;
        }
        let n_pairs = if human.is_some() {
            BodyPart::ALL.len() * robot.len()
        } else {
            0
        };
        let dt = cfg.dt_s;
        let h = dt / f64::from(cfg.substeps);
        let q = cfg.q0.clone();
        let rng = SmallRng::seed_from_u64(seed.unwrap_or(cfg.seed));
        let mut sim = Simulator {
            data: Data::new(&model),
            effort: model.joints.iter().map(|j| j.effort).collect(),
            n,
            h,
            viscous,
            coulomb,
            brake_max,
            human: human.map(Human::new),
            collaborative,
            robot,
            rng,
            t: 0.0,
            human_time_offset: 0.0,
            qd: vec![0.0; n],
            tau_cmd: vec![0.0; n],
            noise: vec![0.0; n],
            tau_motor: vec![0.0; n],
            tau: vec![0.0; n],
            damp_friction: vec![0.0; n],
            damp_brake: vec![0.0; n],
            v_eval: vec![0.0; n],
            v_new: vec![0.0; n],
            rhs: DVector::zeros(n),
            lhs: DMatrix::zeros(n, n),
            prev_distance: vec![0.0; n_pairs],
            wrench: [0.0; 6],
            meas: Measurement {
                t_s: 0.0,
                q: vec![0.0; n],
                tau_applied: vec![0.0; n],
                wrench: None,
            },
            truth: Truth {
                t_s: 0.0,
                q: q.clone(),
                qd: vec![0.0; n],
                tau_ext: vec![0.0; n],
                tau_motor: vec![0.0; n],
                tau_friction: vec![0.0; n],
                contacts: Vec::with_capacity(MAX_CONTACTS),
                contact_pairs: 0,
                min_distance: f64::INFINITY,
                faults: 0,
            },
            q,
            model,
            cfg,
        };
        sim.update_contacts(None, true);
        sim.publish();
        Ok(sim)
    }

    /// Build from a loaded scenario's human and collaborative parts.
    pub fn from_scenario(
        model: Model,
        cfg: SimConfig,
        scenario: &crate::scenario::Scenario,
        seed: Option<u64>,
    ) -> Result<Simulator, SimError> {
        Simulator::new(
            model,
            cfg,
            scenario.human.clone(),
            &scenario.collaborative_parts,
            seed,
        )
    }

    /// Advance exactly one control period with motor torque command
    /// `tau_cmd` [N·m] (clamped to the effort limits; missing or non-finite
    /// entries count as 0), or with the brakes engaged when `brake` is true.
    /// Allocates nothing.
    pub fn step(&mut self, tau_cmd: &[f64], brake: bool) -> &Measurement {
        let n = self.n;
        for i in 0..n {
            let c = tau_cmd
                .get(i)
                .copied()
                .filter(|x| x.is_finite())
                .unwrap_or(0.0);
            self.tau_cmd[i] = c.clamp(-self.effort[i], self.effort[i]);
            // drawn even while braking, so the noise sequence depends on the seed alone
            let noise = self.cfg.torque_noise_std * standard_normal(&mut self.rng);
            self.noise[i] = if brake { 0.0 } else { noise };
        }
        self.truth.tau_motor.fill(0.0);
        self.truth.tau_friction.fill(0.0);
        let substeps = self.cfg.substeps;
        for k in 0..substeps {
            self.substep(brake, k + 1 == substeps);
        }
        let inv = 1.0 / f64::from(substeps);
        for i in 0..n {
            self.truth.tau_motor[i] *= inv;
            self.truth.tau_friction[i] *= inv;
            self.meas.tau_applied[i] = if brake {
                self.truth.tau_motor[i]
            } else {
                self.tau_cmd[i]
            };
        }
        self.publish();
        &self.meas
    }

    /// One integration sub-step of length `h` (velocity Verlet: half kick,
    /// drift, contacts at the new position, half kick). The closing half kick
    /// depends on the velocity it produces (Coriolis, friction), so it is
    /// predicted once and then taken with the forces at the predicted
    /// velocity, which keeps the scheme second order. The contacts at the
    /// current state are already in `truth.tau_ext`.
    fn substep(&mut self, brake: bool, last: bool) {
        let h = self.h;
        self.v_eval.copy_from_slice(&self.qd);
        if !self.kick(0.5 * h, brake, true) {
            self.fault_substep(last);
            return;
        }
        for i in 0..self.n {
            self.q[i] += h * self.qd[i];
            // inelastic end stop
            let j = &self.model.joints[i];
            if self.q[i] < j.lower {
                self.q[i] = j.lower;
                self.qd[i] = self.qd[i].max(0.0);
            } else if self.q[i] > j.upper {
                self.q[i] = j.upper;
                self.qd[i] = self.qd[i].min(0.0);
            }
        }
        self.t += h;
        self.update_contacts(Some(h), last);
        self.v_eval.copy_from_slice(&self.qd);
        let ok = self.kick(0.5 * h, brake, false) && {
            self.v_eval.copy_from_slice(&self.v_new);
            self.kick(0.5 * h, brake, true)
        };
        if !ok {
            self.truth.faults += 1;
        }
        // a joint resting on its end stop cannot move into it
        for i in 0..self.n {
            let j = &self.model.joints[i];
            if (self.q[i] <= j.lower && self.qd[i] < 0.0)
                || (self.q[i] >= j.upper && self.qd[i] > 0.0)
            {
                self.qd[i] = 0.0;
            }
        }
    }

    /// Velocity update over `dt` from `q̇` with the forces evaluated at `(q,
    /// v_eval)` and the contact torque in `truth.tau_ext`; the result goes to
    /// `v_new`, and with `commit` to `q̇` (adding the torques that acted to the
    /// period sums in `truth`).
    ///
    /// Dissipative torques (friction, brake) are written `−D v` with secant
    /// coefficients `D ≥ 0` taken at `v_eval` and act at the new velocity:
    /// `(M + dt D) Δ = dt (τ(v_eval) − C v_eval − g + D (v_eval − q̇))`, which
    /// is unconditionally stable and never reverses the motion they resist.
    /// False if the dynamics failed (nothing changed).
    fn kick(&mut self, dt: f64, brake: bool, commit: bool) -> bool {
        let n = self.n;
        if brake {
            if gravity(&self.model, &mut self.data, &self.q).is_err() {
                return false;
            }
            let b = self.cfg.brake_damping;
            for i in 0..n {
                let lim = self.brake_max[i];
                let v = self.v_eval[i];
                // −sat(b v) = −D_b v with D_b = min(b, lim / |v|)
                let d = if lim <= 0.0 {
                    0.0
                } else if b * v.abs() <= lim {
                    b
                } else {
                    lim / v.abs()
                };
                self.damp_brake[i] = d;
                self.tau_motor[i] = self.data.g[i] - d * v;
            }
        } else {
            for i in 0..n {
                self.tau_motor[i] = self.tau_cmd[i] + self.noise[i];
                self.damp_brake[i] = 0.0;
            }
        }
        let vs = self.cfg.coulomb_smoothing_rad_s;
        let mut any_damping = false;
        for i in 0..n {
            let v = self.v_eval[i];
            let x = v / vs;
            // Coulomb secant: f_c tanh(v / v_s) / v, → f_c / v_s at rest
            let coulomb = if x.abs() > 1e-8 {
                self.coulomb[i] * x.tanh() / v
            } else {
                self.coulomb[i] / vs
            };
            self.damp_friction[i] = self.viscous[i] + coulomb;
            any_damping |= self.damp_friction[i] > 0.0 || self.damp_brake[i] > 0.0;
            self.tau[i] = self.tau_motor[i] - self.damp_friction[i] * v + self.truth.tau_ext[i];
        }
        if forward_dynamics(
            &self.model,
            &mut self.data,
            &self.q,
            &self.v_eval,
            &self.tau,
        )
        .is_err()
        {
            return false;
        }
        // data.m holds M(q) and data.qdd = M⁻¹ (τ − C v_eval − g) after forward_dynamics
        if any_damping {
            self.rhs.gemv(dt, &self.data.m, &self.data.qdd, 0.0);
            self.lhs.copy_from(&self.data.m);
            for i in 0..n {
                let d = self.damp_friction[i] + self.damp_brake[i];
                self.rhs[i] += dt * d * (self.v_eval[i] - self.qd[i]);
                self.lhs[(i, i)] += dt * d;
            }
            if !cholesky_solve_in_place(&mut self.lhs, &mut self.rhs) {
                return false;
            }
        } else {
            self.rhs.copy_from(&self.data.qdd);
            self.rhs *= dt;
        }
        for i in 0..n {
            self.v_new[i] = self.qd[i] + self.rhs[i];
        }
        if commit {
            let weight = dt / self.h;
            for i in 0..n {
                let v_new = self.v_new[i];
                // the dissipative terms acted at the new velocity
                self.truth.tau_motor[i] +=
                    weight * (self.tau_motor[i] - self.damp_brake[i] * (v_new - self.v_eval[i]));
                self.truth.tau_friction[i] -= weight * self.damp_friction[i] * v_new;
                self.qd[i] = v_new;
            }
        }
        true
    }

    /// A sub-step whose dynamics failed: count it, keep the state, let time run.
    fn fault_substep(&mut self, last: bool) {
        self.truth.faults += 1;
        self.t += self.h;
        self.update_contacts(Some(self.h), last);
    }

    /// Robot capsule poses, human pose, pair distances, contact forces and
    /// `tau_ext` at the current `(t, q)`. `dt`: time since the previous
    /// evaluation, for the penetration rate (`None`: rate 0). Unless `exact`,
    /// pairs whose bounding spheres are more than [`CULL_MARGIN`] apart are
    /// skipped (they cannot touch within a sub-step); with `exact` every pair
    /// is measured, so `truth.min_distance` is exact.
    fn update_contacts(&mut self, dt: Option<f64>, exact: bool) {
        if forward_kinematics(&self.model, &mut self.data, &self.q).is_err() {
            self.truth.faults += 1;
            return;
        }
        for rc in self.robot.iter_mut() {
            let pose = self.data.body_placement(rc.body).compose(&rc.placement);
            let half = pose.r.column(2) * rc.half_length;
            rc.a = pose.p - half;
            rc.b = pose.p + half;
            rc.centre = pose.p;
        }
        self.truth.tau_ext.fill(0.0);
        self.truth.contacts.clear();
        self.truth.contact_pairs = 0;
        self.truth.min_distance = f64::INFINITY;
        self.wrench = [0.0; 6];
        let Some(human) = self.human.as_mut() else {
            return;
        };
        let capsules: &[HumanCapsule] = human.pose_at(self.t + self.human_time_offset);
        let n_robot = self.robot.len();
        let last = self.n - 1;
        let last_origin = self.data.body[last].p;
        for (hi, hc) in capsules.iter().enumerate() {
            let k = hc.part.stiffness_n_per_m();
            let h_centre = (hc.a + hc.b) * 0.5;
            let h_bound = (hc.b - hc.a).norm() * 0.5 + hc.radius;
            for (ri, rc) in self.robot.iter().enumerate() {
                let slot = &mut self.prev_distance[hi * n_robot + ri];
                if !exact {
                    // a lower bound of the surface distance
                    let apart = (h_centre - rc.centre).norm() - h_bound - rc.bound_radius;
                    if apart > CULL_MARGIN {
                        *slot = f64::NAN;
                        self.truth.min_distance = self.truth.min_distance.min(apart);
                        continue;
                    }
                }
                let cd = capsule_distance(&hc.a, &hc.b, hc.radius, &rc.a, &rc.b, rc.radius);
                let rate = match dt {
                    Some(dt) if slot.is_finite() => (*slot - cd.distance) / dt,
                    _ => 0.0,
                };
                *slot = cd.distance;
                self.truth.min_distance = self.truth.min_distance.min(cd.distance);
                let depth = -cd.distance;
                let magnitude = contact_force_magnitude(depth, rate, k, self.cfg.contact_damping);
                if depth <= 0.0 {
                    continue;
                }
                self.truth.contact_pairs += 1;
                // the normal points from the human's axis to the robot's: out of the human
                let force = cd.normal * magnitude;
                let point = cd.point_b;
                let wrench = Force {
                    n: point.cross(&force),
                    f: force,
                };
                let mut body = rc.body;
                while let Some(j) = body {
                    self.truth.tau_ext[j] += self.data.s[j].dot(&wrench);
                    body = self.model.joints[j].parent;
                }
                if rc.body.is_some_and(|b| self.model.supports(last, b)) {
                    let m = (point - last_origin).cross(&force);
                    for a in 0..3 {
                        self.wrench[a] += force[a];
                        self.wrench[3 + a] += m[a];
                    }
                }
                let contact = ContactTruth {
                    collision: rc.collision,
                    part: hc.part,
                    intended: self.collaborative[hc.part as usize],
                    force,
                    point,
                    depth,
                };
                keep_deepest(&mut self.truth.contacts, contact);
            }
        }
    }

    /// Copy the state into the measurement and the truth.
    fn publish(&mut self) {
        let res = self.cfg.encoder_resolution_rad;
        self.meas.t_s = self.t;
        for i in 0..self.n {
            self.meas.q[i] = if res > 0.0 {
                (self.q[i] / res).round() * res
            } else {
                self.q[i]
            };
        }
        self.meas.wrench = self.cfg.ft_sensor.then_some(self.wrench);
        self.truth.t_s = self.t;
        self.truth.q.copy_from_slice(&self.q);
        self.truth.qd.copy_from_slice(&self.qd);
    }

    /// The latest measurement (after [`Simulator::new`]: the initial state).
    pub fn measurement(&self) -> &Measurement {
        &self.meas
    }

    /// Ground truth at the current state, for evaluation only.
    pub fn truth(&self) -> &Truth {
        &self.truth
    }

    /// The human's capsules at the current time (empty without a human).
    pub fn human_capsules(&self) -> &[HumanCapsule] {
        self.human.as_ref().map_or(&[], |h| h.capsules())
    }

    /// The robot's collision capsules at the current state.
    pub fn robot_capsule_poses(&self) -> &[RobotCapsule] {
        &self.robot
    }

    /// Link name of `model.collisions[collision]` (e.g. of [`ContactTruth::collision`]).
    pub fn collision_link(&self, collision: usize) -> Option<&str> {
        self.model
            .collisions
            .get(collision)
            .map(|c| c.link.as_str())
    }

    /// True joint positions \[rad\] and velocities [rad/s].
    pub fn state(&self) -> (&[f64], &[f64]) {
        (&self.q, &self.qd)
    }

    /// Simulation time \[s\].
    pub fn time_s(&self) -> f64 {
        self.t
    }

    /// Run the human script `offset_s` \[s\] ahead of the simulation clock
    /// (negative: behind). A restarted simulator uses it to continue the
    /// scenario where the cell is, rather than replaying the person from the
    /// start; lock-step sweeps use it to meet the person at another phase of
    /// the robot's cycle. Non-finite values count as 0.
    pub fn set_human_time_offset(&mut self, offset_s: f64) {
        self.human_time_offset = if offset_s.is_finite() { offset_s } else { 0.0 };
    }

    pub fn model(&self) -> &Model {
        &self.model
    }

    pub fn config(&self) -> &SimConfig {
        &self.cfg
    }

    /// Put the arm at rest at `q` \[rad\] (time keeps running).
    pub fn reset_state(&mut self, q: &[f64]) -> Result<(), SimError> {
        let zeros = [0.0; MAX_JOINTS];
        self.set_state(q, &zeros[..self.n])
    }

    /// Put the arm at `q` \[rad\] with velocity `qd` [rad/s] (time keeps
    /// running). `q` must be inside the position limits.
    pub fn set_state(&mut self, q: &[f64], qd: &[f64]) -> Result<(), SimError> {
        let n = self.n;
        let check = |v: &[f64], what: &'static str| {
            if v.len() != n {
                Err(SimError::State {
                    what,
                    reason: format!("has {} values, the model has {n} joints", v.len()),
                })
            } else if let Some(i) = v.iter().position(|x| !x.is_finite()) {
                Err(SimError::State {
                    what,
                    reason: format!("joint {i}: not a finite number"),
                })
            } else {
                Ok(())
            }
        };
        check(q, "q")?;
        check(qd, "qd")?;
        if let Some((i, j)) = self
            .model
            .joints
            .iter()
            .enumerate()
            .find(|(i, j)| q[*i] < j.lower || q[*i] > j.upper)
        {
            return Err(SimError::State {
                what: "q",
                reason: format!(
                    "joint {i} ('{}'): {} rad is outside the limits [{}, {}]",
                    j.name, q[i], j.lower, j.upper
                ),
            });
        }
        self.q.copy_from_slice(q);
        self.qd.copy_from_slice(qd);
        self.update_contacts(None, true);
        self.publish();
        Ok(())
    }
}

/// Insert `c` into `list` (capacity [`MAX_CONTACTS`]), replacing the
/// shallowest contact when full and `c` is deeper.
fn keep_deepest(list: &mut Vec<ContactTruth>, c: ContactTruth) {
    if list.len() < MAX_CONTACTS {
        list.push(c);
        return;
    }
    if let Some((i, shallowest)) = list
        .iter()
        .enumerate()
        .min_by(|a, b| a.1.depth.total_cmp(&b.1.depth))
    {
        if c.depth > shallowest.depth {
            list[i] = c;
        }
    }
}

/// A standard normal sample (Box–Muller).
fn standard_normal(rng: &mut SmallRng) -> f64 {
    let u1: f64 = 1.0 - rng.gen::<f64>(); // (0, 1]
    let u2: f64 = rng.gen::<f64>();
    (-2.0 * u1.ln()).sqrt() * (std::f64::consts::TAU * u2).cos()
}

/// Solve `A x = b` for symmetric positive definite `A` in place: `A` is
/// overwritten by its Cholesky factor, `b` by `x`. False if `A` is not
/// positive definite.
fn cholesky_solve_in_place(a: &mut DMatrix<f64>, b: &mut DVector<f64>) -> bool {
    let n = a.nrows();
    for j in 0..n {
        let mut d = a[(j, j)];
        for k in 0..j {
            d -= a[(j, k)] * a[(j, k)];
        }
        if !(d > 0.0 && d.is_finite()) {
            return false;
        }
        let d = d.sqrt();
        a[(j, j)] = d;
        for i in (j + 1)..n {
            let mut s = a[(i, j)];
            for k in 0..j {
                s -= a[(i, k)] * a[(j, k)];
            }
            a[(i, j)] = s / d;
        }
    }
    for i in 0..n {
        let mut s = b[i];
        for k in 0..i {
            s -= a[(i, k)] * b[k];
        }
        b[i] = s / a[(i, i)];
    }
    for i in (0..n).rev() {
        let mut s = b[i];
        for k in (i + 1)..n {
            s -= a[(k, i)] * b[k];
        }
        b[i] = s / a[(i, i)];
    }
    true
}
