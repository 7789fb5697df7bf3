//! The deployed configuration and scenarios, for the lock-step tests.

#![allow(dead_code)]

use std::path::PathBuf;

use phri_cell::{Cell, CellOptions, CellSummary};
use phri_config::{HumanScript, Keyframe, Loaded};

pub fn deploy() -> PathBuf {
    PathBuf::from(concat!(
        env!("CARGO_MANIFEST_DIR"),
        "/../../deploy/phri.toml"
    ))
}

/// `scenario` (which must have a person) with its person's keyframes as
/// `edit` leaves them: a variant built in memory, its floor and its
/// collaborative parts kept.
pub fn rescript(scenario: &str, sets: &[&str], edit: impl FnOnce(&mut Vec<Keyframe>)) -> Loaded {
    let mut l = loaded(scenario, sets);
    let script = l.scenario.human.as_ref().expect("a scenario with a person");
    let mut keyframes = script.keyframes().to_vec();
    edit(&mut keyframes);
    l.scenario.human = Some(HumanScript::new(script.floor_z(), keyframes).unwrap());
    l
}

/// A keyframe at `t` \[s\] with the person's base at `base` (x, y \[m\],
/// heading \[rad\]), every limb at rest.
pub fn keyframe(t: f64, base: [f64; 3]) -> Keyframe {
    Keyframe {
        t,
        base,
        ..Default::default()
    }
}

/// `deploy/phri.toml` with `scenario` and `sets` (`section.key=value`).
pub fn loaded(scenario: &str, sets: &[&str]) -> Loaded {
    Loaded::load(&deploy(), Some(scenario), sets).unwrap()
}

pub fn cell(scenario: &str, opts: &CellOptions, sets: &[&str]) -> Cell {
    cell_of(&loaded(scenario, sets), opts)
}

/// A cell of a loaded configuration (one a test changed: its scenario's
/// script, its control points).
pub fn cell_of(l: &Loaded, opts: &CellOptions) -> Cell {
    let model = l.model().unwrap();
    Cell::new(l, model, opts).unwrap()
}

/// Run `scenario` for `seconds` and summarise.
pub fn run(scenario: &str, seconds: f64, opts: &CellOptions, sets: &[&str]) -> CellSummary {
    let mut c = cell(scenario, opts, sets);
    for _ in 0..(seconds * 1000.0).round() as usize {
        c.tick().unwrap();
    }
    c.summary()
}

/// Smallest true surface distance \[m\] between the person's `parts` (body
/// part names, `hand_left`, ...) and the robot's `links` (`lwr_link_4`, ...)
/// in the cell's simulator now, from the capsules.
pub fn parts_to_links(c: &Cell, parts: &[&str], links: &[&str]) -> f64 {
    let mut d = f64::INFINITY;
    for r in c.sim.robot_capsule_poses() {
        if !c
            .sim
            .collision_link(r.collision)
            .is_some_and(|l| links.contains(&l))
        {
            continue;
        }
        for h in c.sim.human_capsules() {
            if parts.contains(&h.part.name()) {
                let x = phri_sim::capsule_distance(&r.a, &r.b, r.radius, &h.a, &h.b, h.radius);
                d = d.min(x.distance);
            }
        }
    }
    d
}
