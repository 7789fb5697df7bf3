//! `phri-control`: answers every `robot/state` with a `robot/command` (the only
//! publisher that channel accepts), a `control/status`, a `collab/state` and a
//! `control/ssm`;
//! reads the collaboration's `hri/request`, `perception/skeleton` and
//! `perception/hand` besides; with several cameras, every camera's
//! `perception/C/repulsion`, `perception/C/skeleton` (merged) and
//! `perception/C/hand` (`phri_ipc::best_hand`). Only channel wiring: the conversions are
//! `phri_control::inputs` and `outputs`.

use std::process::ExitCode;
use std::time::Duration;

use phri_control::cut::{CutLatest, HeldBack};
use phri_control::requests::{RequestQueueWatch, MAX_REQUESTS};
use phri_control::standby::{
    fresher_residual, inputs_fresh, save_behaviour, BehaviourInbox, Duty, RolePriority, Slot,
    Standby,
};
use phri_control::{
    write_collab_state, write_messages, write_ssm_status, CollabInput, ControlInput, Controller,
    InputGate, RepulsionInputs, Stamps,
};
use phri_ipc::{
    CollabState, ControlBehaviour, ControlStatus, HriRequest, Queue, SsmStatus, TorqueCommand,
    Zeroed, COLLAB_STATE, CONTROL_BEHAVIOUR, CONTROL_SSM, CONTROL_STANDBY_BEHAVIOUR,
    CONTROL_STATUS, DYNAMICS_RESIDUAL, DYNAMICS_RESIDUAL_STANDBY, HRI_REQUEST, ROBOT_COMMAND,
    ROBOT_COMMAND_STANDBY, ROBOT_STATE,
};

use phri_runtime::{now_ns, ServiceContext};

/// The controller's own flag.
#[derive(clap::Args, Debug)]
struct StandbyFlag {
    /// Run as the hot standby: answer on robot/command/standby, adopting the
    /// behaviour of the controller in charge every period ([control] standby)
    #[arg(long)]
    standby: bool,
}

/// What the 1 kHz loop logs, through a thread at normal priority.
enum Note {
    /// a refused input: the error and how many so far
    Refused {
        error: phri_control::InputError,
        count: u64,
    },
    /// a peer's behaviour state refused: the error and how many so far
    Behaviour {
        error: phri_control::SnapshotError,
        count: u64,
    },
}

impl std::fmt::Display for Note {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        match self {
            Note::Refused { error, count } => write!(f, "{error} ({count} inputs refused)"),
            Note::Behaviour { error, count } => write!(
                f,
                "the other controller's behaviour state refused: {error} ({count} so far)"
            ),
        }
    }
}

fn main() -> ExitCode {
    phri_runtime::service::run("phri-control", body)
}

