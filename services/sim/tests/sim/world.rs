//! The hybrid cell's simulated arm follows the robot outside: its truth is
//! the newest state's positions, its velocity their difference over the
//! robot's clock, and a state it cannot use leaves it where it was.

use crate::common;

use phri_ipc::{JointState, Zeroed};
use phri_sim::{Simulator, WorldFollower};

fn state(seq: u64, stamp_ms: u64, q: &[f64]) -> JointState {
    let mut s = JointState::zeroed();
    s.seq = seq;
    s.stamp_ns = stamp_ms * 1_000_000;
    s.dof = q.len() as u32;
    s.q[..q.len()].copy_from_slice(q);
    s
}

#[test]
fn the_simulated_arm_is_where_the_robot_outside_says_and_moves_as_fast() {
    let model = common::model();
    let q0 = common::sim_config().q0.clone();
    let n = q0.len();
    let mut sim = Simulator::new(model, common::sim_config(), None, &[], Some(1)).unwrap();
    let mut f = WorldFollower::new(&q0);
    // before any state: at q0, still
    f.step(&mut sim, None);
    assert_eq!(sim.truth().q, q0);
    assert!(sim.truth().qd.iter().all(|v| *v == 0.0));
    // the robot's states, 1 ms apart, joint 2 moving at 0.5 rad/s
    let mut q = q0.clone();
    for k in 1..=20u64 {
        q[1] = q0[1] + 0.0005 * k as f64;
        f.step(&mut sim, Some(&state(k, 1000 + k, &q)));
    }
    assert_eq!(sim.truth().q, q);
    assert!(
        (sim.truth().qd[1] - 0.5).abs() < 1e-9,
        "{:?}",
        sim.truth().qd
    );
    assert_eq!(f.last(), Some((20, 1020 * 1_000_000)));
    // the same state again (no new one this period): the arm stays
    f.step(&mut sim, Some(&state(20, 1020, &q)));
    assert_eq!(sim.truth().q, q);
    // a state of another arm, or with a non-finite joint: refused, the arm stays
    f.step(&mut sim, Some(&state(21, 1021, &q[..n - 1])));
    let mut nan = q.clone();
    nan[3] = f64::NAN;
    f.step(&mut sim, Some(&state(22, 1022, &nan)));
    assert_eq!(f.refused(), 2);
    assert_eq!(sim.truth().q, q);
    // after a long silence (the robot restarted) the next state is no speed
    let mut far = q.clone();
    far[1] += 0.2;
    f.step(&mut sim, Some(&state(1, 2000, &far)));
    assert_eq!(sim.truth().q, far);
    assert!(
        sim.truth().qd.iter().all(|v| *v == 0.0),
        "{:?}",
        sim.truth().qd
    );
}
