//! `phri-control`: answers every `robot/state` with a `robot/command` (the only
//! publisher that channel accepts), a `control/status`, a `collab/state`, a
//! `control/ssm` and, under the barrier filter, a `control/barrier`;
//! reads the collaboration's `hri/request`, `perception/skeleton` and
//! `perception/hand` besides; with several cameras, every camera's
//! `perception/C/repulsion`, `perception/C/skeleton` (merged) and
//! `perception/C/hand` (`phri_ipc::best_hand`). Only wiring: the channels,
//! the period and its messages are `phri_control::service`, the conversions
//! `phri_control::inputs` and `outputs`.

use std::process::ExitCode;

use phri_control::service::{self, ControlService, Note};
use phri_control::standby::{RolePriority, Slot};
use phri_control::{Controller, InputGate, RepulsionInputs};
use phri_runtime::{now_ns, ServiceContext};

/// The controller's own flag.
#[derive(clap::Args, Debug)]
struct StandbyFlag {
    /// Run as the hot standby: answer on robot/command/standby, adopting the
    /// behaviour of the controller in charge every period ([control] standby)
    #[arg(long)]
    standby: bool,
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
    let mut controller = Controller::from_config(ctx.robot_model()?, cfg)?;
    let slot = if standby { Slot::Standby } else { Slot::First };
    // one controller alone is always in charge
    let with_standby = cfg.control.standby || standby;
    // every camera's results, fused point by point (phri_control::inputs)
    let repulsion = RepulsionInputs::for_cell(cfg);
    if ctx.checking() {
        return Ok(());
    }
    if phri_runtime::service::restarted() {
        // the predecessor may have left a hand on the end effector
        controller.restarted();
    }

    let node = ctx.node()?;
    let (mut inputs, outputs) = service::open(
        &node,
        slot,
        with_standby,
        repulsion.cameras(),
        cfg.control.standby_wake_ms,
    )?;
    // with the standby, the loop's priority follows the role (the lower until in charge)
    let rank = RolePriority::for_cell(cfg).filter(|_| with_standby && ctx.rt_priority > 0);
    let mut service = ControlService::new(controller, cfg, repulsion, slot, with_standby, rank);
    // only the services the supervisor started for a channel, and no stamp
    // from the future or past its bound (counted on audit/inputs)
    let gate = InputGate::new(ctx.watch_inputs(), &cfg.control, &cfg.repulsion);
    ctx.start_deadman()?;
    let mut beat = ctx.beat(&node)?;
    // refused inputs are logged by a thread at normal priority
    let log = ctx.deferred_log::<Note>();
    ctx.go_realtime();
    if let Some(p) = service.start_priority() {
        let _ = phri_runtime::rt::set_fifo_priority(p);
    }

    while !ctx.shutdown.requested() {
        // every state, or the resting standby's clock and the robot's call
        inputs.wait(&gate);
        beat.beat(now_ns());
        let Some(state) = inputs.latest_state(&gate)? else {
            continue;
        };
        let woke_ns = now_ns();
        service.period(&mut inputs, &outputs, &gate, &state, woke_ns, &log)?;
    }
    Ok(())
}
