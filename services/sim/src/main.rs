//! `phri-sim`: the simulated robot behind the same channels a real robot
//! adapter uses. Every 1 ms (absolute deadlines) the robot link decides on the
//! newest command, the simulator integrates the arm, and the process
//! publishes `robot/state` (positions and applied torque only) and, for
//! evaluation and the simulated camera, `sim/truth` and `sim/world`;
//! `robot/stats` at 10 Hz.
//!
//! The protocol (reuse a missing command, brake after 20, statistics) is
//! [`phri_sim::RobotLink`], the arm [`phri_sim::Simulator`], the messages
//! [`phri_sim::messages`]. This file wires them to channels and keeps the
//! real-time schedule, with two helper threads: one stamps command arrivals,
//! one saves the arm's state for a restarted simulator. With a robot outside
//! (`[robot] ip`: the hybrid cell) it publishes no `robot/state`: the
//! simulated arm follows the real one's ([`phri_sim::WorldFollower`]) and
//! the person and the camera's world are all it simulates.

use std::error::Error;
use std::path::PathBuf;
use std::process::ExitCode;
use std::sync::atomic::{AtomicU64, Ordering};
use std::sync::Arc;
use std::thread::JoinHandle;
use std::time::Duration;

use phri_ipc::liveness::Beat;
use phri_ipc::{
    CommanderStats, ContactEvent, IpcError, IpcNode, JointState, Publisher, Queue, RobotStats,
    Subscriber, TorqueCommand, Truth, WorldState, Zeroed, ROBOT_COMMAND, ROBOT_COMMANDERS,
    ROBOT_COMMAND_STANDBY, ROBOT_STATE, ROBOT_STATE_STANDBY, ROBOT_STATS, SIM_CONTACTS, SIM_TRUTH,
    SIM_WORLD,
};
use phri_runtime::log::Deferred;
use phri_runtime::{now_ns, sleep_until_ns, ServiceContext, Shutdown};
use phri_sim::link::{CommandGate, GRACE_POLL_NS};
use phri_sim::snapshot::{self, SharedArm};
use phri_sim::{
    fill_state, fill_truth, fill_world, forces_out::ForcesDatagram, ContactLog, CycleTiming,
    RobotLink, Simulator, WorldFollower,
};

/// What the 1 kHz loop has to say, posted to the log's thread.
enum LinkEvent {
    /// a run of missed commands ended
    Missed(phri_sim::MissRun),
    /// so many commands missed in a row that the brakes engaged
    Brakes { missed: u32 },
}

impl std::fmt::Display for LinkEvent {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        match self {
            LinkEvent::Missed(run) => write!(f, "{run}"),
            LinkEvent::Brakes { missed } => write!(f, "{missed} commands missing: brakes engaged"),
        }
    }
}

fn main() -> ExitCode {
    phri_runtime::service::run("phri-sim", body)
}

fn body() -> Result<(), Box<dyn Error>> {
    let (ctx, phri_runtime::cli::NoExtra {}) = ServiceContext::from_cli(
        "phri-sim",
        "sim",
        "The simulated cell: the arm at 1 kHz, the scripted person, contacts (robot/state, sim/world, sim/truth)",
    )?;
    let model = ctx.robot_model()?;
    let n = model.nv();
    let cfg = ctx.config().sim.clone();
    let period_ns = (cfg.dt_s * 1e9).round() as u64;
    let mut sim = Simulator::from_scenario(model, cfg, ctx.scenario(), None)?;
    let mut link = RobotLink::new(n, period_ns)?;
    // without a hot standby nobody is asked for a missing answer
    link.set_standby(ctx.config().control.standby);
    if ctx.checking() {
        return Ok(());
    }
    if !ctx.config().robot.ip.is_empty() {
        // the arm is outside: the person and the world only
        return serve_world(&ctx, sim, period_ns);
    }
    let snapshot_path = phri_runtime::service::run_dir().map(|d| d.join(snapshot::FILE_NAME));
    if let Some(start) = phri_runtime::service::cell_start_ns() {
        let resumed = snapshot::resume(&mut sim, start, now_ns(), snapshot_path.as_deref());
        for line in resumed.log_lines() {
            tracing::info!("{line}");
        }
    }

    serve_robot(&ctx, sim, link, period_ns, snapshot_path)
}

