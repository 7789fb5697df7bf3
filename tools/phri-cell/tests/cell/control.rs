//! The controller in the closed loop, in the lock-step cell (the tests that
//! were private harnesses of `phri-control`): the task, every reaction to a
//! push on the forearm, the protective stop on a stale residual, a restarted
//! controller and a restarted residual, with the real robot link between
//! controller and arm.

use crate::common;

use nalgebra::Vector3;
use phri_cell::{Cell, CellOptions, Down, Outage};
use phri_control::Controller;
use phri_dynamics::DynamicsStep;
use phri_ipc::{ControlMode, Reaction};
use phri_sim::ExternalForce;

/// An ideal arm (no friction, no torque noise) and a residual that compensates
/// no friction, the end effector the deepest link, the posture the one the
/// task starts from, no person and no perception: the closed loop of
/// controller, residual and arm alone.
fn ideal(reaction: Reaction) -> (Cell, phri_config::Loaded) {
    let reaction = format!("control.reaction={}", reaction.name());
    let sets = [
        reaction.as_str(),
        "sim.viscous_friction=0.0",
        "sim.coulomb_friction=0.0",
        "sim.torque_noise_std=0.0",
        "dynamics.viscous_friction=0.0",
        "dynamics.coulomb_friction=0.0",
        "control.ee_link=\"\"",
        "control.posture=[]",
        "control.avoidance=false",
    ];
    let l = common::loaded("free-motion", &sets);
    let model = l.model().unwrap();
    let opts = CellOptions {
        perception: false,
        ..CellOptions::default()
    };
    (Cell::new(&l, model, &opts).unwrap(), l)
}

fn run(cell: &mut Cell, ms: usize) -> ControlMode {
    let mut m = ControlMode::Sync;
    for _ in 0..ms {
        m = cell.tick().unwrap();
    }
    m
}

/// Largest change of the applied motor torque between consecutive periods
/// [Nm] over `ms` periods (the robot's first period is braked: the brakes'
/// torque is the arm's gravity torque, as a held arm's motors would give).
fn max_torque_jump(cell: &mut Cell, ms: usize) -> f64 {
    let mut jump = 0.0f64;
    let mut last: Option<Vec<f64>> = None;
    for _ in 0..ms {
        cell.tick().unwrap();
        let tau = cell.state.tau[..cell.state.dof as usize].to_vec();
        if let Some(l) = &last {
            let j = tau
                .iter()
                .zip(l)
                .map(|(a, b)| (a - b).abs())
                .fold(0.0, f64::max);
            jump = jump.max(j);
        }
        last = Some(tau);
    }
    jump
}

#[test]
fn free_motion_cycles_through_the_waypoints_without_detections() {
    let (mut cell, _) = ideal(Reaction::Reflex);
    // the first periods: braked until the controller answers, then a smooth start
    let jump = max_torque_jump(&mut cell, 2000);
    let m = run(&mut cell, 12_000);
    assert_eq!(m, ControlMode::Task);
    let c = *cell.controller.counters();
    assert_eq!(c.detections, 0);
    assert_eq!(c.protective_stops, 0);
    // approach (≈2 s) then 4 s per cycle of 3 waypoints: at least 2 full cycles
    assert!(c.waypoints_reached >= 6, "reached {}", c.waypoints_reached);
    // the first command re-synced: no jump from holding to moving
    assert!(jump < 20.0, "torque jumped by {jump} Nm");
    assert_eq!(cell.summary().false_detections, 0);
}

