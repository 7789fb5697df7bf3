//! The three services' steps (simulated robot, residual, controller) in one
//! process, in lock-step, with the deployed configuration: deterministic
//! versions of the system scenarios.

use phri_control::{ControlConfig, ControlInput, Controller, ResidualView};
use phri_dynamics::{ResidualConfig, ResidualObserver};
use phri_ipc::control_mode as mode;
use phri_sim::{Scenario, SimConfig, Simulator};

fn deploy() -> toml::Table {
    let path = concat!(env!("CARGO_MANIFEST_DIR"), "/../../deploy/phri.toml");
    std::fs::read_to_string(path).unwrap().parse().unwrap()
}

fn section<T: serde::de::DeserializeOwned>(t: &toml::Table, name: &str) -> T {
    t[name].clone().try_into().unwrap()
}

pub struct Lockstep {
    pub sim: Simulator,
    pub observer: ResidualObserver,
    pub controller: Controller,
    pub tau: Vec<f64>,
    pub r: Vec<f64>,
    pub flags: (bool, bool, bool),
    pub t_ns: u64,
    pub false_detections: u32,
    pub max_r: f64,
}

impl Lockstep {
    pub fn new(scenario: &str, sets: &[(&str, &str, toml::Value)]) -> Lockstep {
        let mut t = deploy();
        for (s, k, v) in sets {
            t[*s]
                .as_table_mut()
                .unwrap()
                .insert(k.to_string(), v.clone());
        }
        let model = phri_model::Model::from_urdf_file(concat!(
            env!("CARGO_MANIFEST_DIR"),
            "/../../deploy/robots/kuka_lwr4.urdf"
        ))
        .unwrap();
        let scen = Scenario::from_file(format!(
            "{}/../../deploy/scenarios/{scenario}.toml",
            env!("CARGO_MANIFEST_DIR")
        ))
        .unwrap();
        let sim_cfg: SimConfig = section(&t, "sim");
        let res_cfg: ResidualConfig = section(&t, "dynamics");
        let ctl_cfg: ControlConfig = section(&t, "control");
        Lockstep {
            sim: Simulator::from_scenario(model.clone(), sim_cfg, &scen, None).unwrap(),
            observer: ResidualObserver::new(model.clone(), &res_cfg).unwrap(),
            controller: Controller::new(model, ctl_cfg).unwrap(),
            tau: vec![0.0; 7],
            r: vec![0.0; 7],
            flags: (false, false, false),
            t_ns: 0,
            false_detections: 0,
            max_r: 0.0,
        }
    }

    /// One period: the robot applies the last command, the residual and the controller answer.
    pub fn tick(&mut self) -> u32 {
        let m = self.sim.step(&self.tau, false).clone();
        self.t_ns += 1_000_000;
        let out = self
            .observer
            .step(
                self.t_ns as f64 * 1e-9,
                &m.q,
                &m.tau_applied,
                m.wrench.as_ref(),
            )
            .unwrap();
        self.r.copy_from_slice(out.r);
        let no_contact = self.sim.truth().contacts.is_empty();
        if out.detection.collision && !self.flags.2 && no_contact {
            self.false_detections += 1;
            eprintln!(
                "false detection at {:.3} s: r = {:?}",
                self.t_ns as f64 * 1e-9,
                out.r
                    .iter()
                    .map(|x| (x * 10.0).round() / 10.0)
                    .collect::<Vec<_>>()
            );
        }
        if no_contact && out.valid {
            self.max_r = self.max_r.max(out.norm);
        }
        self.flags = (out.valid, out.detection.contact, out.detection.collision);
        let view = ResidualView {
            state_stamp_ns: self.t_ns,
            r: &self.r,
            valid: self.flags.0,
            contact: self.flags.1,
            collision: self.flags.2,
        };
        let o = self.controller.step(&ControlInput {
            state_stamp_ns: self.t_ns,
            q: &m.q,
            residual: Some(view),
            perception: None,
        });
        self.tau.copy_from_slice(o.tau);
        o.mode
    }
}

#[test]
fn free_motion_in_lockstep_cycles_without_false_detections() {
    let mut c = Lockstep::new("free-motion", &[]);
    let mut last_mode = mode::SYNC;
    for k in 0..20_000 {
        let m = c.tick();
        if m != last_mode {
            eprintln!(
                "{:.3} s: mode {} -> {}",
                k as f64 / 1000.0,
                mode::name(last_mode),
                mode::name(m)
            );
            last_mode = m;
        }
    }
    eprintln!(
        "waypoints {} max |r| in free motion {:.2} Nm",
        c.controller.waypoints_reached, c.max_r
    );
    assert_eq!(c.false_detections, 0);
    assert!(
        c.controller.waypoints_reached >= 10,
        "waypoints {}",
        c.controller.waypoints_reached
    );
}

