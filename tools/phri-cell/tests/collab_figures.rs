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

use phri_cell::CellOptions;

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
            let mut fig = common::CollabFigures::default();
            for _ in 0..(l.scenario.duration_s * 1000.0).round() as usize {
                c.tick().unwrap();
                fig.observe(&c);
            }
            let s = c.summary();
            let m = c.controller.collaboration().unwrap().machine();
            eprintln!(
                "{scenario} offset {offset:+.1} s: touches {} (episodes {}), switches {}, \
                 F̂ error p50 {:.1} % p95 {:.1} % ({} samples), ended {:?} at {:?}, unintended {}",
                fig.touches,
                s.contacts.iter().filter(|e| e.intended).count(),
                fig.switches,
                fig.error_pct(0.5),
                fig.error_pct(0.95),
                fig.errors.len(),
                m.reason(),
                m.phase(),
                s.unintended_contacts
            );
        }
    }
}
