//! The supervisor as a state machine: events in (a service started, beat,
//! missed its deadline, ended; the clock ticked; a CPU sample, a publisher,
//! a real-time observation arrived; an operator resumed; a signal), actions
//! out (start, kill, restart, write the state, publish the health, log,
//! record in the report). Pure and deterministic: the clock comes in with
//! every event, no process or channel is touched; `crate::run` performs
//! the actions and tells the machine what came of them.
//!
//! Two sequences span several steps: the start-up (each service started in
//! order, its delay waited, an early exit looked for) and a round of the
//! supervision loop (read the channels; judge a stall; gather CPU samples,
//! publishers, real-time observations and exits; kill the frozen and
//! restart what is due; write the state and publish the health). The
//! caller performs a step's actions, in order, then steps [`Event::Done`]
//! while [`Supervision::awaits`].

mod event;
mod exits;
mod frozen;
mod round;
mod startup;
#[cfg(test)]
mod tests;
mod watch;

pub use event::{Action, Ending, Event};

use phri_config::{ServiceSpec, SupervisorConfig};

use crate::cpu::CpuUse;
use crate::realtime::{RealtimeWatch, Wanted};
use crate::roster::Roster;

/// Period of the supervision loop \[ns\].
pub const TICK_NS: u64 = 10_000_000;
/// Period of the watch over who publishes on `robot/command` \[ns\].
pub const WATCH_NS: u64 = 50_000_000;
/// Period of the samples of the services' CPU time \[ns\].
pub const CPU_SAMPLE_NS: u64 = 20_000_000;
/// How long health goes out every tick after a (re)start \[ns\].
pub const FAST_HEALTH_NS: u64 = 1_000_000_000;
/// A due restart waits at most this long for the removal of dead processes'
/// iceoryx2 resources ([`Event::Cleaning`]) \[ns\]: a disk that holds it
/// longer delays no restart past this.
pub const CLEANUP_WAIT_NS: u64 = 5_000_000_000;

/// A supervision loop later than this was a stall of the supervisor itself \[ns\].
pub const STALL_NS: u64 = 100_000_000;
/// A service's real-time process is judged no earlier than this after its
/// (re)start: it opens its ports before it asks for SCHED_FIFO \[ns\].
pub const RT_SETTLE_NS: u64 = 200_000_000;

/// What a supervision is made of.
#[derive(Clone, Debug)]
pub struct Setup {
    /// `[supervisor]`
    pub sup: SupervisorConfig,
    /// the services, in start order
    pub services: Vec<(String, ServiceSpec)>,
    /// per service (same order): the real-time scheduling it is judged
    /// against ([`crate::realtime::role_ranked`])
    pub wanted: Vec<Wanted>,
    /// the real-time watch after the start's probe
    pub realtime: RealtimeWatch,
    /// CPUs online
    pub online: usize,
    /// `--require-rt`: a service without real-time scheduling ends the run
    pub require_rt: bool,
    /// when the run began \[ns\] (the run's length counts from it)
    pub t0_ns: u64,
    /// the run's length \[s\] (`None`: until a signal)
    pub duration_s: Option<f64>,
    /// the run's length is counted on the simulated robot's clock: a run
    /// whose robot loop fell behind (a loaded machine) goes on by as long
    /// as it fell behind, up to its length again, so that the scenario is
    /// played to its end ([`Event::RobotBehind`]); false for a real arm
    pub robot_clock: bool,
}

#[cfg(test)]
impl Setup {
    /// For tests: `services` under `sup`, every one on the normal
    /// scheduler, on 2 CPUs, from t = 0, on the simulator's clock.
    pub(crate) fn unscheduled(
        sup: SupervisorConfig,
        services: Vec<(String, ServiceSpec)>,
    ) -> Setup {
        Setup {
            sup,
            wanted: services
                .iter()
                .map(|_| Wanted {
                    priority: 0,
                    cpus: vec![],
                })
                .collect(),
            services,
            realtime: RealtimeWatch::new(None),
            online: 2,
            require_rt: false,
            t0_ns: 0,
            duration_s: None,
            robot_clock: true,
        }
    }
}

