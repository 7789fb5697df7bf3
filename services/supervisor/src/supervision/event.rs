//! What goes into the supervisor's state machine ([`Event`]) and what comes
//! out of it ([`Action`]), and how a run ended ([`Ending`]).

use std::time::Duration;

use crate::realtime::Observed;

/// Something that happened to the cell, told to [`super::Supervision::step`]
/// with the time it was noticed (CLOCK_MONOTONIC, ns). Services are named
/// by their roster index (the start order).
#[derive(Clone, Debug, PartialEq)]
pub enum Event {
    /// the cell is to start: its services are started (or adopted) in order
    Start,
    /// service `index`'s process `pid`, left by a supervisor that died,
    /// was taken over; that supervisor had restarted it `restarts` times
    Adopted {
        /// the service's roster index
        index: usize,
        /// the process taken over
        pid: u32,
        /// the restarts the dead supervisor counted
        restarts: u32,
    },
    /// service `index` was started (or restarted) as process `pid`
    Started {
        /// the service's roster index
        index: usize,
        /// its new process
        pid: u32,
    },
    /// service `index` could not be started (`error`: why, in one line)
    SpawnFailed {
        /// the service's roster index
        index: usize,
        /// why, in one line
        error: String,
    },
    /// the actions of the last step are done: the sequence under way (the
    /// start-up, a round) goes on while [`super::Supervision::awaits`]
    Done,
    /// the supervision loop's timer fired: a round of duties is due
    Tick,
    /// service `index` beat on its liveness service
    Beat(usize),
    /// service `index` missed its liveness deadline
    Missed(usize),
    /// service `index`'s liveness service says it ended or died
    Gone(usize),
    /// the wait is over and its wakes were told: a round of duties when one
    /// is due (a tick, a death, a missed deadline, or a tick's time passed)
    Round,
    /// an operator asked to resume (`phri-hri resume`)
    Resume,
    /// the robot refused commands from a process the supervisor did not
    /// start (`reason`, in words)
    RobotIntruder(String),
    /// service `index`'s process had used `cpu_ns` of CPU time so far
    /// (`None`: not running, or not readable)
    CpuTime {
        /// the service's roster index
        index: usize,
        /// CPU time its process used so far \[ns\] (`None`: not running, or
        /// not readable)
        cpu_ns: Option<u64>,
    },
    /// the machine had lost `steal_ns` per CPU to its hypervisor so far
    Steal {
        /// stolen time per CPU so far \[ns\] (`None`: `/proc/stat` not readable)
        steal_ns: Option<u64>,
    },
    /// process `pid` (`who`: its command line), not a controller this
    /// supervisor started, publishes on the robot's command `channel`
    CommandIntruder {
        /// the intruder's pid
        pid: i32,
        /// its command line
        who: String,
        /// the command channel it publishes on
        channel: &'static str,
    },
    /// process `pid` (`who`: its command line) publishes on the owned
    /// `channel` without being the service that owns it
    Stranger {
        /// the owned channel
        channel: &'static str,
        /// the stranger's pid
        pid: i32,
        /// its command line
        who: String,
    },
    /// what service `index`'s process `pid` got of real-time scheduling
    Realtime {
        /// the service's roster index
        index: usize,
        /// its process
        pid: u32,
        /// what the kernel reports that process has
        observed: Observed,
    },
    /// service `index`'s process ended (`detail`: its exit status in words)
    Exited {
        /// the service's roster index
        index: usize,
        /// its exit status in words
        detail: String,
    },
    /// iceoryx2's node counter is no longer this user's alone (`reason`)
    NodeCounter(String),
    /// SIGINT or SIGTERM: the run is to end
    Signal,
    /// the simulated robot's loop is this far behind the wall clock \[ns\]
    /// (periods it did not run since the cell started, all its processes
    /// added up): the scenario's time, which the person, the microphone
    /// and the contacts follow, is the robot's
    RobotBehind(u64),
    /// whether dead processes' iceoryx2 resources are still being removed
    /// (beside the loop): a due restart waits for that, at most
    /// [`super::CLEANUP_WAIT_NS`], so that the new process does not meet
    /// the dead one's files in its own start
    Cleaning(bool),
}

/// What the supervisor is to do, in order; the caller performs it and tells
/// [`super::Supervision::step`] what came of it (the events named).
#[derive(Clone, Debug, PartialEq)]
pub enum Action {
    /// start service `index`, or take over its process from the supervisor
    /// that died (→ [`Event::Adopted`], [`Event::Started`], [`Event::SpawnFailed`])
    Launch(usize),
    /// restart service `index` (→ [`Event::Started`], [`Event::SpawnFailed`])
    Start(usize),
    /// wait this long before the next start (the service's `start_delay_ms`)
    Pause(Duration),
    /// see whether a service started so far has ended (→ [`Event::Exited`])
    CheckStart,
    /// read the channels: the report's samples, the operator's requests
    /// (→ [`Event::RobotIntruder`], [`Event::Resume`])
    Drain,
    /// read each service's CPU time (→ [`Event::CpuTime`])
    SampleCpu,
    /// read who publishes on the robot's command channels and the owned
    /// channels (→ [`Event::CommandIntruder`], [`Event::Stranger`])
    Watch,
    /// read what service `index`'s process `pid` got of real-time
    /// scheduling (→ [`Event::Realtime`])
    Observe {
        /// the service's roster index
        index: usize,
        /// its process
        pid: u32,
    },
    /// reap the processes that ended (→ [`Event::Exited`], each noticed at
    /// its own time), while [`super::Supervision::reaping`]
    Reap,
    /// SIGKILL service `index` (frozen, or starving another): it is then
    /// reaped and restarted as any exit
    Kill(usize),
    /// write `state.json` and `supervisor.state`
    WriteState,
    /// publish the health (and beat with it) stamped `now_ns`
    PublishHealth {
        /// the health's stamp \[ns, CLOCK_MONOTONIC\]
        now_ns: u64,
    },
    /// check that iceoryx2's node counter is still this user's alone
    /// (→ [`Event::NodeCounter`] when not)
    CheckNodeCounter,
    /// a log line, at info level
    Info(String),
    /// a log line, at warn level
    Warn(String),
    /// an event in the report: at `at_ns`, of `kind`, about `service`
    Record {
        /// when \[ns, CLOCK_MONOTONIC\]
        at_ns: u64,
        /// the report event's kind: `restart`, `exit`, `frozen`, ...
        kind: &'static str,
        /// the service it concerns, or `supervisor` or `robot`
        service: String,
        /// in words
        detail: String,
    },
    /// the run is reported degraded, for `reason`
    Degrade(String),
}

/// How a run ended.
#[derive(Clone, Debug, PartialEq, Eq)]
pub enum Ending {
    /// the cell did not start whole (`reason`): stop what started, no report
    StartFailed(String),
    /// stopped (the run's length, a signal), the report follows;
    /// `Some(reason)`: it ended early or degraded
    Stopped(Option<String>),
}