/// What the simulated robot publishes and the two command slots it reads.
struct RobotPorts {
    state: Publisher<JointState>,
    truth: Publisher<Truth>,
    stats: Publisher<RobotStats>,
    world: Publisher<WorldState>,
    contacts: Publisher<ContactEvent>,
    commanders: Publisher<CommanderStats>,
    /// the controller in charge's commands (slot 0)
    commands: Subscriber<TorqueCommand>,
    /// the hot standby's (slot 1): applied when the controller in charge misses
    standby: Subscriber<TorqueCommand>,
    /// the state again for the standby, when its answer is wanted
    standby_state: Publisher<JointState>,
}

impl RobotPorts {
    fn open(node: &IpcNode) -> Result<RobotPorts, IpcError> {
        Ok(RobotPorts {
            state: ROBOT_STATE.publisher(node)?,
            truth: SIM_TRUTH.publisher(node)?,
            stats: ROBOT_STATS.publisher(node)?,
            world: SIM_WORLD.publisher(node)?,
            contacts: SIM_CONTACTS.publisher(node)?,
            commands: ROBOT_COMMAND.subscriber(node, Queue::Latest)?,
            standby: ROBOT_COMMAND_STANDBY.subscriber(node, Queue::Latest)?,
            commanders: ROBOT_COMMANDERS.publisher(node)?,
            standby_state: ROBOT_STATE_STANDBY.publisher(node)?,
        })
    }
}

/// One period's outgoing messages, preallocated: the state, its truth and
/// its world, the contacts that began or ended, and the arm's positions for
/// a successor.
struct Outbox {
    state: JointState,
    truth: Truth,
    world: WorldState,
    contact_log: ContactLog,
    shared_arm: Arc<SharedArm>,
}

impl Outbox {
    /// Publish state `seq` (stamped `stamp_ns` on the robot's clock), its
    /// truth and its world; returns when the state was published \[ns\].
    fn publish(
        &mut self,
        ports: &RobotPorts,
        sim: &Simulator,
        out: &phri_sim::LinkOutput,
        seq: u64,
        stamp_ns: u64,
    ) -> Result<u64, IpcError> {
        let published = now_ns();
        fill_state(sim, out, seq, stamp_ns, published, &mut self.state);
        ports.state.publish(&self.state)?;
        self.shared_arm
            .store(&sim.truth().q, published, sim.human_time_s());
        fill_truth(sim, seq, stamp_ns, &mut self.truth);
        ports.truth.publish(&self.truth)?;
        for e in self.contact_log.step(stamp_ns, &sim.truth().contacts) {
            ports.contacts.publish(e)?;
        }
        fill_world(sim, seq, stamp_ns, &mut self.world);
        ports.world.publish(&self.world)?;
        Ok(published)
    }
}

/// The simulated robot behind `robot/state`: its ports, its helper threads
/// (command arrivals, the successor's snapshot), then [`robot_loop`] under
/// real-time scheduling until shutdown, then the last statistics.
fn serve_robot(
    ctx: &ServiceContext,
    mut sim: Simulator,
    mut link: RobotLink,
    period_ns: u64,
    snapshot_path: Option<PathBuf>,
) -> Result<(), Box<dyn Error>> {
    let node = ctx.node()?;
    let ports = RobotPorts::open(&node)?;
    // commands only from the controllers the supervisor started (every
    // sender without a supervisor); the owners follow supervisor/health
    link.set_gate(CommandGate::new(ctx.watch_inputs()));
    // the arm's positions for a successor, saved by a thread at normal
    // priority (started before this one turns real-time)
    let shared_arm = Arc::new(SharedArm::new(sim.model().nv()));
    let saver_thread =
        snapshot_path.map(|path| spawn_saver(path, Arc::clone(&shared_arm), ctx.shutdown.clone()));
    ctx.start_deadman()?;
    let mut beat = ctx.beat(&node)?;
    // the 1 kHz loop's events are logged by a thread at normal priority
    let log = ctx.deferred_log::<LinkEvent>();
    ctx.go_realtime();
    // notes when command events arrive, so that latency is measured at
    // receipt, not at the next tick
    let last_command_event = Arc::new(AtomicU64::new(0));
    let listener_thread = spawn_listener(ctx, Arc::clone(&last_command_event));
    let mut outbox = Outbox {
        state: JointState::zeroed(),
        truth: Truth::zeroed(),
        world: WorldState::zeroed(),
        contact_log: ContactLog::new(),
        shared_arm,
    };
    let result = robot_loop(
        ctx,
        (&mut sim, &mut link),
        (&ports, &mut outbox),
        &mut beat,
        &log,
        &last_command_event,
        period_ns,
    );
    for e in outbox.contact_log.finish() {
        let _ = ports.contacts.publish(e);
    }
    // last word on the statistics
    let _ = ports.stats.publish(link.stats_message(now_ns()));
    let _ = ports.commanders.publish(link.commanders_message(now_ns()));
    ctx.shutdown.request();
    let _ = listener_thread.join();
    if let Some(t) = saver_thread {
        let _ = t.join();
    }
    if let Some(run) = link.finish() {
        tracing::warn!("{run}");
    }
    result
}