/// Where the machine is in a sequence of steps.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
enum Stage {
    /// between rounds (or not started yet)
    Idle,
    /// the start-up: service `index` is being started
    Starting(usize),
    /// a round: the channels are being read
    Reading,
    /// a round: CPU samples, publishers, real-time and exits are being gathered
    Gathering,
    /// a round: the frozen are being killed, the due restarted
    Acting,
}

/// The round's timers [ns].
#[derive(Clone, Copy, Debug, Default)]
struct Timers {
    /// the start-up's end: an exit before it fails the start
    starting_until: Option<u64>,
    next_health: u64,
    /// after a (re)start, health every tick until then
    fast_health_until: u64,
    next_watch: u64,
    next_cpu_sample: u64,
    last_round: u64,
    /// the health's period
    health_period: u64,
}

/// The supervisor's decisions over a run, step by step.
#[derive(Clone, Debug)]
pub struct Supervision {
    roster: Roster,
    cpu: CpuUse,
    realtime: RealtimeWatch,
    /// per service: its real-time scheduling to judge
    wanted: Vec<Wanted>,
    online: usize,
    require_rt: bool,
    /// the dead-man's time [ns]
    deadman_ns: u64,
    /// the run's end [ns] on the wall clock
    end_ns: Option<u64>,
    /// how much later the run may end when its robot fell behind [ns]
    /// (0: a real arm's run ends on the wall clock)
    max_extension_ns: u64,
    /// how far the simulated robot is behind the wall clock [ns]
    robot_behind_ns: u64,
    stage: Stage,
    timers: Timers,
    /// a service was taken over from a supervisor that died
    adopted_any: bool,
    /// a round was asked for by the last wait's wakes
    round_asked: bool,
    /// how long this supervisor did not run before this round [ns]
    stalled_ns: u64,
    /// since when dead processes' resources are being removed [ns]
    /// ([`Event::Cleaning`]; `None`: not now)
    cleaning_since_ns: Option<u64>,
    /// a service ended or started in this round
    changed: bool,
    /// a verdict ended this round's reaping
    reaped_enough: bool,
    /// (owned channel, pid) of every stranger reported, each once
    strangers_seen: Vec<(&'static str, i32)>,
    start_error: Option<String>,
    stop_reason: Option<String>,
    signalled: bool,
}

impl Supervision {
    /// A supervision of `setup`, nothing started yet.
    pub fn new(setup: Setup) -> Supervision {
        let n = setup.services.len();
        let deadman_ns = (setup.sup.deadman_s * 1e9) as u64;
        Supervision {
            roster: Roster::new(setup.sup, setup.services),
            cpu: CpuUse::new(n),
            realtime: setup.realtime,
            wanted: setup.wanted,
            online: setup.online,
            require_rt: setup.require_rt,
            deadman_ns,
            end_ns: setup.duration_s.map(|d| setup.t0_ns + (d * 1e9) as u64),
            max_extension_ns: match (setup.robot_clock, setup.duration_s) {
                (true, Some(d)) => (d * 1e9) as u64,
                _ => 0,
            },
            robot_behind_ns: 0,
            stage: Stage::Idle,
            timers: Timers::default(),
            adopted_any: false,
            round_asked: false,
            stalled_ns: 0,
            cleaning_since_ns: None,
            changed: false,
            reaped_enough: false,
            strangers_seen: Vec::new(),
            start_error: None,
            stop_reason: None,
            signalled: false,
        }
    }