#[test]
fn collision_in_lockstep_detects_reacts_and_has_no_false_detections() {
    let mut c = Lockstep::new("collision", &[]);
    let mut last_mode = mode::SYNC;
    let mut in_contact = false;
    for k in 0..16_000 {
        let m = c.tick();
        let contact = !c.sim.truth().contacts.is_empty();
        if contact != in_contact {
            let t = c.sim.truth();
            eprintln!(
                "{:.3} s: contact {} {:?}",
                k as f64 / 1000.0,
                contact,
                t.contacts
                    .first()
                    .map(|x| (x.collision, x.part, x.force.norm()))
            );
            in_contact = contact;
        }
        if m != last_mode {
            let (q, _) = c.sim.state();
            eprintln!(
                "{:.3} s: mode {} -> {} q4 {:.3}",
                k as f64 / 1000.0,
                mode::name(last_mode),
                mode::name(m),
                q[3]
            );
            last_mode = m;
        }
    }
    assert_eq!(c.false_detections, 0);
    assert!(c.controller.detections >= 2);
}

/// Contacts (count of new contact episodes, peak force) over a scenario without avoidance.
fn contacts_without_avoidance(scenario: &str, seconds: usize) -> (u32, f64) {
    let mut c = Lockstep::new(scenario, &[]);
    let (mut episodes, mut peak, mut was) = (0, 0.0f64, false);
    for _ in 0..seconds * 1000 {
        c.tick();
        let t = c.sim.truth();
        let now = !t.contacts.is_empty();
        if now && !was {
            episodes += 1;
        }
        was = now;
        peak = t
            .contacts
            .iter()
            .map(|x| x.force.norm())
            .fold(peak, f64::max);
    }
    (episodes, peak)
}

#[test]
fn perception_scenarios_are_real_tests_without_avoidance() {
    // without avoidance these scenarios produce contacts: the avoidance tests are not vacuous
    for (s, secs) in [("coexistence", 29), ("elbow", 28)] {
        let (episodes, peak) = contacts_without_avoidance(s, secs);
        eprintln!("{s}: {episodes} contacts, peak {peak:.0} N");
        assert!(episodes >= 2, "{s}: {episodes} contacts");
    }
}

/// A lock-step cell with avoidance but an empty scene: perception always
/// fresh, nothing near. The task must track as well as without avoidance.
#[test]
fn avoidance_with_nothing_near_keeps_the_task() {
    let mut c = Lockstep::new("free-motion", &[]);
    c.controller
        .set_control_points(&[
            ("lwr_flange".to_string(), [0.0; 3]),
            ("lwr_link_4".to_string(), [0.0; 3]),
        ])
        .unwrap();
    let points = [
        phri_ipc::PointRepulsion {
            point: 0,
            active: 0,
            v_call: [0.0; 3],
            min_distance: 1.0,
            obstacle: [0.0; 3],
            position: [0.0; 3],
        },
        phri_ipc::PointRepulsion {
            point: 1,
            ..Default::default()
        },
    ];
    for _ in 0..20_000 {
        let m = c.sim.step(&c.tau, false).clone();
        c.t_ns += 1_000_000;
        let out = c
            .observer
            .step(c.t_ns as f64 * 1e-9, &m.q, &m.tau_applied, None)
            .unwrap();
        c.r.copy_from_slice(out.r);
        c.flags = (out.valid, out.detection.contact, out.detection.collision);
        let view = ResidualView {
            state_stamp_ns: c.t_ns,
            r: &c.r,
            valid: c.flags.0,
            contact: c.flags.1,
            collision: c.flags.2,
        };
        let p = phri_control::PerceptionView {
            capture_ns: c.t_ns - 20_000_000,
            points: &points,
        };
        let o = c.controller.step(&ControlInput {
            state_stamp_ns: c.t_ns,
            q: &m.q,
            residual: Some(view),
            perception: Some(p),
        });
        c.tau.copy_from_slice(o.tau);
    }
    eprintln!(
        "waypoints with avoidance: {}",
        c.controller.waypoints_reached
    );
    assert!(
        c.controller.waypoints_reached >= 10,
        "waypoints {}",
        c.controller.waypoints_reached
    );
    assert_eq!(c.controller.detections, 0);
}
