//! `Simulator::step`, `RobotLink::cycle` and the message adapters allocate
//! nothing: counted with a global allocator (the test thread's own
//! allocations).

mod common;

use common::counting::{allocations, Counting};

use phri_config::{Scenario, SimConfig};
use phri_ipc::{JointState, TorqueCommand, Truth, WorldState, Zeroed};
use phri_sim::{fill_state, fill_truth, fill_world, CycleTiming, RobotLink, Simulator};

#[global_allocator]
static GLOBAL: Counting = Counting;

/// Through the whole collision scenario with the robot held in the human's
/// way (contacts, sensor, brake on and off), and report the cost of a step.
#[test]
fn step_does_not_allocate() {
    let model = common::model();
    let q = common::ik(&model, common::P2);
    let sc = Scenario::from_file(common::scenario_path("collision.toml")).expect("scenario");
    let cfg = SimConfig {
        q0: q.clone(),
        ft_sensor: true,
        ..common::sim_config()
    };
    let mut sim = Simulator::from_scenario(model, cfg, &sc, Some(1)).expect("sim");
    let tau = [0.0, 20.0, 0.0, 10.0, 0.0, 1.0, 0.0];
    let mut contacts = 0usize;
    let start = allocations();
    let t0 = std::time::Instant::now();
    for k in 0..16_000 {
        if k % 50 == 0 {
            sim.reset_state(&q).expect("pose");
        }
        let m = sim.step(&tau, k % 3000 > 2500);
        contacts += usize::from(m.wrench.is_some_and(|w| w.iter().any(|x| *x != 0.0)));
        contacts += sim.truth().contacts.len();
    }
    let elapsed = t0.elapsed();
    let allocated = allocations() - start;
    println!(
        "16 000 steps with a human: {:.1} µs per step, {contacts} contacts seen",
        elapsed.as_secs_f64() * 1e6 / 16_000.0
    );
    assert!(contacts > 1000, "the run had contacts");
    assert_eq!(allocated, 0, "step allocated {allocated} times");

    let mut empty =
        Simulator::new(common::model(), common::sim_config(), None, &[], None).expect("sim");
    let start = allocations();
    let t0 = std::time::Instant::now();
    for _ in 0..10_000 {
        empty.step(&[0.0; 7], false);
    }
    let elapsed = t0.elapsed();
    let allocated = allocations() - start;
    println!(
        "10 000 steps without a human: {:.1} µs per step",
        elapsed.as_secs_f64() * 1e6 / 10_000.0
    );
    assert_eq!(allocated, 0, "step allocated {allocated} times");

    // the robot side of the loop: commands fresh, stale, malformed and
    // missing (brakes on and off, runs of misses reported), the messages filled
    let mut link = RobotLink::new(7, 1_000_000).expect("link");
    let (mut state, mut truth, mut world) =
        (JointState::zeroed(), Truth::zeroed(), WorldState::zeroed());
    let mut cmd = TorqueCommand::zeroed();
    cmd.dof = 7;
    let mut reports = 0usize;
    let start = allocations();
    for seq in 1..=10_000u64 {
        cmd.seq = seq;
        cmd.state_seq = if seq % 7 == 0 { seq - 1 } else { seq };
        cmd.tau[2] = if seq % 11 == 0 { f64::NAN } else { 1.0 };
        let newest = if seq % 1000 > 970 { None } else { Some(&cmd) };
        let timing = CycleTiming {
            state_published_ns: seq * 1_000_000,
            command_event_ns: seq * 1_000_000 + 300_000,
            now_ns: seq * 1_000_000 + 1_000_000,
            behind_schedule_ns: 0,
            standby_asked: false,
        };
        let out = link.cycle(newest, seq, &timing);
        reports += usize::from(out.miss_run.is_some()) + usize::from(out.brake_engaged);
        empty.step(out.torque(), out.brake);
        fill_state(&empty, &out, seq + 1, seq, seq, &mut state);
        fill_truth(&empty, seq + 1, seq, &mut truth);
        fill_world(&empty, seq + 1, seq, &mut world);
    }
    let allocated = allocations() - start;
    println!(
        "10 000 link cycles: {} braked, {} missed, {reports} reports",
        link.stats().braked_cycles,
        link.stats().missed_deadlines
    );
    assert!(
        link.stats().brake_events > 0 && reports > 10,
        "the run braked and missed"
    );
    assert_eq!(allocated, 0, "the link allocated {allocated} times");
}
