//! `phri-franka`: a Franka arm over the Franka Control Interface behind
//! `robot/state` and `robot/command`, as `phri-sim` serves them. Per state
//! of the control box (1 kHz): publish `robot/state`, wait for the command
//! answering it, send it less gravity ([`phri_franka::FciCycle`]). Under the
//! protocol's brakes (more than 20 commands missing) the torque control
//! ends (the box stops the arm by its own rule) and the adapter goes on
//! publishing the arm's states; the first command that answers one starts
//! torque control again, from zero torque. Only channel wiring and the FCI
//! session live here.
//!
//! It takes states only from its box: its FCI client (franka-rs, patched:
//! `patches/franka-rs/PATCH.md`) drops datagrams of any other sender, of the
//! wrong size, or with a stale or far-ahead message id; a state whose joints
//! are not finite or moved faster than their velocity limits allow
//! ([`phri_franka::StateGuard`]) is not published and gets the last torque
//! again. Everything refused is counted on `robot/box`. The start-up
//! (connect, handshake, first state, robot model) has a deadline.

use std::error::Error;
use std::process::ExitCode;
use std::time::Duration;

use phri_franka::{
    fill_state, first_difference, BoxError, BoxLog, BoxTorques, FciCycle, FciError, Refused,
    StateGuard, JOINTS,
};
use phri_ipc::{
    BoxStatus, JointState, Publisher, Queue, TorqueCommand, Zeroed, ROBOT_BOX, ROBOT_COMMAND,
    ROBOT_COMMANDERS, ROBOT_COMMAND_STANDBY, ROBOT_STATE, ROBOT_STATE_STANDBY, ROBOT_STATS,
};
use phri_robot::{CommandGate, CycleTiming, LinkOutput, GRACE_POLL_NS, MAX_MISSED};
use phri_runtime::{now_ns, sleep_until_ns, ServiceContext};

/// The adapter's own flag.
#[derive(clap::Args, Debug)]
struct RobotAddress {
    /// The control box's address (FCI), optionally with the command port:
    /// `172.16.0.2`, or `127.0.0.1:1337` for franka-sim [default: the
    /// configuration's `robot.ip`]
    #[arg(long, value_name = "ADDRESS")]
    robot_ip: Option<String>,
}

/// How long after publishing a state the adapter waits for its command [ns]
/// (the box wants one every millisecond).
const ANSWER_BUDGET_NS: u64 = 700_000;

/// The start-up's deadline: connect, the FCI handshake, the first state and
/// the robot model \[s\] (a box that accepts and never answers ends here).
const START_DEADLINE_S: f64 = 5.0;

/// The box's period \[s\] (FCI: one state per millisecond).
const FCI_PERIOD_S: f64 = 1e-3;

/// Connect to the box at `address` and fetch its URDF (FCI v10; v5 serves
/// none), within [`START_DEADLINE_S`]. The FCI client's own timeouts end
/// most failures earlier; this one also covers a box that goes silent
/// after the handshake. The connecting thread is left behind on a timeout
/// (the process then exits).
fn connect(address: &str) -> Result<(franka::Robot, Option<String>), FciError> {
    let (tx, rx) = std::sync::mpsc::channel();
    let a = address.to_owned();
    std::thread::Builder::new()
        .name("fci-connect".into())
        .spawn(move || {
            // phri keeps its own real-time discipline (go_realtime)
            let result = franka::Robot::new(&a, franka::RealtimeConfig::Ignore)
                .map_err(|e| FciError::from_franka(&a, "connect", e))
                .and_then(|robot| {
                    let urdf = match robot.server_version() >= 10 {
                        true => Some(
                            robot
                                .robot_model()
                                .map_err(|e| FciError::from_franka(&a, "GetRobotModel", e))?,
                        ),
                        false => None,
                    };
                    Ok((robot, urdf))
                });
            let _ = tx.send(result);
        })
        .map_err(|_| FciError::StartDeadline {
            address: address.to_owned(),
            seconds: 0.0,
        })?;
    rx.recv_timeout(Duration::from_secs_f64(START_DEADLINE_S))
        .map_err(|_| FciError::StartDeadline {
            address: address.to_owned(),
            seconds: START_DEADLINE_S,
        })?
}