/// Push on the forearm with a wall that pushes back where the arm enters it
/// (50 N/cm) while the task runs; stop pushing once the arm has been clear for
/// 100 ms (the person does not follow), or after 1.5 s of contact (the person
/// withdraws). Returns the cell and whether the robot's own motion ended the contact.
fn collision_scenario(reaction: Reaction) -> (Cell, bool) {
    let (mut cell, _) = ideal(reaction);
    run(&mut cell, 4000);
    assert_eq!(cell.controller.mode(), ControlMode::Task);
    let model = cell.sim.model().clone();
    let frame = model.frame_id("lwr_link_4").unwrap();
    let point = Vector3::new(0.0, -0.15, 0.0);
    let mut data = phri_model::Data::new(&model);
    let mut at = |q: &[f64]| {
        phri_model::forward_kinematics(&model, &mut data, q).unwrap();
        phri_model::frame_placement(&model, &data, frame).apply(&point)
    };
    let contact = at(cell.sim.state().0);
    let dir = Vector3::new(-contact.x, -contact.y, 0.0).normalize();
    let mut detected_at = None;
    let (mut released, mut pushed_away) = (false, false);
    let mut first_contact = None;
    let mut clear_for = 0;
    for k in 0..6000 {
        let here = at(cell.sim.state().0);
        let depth = (contact - here).dot(&dir) + 0.01;
        let push = (!released && depth > 0.0).then(|| ExternalForce {
            frame,
            point,
            force: dir * (5000.0 * depth),
        });
        cell.sim.set_external_force(push);
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
        let m = cell.tick().unwrap();
        if m == ControlMode::Reaction && detected_at.is_none() {
            detected_at = Some(k);
        }
    }
    cell.sim.set_external_force(None);
    assert!(detected_at.is_some(), "{reaction:?}: never reacted");
    (cell, pushed_away)
}

#[test]
fn every_reaction_ends_the_contact_and_the_task_resumes() {
    for &reaction in Reaction::ALL {
        let (mut cell, pushed_away) = collision_scenario(reaction);
        assert!(cell.controller.counters().detections >= 1, "{reaction:?}");
        // every strategy but stop moves the arm out of the contact by itself
        assert_eq!(pushed_away, reaction != Reaction::Stop, "{reaction:?}");
        let m = run(&mut cell, 4000);
        assert!(
            cell.controller.counters().resumes >= 1,
            "{reaction:?}: never resumed (mode {m})"
        );
        assert_eq!(m, ControlMode::Task, "{reaction:?}");
        // braked only in the first period, before the controller's first answer
        assert!(
            cell.summary().braked_s <= 0.0011,
            "{reaction:?}: the robot braked"
        );
    }
}

#[test]
fn stale_residual_holds_a_protective_stop_and_recovers() {
    let (mut cell, l) = ideal(Reaction::Stop);
    run(&mut cell, 3000);
    // the residual service dies for 1.51 s: its last message ages
    let now_s = cell.time_ns() as f64 * 1e-9;
    cell.add_outage(Outage {
        service: Down::Dynamics,
        from_s: now_s,
        to_s: now_s + 1.51,
    });
    let m = run(&mut cell, 10);
    assert_eq!(m, ControlMode::ProtectiveStop);
    let q_stop = cell.sim.state().0.to_vec();
    run(&mut cell, 1500);
    let drift = cell
        .sim
        .state()
        .0
        .iter()
        .zip(&q_stop)
        .map(|(a, b)| (a - b).abs())
        .fold(0.0, f64::max);
    // it was moving when stopped: it comes to rest close by and stays
    assert!(drift < 0.1, "moved {drift} rad while stopped");
    let speed = cell
        .sim
        .state()
        .1
        .iter()
        .map(|v| v.abs())
        .fold(0.0, f64::max);
    assert!(speed < 0.01, "still moving at {speed} rad/s");
    assert_eq!(cell.controller.counters().protective_stops, 1);
    // the residual comes back (a restarted service starts from scratch)
    let model = l.model().unwrap();
    cell.restart_dynamics(DynamicsStep::new(model, &l.config.dynamics).unwrap());
    let m = run(&mut cell, 3000);
    assert_eq!(m, ControlMode::Task);
    assert_eq!(cell.controller.counters().resumes, 1);
    assert_eq!(
        cell.controller.counters().detections,
        0,
        "restart of the residual caused a false detection"
    );
}