fn body() -> Result<(), Box<dyn std::error::Error>> {
    let (ctx, StandbyFlag { standby }) = ServiceContext::from_cli(
        "phri-control",
        "control",
        "The reaction controller: answers every robot/state with the only robot/command (avoidance, detection and reaction, collaboration)",
    )?;
    let cfg = ctx.config();
    let model = ctx.robot_model()?;
    let n = model.nv();
    let mut controller = Controller::from_config(model, cfg)?;
    let slot = if standby { Slot::Standby } else { Slot::First };
    // one controller alone is always in charge
    let with_standby = cfg.control.standby || standby;
    let mut role = Standby::new(slot);
    let (command_channel, own_behaviour, peer_behaviour) = match slot {
        Slot::First => (ROBOT_COMMAND, CONTROL_BEHAVIOUR, CONTROL_STANDBY_BEHAVIOUR),
        Slot::Standby => (
            ROBOT_COMMAND_STANDBY,
            CONTROL_STANDBY_BEHAVIOUR,
            CONTROL_BEHAVIOUR,
        ),
    };
    // every camera's results, fused point by point (phri_control::inputs)
    let mut repulsion = RepulsionInputs::for_cell(cfg);
    let avoidance = cfg.control.avoidance;
    if ctx.checking() {
        return Ok(());
    }
    if phri_runtime::service::restarted() {
        // the predecessor may have left a hand on the end effector
        controller.restarted();
    }

    let node = ctx.node()?;
    let states = ROBOT_STATE.waking_subscriber(&node, Queue::Latest)?;
    let mut residuals = DYNAMICS_RESIDUAL.latest_reader(&node)?;
    // the hot standby's residual: the fresher of the two is acted on
    let mut standby_residuals = match with_standby {
        true => Some(DYNAMICS_RESIDUAL_STANDBY.latest_reader(&node)?),
        false => None,
    };
    // a second controller of this slot fails here: the command channel accepts exactly one publisher
    let commands = command_channel.publisher(&node)?;
    let behaviour_pub = own_behaviour.publisher(&node)?;
    let behaviour_sub = peer_behaviour.subscriber(&node, Queue::Drain)?;
    let mut inbox = BehaviourInbox::default();
    let mut behaviour = Box::new(ControlBehaviour::zeroed());
    let status_pub = CONTROL_STATUS.publisher(&node)?;
    let results = phri_ipc::cameras(repulsion.cameras())
        .iter()
        .map(|c| c.repulsion.subscriber(&node, Queue::Drain))
        .collect::<Result<Vec<_>, _>>()?;
    let collaborating = cfg.collaboration.enabled;
    let requests = HRI_REQUEST.subscriber(&node, Queue::Drain)?;
    // every camera's body tracker, merged (a joint either camera sees is seen)
    let mut skeletons = phri_ipc::cameras(repulsion.cameras())
        .iter()
        .map(|c| c.skeleton.latest_reader(&node))
        .collect::<Result<Vec<_>, _>>()?;
    let mut skeleton = phri_ipc::Skeleton::zeroed();
    // with a standby, the perception as of each state's publication (phri_control::cut)
    let mut held_results =
        HeldBack::with_capacity(4 * cfg.repulsion.workers.max(1) as usize * results.len());
    let mut cut_skeletons = [CutLatest::default(); phri_ipc::MAX_CAMERAS];
    let mut cut_hands = [CutLatest::default(); phri_ipc::MAX_CAMERAS];
    let skeleton_spread_ns = (cfg.control.perception_max_age_ms * 1e6) as u64;
    // every camera's refined hand; the first camera's that observes it counts (phri_ipc::best_hand)
    let mut hands = phri_ipc::cameras(repulsion.cameras())
        .iter()
        .map(|c| c.hand.latest_reader(&node))
        .collect::<Result<Vec<_>, _>>()?;
    let collab_pub = COLLAB_STATE.publisher(&node)?;
    let ssm_pub = CONTROL_SSM.publisher(&node)?;
    // only the services the supervisor started for a channel, and no stamp
    // from the future or past its bound (counted on audit/inputs)
    let gate = InputGate::new(ctx.watch_inputs(), &cfg.control, &cfg.repulsion);
    ctx.start_deadman()?;
    let mut beat = ctx.beat(&node)?;
    // refused inputs are logged by a thread at normal priority
    let log = ctx.deferred_log::<Note>();
    let mut refused = 0u64;
    let mut behaviour_refused = 0u64;
    ctx.go_realtime();
    // with the standby, the loop's priority follows the role (the lower until in charge)
    let mut rank = RolePriority::for_cell(cfg).filter(|_| with_standby && ctx.rt_priority > 0);
    if let Some(p) = rank.as_mut().and_then(|r| r.change(false)) {
        let _ = phri_runtime::rt::set_fifo_priority(p);
    }

    let (mut cmd, mut status) = (TorqueCommand::zeroed(), ControlStatus::zeroed());
    let mut collab_state = CollabState::zeroed();
    let mut ssm_status = SsmStatus::zeroed();
    let mut pending = vec![HriRequest::zeroed(); MAX_REQUESTS];
    // the requests this controller may have lost (collab/state's requests_dropped)
    let mut request_watch = RequestQueueWatch::default();
    let mut seq = 0u64;
    while !ctx.shutdown.requested() {
        // a wait ended early (a signal, a failed wake-up) is one more poll
        let _ = states.wait(Duration::from_millis(50));
        beat.beat(now_ns());
        let mut latest = None;
        states.drain_from(|pid, s| {
            if gate.state(pid) {
                latest = Some(*s);
            }
        })?;
        let Some(state) = latest else {
            continue;
        };
        let woke_ns = now_ns();
        let now = state.stamp_ns;
        // two controllers answering this state act on what was published before it
        let cut = match with_standby {
            true => state.published_ns,
            false => u64::MAX,
        };
        // the newest residual of this robot's dof; an older one stays until then
        residuals.update_from(|pid, r| r.dof as usize == n && gate.residual(pid, r, now))?;
        if let Some(s) = standby_residuals.as_mut() {
            s.update_from(|pid, r| r.dof as usize == n && gate.residual(pid, r, now))?;
        }
        let residual = fresher_residual(
            residuals.get(),
            standby_residuals.as_ref().and_then(|s| s.get()),
        );
        // refused results are counted by the accumulator (perception then turns stale)
        held_results.release(cut, |camera, r| {
            let _ = repulsion.push_camera(camera, r);
        });
        for (camera, results) in results.iter().enumerate() {
            results.drain_from(|pid, r| {
                if gate.repulsion(pid, r, now) {
                    held_results.offer(camera, r, cut, |camera, r| {
                        let _ = repulsion.push_camera(camera, r);
                    });
                }
            })?;
        }
        repulsion.fuse(now);
        let perception = avoidance.then_some(&repulsion);
        let mut input = match ControlInput::from_messages(&state, residual, perception, n) {
            Ok(input) => input,
            Err(e) => {
                refused += 1;
                if refused.is_power_of_two() {
                    log.post(Note::Refused {
                        error: e,
                        count: refused,
                    });
                }
                continue;
            }
        };
        // every pending request, stops acted on wherever they are among them
        // (phri_control's collaboration; without one, a stop all the same)
        let mono = now_ns();
        let (mut k, mut taken) = (0, 0);
        while taken < MAX_REQUESTS {
            let Some((pid, mut r)) = requests.receive_from()? else {
                break;
            };
            taken += 1;
            if gate.request(pid, &mut r, mono) {
                pending[k] = r;
                k += 1;
            }
        }
        // a request lost may have been a stop: the controller in charge stops
        // (seen as the standby, when the charge comes here within the hold)
        request_watch.read(taken, mono);
        if request_watch.stop_for_loss(!with_standby || role.in_charge(&state), mono) {
            controller.requests_lost();
        }
        input.collab.requests = &pending[..k];
        if collaborating {
            let mut views = [None; phri_ipc::MAX_CAMERAS];
            for ((v, r), c) in views
                .iter_mut()
                .zip(skeletons.iter_mut())
                .zip(&mut cut_skeletons)
            {
                r.update_from(|pid, s| gate.skeleton(pid, s, now))?;
                *v = c.take(r.get(), cut);
            }
            let seen = phri_ipc::merge_newest(&views, skeleton_spread_ns, &mut skeleton);
            let mut seen_hands = [None; phri_ipc::MAX_CAMERAS];
            for ((v, r), c) in seen_hands
                .iter_mut()
                .zip(hands.iter_mut())
                .zip(&mut cut_hands)
            {
                r.update_from(|pid, h| gate.hand(pid, h, now))?;
                *v = c.take(r.get(), cut);
            }
            let hand = phri_ipc::best_hand(&seen_hands, skeleton_spread_ns);
            input.collab = CollabInput {
                requests: &pending[..k],
                skeleton: seen.then_some(&skeleton),
                hand,
            };
        }
        // the hot standby: the behaviour the one in charge left after the state before
        if with_standby {
            behaviour_sub.drain_from(|pid, b| {
                if gate.behaviour(pid) {
                    inbox.push(b);
                }
            })?;
            let before = inbox.after_state(state.seq.saturating_sub(1));
            match role.adopt(&mut controller, &state, before) {
                // one numbering of the messages, whoever is in charge
                Ok(true) => seq = before.map_or(seq, |b| b.seq),
                Ok(false) => {}
                Err(error) => {
                    behaviour_refused += 1;
                    if behaviour_refused.is_power_of_two() {
                        log.post(Note::Behaviour {
                            error,
                            count: behaviour_refused,
                        });
                    }
                }
            }
        }
        controller.step(&input);
        seq += 1;
        let stamps = Stamps {
            woke_ns,
            done_ns: now_ns(),
        };
        let duty = match with_standby {
            true => role.duty(&state, inputs_fresh(&controller, &cfg.control)),
            false => Duty {
                in_charge: true,
                command: true,
            },
        };
        write_messages(&controller, &state, seq, stamps, &mut cmd, &mut status);
        if duty.command {
            commands.publish(&cmd)?;
        }
        if let Some(p) = rank.as_mut().and_then(|r| r.change(duty.in_charge)) {
            // refused: the priority stays (the supervisor's watch reports it)
            let _ = phri_runtime::rt::set_fifo_priority(p);
        }
        if !duty.in_charge {
            // ready to take charge: the publishers of the one in charge connected
            status_pub.update_connections();
            collab_pub.update_connections();
            ssm_pub.update_connections();
            behaviour_pub.update_connections();
            continue;
        }
        status_pub.publish(&status)?;
        write_collab_state(&controller, &state, seq, now_ns(), &mut collab_state);
        collab_state.requests_dropped = request_watch.dropped();
        collab_pub.publish(&collab_state)?;
        write_ssm_status(&controller, &state, seq, now_ns(), &mut ssm_status);
        ssm_pub.publish(&ssm_status)?;
        if with_standby
            && save_behaviour(&controller, &state, seq, now_ns(), &mut behaviour).is_ok()
        {
            behaviour_pub.publish(&behaviour)?;
        }
    }
    Ok(())
}
