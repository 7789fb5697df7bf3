//! The collaboration scenarios' figures in lock-step, as the report grades
//! them (ignored: a measurement, not a test; BENCHMARKS.md quotes it):
//!
//!   cargo test --release -p phri-cell --test collab_figures -- --ignored --nocapture
//!
//! Per scenario and offset of the person's script: touches of the
//! collaborative hand (its contacts with any link, apart < 0.5 s merged, as
//! `collaboration.contacts_intended`), the simulator's intended episodes,
//! contact ↔ follow switches, F̂'s error ‖F̂ − F‖/‖F‖ p50/p95 over the
//! contact phase's observable samples with ‖F‖ ≥ 5 N (as
//! `collaboration.force_error`), how it ended, unintended contacts.
//! `FIGURES_SCENARIOS` / `FIGURES_OFFSETS` (comma-separated) narrow it;
//! `FIGURES_SET` (space-separated `key=value`) overrides `deploy/phri.toml`.

mod common;

use nalgebra::Vector3;
use phri_cell::CellOptions;
use phri_ipc::CollabPhase;

#[test]
#[ignore]
fn collaboration_figures() {
    let scenarios = std::env::var("FIGURES_SCENARIOS").unwrap_or_else(|_| {
        "collaboration,safe-collaboration,safe-collaboration-elbow,voice-collaboration".into()
    });
    let offsets = std::env::var("FIGURES_OFFSETS").unwrap_or_else(|_| "0,-0.7,0.4".into());
    for scenario in scenarios.split(',') {
        for offset in offsets
            .split(',')
            .filter_map(|o| o.trim().parse::<f64>().ok())
        {
            let sets = std::env::var("FIGURES_SET").unwrap_or_default();
            let sets: Vec<&str> = sets.split_whitespace().collect();
            let l = common::loaded(scenario, &sets);
            let opts = CellOptions {
                human_time_offset_s: offset,
                ..CellOptions::default()
            };
            let mut c = common::cell_of(&l, &opts);
            let (mut errors, mut switches, mut touches) = (Vec::new(), 0, 0);
            let mut last_touch: Option<f64> = None;
            let mut phase = CollabPhase::Idle;
            for _ in 0..(l.scenario.duration_s * 1000.0).round() as usize {
                c.tick().unwrap();
                let t = c.time_ns() as f64 * 1e-9;
                let col = c.controller.collaboration().unwrap();
                let now = col.phase();
                if matches!(
                    (phase, now),
                    (CollabPhase::Contact, CollabPhase::Follow)
                        | (CollabPhase::Follow, CollabPhase::Contact)
                ) {
                    switches += 1;
                }
                phase = now;
                let hand = col.machine().part().body_part();
                let mut f = Vector3::zeros();
                let mut touching = false;
                for k in c.sim.truth().contacts.iter() {
                    if k.intended && Some(k.part) == hand {
                        f += k.force;
                        touching = true;
                    }
                }
                if touching {
                    if last_touch.is_none_or(|l| t - l > 0.5) {
                        touches += 1;
                    }
                    last_touch = Some(t);
                }
                if now == CollabPhase::Contact && f.norm() >= 5.0 {
                    if let Some(e) = col.estimate().filter(|e| e.observable[0]) {
                        errors.push((e.forces[0] - f).norm() / f.norm());
                    }
                }
            }
            errors.sort_by(f64::total_cmp);
            let p = |q: f64| {
                errors
                    .get(((errors.len().max(1) - 1) as f64 * q).round() as usize)
                    .map_or(f64::NAN, |x| x * 100.0)
            };
            let s = c.summary();
            let m = c.controller.collaboration().unwrap().machine();
            eprintln!(
                "{scenario} offset {offset:+.1} s: touches {touches} (episodes {}), switches {switches}, \
                 F̂ error p50 {:.1} % p95 {:.1} % ({} samples), ended {:?} at {:?}, unintended {}",
                s.contacts.iter().filter(|e| e.intended).count(),
                p(0.5),
                p(0.95),
                errors.len(),
                m.reason(),
                m.phase(),
                s.unintended_contacts
            );
        }
    }
}
