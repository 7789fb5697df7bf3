//! The adapter's period against a control box nobody here wrote: PyPI's
//! franka-sim (MuJoCo, the FCI wire protocol, server version 10, FR3),
//! installed by `deploy/franka-sim/install` and started by this test on
//! 127.0.0.1, enforcing the communication constraints. The arm's model comes
//! from the box (`GetRobotModel`); a joint PD hold plays phri's controller
//! (its command carries gravity, as phri's does); the adapter removes
//! gravity with phri's model of that URDF before the box adds its own.

mod common;

use std::time::{Duration, Instant};

use phri_franka::FciCycle;
use phri_ipc::{TorqueCommand, Zeroed};
use phri_robot::CycleTiming;

#[test]
fn the_adapter_holds_the_fr3_of_franka_sim_with_gravity_left_to_the_box() {
    let port = common::port(0);
    let _server = common::serve(port);
    let address = format!("127.0.0.1:{port}");
    let deadline = Instant::now() + Duration::from_secs(30);
    let robot = loop {
        match franka::Robot::new(&address, franka::RealtimeConfig::Ignore) {
            Ok(r) => break r,
            Err(e) => {
                assert!(Instant::now() < deadline, "no connection to {address}: {e}");
                std::thread::sleep(Duration::from_millis(200));
            }
        }
    };
    assert_eq!(robot.server_version(), 10);
    let urdf = robot.robot_model().expect("GetRobotModel");
    let model = phri_model::Model::from_urdf_str(&urdf).expect("phri reads the FR3's URDF");
    let mut cycle = FciCycle::new(model, 1e-3).expect("a 7-joint arm");

    let mut control = robot.start_torque_control().expect("torque control");
    // a stiff joint PD about where the arm stands; from HOLD on, phri's
    // command adds PUSH on every joint: the arm settles PUSH/KP away
    const KP: f64 = 200.0;
    const KD: f64 = 20.0;
    const PUSH: f64 = 2.0;
    const HOLD: u64 = 1500;
    const END: u64 = 4000;
    let mut q0 = None;
    let (mut drift, mut state) = (0.0f64, None);
    for seq in 1..=END {
        let (s, _) = control.read_once().expect("a state");
        let q0 = *q0.get_or_insert(s.q);
        let g = cycle.gravity(&s.q).expect("gravity");
        let push = if seq > HOLD { PUSH } else { 0.0 };
        let mut cmd = TorqueCommand::zeroed();
        cmd.seq = seq;
        cmd.state_seq = seq;
        cmd.dof = 7;
        for k in 0..7 {
            cmd.tau[k] = g[k] + KP * (q0[k] - s.q[k]) - KD * s.dq[k] + push;
        }
        let timing = CycleTiming {
            state_published_ns: seq * 1_000_000,
            command_event_ns: seq * 1_000_000 + 100_000,
            now_ns: seq * 1_000_000 + 100_000,
            behind_schedule_ns: 0,
            standby_asked: false,
        };
        let (_, out) = cycle.step(Some(&cmd), seq, &timing, &s.q).expect("a step");
        assert!(!out.brake);
        control
            .write_once(&franka::Torques::new(out.tau))
            .expect("the box takes the torque");
        if (500..=HOLD).contains(&seq) {
            for k in 0..7 {
                drift = drift.max((s.q[k] - q0[k]).abs());
            }
        }
        state = Some((s, q0));
    }
    control
        .write_once(&franka::motion_finished(franka::Torques::new([0.0; 7])))
        .expect("the motion ends");
    let (s, q0) = state.expect("states");
    let moved: Vec<f64> = (0..7).map(|k| s.q[k] - q0[k]).collect();
    eprintln!(
        "held within {drift:.6} rad; under {PUSH} Nm a joint each: moved {moved:.4?} rad \
         (PUSH/KP = {:.4}); success rate {:.4}",
        PUSH / KP,
        s.control_command_success_rate
    );
    // gravity: phri's g(q) of the box's URDF, taken out again, leaves the
    // arm where it stands (26 Nm left on joint 2 would sag it 0.13 rad)
    assert!(drift < 1e-3, "the arm drifted {drift} rad");
    // the box applies the torque sent: each joint settles PUSH/KP away
    for (k, m) in moved.iter().enumerate() {
        assert!(
            (m - PUSH / KP).abs() < 0.2 * PUSH / KP,
            "joint {}: moved {m} rad under {PUSH} Nm, not {}",
            k + 1,
            PUSH / KP
        );
    }
    // no command lost for long (the server enforces FCI's communication
    // constraints: 20 lost in a row would have ended the motion and failed
    // `read_once` above); over its last 100, a few late from this test
    // thread, which is not real-time and shares 2 cores with the MuJoCo
    // server (CI saw 2). The cell's figure, averaged over a run with the
    // real-time adapter, is held to 0.999 by the hybrid tests
    assert!(
        s.control_command_success_rate >= 0.95,
        "{}",
        s.control_command_success_rate
    );
}
