//! The 1 kHz path allocates nothing: `Controller::step` in every mode (with
//! avoidance and perception), the repulsion accumulator and the message
//! writer, on an exact-model arm with the residual observer in the loop;
//! and a hot standby's: its step, the primary's `save_behaviour`, its
//! `adopt_behaviour` (refusals included).

use std::alloc::{GlobalAlloc, Layout, System};
use std::cell::Cell;
use std::collections::BTreeSet;

use nalgebra::Vector3;
use phri_config::{Config, PerJoint, ResidualConfig};
use phri_control::{
    write_barrier_status, write_collab_state, write_messages, write_ssm_status, CollabInput,
    ControlInput, ControlMode, Controller, Reaction, RepulsionInputs, ResidualView, Stamps,
    BEHAVIOUR_BYTES,
};
use phri_estimation::ResidualObserver;
use phri_ipc::{
    CollabPart, CollabState, ControlStatus, HriRequest, JointState, PointRepulsion,
    RepulsionResult, RequestKind, RequestSource, Skeleton, SkeletonJoint, TorqueCommand, Zeroed,
};
use phri_model::Data;

struct Counting;

thread_local! {
    static ALLOCS: Cell<usize> = const { Cell::new(0) };
}

unsafe impl GlobalAlloc for Counting {
    unsafe fn alloc(&self, layout: Layout) -> *mut u8 {
        let _ = ALLOCS.try_with(|c| c.set(c.get() + 1));
        System.alloc(layout)
    }
    unsafe fn dealloc(&self, ptr: *mut u8, layout: Layout) {
        System.dealloc(ptr, layout)
    }
    unsafe fn realloc(&self, ptr: *mut u8, layout: Layout, new_size: usize) -> *mut u8 {
        let _ = ALLOCS.try_with(|c| c.set(c.get() + 1));
        System.realloc(ptr, layout, new_size)
    }
}

#[global_allocator]
static GLOBAL: Counting = Counting;

fn allocations() -> usize {
    ALLOCS.with(|c| c.get())
}

const Q0: [f64; 7] = [0.0, -0.4, 0.0, 1.8, 0.0, -0.6, 0.0];