/// The 1 kHz loop until shutdown: wait for the tick (absolute deadlines),
/// take the newest command of either slot (with a grace when the machine
/// stalled this process), step the arm, publish.
fn robot_loop(
    ctx: &ServiceContext,
    (sim, link): (&mut Simulator, &mut RobotLink),
    (ports, outbox): (&RobotPorts, &mut Outbox),
    beat: &mut Beat,
    log: &Deferred<LinkEvent>,
    last_command_event: &AtomicU64,
    period_ns: u64,
) -> Result<(), Box<dyn Error>> {
    // the initial state: the arm at rest, brakes on
    let mut seq = 1u64;
    let first = *link.output();
    sim.step(first.torque(), first.brake);
    let mut tick = now_ns();
    let epoch = tick;
    let mut state_published_ns = outbox.publish(ports, sim, &first, seq, epoch)?;
    let slots = [&ports.commands, &ports.standby];
    while !ctx.shutdown.requested() {
        tick += period_ns;
        sleep_until_ns(tick);
        beat.beat(now_ns());
        let wake = link.wake(tick, now_ns());
        tick = wake.deadline_ns;
        let mut newest = [None, None];
        link.poll(slots, &mut newest, seq)?;
        // the machine stalled us and maybe the controller too (in simulated
        // time the cycle is not over yet), or the one in charge has not
        // answered and the resting standby is asked
        let grace = link.grace(&wake, &newest, seq, now_ns());
        if grace.standby_asked {
            ports.standby_state.publish(&outbox.state)?;
        }
        if let Some(until) = grace.until_ns {
            while now_ns() < until {
                sleep_until_ns(now_ns() + GRACE_POLL_NS);
                if link.poll(slots, &mut newest, seq)? {
                    break;
                }
            }
        }
        let timing = CycleTiming {
            state_published_ns,
            command_event_ns: last_command_event.load(Ordering::Acquire),
            now_ns: now_ns(),
            behind_schedule_ns: wake.behind_schedule_ns(),
            standby_asked: grace.standby_asked,
        };
        let out = link.cycle_slots(newest.each_ref().map(Option::as_ref), seq, &timing);
        if let Some(run) = out.miss_run {
            log.post(LinkEvent::Missed(run));
        }
        if out.brake_engaged {
            log.post(LinkEvent::Brakes { missed: out.missed });
        }
        sim.step(out.torque(), out.brake);
        seq += 1;
        state_published_ns =
            outbox.publish(ports, sim, &out, seq, link.state_stamp_ns(epoch, seq))?;
        if out.in_charge == 1 {
            // the standby in charge is woken by every state
            ports.standby_state.publish(&outbox.state)?;
        }
        if out.publish_stats {
            ports.stats.publish(link.stats_message(now_ns()))?;
        }
        if out.publish_stats || out.takeover || out.refused {
            ports
                .commanders
                .publish(link.commanders_message(now_ns()))?;
        }
    }
    Ok(())
}

