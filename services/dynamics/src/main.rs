//! `phri-dynamics`: wakes on `robot/state`, steps [`DynamicsStep`] over every
//! queued state and publishes the last residual on `dynamics/residual`
//! (`--standby`: on `dynamics/residual/standby`, the hot standby's; the
//! controller takes the fresher of the two).

use std::error::Error;
use std::process::ExitCode;

use phri_dynamics::{DynamicsStep, Wake};
use phri_ipc::{
    Queue, DYNAMICS_RESIDUAL, DYNAMICS_RESIDUAL_CALL, DYNAMICS_RESIDUAL_STANDBY, ROBOT_STATE,
};
use phri_runtime::{now_ns, ServiceContext};

/// A refused `robot/state` sample, for the log: the error and how many so far.
struct BadSample {
    error: phri_dynamics::DynamicsError,
    count: u64,
}

impl std::fmt::Display for BadSample {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        write!(
            f,
            "{}: {} ({} bad samples)",
            ROBOT_STATE.name, self.error, self.count
        )
    }
}

/// The service's own flag.
#[derive(clap::Args, Debug)]
struct StandbyFlag {
    /// Run as the hot standby: publish on dynamics/residual/standby ([control] standby)
    #[arg(long)]
    standby: bool,
}

fn main() -> ExitCode {
    phri_runtime::service::run("phri-dynamics", body)
}

fn body() -> Result<(), Box<dyn Error>> {
    let (ctx, StandbyFlag { standby }) = ServiceContext::from_cli(
        "phri-dynamics",
        "dynamics",
        "The momentum residual of robot/state (collision detection, eqs. 4-8) on dynamics/residual",
    )?;
    let mut step = DynamicsStep::new(ctx.robot_model()?, &ctx.config().dynamics)?;
    if ctx.checking() {
        return Ok(());
    }
    let node = ctx.node()?;
    // the hot standby wakes on its own clock ([dynamics] standby_wake_ms)
    // and when the controller in charge calls it, the one in charge at
    // every state
    let wait = Wake::of(standby, ctx.config().dynamics.standby_wake_ms);
    let (states, calls) = match wait {
        Wake::EveryState(_) => (ROBOT_STATE.waking_subscriber(&node, Queue::Drain)?, None),
        Wake::Every(_) => (
            ROBOT_STATE.subscriber(&node, Queue::Drain)?,
            Some(DYNAMICS_RESIDUAL_CALL.waking_subscriber(&node, Queue::Latest)?),
        ),
    };
    let channel = match standby {
        false => DYNAMICS_RESIDUAL,
        true => DYNAMICS_RESIDUAL_STANDBY,
    };
    let residuals = channel.publisher(&node)?;
    // states only from the robot the supervisor started (counted on audit/inputs)
    let owners = ctx.watch_inputs();
    ctx.start_deadman()?;
    let mut beat = ctx.beat(&node)?;
    // bad samples are logged by a thread at normal priority
    let log = ctx.deferred_log::<BadSample>();
    ctx.go_realtime();

    let mut bad_samples = 0u64;
    while !ctx.shutdown.requested() {
        // a wake-up without a sample (timeout, signal) just loops; a
        // channel read without waking sleeps the whole timeout
        match &calls {
            Some(calls) => {
                let _ = calls.wait(wait.timeout());
                // a call only wakes: the states are robot/state's
                calls.drain_from(|pid, _| {
                    owners.admit(phri_ipc::Owned::CONTROL_BEHAVIOUR, pid);
                })?;
            }
            None => {
                let _ = states.wait(wait.timeout());
            }
        }
        beat.beat(now_ns());
        let mut fresh = None;
        states.drain_from(|pid, s| {
            if !owners.admit(phri_ipc::Owned::ROBOT_STATE, pid).accepted() {
                return;
            }
            let t0 = now_ns();
            match step.step(s) {
                Ok(_) => fresh = Some(now_ns() - t0),
                Err(e) => {
                    bad_samples += 1;
                    if bad_samples.is_power_of_two() {
                        log.post(BadSample {
                            error: e,
                            count: bad_samples,
                        });
                    }
                }
            }
        })?;
        if let Some(compute_ns) = fresh {
            residuals.publish(step.seal(now_ns(), compute_ns))?;
        }
    }
    Ok(())
}
