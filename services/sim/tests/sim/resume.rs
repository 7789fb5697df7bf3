//! A simulator restarted inside a running cell: the person goes on from the
//! predecessor's script time (the robot's clock, behind the wall clock on a
//! loaded machine), not from the wall clock's time since the cell started.

use crate::common;

use phri_sim::snapshot::{self, ArmSnapshot};
use phri_sim::Simulator;

const S: u64 = 1_000_000_000;

fn run_dir(name: &str) -> std::path::PathBuf {
    let d = std::env::temp_dir().join(format!("phri-sim-resume-{}-{name}", std::process::id()));
    std::fs::create_dir_all(&d).unwrap();
    d.join(snapshot::FILE_NAME)
}

fn sim() -> Simulator {
    Simulator::new(common::model(), common::sim_config(), None, &[], Some(1)).unwrap()
}

#[test]
fn the_person_continues_from_the_predecessor_s_script_time() {
    // the cell started 20 s ago by the wall clock; the robot's clock, behind
    // it, had brought the person's script to 12 s when the last snapshot was
    // taken, 0.3 s ago
    let (start, now) = (100 * S, 120 * S);
    let path = run_dir("behind");
    let q = common::sim_config().q0.clone();
    let s = ArmSnapshot {
        version: snapshot::VERSION,
        stamp_ns: now - 3 * S / 10,
        q: q.clone(),
        scenario_s: 12.0,
    };
    snapshot::save(&path, &s).unwrap();
    let mut resumed_sim = sim();
    let r = snapshot::resume(&mut resumed_sim, start, now, Some(&path));
    assert!((r.scenario_s - 12.3).abs() < 1e-9, "{r:?}");
    assert!((r.behind_s - 20.0).abs() < 1e-9, "{r:?}");
    assert!((resumed_sim.human_time_s() - 12.3).abs() < 1e-9);
    assert!(
        matches!(r.arm, snapshot::ArmResume::Restored { .. }),
        "{r:?}"
    );
    let line = r.log_lines().join("\n");
    assert!(line.contains("continues from 12.3 s"), "{line}");
    // without a snapshot of this cell: the wall clock's time since it started
    std::fs::remove_file(&path).unwrap();
    let mut fresh = sim();
    let r = snapshot::resume(&mut fresh, start, now, Some(&path));
    assert!((r.scenario_s - 20.0).abs() < 1e-9, "{r:?}");
    assert!((fresh.human_time_s() - 20.0).abs() < 1e-9);
    assert!(matches!(r.arm, snapshot::ArmResume::Initial), "{r:?}");
    let mut none = sim();
    let r = snapshot::resume(&mut none, start, now, None);
    assert!((none.human_time_s() - 20.0).abs() < 1e-9, "{r:?}");
}

#[test]
fn a_configured_offset_of_the_person_s_script_carries_into_a_restart() {
    use phri_config::SimConfig;
    let cfg = SimConfig {
        human_offset_s: 5.0,
        ..common::sim_config()
    };
    let offset = || Simulator::new(common::model(), cfg.clone(), None, &[], Some(1)).unwrap();
    // a fresh simulator meets the person 5 s into the script
    let mut fresh = offset();
    assert!((fresh.human_time_s() - 5.0).abs() < 1e-9);
    fresh.step(&[0.0; 7], true);
    assert!((fresh.human_time_s() - 5.001).abs() < 1e-9);
    // restarted 20 s into the cell without a snapshot: 25 s into the script
    let (start, now) = (100 * S, 120 * S);
    let mut restarted = offset();
    let r = snapshot::resume(&mut restarted, start, now, None);
    assert!((r.scenario_s - 25.0).abs() < 1e-9, "{r:?}");
    assert!((restarted.human_time_s() - 25.0).abs() < 1e-9);
    // a snapshot's script time already holds the offset
    let path = run_dir("offset");
    let s = ArmSnapshot {
        version: snapshot::VERSION,
        stamp_ns: now,
        q: cfg.q0.clone(),
        scenario_s: 24.0,
    };
    snapshot::save(&path, &s).unwrap();
    let mut resumed = offset();
    let r = snapshot::resume(&mut resumed, start, now, Some(&path));
    assert!((r.scenario_s - 24.0).abs() < 1e-9, "{r:?}");
}