/// The states the adapter acts on ([`StateGuard`]) and what it and the FCI
/// client refused.
struct Gate<'a> {
    robot: &'a franka::Robot,
    guard: StateGuard,
}

impl Gate<'_> {
    /// Is state `s` one to act on (counted when not)?
    fn take(&mut self, s: &franka::RobotState) -> bool {
        self.guard.check(&s.q, &s.dq, s.time.as_millis()).is_ok()
    }

    /// Everything refused so far.
    fn refused(&self) -> Refused {
        let d = self.robot.refused_datagrams();
        Refused {
            foreign: d.foreign,
            malformed: d.malformed,
            stale_id: d.stale_id,
            id_ahead: d.id_ahead,
            non_finite: self.guard.non_finite,
            too_fast: self.guard.too_fast,
        }
    }
}

/// Why torque control ended other than by the protocol's brakes.
enum Served {
    /// the control box aborted the motion (a reflex, a limit, lost commands)
    Box(franka::ControlException),
    /// the connection, the channels: the process ends (the supervisor restarts it)
    Fatal(Box<dyn Error>),
}

impl From<franka::FrankaError> for Served {
    fn from(e: franka::FrankaError) -> Self {
        match e {
            franka::FrankaError::Control(c) => Served::Box(c),
            other => Served::Fatal(other.into()),
        }
    }
}

impl From<Box<dyn Error>> for Served {
    fn from(e: Box<dyn Error>) -> Self {
        Served::Fatal(e)
    }
}

/// One period of the adapter: the state published, its answer awaited and decided.
type Period<'a> = dyn FnMut(
        &[f64; JOINTS],
        u64,
        &mut FciCycle,
    ) -> Result<(LinkOutput, phri_franka::FciTorque), Box<dyn Error>>
    + 'a;

/// `robot/box`: the box's figures, published every [`BoxLog::EVERY`] states
/// and at every error.
struct BoxChannel {
    log: BoxLog,
    publisher: Publisher<BoxStatus>,
}

impl BoxChannel {
    /// A state the adapter took (`refused`: everything refused so far).
    fn state(
        &mut self,
        controlled: bool,
        s: &franka::RobotState,
        refused: &Refused,
    ) -> Result<(), Box<dyn Error>> {
        let torques = BoxTorques {
            tau_j: s.tau_J,
            tau_ext_hat: s.tau_ext_hat_filtered,
        };
        if self
            .log
            .on_state(controlled, s.control_command_success_rate, &torques)
        {
            self.log.set_refused(refused);
            self.publisher.publish(self.log.message(now_ns()))?;
        }
        Ok(())
    }

    /// Publish now, with everything refused so far.
    fn publish(&mut self, refused: &Refused) -> Result<(), Box<dyn Error>> {
        self.log.set_refused(refused);
        self.publisher.publish(self.log.message(now_ns()))?;
        Ok(())
    }

    fn error(&mut self, e: &BoxError) -> Result<(), Box<dyn Error>> {
        self.log.on_error(now_ns(), e);
        self.publisher.publish(self.log.message(now_ns()))?;
        Ok(())
    }
}

/// Torque control until the protocol brakes, then the arm's states until a
/// command answers one (or shutdown).
fn serve(
    robot: &franka::Robot,
    cycle: &mut FciCycle,
    period: &mut Period<'_>,
    boxed: &mut BoxChannel,
    gate: &mut Gate<'_>,
    shutdown: &phri_runtime::Shutdown,
) -> Result<(), Served> {
    cycle.restart();
    let mut control = robot.start_torque_control()?;
    // refused states in a row: past the protocol's brakes, the torque
    // control ends as it would without commands
    let mut refused_run = 0u32;
    loop {
        let (s, _) = control.read_once()?;
        if !gate.take(&s) {
            refused_run += 1;
            let held = franka::Torques::new(cycle.held());
            if refused_run > MAX_MISSED || shutdown.requested() {
                control.write_once(&franka::motion_finished(held))?;
                break;
            }
            control.write_once(&held)?;
            continue;
        }
        refused_run = 0;
        boxed.state(true, &s, &gate.refused())?;
        let (_, out) = period(&s.q, s.time.as_millis(), cycle)?;
        if out.brake || shutdown.requested() {
            control.write_once(&franka::motion_finished(franka::Torques::new(out.tau)))?;
            break;
        }
        control.write_once(&franka::Torques::new(out.tau))?;
    }
    drop(control);
    // braked: the arm's states go on; a fresh answer resumes control
    while !shutdown.requested() {
        let s = robot.read_once()?;
        if !gate.take(&s) {
            continue;
        }
        boxed.state(false, &s, &gate.refused())?;
        let (link, _) = period(&s.q, s.time.as_millis(), cycle)?;
        if !link.brake {
            break;
        }
    }
    Ok(())
}