    /// Take `event`, noticed at `now_ns`; what to do next is appended to `out`.
    pub fn step(&mut self, now_ns: u64, event: Event, out: &mut Vec<Action>) {
        match event {
            Event::Start => self.start(now_ns, out),
            Event::Adopted {
                index,
                pid,
                restarts,
            } => self.adopted(index, now_ns, pid, restarts, out),
            Event::Started { index, pid } => self.started(index, now_ns, pid, out),
            Event::SpawnFailed { index, error } => self.spawn_failed(index, now_ns, error, out),
            Event::Done => self.done(now_ns, out),
            Event::Tick | Event::Gone(_) => self.round_asked = true,
            Event::Beat(i) => self.roster.heard(i, now_ns),
            Event::Missed(i) => {
                self.roster.deadline_missed(i);
                self.round_asked = true;
            }
            Event::Round => self.round(now_ns, out),
            Event::Resume => self.resume(now_ns, out),
            Event::RobotIntruder(reason) => {
                out.push(Action::Warn(reason.clone()));
                self.record(out, now_ns, "intruder", "robot", &reason);
                out.push(Action::Degrade(reason));
            }
            Event::CpuTime { index, cpu_ns } => self.cpu.record(index, now_ns, cpu_ns),
            Event::Steal { steal_ns } => self.cpu.record_steal(now_ns, steal_ns),
            Event::CommandIntruder { pid, who, channel } => {
                self.command_intruder(now_ns, pid, &who, channel, out)
            }
            Event::Stranger { channel, pid, who } => self.stranger(now_ns, channel, pid, &who, out),
            Event::Realtime {
                index,
                pid,
                observed,
            } => self.observed(index, pid, &observed, out),
            Event::Exited { index, detail } => self.exited(index, now_ns, detail, out),
            Event::NodeCounter(reason) => {
                out.push(Action::Warn(format!("{reason}; stopping the cell")));
                self.stop(reason, out);
            }
            Event::Signal => self.signalled = true,
            Event::RobotBehind(ns) => self.robot_behind_ns = ns,
            Event::Cleaning(busy) => {
                self.cleaning_since_ns = match busy {
                    false => None,
                    true => self.cleaning_since_ns.or(Some(now_ns)),
                }
            }
        }
    }

    /// The next stage of the sequence under way.
    fn done(&mut self, now_ns: u64, out: &mut Vec<Action>) {
        match self.stage {
            Stage::Idle => {}
            Stage::Starting(index) => self.next_start(index, now_ns, out),
            Stage::Reading => self.gather(now_ns, out),
            Stage::Gathering => self.act(now_ns, out),
            Stage::Acting => self.commit(now_ns, out),
        }
    }

    /// A sequence is under way: step [`Event::Done`] once this step's
    /// actions are performed.
    pub fn awaits(&self) -> bool {
        self.stage != Stage::Idle
    }

    /// The supervision goes on at `now_ns`: the cell started, no verdict
    /// ended the run, no signal came, the run's length is not reached.
    pub fn running(&self, now_ns: u64) -> bool {
        self.start_error.is_none()
            && self.stop_reason.is_none()
            && !self.signalled
            && self.end_ns().is_none_or(|e| now_ns < e)
    }

    /// When the run's length is reached \[ns\]: its end on the wall clock,
    /// later by as much as the simulated robot fell behind (at most the
    /// length again).
    pub fn end_ns(&self) -> Option<u64> {
        self.end_ns
            .map(|e| e + self.robot_behind_ns.min(self.max_extension_ns))
    }

    /// Exits are still taken in this round ([`Action::Reap`]).
    pub fn reaping(&self) -> bool {
        !self.reaped_enough
    }

    /// Whether `(channel, pid)` was reported a stranger already.
    pub fn stranger_known(&self, channel: &str, pid: i32) -> bool {
        self.strangers_seen
            .iter()
            .any(|&(c, p)| c == channel && p == pid)
    }

    /// How the run ended (meaningful once [`Supervision::running`] is false).
    pub fn ending(&self) -> Ending {
        match &self.start_error {
            Some(reason) => Ending::StartFailed(reason.clone()),
            None => Ending::Stopped(self.stop_reason.clone()),
        }
    }

    /// The services' bookkeeping.
    pub fn roster(&self) -> &Roster {
        &self.roster
    }

    /// The services' CPU use so far.
    pub fn cpu(&self) -> &CpuUse {
        &self.cpu
    }

    /// What the services got of real-time scheduling.
    pub fn realtime(&self) -> &RealtimeWatch {
        &self.realtime
    }

    /// SCHED_FIFO was permitted when the run started.
    pub fn realtime_permitted(&self) -> bool {
        self.realtime.permitted()
    }

    /// An event for the report.
    fn record(
        &self,
        out: &mut Vec<Action>,
        at_ns: u64,
        kind: &'static str,
        service: &str,
        detail: &str,
    ) {
        out.push(Action::Record {
            at_ns,
            kind,
            service: service.to_string(),
            detail: detail.to_string(),
        });
    }

    /// `reason` ends the run: reported degraded.
    fn stop(&mut self, reason: String, out: &mut Vec<Action>) {
        out.push(Action::Degrade(reason.clone()));
        self.stop_reason = Some(reason);
    }
}
