//! Closed-loop scenarios in lock-step: controller + residual observer + an
//! exact-model arm integrated at 10 kHz, all in one process.

use nalgebra::Vector3;
use phri_control::{ControlConfig, ControlInput, Controller, Reaction, ResidualView};
use phri_dynamics::{ResidualConfig, ResidualObserver};
use phri_ipc::control_mode as mode;
use phri_model::{Data, Model};

fn lwr4() -> Model {
    Model::from_urdf_file(concat!(
        env!("CARGO_MANIFEST_DIR"),
        "/../../deploy/robots/kuka_lwr4.urdf"
    ))
    .unwrap()
}

const Q0: [f64; 7] = [0.0, -0.4, 0.0, 1.8, 0.0, -0.6, 0.0];

struct Cell {
    model: Model,
    data: Data,
    q: Vec<f64>,
    qd: Vec<f64>,
    t_ns: u64,
    observer: ResidualObserver,
    controller: Controller,
    tau: Vec<f64>,
    /// external force [N] at a point [m] fixed on a link
    ext: Option<(usize, Vector3<f64>, Vector3<f64>)>,
    residual_alive: bool,
    last_r: Vec<f64>,
    last_flags: (bool, bool, bool),
    last_r_stamp: u64,
    max_tau_jump: f64,
}

impl Cell {
    fn new(reaction: Reaction) -> Cell {
        let model = lwr4();
        let cfg = ControlConfig {
            reaction,
            ..ControlConfig::default()
        };
        let rcfg = ResidualConfig {
            viscous_friction: vec![0.0],
            coulomb_friction: vec![0.0],
            ..ResidualConfig::default()
        };
        Cell {
            data: Data::new(&model),
            q: Q0.to_vec(),
            qd: vec![0.0; 7],
            t_ns: 1_000_000_000,
            observer: ResidualObserver::new(model.clone(), &rcfg).unwrap(),
            controller: Controller::new(model.clone(), cfg).unwrap(),
            tau: phri_model::gravity(&model, &mut Data::new(&model), &Q0)
                .unwrap()
                .as_slice()
                .to_vec(),
            ext: None,
            residual_alive: true,
            last_r: vec![0.0; 7],
            last_flags: (false, false, false),
            last_r_stamp: 0,
            max_tau_jump: 0.0,
            model,
        }
    }

    fn ee(&mut self) -> Vector3<f64> {
        phri_model::forward_kinematics(&self.model, &mut self.data, &self.q).unwrap();
        phri_model::frame_placement(&self.model, &self.data, self.model.frames.len() - 1).p
    }

    /// One millisecond: the arm moves under the last torque, then the residual
    /// and the controller answer the new state.
    fn tick(&mut self) -> u32 {
        let mut te = vec![0.0; 7];
        for _ in 0..10 {
            te.fill(0.0);
            if let Some((link, p, f)) = self.ext {
                let mut j = Data::jacobian_buffer(&self.model);
                phri_model::forward_kinematics(&self.model, &mut self.data, &self.q).unwrap();
                phri_model::point_jacobian(&self.model, &self.data, link, &p, &mut j).unwrap();
                for i in 0..7 {
                    te[i] = (0..3).map(|k| j[(k, i)] * f[k]).sum();
                }
            }
            let total: Vec<f64> = self.tau.iter().zip(&te).map(|(a, b)| a + b).collect();
            let qdd = phri_model::forward_dynamics(
                &self.model,
                &mut self.data,
                &self.q,
                &self.qd,
                &total,
            )
            .unwrap()
            .clone();
            for i in 0..7 {
                self.qd[i] += 1e-4 * qdd[i];
                self.q[i] += 1e-4 * self.qd[i];
            }
        }
        self.t_ns += 1_000_000;
        if self.residual_alive {
            let out = self
                .observer
                .step(self.t_ns as f64 * 1e-9, &self.q, &self.tau, None)
                .unwrap();
            self.last_r.copy_from_slice(out.r);
            self.last_flags = (out.valid, out.detection.contact, out.detection.collision);
            self.last_r_stamp = self.t_ns;
        }
        let residual = ResidualView {
            state_stamp_ns: self.last_r_stamp,
            r: &self.last_r,
            valid: self.last_flags.0,
            contact: self.last_flags.1,
            collision: self.last_flags.2,
        };
        let out = self.controller.step(&ControlInput {
            state_stamp_ns: self.t_ns,
            q: &self.q,
            residual: Some(residual),
            perception: None,
        });
        let jump = out
            .tau
            .iter()
            .zip(&self.tau)
            .map(|(a, b)| (a - b).abs())
            .fold(0.0, f64::max);
        self.max_tau_jump = self.max_tau_jump.max(jump);
        self.tau.copy_from_slice(out.tau);
        out.mode
    }

