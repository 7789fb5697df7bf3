//! The simulated arm: torque in, quantized joint positions out, one control
//! period per [`Simulator::step`]. The simulator's concerns, one file each:
//!
//! - `integrate`: the arm's dynamics over one control period ([`Simulator::step`]:
//!   sub-steps, friction, torque noise, brakes, end stops);
//! - `contacts`: the robot's collision capsules against the human's, the
//!   contact forces and the joint torques they cause;
//! - `truth`: what the sensors report ([`Measurement`]) and the ground truth
//!   for evaluation ([`Truth`]).
//!
//! This file holds the simulator's state, its construction and its accessors.
//! Every buffer is allocated in [`Simulator::new`]: stepping allocates nothing.

mod contacts;
mod integrate;
mod truth;

use nalgebra::{DMatrix, DVector};
use phri_config::{HumanScript, Scenario, SimConfig};
use phri_ipc::BodyPart;
use phri_model::{check_len, Data, Model};
use rand::rngs::SmallRng;
use rand::SeedableRng;

use crate::error::SimError;
use crate::human::{Human, HumanCapsule};

pub use contacts::RobotCapsule;
pub use truth::{ContactTruth, Measurement, Truth};

/// Largest number of joints the simulator accepts: as many as the messages carry.
pub const MAX_JOINTS: usize = phri_ipc::MAX_DOF;
/// Largest number of contacts reported in [`Truth::contacts`] (the deepest
/// ones; every contact acts on the robot regardless): as many as `sim/truth` carries.
pub const MAX_CONTACTS: usize = phri_ipc::MAX_CONTACTS;

/// A force on the arm that is not a contact with the scripted person's
/// capsules: it adds to the external joint torque (and to the wrist sensor's
/// reading beyond the last joint) but to no contact of the ground truth.
/// (A push of the scenario's script, `push = {…}` in a keyframe, is a
/// ground-truth contact instead: see [`ScriptedPush`].)
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct ExternalForce {
    /// link frame it acts on (`Model::frame_id`)
    pub frame: usize,
    /// point of application \[m\], in that link's frame
    pub point: nalgebra::Vector3<f64>,
    /// force on the robot \[N\], base frame
    pub force: nalgebra::Vector3<f64>,
}

/// A keyframe's `push` ([`phri_config::Push`]) resolved against the robot
/// model. While it acts ([`crate::Human::push_at`]), each contact evaluation
/// applies `F = ramp · force_n · d` at the point, `d` the horizontal unit
/// vector from the person's base position towards the point (the person's
/// heading if the point is right above it), and reports it in
/// [`Truth::contacts`] as a contact of the hand on the link: `collision` the
/// link's collision capsule, `intended` as scripted, `depth = |F| / k` with
/// `k` the hand's stiffness ([`crate::stiffness_n_per_m`]), the depth of a
/// compliant contact of that force. The hand is put on the link (its surface
/// on the capsule's, on the line through the point along `−d`), and its own
/// capsule contacts give no force meanwhile (the push replaces them).
#[derive(Clone, Debug, PartialEq)]
pub struct ScriptedPush {
    /// link frame (`Model::frame_id`) and its body (`None`: the base)
    pub frame: usize,
    /// the link's body (joint index), `None` for the base
    pub body: Option<usize>,
    /// index into `model.collisions` of the capsule reported as touched: the
    /// link's own, else the first on the same body
    pub collision: usize,
    /// point of application \[m\], link frame
    pub point: nalgebra::Vector3<f64>,
    /// \[N\] once ramped up
    pub force_n: f64,
    /// the pushing hand's body part
    pub part: BodyPart,
    /// whether the contact counts as intended (collaboration), as scripted
    pub intended: bool,
}

