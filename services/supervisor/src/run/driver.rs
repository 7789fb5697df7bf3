//! The I/O around the supervision's state machine: each action performed on
//! the processes, the channels and the files, and what came of it stepped
//! back into the machine; the start-up and the supervision loop.

use std::path::Path;
use std::time::Duration;

use phri_ipc::liveness::{self, Pulse, Wake};
use phri_ipc::IpcNode;
use phri_runtime::{now_ns, Shutdown};

use super::cell::Cell;
use super::cleaner::Cleaner;
use super::ports::{Liveness, Ports};
use super::publishers::Publishers;
use crate::evaluation::Evaluation;
use crate::process::cpu_time_ns;
use crate::realtime;
use crate::shm::{self, SHM_DIR};
use crate::supervision::{Action, Event, Supervision, TICK_NS};
use crate::{SupervisorError, SupervisorState};

/// What the supervision acts on: the processes, the channels, the report's
/// evaluators.
pub struct Driver {
    /// the supervisor's node
    pub node: IpcNode,
    /// its ports
    pub ports: Ports,
    /// the services' processes
    pub cell: Cell,
    /// what the report is built from
    pub evaluation: Evaluation,
    /// who publishes on the command and owned channels
    pub publishers: Publishers,
    /// the state of a supervisor that died (its services are taken over)
    pub previous: Option<SupervisorState>,
    /// the iceoryx2 prefix of the cell
    pub prefix: String,
    /// removes dead processes' iceoryx2 resources beside the loop
    pub cleaner: Cleaner,
}

impl Driver {
    /// Step `event`, noticed at `now_ns`, and perform what follows.
    pub fn feed(
        &mut self,
        sup: &mut Supervision,
        now_ns: u64,
        event: Event,
    ) -> Result<(), SupervisorError> {
        let mut out = Vec::new();
        sup.step(now_ns, event, &mut out);
        for action in out {
            self.apply(sup, now_ns, action)?;
        }
        Ok(())
    }

    /// Step `event` and the sequence it begins to its end, at `now_ns`
    /// (`None`: the time of each step).
    fn sequence(
        &mut self,
        sup: &mut Supervision,
        now_ns: Option<u64>,
        event: Event,
        shutdown: &Shutdown,
    ) -> Result<(), SupervisorError> {
        let clock = || now_ns.unwrap_or_else(phri_runtime::now_ns);
        self.feed(sup, clock(), event)?;
        while sup.awaits() {
            if shutdown.requested() {
                self.feed(sup, clock(), Event::Signal)?;
            }
            self.feed(sup, clock(), Event::Done)?;
        }
        Ok(())
    }

    /// Start (or take over) every service in order; a start that fails
    /// ends the supervision ([`Supervision::ending`]).
    pub fn start(
        &mut self,
        sup: &mut Supervision,
        shutdown: &Shutdown,
    ) -> Result<(), SupervisorError> {
        self.sequence(sup, None, Event::Start, shutdown)
    }

    /// The supervision loop: one WaitSet sleeps until the tick or a watched
    /// service's liveness wakes it (a beat, a death, a missed deadline);
    /// then a round of duties, until the supervision ends.
    pub fn supervise(
        &mut self,
        sup: &mut Supervision,
        liveness: &Liveness,
        shutdown: &Shutdown,
    ) -> Result<(), SupervisorError> {
        let waitset = liveness::waitset()?;
        let tick = Duration::from_nanos(TICK_NS);
        let vigil = liveness::Vigil::new(&waitset, &liveness.watched, tick)?;
        let mut woke: Vec<Wake> = Vec::with_capacity(liveness.watched.len() + 1);
        let mut pulses: Vec<Event> = Vec::new();
        loop {
            if shutdown.requested() {
                self.feed(sup, now_ns(), Event::Signal)?;
            }
            if !sup.running(now_ns()) {
                return Ok(());
            }
            woke.clear();
            vigil.wait(tick, |w| woke.push(w))?;
            let now = now_ns();
            for &w in &woke {
                match w {
                    Wake::Tick => pulses.push(Event::Tick),
                    Wake::Missed(k) => pulses.push(Event::Missed(liveness.index[k])),
                    Wake::Pulse(k) => liveness.watched[k].take(|p| match p {
                        Pulse::Beat => pulses.push(Event::Beat(liveness.index[k])),
                        // reaped in the round (a child) or found gone (adopted)
                        Pulse::Ended | Pulse::Dead => pulses.push(Event::Gone(liveness.index[k])),
                    })?,
                }
                for event in pulses.drain(..) {
                    self.feed(sup, now, event)?;
                }
            }
            self.sequence(sup, Some(now), Event::Round, shutdown)?;
        }
    }