#[test]
fn a_restarted_controller_resyncs_without_a_jump() {
    let (mut cell, l) = ideal(Reaction::Reflex);
    run(&mut cell, 5000);
    let model = l.model().unwrap();
    let ee = |cell: &Cell| {
        let mut d = phri_model::Data::new(&model);
        phri_model::forward_kinematics(&model, &mut d, cell.sim.state().0).unwrap();
        phri_model::frame_placement(&model, &d, model.frames.len() - 1).p
    };
    let ee_before = ee(&cell);
    // the controller process dies and a new one starts while the arm moves
    cell.restart_controller(Controller::from_config(model.clone(), &l.config).unwrap());
    let mut jump = 0.0f64;
    let mut max_dev: f64 = 0.0;
    let mut last = cell.state.tau[..7].to_vec();
    for _ in 0..300 {
        cell.tick().unwrap();
        let tau = &cell.state.tau[..7];
        jump = jump.max(
            tau.iter()
                .zip(&last)
                .map(|(a, b)| (a - b).abs())
                .fold(0.0, f64::max),
        );
        last = tau.to_vec();
        max_dev = max_dev.max((ee(&cell) - ee_before).norm());
    }
    assert!(jump < 30.0, "first commands jumped by {jump} Nm");
    assert!(
        max_dev < 0.15,
        "end effector strayed {max_dev} m after the restart"
    );
    let m = run(&mut cell, 5000);
    assert_eq!(m, ControlMode::Task);
    assert!(cell.controller.counters().waypoints_reached >= 2);
}

#[test]
fn free_motion_in_lockstep_cycles_without_false_detections() {
    let opts = CellOptions {
        perception: false,
        ..CellOptions::default()
    };
    let s = common::run("free-motion", 20.0, &opts, &[]);
    eprintln!("free motion: {} waypoints", s.waypoints);
    assert_eq!(s.false_detections, 0);
    assert!(s.waypoints >= 10, "waypoints {}", s.waypoints);
}

#[test]
fn collision_in_lockstep_detects_reacts_and_has_no_false_detections() {
    let opts = CellOptions {
        perception: false,
        ..CellOptions::default()
    };
    let s = common::run("collision", 16.0, &opts, &["control.avoidance=false"]);
    eprintln!("collision: {:?}", s.contacts);
    assert_eq!(s.false_detections, 0);
    assert!(s.detections >= 2, "detections {}", s.detections);
}

#[test]
fn perception_scenarios_are_real_tests_without_avoidance() {
    // without avoidance these scenarios produce contacts: the avoidance tests are not vacuous
    for (scenario, secs) in [("coexistence", 29.0), ("elbow", 28.0)] {
        let s = common::run(
            scenario,
            secs,
            &CellOptions::default(),
            &["control.avoidance=false"],
        );
        let peak = s
            .contacts
            .iter()
            .map(|c| c.peak_force_n)
            .fold(0.0, f64::max);
        eprintln!(
            "{scenario}: {} contacts, peak {peak:.0} N",
            s.contacts.len()
        );
        assert!(s.contacts.len() >= 2, "{scenario}: {:?}", s.contacts);
    }
}

#[test]
fn avoidance_with_nothing_near_keeps_the_task() {
    // the whole perception pipeline in an empty scene: always fresh, nothing near
    let with = common::run("free-motion", 20.0, &CellOptions::default(), &[]);
    assert!(with.frames > 550, "the camera ran: {} frames", with.frames);
    assert!(with.waypoints >= 10, "waypoints {}", with.waypoints);
    assert_eq!(with.detections, 0);
    assert_eq!(with.protective_stop_s, 0.0);
}

/// `[sim] human_offset_s` (the process cell's way to meet the person later
/// in the scenario) is the lock-step cell's `--offset`: the same run, and
/// the two add up.
#[test]
fn the_configured_offset_of_the_person_is_the_lock_step_offset() {
    let summary = |offset: f64, sets: &[&str]| {
        let opts = CellOptions {
            human_time_offset_s: offset,
            ..Default::default()
        };
        serde_json::to_string(&common::run("coexistence", 6.0, &opts, sets)).unwrap()
    };
    let by_option = summary(6.0, &[]);
    assert_eq!(by_option, summary(0.0, &["sim.human_offset_s=6"]));
    assert_eq!(by_option, summary(2.0, &["sim.human_offset_s=4"]));
    // and it is an offset: without it the person is elsewhere
    assert_ne!(by_option, summary(0.0, &[]));
}