#[test]
fn the_control_period_allocates_nothing_in_any_mode() {
    for (i, reaction) in [
        Reaction::Reflex,
        Reaction::Admittance,
        Reaction::Float,
        Reaction::Retreat,
    ]
    .into_iter()
    .enumerate()
    {
        let mut cfg = Config::defaults();
        cfg.control.reaction = reaction;
        // both avoidance laws, each through every mode: the paper's, and
        // the control-barrier filter with its QP
        let cbf = i % 2 == 1;
        if cbf {
            cfg.avoidance.law = phri_config::AvoidanceLaw::Cbf;
        }
        // speed and separation monitoring on the 1 kHz path too, its
        // intrusion distance such that it bounds every point's approach
        cfg.ssm.enabled = true;
        cfg.ssm.intrusion_m = 0.7;
        cfg.control.posture.clear(); // taken from the arm at the first start
        let model = cfg_model(&cfg);
        let mut ctl = Controller::from_config(model.clone(), &cfg).unwrap();
        // a hot standby from 1 s on: it steps the same states and adopts the
        // primary's behaviour after each step (commanding what it does)
        let mut standby = Controller::from_config(model.clone(), &cfg).unwrap();
        let mut snapshot = [0u8; BEHAVIOUR_BYTES];
        let standby_from = 1000;
        let rcfg = ResidualConfig {
            viscous_friction: PerJoint::All(0.0),
            coulomb_friction: PerJoint::All(0.0),
            ..cfg.dynamics.clone()
        };
        let mut observer = ResidualObserver::new(model.clone(), &rcfg).unwrap();
        let mut repulsion = RepulsionInputs::from_config(&cfg.repulsion);
        let workers = cfg.repulsion.workers;
        let mut data = Data::new(&model);
        let (mut q, mut qd) = (Q0.to_vec(), vec![0.0; 7]);
        let mut tau = phri_model::gravity(&model, &mut data, &Q0)
            .unwrap()
            .as_slice()
            .to_vec();
        let (mut r, mut flags, mut r_stamp) = (vec![0.0; 7], (false, false, false), 0u64);
        let (mut cmd, mut status) = (TorqueCommand::zeroed(), ControlStatus::zeroed());
        let mut state = JointState::zeroed();
        let link = model.frame_id("lwr_link_4").unwrap();
        let mut jac = Data::jacobian_buffer(&model);
        let (mut step_allocs, mut modes) = (0usize, BTreeSet::new());
        // from 8.5 s a person holds the right hand out 0.25 m in front of the
        // end effector and asks, every 100 ms until accepted, to collaborate
        let mut collab = CollabState::zeroed();
        let mut ssm = phri_ipc::SsmStatus::zeroed();
        // `control/barrier`: one per period under the filter, none otherwise;
        // its flags summed over the run
        let mut barrier = phri_ipc::BarrierStatus::zeroed();
        let (mut barrier_msgs, mut flags_sum) = (0u64, [0u64; 3]);
        let mut request = HriRequest::zeroed();
        request.source = RequestSource::Cli as u32;
        request.kind = RequestKind::Follow as u32;
        request.part = CollabPart::RightHand as u32;
        request.person = u32::MAX;
        let mut skeleton = Skeleton::zeroed();
        skeleton.n_people = 1;
        skeleton.people[0].id = 1;
        skeleton.people[0].tracked = 1;
        skeleton.people[0].confidence = [0.9; 15];
        let hand_link = model.frame_id("lwr_link_7").unwrap();
        let mut hand: Option<[f64; 3]> = None;
        for k in 1..=11_500u64 {
            let t_s = k as f64 * 1e-3;
            // the arm: 10 sub-steps of exact dynamics, pushed on the forearm at
            // 3-3.3 s, and on the end effector by the collaborating hand with
            // 120 N at 10.8-11.1 s (above the force limit: back off)
            let push = (3.0..3.3).contains(&t_s);
            let hand_push = (10.8..11.1).contains(&t_s);
            for _ in 0..10 {
                let mut total = tau.clone();
                if push || hand_push {
                    // the hand's push acts along the line from the hand through
                    // the top of link 7's capsule, where F̂ is estimated
                    let (at, point, f) = match push {
                        true => (link, Vector3::zeros(), Vector3::new(0.0, 60.0, 0.0)),
                        false => (
                            hand_link,
                            Vector3::new(0.0, 0.0, 0.07),
                            Vector3::new(-120.0, 0.0, 0.0),
                        ),
                    };
                    phri_model::forward_kinematics(&model, &mut data, &q).unwrap();
                    phri_model::point_jacobian(&model, &data, at, &point, &mut jac).unwrap();
                    for (i, t) in total.iter_mut().enumerate() {
                        *t += (0..3).map(|a| f[a] * jac[(a, i)]).sum::<f64>();
                    }
                }
                let qdd = phri_model::forward_dynamics(&model, &mut data, &q, &qd, &total)
                    .unwrap()
                    .clone();
                for i in 0..7 {
                    qd[i] += 1e-4 * qdd[i];
                    q[i] += 1e-4 * qd[i];
                }
            }
            let stamp = k * 1_000_000;
            // the residual falls silent at 6-6.1 s (a protective stop)
            if !(6.0..6.1).contains(&t_s) {
                let out = observer.step(t_s, &q, &tau, None).unwrap();
                r.copy_from_slice(out.r);
                flags = (out.valid, out.detection.contact, out.detection.collision);
                r_stamp = stamp;
            }
            // every worker answers a frame every 33 ms, 20 ms after its capture,
            // except at 7.5-7.8 s (stale perception: slow)
            let results: Vec<RepulsionResult> = if k % 33 == 0 && !(7.5..7.8).contains(&t_s) {
                (0..workers)
                    .map(|w| worker_result(&cfg, w, stamp - 20_000_000, t_s))
                    .collect()
            } else {
                Vec::new()
            };
            state.stamp_ns = stamp;
            state.dof = 7;
            state.q[..7].copy_from_slice(&q);

            let before = allocations();
            for res in &results {
                repulsion.push(res).unwrap();
            }
            let input = ControlInput {
                state_stamp_ns: stamp,
                q: &state.q[..7],
                residual: Some(ResidualView {
                    state_stamp_ns: r_stamp,
                    r: &r,
                    valid: flags.0,
                    contact: flags.1,
                    collision: flags.2,
                }),
                perception: Some(repulsion.view()),
                collab: Default::default(),
            };
            let mut input = input;
            let asking = t_s >= 8.5 && k % 100 == 0 && collab.phase == 0;
            if t_s >= 8.5 {
                skeleton.capture_ns = stamp - 30_000_000;
                let ee = status.ee;
                let h = *hand.get_or_insert([ee[0] + 0.25, ee[1], ee[2]]);
                skeleton.people[0].joints[SkeletonJoint::RightHand as usize] = h;
                input.collab = CollabInput {
                    requests: if asking {
                        std::slice::from_ref(&request)
                    } else {
                        &[]
                    },
                    skeleton: Some(&skeleton),
                    hand: None,
                };
            }
            let mode = ctl.step(&input).mode;
            if k >= standby_from {
                let out = standby.step(&input);
                let same = out.tau == ctl.tau() && out.mode == mode;
                assert!(same || k == standby_from, "{reaction}: the standby at {k}");
                let len = ctl.save_behaviour(&mut snapshot).unwrap();
                assert!(standby.adopt_behaviour(&snapshot[..len - 1]).is_err());
                standby.adopt_behaviour(&snapshot[..len]).unwrap();
            }
            let stamps = Stamps {
                woke_ns: stamp,
                done_ns: stamp + 1,
            };
            write_messages(&ctl, &state, k, stamps, &mut cmd, &mut status);
            write_collab_state(&ctl, &state, k, stamp + 1, &mut collab);
            write_ssm_status(&ctl, &state, k, stamp + 1, &mut ssm);
            if write_barrier_status(&ctl, &state, k, stamp + 1, &mut barrier) {
                barrier_msgs += 1;
                flags_sum[0] += u64::from(barrier.braking);
                flags_sum[1] += u64::from(barrier.slack);
                flags_sum[2] += u64::from(barrier.failed);
            }
            step_allocs += allocations() - before;

            tau.copy_from_slice(&cmd.tau[..7]);
            modes.insert(mode as u32);
        }
        assert_eq!(
            step_allocs, 0,
            "{reaction}: the control period (or the standby's) allocated"
        );
        let visited: Vec<&str> = modes.iter().map(|m| ControlMode::name_of(*m)).collect();
        for m in [
            "sync",
            "task",
            "reaction",
            "protective_stop",
            "recover",
            "slow",
            "approach",
            "back_off",
        ] {
            assert!(
                visited.contains(&m),
                "{reaction}: never in {m} ({visited:?})"
            );
        }
        assert_eq!(ctl.model_errors(), 0);
        assert!(
            ctl.ssm_counters().limited_periods > 0,
            "{reaction:?}: the monitor never bounded"
        );
        assert_eq!(ctl.counters().avoidance_errors, 0);
        if cbf {
            // not vacuous: the QP ran (it runs only with barrier rows)
            let b = ctl.cbf_counters().expect("the barrier filter is the law");
            assert!(
                b.max_iterations > 0,
                "{reaction:?}: the QP never ran: {b:?}"
            );
            // every period's message, its flags adding up to the counts
            assert_eq!(barrier_msgs, 11_500);
            assert_eq!(
                flags_sum,
                [b.braking_periods, b.slack_periods, b.infeasible_periods],
                "{barrier:?}"
            );
            assert_eq!(
                (
                    barrier.periods,
                    barrier.braking_periods,
                    barrier.max_iterations
                ),
                (b.periods, b.braking_periods, b.max_iterations)
            );
        } else {
            assert_eq!(barrier_msgs, 0, "the paper's law publishes no barrier");
        }
    }
}

fn cfg_model(cfg: &Config) -> phri_model::Model {
    phri_model::Model::from_urdf_file(&cfg.robot.urdf).unwrap()
}

/// Worker `w`'s result for its points: a person far away (small repulsion,
/// turning) so that the task keeps running.
fn worker_result(cfg: &Config, w: u32, capture_ns: u64, t_s: f64) -> RepulsionResult {
    let mut r = RepulsionResult::zeroed();
    r.worker = w;
    r.workers = cfg.repulsion.workers;
    r.capture_ns = capture_ns;
    let points = cfg.repulsion.points_of(w);
    r.n_points = points.len() as u32;
    for (slot, &p) in r.points.iter_mut().zip(&points) {
        let a = 0.02 * (t_s + p as f64).sin().max(0.0);
        *slot = PointRepulsion {
            point: p as u32,
            active: u32::from(a > 0.0),
            v_call: [a, 0.5 * a, 0.0],
            min_distance: 0.8,
            position: [0.5, 0.0, 0.4],
            obstacle: [1.3, 0.0, 0.4],
        };
    }
    r
}