/// The control box's address: `--robot-ip`, else the configuration's
/// `robot.ip`; neither, or an empty flag, is an error naming them.
fn address(ctx: &ServiceContext, robot_ip: Option<String>) -> Result<String, Box<dyn Error>> {
    Ok(match robot_ip {
        Some(ip) if ip.trim().is_empty() => return Err(FciError::EmptyAddress.into()),
        Some(ip) => ip,
        None => Some(ctx.config().robot.ip.clone())
            .filter(|ip| !ip.is_empty())
            .ok_or(
                "--robot-ip: the control box's address is required (or robot.ip in the configuration)",
            )?,
    })
}

/// [`connect`] to the box at `address`, then compare the arm it serves with
/// the configured model of `cycle` (FCI v10, the FR3, serves its URDF; v5,
/// the Panda/FER, none: then the configuration is taken unchecked).
fn connect_checked(
    ctx: &ServiceContext,
    address: &str,
    cycle: &FciCycle,
) -> Result<franka::Robot, Box<dyn Error>> {
    let (robot, urdf) = connect(address)?;
    if let Some(urdf) = urdf {
        // the arm's joints to lock may be missing from another arm's URDF:
        // then the comparison below names the difference
        let served =
            phri_model::Model::from_urdf_str_locked(&urdf, &ctx.config().robot.locked_joints)
                .or_else(|_| phri_model::Model::from_urdf_str(&urdf))
                .map_err(|e| format!("{address}: the robot's URDF: {e}"))?;
        if let Some(d) = first_difference(cycle.model(), &served) {
            return Err(format!("robot.urdf is not the arm at {address}: {d}").into());
        }
    } else {
        tracing::warn!(
            "{address}: FCI v{} serves no URDF: robot.urdf is taken as the arm's, unchecked",
            robot.server_version()
        );
    }
    Ok(robot)
}

/// The box ended the motion with `e` (a reflex, a joint limit, commands
/// lost): said on `robot/box`, then the box's own error recovery, after
/// which torque control may start again; a recovery that failed ends the
/// adapter (its error names the box at `address`).
fn recover(
    robot: &franka::Robot,
    e: &franka::ControlException,
    boxed: &mut BoxChannel,
    gate: &Gate<'_>,
    address: &str,
) -> Result<(), Box<dyn Error>> {
    let error = BoxError::new(&e.last_motion_errors.names(), &e.message);
    boxed.error(&error)?;
    tracing::warn!("{error}; automatic error recovery");
    if let Err(e) = robot.automatic_error_recovery() {
        let _ = boxed.publish(&gate.refused());
        return Err(FciError::from_franka(address, "automatic error recovery", e).into());
    }
    boxed.log.on_recovery();
    Ok(())
}

fn main() -> ExitCode {
    phri_runtime::service::run("phri-franka", body)
}