impl ScriptedPush {
    /// Resolve keyframe `index`'s push against `model`.
    fn resolve(
        model: &Model,
        index: usize,
        push: &phri_config::Push,
    ) -> Result<ScriptedPush, SimError> {
        let err = |reason: String| SimError::PushLink {
            index,
            link: push.link.clone(),
            reason,
        };
        let frame = model.frame_id(&push.link).map_err(|_| {
            let names: Vec<&str> = model.frames.iter().map(|f| f.name.as_str()).collect();
            err(format!(
                "is not a link of robot '{}' (links: {})",
                model.name,
                names.join(", ")
            ))
        })?;
        let body = model.frames[frame].body;
        let collision = model
            .collisions
            .iter()
            .position(|c| c.link == push.link)
            .or_else(|| model.collisions.iter().position(|c| c.body == body))
            .ok_or_else(|| err("has no collision capsule on its body".into()))?;
        Ok(ScriptedPush {
            frame,
            body,
            collision,
            point: nalgebra::Vector3::from(push.point),
            force_n: push.force_n,
            part: push.hand.part(),
            intended: push.intended,
        })
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
    /// an external force on the arm besides the person's contacts (a test's
    /// wall, a push), held until changed
    push: Option<ExternalForce>,
    /// the script's pushes, by keyframe (`None`: that keyframe pushes nothing)
    scripted_pushes: Vec<Option<ScriptedPush>>,
    meas: Measurement,
    truth: Truth,
}

impl Simulator {
    /// Build a simulator. `human` is the scripted human (none: an empty cell),
    /// contacts with `collaborative_parts` are marked intended, and `seed`
    /// seeds the torque noise (`None`: `cfg.seed`). The arm starts at
    /// `cfg.q0` at rest, at time 0.
    ///
    /// `intended` of a capsule contact depends on the human part alone: a
    /// contact of a collaborative part with any robot capsule is intended,
    /// every other contact is not. A scripted push carries its own
    /// `intended` (the scenario defaults it to the same rule). The links of
    /// the script's pushes are checked against `model` here
    /// ([`SimError::PushLink`]).
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
        let viscous = cfg.viscous_friction.resolve(n, "sim.viscous_friction")?;
        let coulomb = cfg.coulomb_friction.resolve(n, "sim.coulomb_friction")?;
        let brake_max = cfg.brake_torque_max.resolve(n, "sim.brake_torque_max")?;
        check_len("sim.q0", n, cfg.q0.len())?;
        check_within_limits(&model, "sim.q0", &cfg.q0)?;
        let robot = model
            .collisions
            .iter()
            .enumerate()
            .map(|(collision, c)| RobotCapsule::new(collision, c))
            .collect::<Vec<_>>();
        let scripted_pushes = match &human {
            None => Vec::new(),
            Some(script) => script
                .keyframes()
                .iter()
                .enumerate()
                .map(|(i, k)| {
                    k.push
                        .as_ref()
                        .map(|p| ScriptedPush::resolve(&model, i, p))
                        .transpose()
                })
                .collect::<Result<Vec<_>, _>>()?,
        };
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
            effort: model.actuated().iter().map(|j| j.effort).collect(),
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
            human_time_offset: cfg.human_offset_s,
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
            push: None,
            scripted_pushes,
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
        sim.update_readings();
        Ok(sim)
    }

    /// Build from a loaded scenario's human and collaborative parts.
    pub fn from_scenario(
        model: Model,
        cfg: SimConfig,
        scenario: &Scenario,
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

    /// The person's script time \[s\]: the simulation time plus the offset
    /// of [`Simulator::set_human_time_offset`].
    pub fn human_time_s(&self) -> f64 {
        self.t + self.human_time_offset
    }

    /// Run the human script `offset_s` \[s\] ahead of the simulation clock
    /// (negative: behind; at first `[sim] human_offset_s`). A restarted
    /// simulator uses it to continue the scenario where the cell is, rather
    /// than replaying the person from the start; lock-step sweeps use it to
    /// meet the person at another phase of the robot's cycle. Non-finite
    /// values count as 0.
    pub fn set_human_time_offset(&mut self, offset_s: f64) {
        self.human_time_offset = if offset_s.is_finite() { offset_s } else { 0.0 };
    }

    /// Apply `force` from the next step on (`None`: remove it); it acts until
    /// changed. A frame out of range or a non-finite force is ignored (no force).
    pub fn set_external_force(&mut self, force: Option<ExternalForce>) {
        self.push = force.filter(|f| {
            f.frame < self.model.frames.len()
                && f.point.iter().chain(f.force.iter()).all(|x| x.is_finite())
        });
    }

    /// An external force acts ([`Simulator::set_external_force`]).
    pub fn has_external_force(&self) -> bool {
        self.push.is_some()
    }

    /// The robot model the simulator was built with.
    pub fn model(&self) -> &Model {
        &self.model
    }

    /// The `[sim]` configuration the simulator was built with.
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
        check_len("q", n, q.len())?;
        check_finite("q", q)?;
        check_len("qd", n, qd.len())?;
        check_finite("qd", qd)?;
        check_within_limits(&self.model, "q", q)?;
        self.q.copy_from_slice(q);
        self.qd.copy_from_slice(qd);
        self.update_contacts(None, true);
        self.update_readings();
        Ok(())
    }
}

/// Every entry of `v` finite; `what` names the argument.
fn check_finite(what: &'static str, v: &[f64]) -> Result<(), SimError> {
    match v.iter().position(|x| !x.is_finite()) {
        Some(joint) => Err(SimError::NotFinite { what, joint }),
        None => Ok(()),
    }
}

/// Every joint position of `q` \[rad\] finite and within the model's limits;
/// `what` names the argument or key.
fn check_within_limits(model: &Model, what: &'static str, q: &[f64]) -> Result<(), SimError> {
    for (i, (x, j)) in q.iter().zip(&model.joints).enumerate() {
        if !(x.is_finite() && *x >= j.lower && *x <= j.upper) {
            return Err(SimError::OutsideLimits {
                what,
                joint: i,
                name: j.name.clone(),
                value: *x,
                lower: j.lower,
                upper: j.upper,
            });
        }
    }
    Ok(())
}