    fn run(&mut self, ms: usize) -> u32 {
        let mut m = 0;
        for _ in 0..ms {
            m = self.tick();
        }
        m
    }
}

#[test]
fn free_motion_cycles_through_the_waypoints_without_detections() {
    let mut cell = Cell::new(Reaction::Reflex);
    let m = cell.run(14_000);
    assert_eq!(m, mode::TASK);
    assert_eq!(cell.controller.detections, 0);
    assert_eq!(cell.controller.protective_stops, 0);
    // approach (≈2 s) then 4 s per cycle of 3 waypoints: at least 2 full cycles
    assert!(
        cell.controller.waypoints_reached >= 6,
        "reached {}",
        cell.controller.waypoints_reached
    );
    // the first command re-synced: no jump from the gravity torque it started with
    assert!(
        cell.max_tau_jump < 20.0,
        "torque jumped by {} Nm",
        cell.max_tau_jump
    );
}

/// Push on the forearm with a growing force while the task runs; stop
/// pushing once the arm has been clear for 100 ms (the person does not follow),
/// or after 1.5 s of contact (the person withdraws). Returns the cell and
/// whether the robot's own motion ended the contact.
fn collision_scenario(reaction: Reaction) -> (Cell, bool) {
    let mut cell = Cell::new(reaction);
    cell.run(4000);
    assert_eq!(cell.controller.mode(), mode::TASK);
    let link = cell.model.frame_id("lwr_link_4").unwrap();
    let point = Vector3::new(0.0, -0.15, 0.0);
    phri_model::forward_kinematics(&cell.model, &mut cell.data, &cell.q).unwrap();
    let contact = phri_model::frame_placement(&cell.model, &cell.data, link).apply(&point);
    let dir = Vector3::new(-contact.x, -contact.y, 0.0).normalize();
    let mut detected_at = None;
    let mut released = false;
    let mut pushed_away = false;
    let mut first_contact = None;
    let mut clear_for = 0;
    for k in 0..6000 {
        phri_model::forward_kinematics(&cell.model, &mut cell.data, &cell.q).unwrap();
        let here = phri_model::frame_placement(&cell.model, &cell.data, link).apply(&point);
        // a wall that pushes back where the arm enters it (50 N/cm), until released
        let depth = (contact - here).dot(&dir) + 0.01;
        cell.ext = if !released && depth > 0.0 {
            Some((link, point, dir * (5000.0 * depth)))
        } else {
            None
        };
        if depth > 0.0 && first_contact.is_none() {
            first_contact = Some(k);
        }
        clear_for = if depth < 0.0 { clear_for + 1 } else { 0 };
        if clear_for >= 100 && first_contact.is_some() && !released {
            released = true;
            pushed_away = true;
        }
        if first_contact.is_some_and(|k0| k - k0 > 1500) {
            released = true;
        }
        let m = cell.tick();
        if m == mode::REACTION && detected_at.is_none() {
            detected_at = Some(k);
        }
    }
    assert!(detected_at.is_some(), "{reaction:?}: never reacted");
    (cell, pushed_away)
}