fn body() -> Result<(), Box<dyn Error>> {
    let (ctx, RobotAddress { robot_ip }) = ServiceContext::from_cli(
        "phri-franka",
        "robot",
        "A Franka arm over FCI behind robot/state and robot/command (torques sent without gravity: the box adds it)",
    )?;
    let address = address(&ctx, robot_ip)?;
    let model = ctx.robot_model()?;
    let guard = StateGuard::for_model(&model, FCI_PERIOD_S);
    // 7 joints, a positive period: refused here, before any connection
    let mut cycle = FciCycle::new(model, FCI_PERIOD_S)?;
    if ctx.checking() {
        return Ok(());
    }
    let robot = connect_checked(&ctx, &address, &cycle)?;

    let node = ctx.node()?;
    let state_pub = ROBOT_STATE.publisher(&node)?;
    // the box leaves no grace to wake the standby in: it gets every state
    let standby_state_pub = ROBOT_STATE_STANDBY.publisher(&node)?;
    let stats_pub = ROBOT_STATS.publisher(&node)?;
    let commands = ROBOT_COMMAND.subscriber(&node, Queue::Latest)?;
    // the hot standby's (slot 1): applied when the controller in charge misses
    let standby = ROBOT_COMMAND_STANDBY.subscriber(&node, Queue::Latest)?;
    let commanders_pub = ROBOT_COMMANDERS.publisher(&node)?;
    // commands only from the controllers the supervisor started (every
    // sender without a supervisor); the owners follow supervisor/health
    cycle.set_gate(CommandGate::new(ctx.watch_inputs()));
    let mut gate = Gate {
        robot: &robot,
        guard,
    };
    let mut boxed = BoxChannel {
        log: BoxLog::default(),
        publisher: ROBOT_BOX.publisher(&node)?,
    };
    ctx.start_deadman()?;
    let mut beat = ctx.beat(&node)?;
    ctx.go_realtime();

    let mut state = JointState::zeroed();
    let mut seq = 0u64;
    let mut clock: Option<(u64, u64)> = None;
    // one state: publish it, wait for its answer, decide
    let mut period = |q: &[f64; JOINTS],
                      box_ms: u64,
                      cycle: &mut FciCycle|
     -> Result<(LinkOutput, phri_franka::FciTorque), Box<dyn Error>> {
        seq += 1;
        beat.beat(now_ns());
        // the robot's clock, on this machine's: the box's milliseconds from the first state
        let (epoch, ms0) = *clock.get_or_insert((now_ns(), box_ms));
        let stamp = epoch + box_ms.saturating_sub(ms0) * 1_000_000;
        let published = now_ns();
        let applied = cycle.applied(q)?;
        fill_state(
            q,
            &applied,
            cycle.link().output(),
            seq,
            stamp,
            published,
            &mut state,
        );
        state_pub.publish(&state)?;
        standby_state_pub.publish(&state)?;
        let mut newest: [Option<TorqueCommand>; 2] = [None, None];
        while !cycle.poll([&commands, &standby], &mut newest, seq)?
            && now_ns() < published + ANSWER_BUDGET_NS
        {
            sleep_until_ns(now_ns() + GRACE_POLL_NS);
        }
        let timing = CycleTiming {
            state_published_ns: published,
            command_event_ns: 0,
            now_ns: now_ns(),
            behind_schedule_ns: 0,
            standby_asked: false,
        };
        let decided = cycle.step_slots(newest.each_ref().map(Option::as_ref), seq, &timing, q)?;
        if decided.0.publish_stats {
            stats_pub.publish(cycle.stats_message(now_ns()))?;
        }
        if decided.0.publish_stats || decided.0.takeover || decided.0.refused {
            commanders_pub.publish(cycle.commanders_message(now_ns()))?;
        }
        Ok(decided)
    };

    while !ctx.shutdown.requested() {
        match serve(
            &robot,
            &mut cycle,
            &mut period,
            &mut boxed,
            &mut gate,
            &ctx.shutdown,
        ) {
            Ok(()) => {}
            // the box ended the motion (a reflex, a joint limit, commands
            // lost): its own error recovery, then torque control again
            Err(Served::Box(e)) => recover(&robot, &e, &mut boxed, &gate, &address)?,
            Err(Served::Fatal(e)) => {
                // the FCI client's errors named by what happened at the box
                let e = match e.downcast::<franka::FrankaError>() {
                    Ok(f) => Box::new(FciError::from_franka(&address, "FCI", *f)) as Box<dyn Error>,
                    Err(e) => e,
                };
                // the last word on what was refused, then the one line
                let _ = boxed.publish(&gate.refused());
                let _ = commanders_pub.publish(cycle.commanders_message(now_ns()));
                return Err(e);
            }
        }
    }
    let _ = stats_pub.publish(cycle.stats_message(now_ns()));
    let _ = commanders_pub.publish(cycle.commanders_message(now_ns()));
    let _ = boxed.publish(&gate.refused());
    Ok(())
}
