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

/// A collaboration's figures as the report grades them, gathered period by
/// period: touches of the collaborative hand (its contacts with any link,
/// apart < 0.5 s merged, as `collaboration.contacts_intended`), contact ↔
/// follow switches, and F̂'s error ‖F̂ − F‖/‖F‖ over the contact phase's
/// observable samples with ‖F‖ ≥ 5 N (as `collaboration.force_error`).
#[derive(Debug, Default)]
pub struct CollabFigures {
    pub touches: usize,
    pub switches: usize,
    /// F̂'s relative errors, one per sample counted
    pub errors: Vec<f64>,
    last_touch: Option<f64>,
    phase: Option<phri_ipc::CollabPhase>,
}

impl CollabFigures {
    /// Take in the period `c` just stepped.
    pub fn observe(&mut self, c: &Cell) {
        use phri_ipc::CollabPhase;
        let Some(col) = c.controller.collaboration() else {
            return;
        };
        let t = c.time_ns() as f64 * 1e-9;
        let now = col.phase();
        if matches!(
            (self.phase, now),
            (Some(CollabPhase::Contact), CollabPhase::Follow)
                | (Some(CollabPhase::Follow), CollabPhase::Contact)
        ) {
            self.switches += 1;
        }
        self.phase = Some(now);
        let hand = col.machine().part().body_part();
        let (mut f, mut touching) = (nalgebra::Vector3::zeros(), false);
        for k in c.sim.truth().contacts.iter() {
            if k.intended && Some(k.part) == hand {
                f += k.force;
                touching = true;
            }
        }
        if touching {
            if self.last_touch.is_none_or(|l| t - l > 0.5) {
                self.touches += 1;
            }
            self.last_touch = Some(t);
        }
        if now == CollabPhase::Contact && f.norm() >= 5.0 {
            if let Some(e) = col.estimate().filter(|e| e.observable[0]) {
                self.errors.push((e.forces[0] - f).norm() / f.norm());
            }
        }
    }

    /// F̂'s error at quantile `q` \[%\] (NaN without samples).
    pub fn error_pct(&self, q: f64) -> f64 {
        let mut e = self.errors.clone();
        e.sort_by(f64::total_cmp);
        e.get(((e.len().max(1) - 1) as f64 * q).round() as usize)
            .map_or(f64::NAN, |x| x * 100.0)
    }
}

/// A deterministic uniform sequence in [0, 1) (xorshift64*).
pub struct Uniform(pub u64);

impl Uniform {
    pub fn next(&mut self) -> f64 {
        self.0 ^= self.0 >> 12;
        self.0 ^= self.0 << 25;
        self.0 ^= self.0 >> 27;
        (self.0.wrapping_mul(0x2545_f491_4f6c_dd1d) >> 11) as f64 / (1u64 << 53) as f64
    }

    /// A direction uniform on the unit sphere.
    pub fn direction(&mut self) -> nalgebra::Vector3<f64> {
        let z = 2.0 * self.next() - 1.0;
        let phi = std::f64::consts::TAU * self.next();
        let s = (1.0 - z * z).max(0.0).sqrt();
        nalgebra::Vector3::new(s * phi.cos(), s * phi.sin(), z)
    }
}