/// The hybrid cell: the arm behind `robot/state` is a robot outside; every
/// period the simulated arm follows its newest state and the person moves,
/// and `sim/truth`, `sim/world` and `sim/contacts` go out stamped with that
/// state. Nothing is published on `robot/state`.
fn serve_world(
    ctx: &ServiceContext,
    mut sim: Simulator,
    period_ns: u64,
) -> Result<(), Box<dyn Error>> {
    let node = ctx.node()?;
    let truth_pub = SIM_TRUTH.publisher(&node)?;
    let world_pub = SIM_WORLD.publisher(&node)?;
    let contacts_pub = SIM_CONTACTS.publisher(&node)?;
    let states = ROBOT_STATE.subscriber(&node, Queue::Latest)?;
    let mut follower = WorldFollower::new(&sim.truth().q);
    let mut contact_log = ContactLog::new();
    let (mut truth, mut world) = (Truth::zeroed(), WorldState::zeroed());
    // the person's contact forces, to an outside arm that is itself simulated
    let forces_to = &ctx.config().sim.forces_to;
    let forces_socket = if forces_to.is_empty() {
        None
    } else {
        let socket = std::net::UdpSocket::bind("0.0.0.0:0")
            .and_then(|s| s.connect(forces_to.as_str()).map(|()| s))
            .and_then(|s| s.set_nonblocking(true).map(|()| s))
            .map_err(|e| format!("sim.forces_to {forces_to}: {e}"))?;
        tracing::info!("the person's contact forces go to {forces_to} (sim.forces_to)");
        Some(socket)
    };
    let mut datagram = ForcesDatagram::default();
    let mut forces_unsent = 0u64;
    ctx.start_deadman()?;
    let mut beat = ctx.beat(&node)?;
    ctx.go_realtime();
    tracing::info!(
        "following the arm on robot/state (robot.ip set): simulating the person and the world only"
    );
    let mut newest: Option<JointState> = None;
    let (mut tick, mut seq) = (now_ns(), 0u64);
    let mut run = || -> Result<(), Box<dyn Error>> {
        while !ctx.shutdown.requested() {
            tick += period_ns;
            sleep_until_ns(tick);
            beat.beat(now_ns());
            if let Some(s) = states.latest()? {
                newest = Some(s);
            }
            follower.step(&mut sim, newest.as_ref());
            seq += 1;
            // the robot's clock when there is a state, else ours
            let stamp = follower.last().map_or(now_ns(), |(_, t)| t);
            fill_truth(&sim, seq, stamp, &mut truth);
            // the arm's truth is the robot's state it follows
            truth.state_seq = follower.last().map_or(0, |(s, _)| s);
            truth_pub.publish(&truth)?;
            for e in contact_log.step(stamp, &sim.truth().contacts) {
                contacts_pub.publish(e)?;
            }
            if let Some(socket) = &forces_socket {
                if let Some(bytes) = datagram.encode(sim.model(), &sim.truth().contacts) {
                    // a receiver not (yet) listening loses these forces, never the period
                    if socket.send(bytes).is_err() {
                        forces_unsent += 1;
                    }
                }
            }
            fill_world(&sim, seq, stamp, &mut world);
            world_pub.publish(&world)?;
        }
        Ok(())
    };
    let result = run();
    if forces_unsent > 0 {
        tracing::warn!(
            "{forces_unsent} datagrams of contact forces not sent to {forces_to} (sim.forces_to)"
        );
    }
    for e in contact_log.finish() {
        let _ = contacts_pub.publish(e);
    }
    if follower.refused() > 0 {
        tracing::warn!(
            "{} states on robot/state refused (a joint count other than the model's)",
            follower.refused()
        );
    }
    result
}

/// Stamp the arrival of every command event into `stamp` [ns] until shutdown.
fn spawn_listener(ctx: &ServiceContext, stamp: Arc<AtomicU64>) -> JoinHandle<Result<(), IpcError>> {
    let shutdown = ctx.shutdown.clone();
    let (name, prefix) = (format!("{}-listener", ctx.name), ctx.prefix.clone());
    std::thread::spawn(move || {
        let node = phri_ipc::node(&name, &prefix)?;
        let events = ROBOT_COMMAND.listener(&node)?;
        while !shutdown.requested() {
            let _ = events.wait_each(Duration::from_millis(50), || {
                stamp.store(now_ns(), Ordering::Release)
            });
        }
        Ok(())
    })
}

/// Save the arm's positions to `path` every [`snapshot::SAVE_PERIOD`] until
/// shutdown (a failure is reported once).
fn spawn_saver(path: PathBuf, arm: Arc<SharedArm>, shutdown: Shutdown) -> JoinHandle<()> {
    std::thread::spawn(move || {
        let mut reported = false;
        let mut writer = snapshot::SnapshotWriter::new(path);
        while !shutdown.requested() {
            std::thread::sleep(snapshot::SAVE_PERIOD);
            if let Some(s) = arm.load() {
                if let Err(e) = writer.save(&s) {
                    if !reported {
                        tracing::warn!("cannot save the arm's state: {e}");
                        reported = true;
                    }
                }
            }
        }
    })
}
