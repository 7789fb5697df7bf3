//! Shared test helpers: the default robot, the `[sim]` configurations the
//! tests start from, an inverse kinematics for poses on the task path,
//! energies.
#![allow(dead_code)]

pub mod counting;

use nalgebra::{DMatrix, DVector, Vector3};
use phri_config::{Config, SimConfig};
use phri_model::{
    forward_kinematics, frame_placement, kinetic_energy, point_jacobian, potential_energy, Data,
    Model,
};

pub fn model() -> Model {
    Model::from_urdf_file(concat!(
        env!("CARGO_MANIFEST_DIR"),
        "/../../deploy/robots/kuka_lwr4.urdf"
    ))
    .expect("default robot loads")
}

pub fn scenario_path(name: &str) -> String {
    format!(
        "{}/../../deploy/scenarios/{name}",
        env!("CARGO_MANIFEST_DIR")
    )
}

/// Elbow-up posture with the tool in front and down: `q0` and the controller's
/// null-space posture in `deploy/phri.toml`.
pub const FRONT: [f64; 7] = [0.0, -0.4, 0.0, 1.8, 0.0, -0.6, 0.0];

/// A posture leaning the other way, flange at x = −0.64 m, behind the robot:
/// where the physics tests start the arm (the simulator's own default `q0`
/// before `deploy/phri.toml` became the one place for defaults; the tests'
/// figures are for it).
pub const BEHIND: [f64; 7] = [0.0, 0.5, 0.0, -1.2, 0.0, 0.6, 0.0];

/// `[sim]` of `deploy/phri.toml`, the arm starting at [`BEHIND`].
pub fn sim_config() -> SimConfig {
    SimConfig {
        q0: BEHIND.to_vec(),
        ..Config::defaults().sim
    }
}

/// [`sim_config`] with friction and noise off (ideal actuators).
pub fn ideal() -> SimConfig {
    sim_config().ideal()
}

/// The task's waypoints [m], base frame.
pub const P1: [f64; 3] = [0.45, -0.35, 0.45];
pub const P2: [f64; 3] = [0.55, 0.0, 0.30];
pub const P3: [f64; 3] = [0.45, 0.35, 0.45];

/// Joint positions putting the flange at `target`: damped least squares from
/// [`FRONT`], pulled towards it in the null space, kept inside the limits.
pub fn ik(model: &Model, target: [f64; 3]) -> Vec<f64> {
    let mut data = Data::new(model);
    let flange = model.frame_id("lwr_flange").expect("flange frame");
    let target = Vector3::from(target);
    let n = model.nv();
    let mut q = FRONT.to_vec();
    let mut jac = Data::jacobian_buffer(model);
    for it in 0..3000 {
        forward_kinematics(model, &mut data, &q).expect("fk");
        let e = target - frame_placement(model, &data, flange).p;
        if e.norm() < 1e-10 {
            break;
        }
        point_jacobian(model, &data, flange, &Vector3::zeros(), &mut jac).expect("jacobian");
        let jl = DMatrix::from_fn(3, n, |r, c| jac[(r, c)]);
        let jjt = &jl * jl.transpose() + DMatrix::identity(3, 3) * 1e-4;
        let jpinv = jl.transpose() * jjt.try_inverse().expect("damped JJᵀ is invertible");
        // posture pull first, then converge on the target alone
        let pull = if it < 2000 { 0.05 } else { 0.0 };
        let z = DVector::from_fn(n, |i, _| pull * (FRONT[i] - q[i]));
        let dq = &jpinv * DVector::from_column_slice((e * 0.3).as_slice())
            + (DMatrix::identity(n, n) - &jpinv * &jl) * z;
        for (i, j) in model.joints.iter().enumerate() {
            q[i] = (q[i] + dq[i]).clamp(j.lower + 0.05, j.upper - 0.05);
        }
    }
    forward_kinematics(model, &mut data, &q).expect("fk");
    assert!(
        (frame_placement(model, &data, flange).p - target).norm() < 1e-6,
        "IK reaches {target:?}"
    );
    q
}

/// Total mechanical energy `T + V` [J].
pub fn energy(model: &Model, data: &mut Data, q: &[f64], qd: &[f64]) -> f64 {
    kinetic_energy(model, data, q, qd).expect("T") + potential_energy(model, data, q).expect("V")
}