#[test]
fn every_reaction_ends_the_contact_and_the_task_resumes() {
    for reaction in Reaction::ALL {
        let (mut cell, pushed_away) = collision_scenario(reaction);
        assert!(cell.controller.detections >= 1, "{reaction:?}");
        // every strategy but stop moves the arm out of the contact by itself
        assert_eq!(pushed_away, reaction != Reaction::Stop, "{reaction:?}");
        let m = cell.run(4000);
        assert!(
            cell.controller.resumes >= 1,
            "{reaction:?}: never resumed (mode {m})"
        );
        assert_eq!(m, mode::TASK, "{reaction:?}");
        assert!(cell.ext.is_none() || cell.controller.mode() == mode::TASK);
    }
}

#[test]
fn stale_residual_holds_a_protective_stop_and_recovers() {
    let mut cell = Cell::new(Reaction::Stop);
    cell.run(3000);
    cell.residual_alive = false;
    let m = cell.run(10);
    assert_eq!(m, mode::PROTECTIVE_STOP);
    let q_stop = cell.q.clone();
    cell.run(1500);
    let drift = cell
        .q
        .iter()
        .zip(&q_stop)
        .map(|(a, b)| (a - b).abs())
        .fold(0.0, f64::max);
    // it was moving when stopped: it comes to rest close by and stays
    assert!(drift < 0.1, "moved {drift} rad while stopped");
    let speed = cell.qd.iter().map(|v| v.abs()).fold(0.0, f64::max);
    assert!(speed < 0.01, "still moving at {speed} rad/s");
    assert_eq!(cell.controller.protective_stops, 1);
    // the residual comes back (a restarted service starts from scratch)
    cell.observer = ResidualObserver::new(
        cell.model.clone(),
        &ResidualConfig {
            viscous_friction: vec![0.0],
            coulomb_friction: vec![0.0],
            ..ResidualConfig::default()
        },
    )
    .unwrap();
    cell.residual_alive = true;
    let m = cell.run(3000);
    assert_eq!(m, mode::TASK);
    assert_eq!(cell.controller.resumes, 1);
    assert_eq!(
        cell.controller.detections, 0,
        "restart of the residual caused a false detection"
    );
}

#[test]
fn a_restarted_controller_resyncs_without_a_jump() {
    let mut cell = Cell::new(Reaction::Reflex);
    cell.run(5000);
    let ee_before = cell.ee();
    // the controller process dies and a new one starts while the arm moves
    cell.controller = Controller::new(cell.model.clone(), ControlConfig::default()).unwrap();
    cell.max_tau_jump = 0.0;
    let mut max_dev: f64 = 0.0;
    for _ in 0..300 {
        cell.tick();
        max_dev = max_dev.max((cell.ee() - ee_before).norm());
    }
    assert!(
        cell.max_tau_jump < 30.0,
        "first commands jumped by {} Nm",
        cell.max_tau_jump
    );
    assert!(
        max_dev < 0.15,
        "end effector strayed {max_dev} m after the restart"
    );
    let m = cell.run(5000);
    assert_eq!(m, mode::TASK);
    assert!(cell.controller.waypoints_reached >= 2);
}

#[test]
fn malformed_state_never_panics() {
    let mut c = Controller::new(lwr4(), ControlConfig::default()).unwrap();
    let out = c.step(&ControlInput {
        state_stamp_ns: 1,
        q: &[f64::NAN; 7],
        residual: None,
        perception: None,
    });
    assert!(out.tau.iter().all(|t| t.is_finite()));
    let out = c.step(&ControlInput {
        state_stamp_ns: 2,
        q: &[0.0; 3],
        residual: None,
        perception: None,
    });
    assert_eq!(out.tau.len(), 7);
    let bad = ControlConfig {
        waypoints: vec![[0.0; 3]],
        ..ControlConfig::default()
    };
    assert!(Controller::new(lwr4(), bad).is_err());
    let bad = ControlConfig {
        ee_link: "nope".into(),
        ..ControlConfig::default()
    };
    assert!(Controller::new(lwr4(), bad).is_err());
}