    /// Perform `action` (`now_ns`: the step's time).
    fn apply(
        &mut self,
        sup: &mut Supervision,
        now_ns: u64,
        action: Action,
    ) -> Result<(), SupervisorError> {
        if self.evaluation.apply(&action) {
            return Ok(());
        }
        match action {
            Action::Launch(i) => {
                let event = self.cell.launch(sup.roster(), i, self.previous.as_ref());
                self.feed(sup, phri_runtime::now_ns(), event)?;
            }
            Action::Start(i) => {
                let event = self.cell.start(sup.roster(), i);
                self.feed(sup, now_ns, event)?;
            }
            Action::Pause(delay) => std::thread::sleep(delay),
            Action::CheckStart => {
                if let Some((index, detail)) = self.cell.first_exit() {
                    self.feed(sup, phri_runtime::now_ns(), Event::Exited { index, detail })?;
                }
            }
            Action::Drain => self.drain(sup, now_ns)?,
            Action::SampleCpu => {
                for index in 0..sup.roster().len() {
                    let cpu_ns = sup.roster().get(index).pid.and_then(cpu_time_ns);
                    self.feed(sup, now_ns, Event::CpuTime { index, cpu_ns })?;
                }
                let steal_ns = phri_runtime::cputime::steal_ns();
                self.feed(sup, now_ns, Event::Steal { steal_ns })?;
            }
            Action::Watch => {
                let me = std::process::id() as i32;
                for event in self.publishers.read(&self.node, sup, me) {
                    self.feed(sup, now_ns, event)?;
                }
            }
            Action::Observe { index, pid } => {
                if let Some(observed) = realtime::observe(pid) {
                    self.feed(
                        sup,
                        now_ns,
                        Event::Realtime {
                            index,
                            pid,
                            observed,
                        },
                    )?;
                }
            }
            Action::Reap => self.reap(sup)?,
            Action::Kill(i) => self.cell.kill(i),
            Action::WriteState => self.cell.write_state(sup.roster()),
            Action::PublishHealth { now_ns } => self.ports.publish_health(sup.roster(), now_ns),
            Action::CheckNodeCounter => {
                if let Err(e) = shm::check_global_mgmt(Path::new(SHM_DIR), &self.prefix) {
                    self.feed(sup, now_ns, Event::NodeCounter(e.to_string()))?;
                }
            }
            Action::Info(line) => tracing::info!("{line}"),
            Action::Warn(line) => tracing::warn!("{line}"),
            Action::Record { .. } | Action::Degrade(_) => {}
        }
        Ok(())
    }

    /// Read the channels into the evaluation: the robot first, then the
    /// refused intruders and an operator's resume, then the rest.
    fn drain(&mut self, sup: &mut Supervision, now_ns: u64) -> Result<(), SupervisorError> {
        // what was read before a failed read is judged all the same: a
        // stranger the robot named is never left out of the report
        let robot = self.ports.read_robot(&mut self.evaluation);
        // commands the robot refused from a process this supervisor did not start
        let roster = sup.roster();
        let intruders = self
            .evaluation
            .boxes
            .intruders(|pid| !roster.runs(pid as u32));
        for reason in intruders {
            self.feed(sup, now_ns, Event::RobotIntruder(reason))?;
        }
        robot?;
        if self.ports.read_requests(&mut self.evaluation)? {
            self.feed(sup, now_ns, Event::Resume)?;
        }
        self.ports.read_rest(&mut self.evaluation)?;
        let behind = self.evaluation.eval.robot_behind_ns();
        self.feed(sup, now_ns, Event::RobotBehind(behind))?;
        self.feed(sup, now_ns, Event::Cleaning(self.cleaner.busy()))?;
        Ok(())
    }

    /// Reap what ended, each noticed at its own time.
    fn reap(&mut self, sup: &mut Supervision) -> Result<(), SupervisorError> {
        for index in 0..self.cell.procs.len() {
            if !sup.reaping() {
                break;
            }
            let Some(detail) = self.cell.reap(index) else {
                continue;
            };
            let now = phri_runtime::now_ns();
            self.cleaner.request();
            self.feed(sup, now, Event::Exited { index, detail })?;
        }
        Ok(())
    }
}
