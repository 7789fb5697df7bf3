//! The robot side of the 1 kHz protocol: what a torque-controlled arm does
//! with the commands it receives, as a real robot adapter would wrap it
//! (libfranka's contract). It decides from commands and time alone; the
//! simulator (or a real arm) applies its decision.
//!
//! Every control period the robot publishes a state, numbered `state_seq`;
//! the controller answers it with a [`TorqueCommand`] carrying that number.
//! At the next period:
//!
//! - a valid command (one torque per joint, all finite) that answers the last
//!   state is **fresh**: its torque is applied and its latency (state
//!   published → command received) goes into the histogram;
//! - a valid command that answers an older state is still the newest torque:
//!   it is reused, and the period counts as a **missed deadline**; so does a
//!   period without any command (the last torque is reused);
//! - malformed commands (wrong joint count, non-finite torque) are ignored;
//! - more than [`MAX_MISSED`] missing commands in a row engage the **brakes**
//!   until a fresh command arrives (the arm starts braked: a controller must
//!   answer first).
//!
//! When this process itself woke late (the machine stalled it, and the
//! simulated world paused with it), the controller gets
//! [`LATE_CYCLE_GRACE_NS`] more to answer: [`Wake::grace_until`] says until
//! when; the waiting is the caller's. Missed deadlines are reported as runs
//! ([`MissRun`]), one per run of consecutive misses, when it ends.
//!
//! With a hot standby ([`RobotLink::cycle_slots`]) two controllers answer,
//! each on a command channel of its own (slot 0 `robot/command`, slot 1
//! `robot/command/standby`). The slot in charge commands while it answers
//! in time; when its fresh answer is missing and the other slot's is there,
//! the other slot's is applied in the same period and that slot is in
//! charge from then on (a **takeover**, counted with the torque step it
//! made in [`CommanderStats`]). The state's `STANDBY_IN_CHARGE` bit tells
//! both controllers which one is in charge. Slot 0 is woken by every state;
//! slot 1 rests on its own clock and is woken (`robot/state/standby`) by
//! every state while it is in charge, and by a state slot 0 has not
//! answered at the deadline ([`RobotLink::standby_wanted`]): then the
//! adapter waits up to [`STANDBY_GRACE_NS`] for an answer, applies it, and
//! counts the period as a missed deadline ([`CycleTiming::standby_asked`]).
//!
//! **Who may command**: a command sample is taken only from the controller
//! the supervisor started for its slot ([`CommandGate`]: `control` for slot
//! 0, `control_standby` for slot 1), judged per sample by its sender's pid
//! as [`RobotLink::poll`] receives it; any other sender's sample is never
//! applied, and is counted (`refused_stranger`, the newest one's pid in
//! `stranger_pid` of `robot/commanders`), as are malformed ones. Without a
//! supervisor (a robot run by hand, the lock-step cell) every sender is
//! taken, as the controller takes its inputs ([`phri_ipc::OwnerTable`]).
//!
//! [`RobotLink::cycle`] is pure and allocates nothing: every time it needs
//! enters as a number ([`CycleTiming`], nanoseconds on one clock).

use std::sync::Arc;

use phri_ipc::{
    robot_status, CommanderStats, OwnerTable, RobotStats, TorqueCommand, Zeroed, LATENCY_BINS,
    MAX_DOF,
};

/// Consecutive missing commands the robot tolerates before braking (as Franka's FCI).
pub const MAX_MISSED: u32 = 20;
/// Period of `robot/stats` \[cycles\].
pub const STATS_EVERY: u64 = 100;
/// When this process itself woke late (the simulated world paused with it),
/// the controller gets this much more to answer before the cycle counts as missed \[ns\].
pub const LATE_CYCLE_GRACE_NS: u64 = 500_000;
/// How long the adapter waits for an answer after asking the standby for
/// one ([`RobotLink::standby_wanted`]) \[ns\]: a standby woken at its
/// lower priority, adopting and stepping, answers within it on these
/// 2-core machines (its state-to-command time is the in-charge's, p99
/// 0.1-0.2 ms, plus its wake-up).
pub const STANDBY_GRACE_NS: u64 = 500_000;
/// How often the caller looks for the answer during the grace \[ns\].
pub const GRACE_POLL_NS: u64 = 50_000;
/// Runs of missed deadlines logged in full; afterwards only runs whose last
/// miss number is a power of two.
const MISS_LOG_LINES: u64 = 2000;
/// While commands are being refused, `robot/commanders` is due at most this
/// often ([`LinkOutput::refused`]) \[cycles\].
const REFUSED_PUBLISH_EVERY: u64 = 10;
/// The services that may command each slot (their names in the
/// supervisor's configuration and `supervisor/health`).
pub const SLOT_SERVICES: [&str; SLOTS] = ["control", "control_standby"];

/// Why a [`RobotLink`] could not be built.
#[derive(Clone, Debug, PartialEq, Eq, thiserror::Error)]
pub enum LinkError {
    /// the joint count is 0 or more than a command carries
    #[error("robot link: {dof} joints; a command carries 1 to {max}")]
    Joints {
        /// the joint count asked for
        dof: usize,
        /// the most joints a command carries (`phri_ipc::MAX_DOF`)
        max: usize,
    },
    /// the control period is 0 ns
    #[error("robot link: the control period must be at least 1 ns")]
    Period,
}

/// The start of a cycle ([`RobotLink::wake`]).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct Wake {
    /// when this process woke \[ns\]
    pub woke_ns: u64,
    /// the cycle's deadline \[ns\]; when late, the schedule slips to `woke_ns`
    /// (the controller gets a full period for every state, rather than
    /// cycles back to back)
    pub deadline_ns: u64,
    /// woke more than half a period after the deadline (an overrun)
    pub late: bool,
}

impl Wake {
    /// How far behind the (slipped) schedule this cycle woke \[ns\]: 0 when it slipped.
    pub fn behind_schedule_ns(&self) -> u64 {
        self.woke_ns.saturating_sub(self.deadline_ns)
    }

    /// Until when \[ns\] to wait for the answer to state `state_seq` before
    /// deciding: only in a late cycle whose `newest` command does not answer
    /// it yet (`None`: decide now).
    pub fn grace_until(&self, newest: Option<&TorqueCommand>, state_seq: u64) -> Option<u64> {
        self.grace_until_any(&[newest], state_seq)
    }

    /// [`Wake::grace_until`] for several command slots: no grace once any
    /// slot's newest command answers state `state_seq`.
    pub fn grace_until_any(
        &self,
        newest: &[Option<&TorqueCommand>],
        state_seq: u64,
    ) -> Option<u64> {
        let answered = newest
            .iter()
            .flatten()
            .any(|c| RobotLink::answers(c, state_seq));
        (self.late && !answered).then_some(self.woke_ns + LATE_CYCLE_GRACE_NS)
    }
}

/// When things happened, for one cycle's decision [ns, one clock for all].
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub struct CycleTiming {
    /// when the state the command should answer was published
    pub state_published_ns: u64,
    /// when the last command wake-up arrived (0: unknown); a fresh command was
    /// received at this or at its own stamp, whichever is later
    pub command_event_ns: u64,
    /// when the decision is taken (after any grace wait)
    pub now_ns: u64,
    /// how far behind its schedule this cycle woke ([`Wake::behind_schedule_ns`])
    pub behind_schedule_ns: u64,
    /// the standby was asked for this period's answer at its deadline
    /// ([`RobotLink::standby_wanted`]): an answer is applied, late, and
    /// the period counts as a missed deadline
    pub standby_asked: bool,
}

/// What a cycle waits for before deciding ([`RobotLink::grace`]).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct Grace {
    /// the standby was asked for the answer ([`RobotLink::standby_wanted`]):
    /// publish the state to it now
    pub standby_asked: bool,
    /// poll the command slots until this time \[ns\] or an answer (`None`:
    /// decide now)
    pub until_ns: Option<u64>,
}

/// A run of consecutive missed deadlines, reported when it ends.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct MissRun {
    /// numbers of the run's first and last missed deadline (counted since start)
    pub first: u64,
    /// number of the run's last missed deadline (counted since start)
    pub last: u64,
    /// cycles of the first and last miss
    pub first_cycle: u64,
    /// cycle of the last miss
    pub last_cycle: u64,
    /// first miss: time from its state's publication to the decision \[µs\]
    pub since_published_us: u64,
    /// first miss: how far behind its schedule the cycle woke \[µs\]
    pub behind_schedule_us: u64,
}

impl std::fmt::Display for MissRun {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        write!(
            f,
            "missed deadlines {}-{} at cycles {}-{} (first: state published {} µs before, cycle woke {} µs late)",
            self.first,
            self.last,
            self.first_cycle,
            self.last_cycle,
            self.since_published_us,
            self.behind_schedule_us
        )
    }
}

/// What the robot does this period ([`RobotLink::cycle`]).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct LinkOutput {
    /// motor torque command [N·m], joint order, `dof` entries valid (the rest
    /// 0): the newest valid command's, reused while commands are missing;
    /// ignored while braking
    pub tau: [f64; MAX_DOF],
    /// the arm's joint count: how many entries of `tau` are valid
    pub dof: usize,
    /// engage the brakes this period
    pub brake: bool,
    /// the command answered the last state in time
    pub fresh: bool,
    /// [`robot_status`] bits for the next state: `BRAKING`, `COMMAND_FRESH`
    /// (the arm adds `FT_VALID`)
    pub status: u32,
    /// `seq` of the command whose torque is applied (0: none yet)
    pub command_seq: u64,
    /// consecutive periods without a fresh command
    pub missed: u32,
    /// the brakes engaged this period (they were released before)
    pub brake_engaged: bool,
    /// a run of missed deadlines ended this period (and is to be logged)
    pub miss_run: Option<MissRun>,
    /// time to publish the statistics ([`RobotLink::stats_message`],
    /// [`RobotLink::commanders_message`])
    pub publish_stats: bool,
    /// the command slot in charge after this period (0: `robot/command`,
    /// 1: `robot/command/standby`)
    pub in_charge: usize,
    /// the slot not in charge answered for the one in charge this period
    /// (publish [`RobotLink::commanders_message`] now)
    pub takeover: bool,
    /// commands were refused since the last [`RobotLink::commanders_message`]
    /// (a stranger's, a malformed one): publish it now (at most every
    /// `REFUSED_PUBLISH_EVERY` periods)
    pub refused: bool,
}

impl LinkOutput {
    /// The motor torque command [N·m], one per joint.
    pub fn torque(&self) -> &[f64] {
        &self.tau[..self.dof]
    }
}

/// Missed deadlines as runs: one report per run of consecutive misses, when
/// it ends; after [`MISS_LOG_LINES`] runs only those whose last miss number
/// is a power of two.
#[derive(Clone, Debug, Default)]
struct MissLog {
    /// (first miss number, its cycle, µs since the state was published, µs behind schedule)
    first: Option<(u64, u64, u64, u64)>,
    /// (last miss number, its cycle)
    last: (u64, u64),
    runs: u64,
}

impl MissLog {
    fn miss(&mut self, n: u64, cycle: u64, since_published_us: u64, behind_us: u64) {
        if self.first.is_none() {
            self.first = Some((n, cycle, since_published_us, behind_us));
        }
        self.last = (n, cycle);
    }

    /// End the current run, if any; the run if it is to be logged.
    fn end(&mut self) -> Option<MissRun> {
        let (first, first_cycle, since_published_us, behind_schedule_us) = self.first.take()?;
        let (last, last_cycle) = self.last;
        self.runs += 1;
        (self.runs <= MISS_LOG_LINES || last.is_power_of_two()).then_some(MissRun {
            first,
            last,
            first_cycle,
            last_cycle,
            since_published_us,
            behind_schedule_us,
        })
    }
}

/// Who may command each slot: the process of the controller the supervisor
/// started for it ([`SLOT_SERVICES`]), as `supervisor/health` names it
/// (the [`OwnerTable`] a service's supervision thread keeps up to date).
/// Locks nothing, allocates nothing.
#[derive(Clone, Debug, Default)]
pub struct CommandGate {
    /// `None`: every sender is taken (no supervisor)
    owners: Option<Arc<OwnerTable>>,
}

impl CommandGate {
    /// The gate of a supervised cell's owner table (one that is not
    /// supervised takes every sender, as [`CommandGate::unchecked`]).
    pub fn new(owners: Arc<OwnerTable>) -> CommandGate {
        CommandGate {
            owners: Some(owners),
        }
    }

    /// Every sender taken: a robot run by hand, a test, the lock-step cell.
    pub fn unchecked() -> CommandGate {
        CommandGate { owners: None }
    }

    /// May process `pid` command `slot`? Supervised, only the pid the
    /// supervisor gave for the slot's controller (none known yet, or the
    /// controller down: nobody), as the controller judges its inputs.
    pub fn admits(&self, slot: usize, pid: i32) -> bool {
        match &self.owners {
            Some(o) if o.supervised() => {
                pid > 0
                    && SLOT_SERVICES
                        .get(slot)
                        .is_some_and(|name| o.pid_of(name) == pid)
            }
            _ => true,
        }
    }
}

/// The robot's protocol state: the command in force, missed commands,
/// brakes, loop statistics. One per robot; [`RobotLink::cycle`] once per
/// control period.
#[derive(Clone, Debug)]
pub struct RobotLink {
    dof: usize,
    period_ns: u64,
    consecutive_missed: u32,
    loop_established: bool,
    misses: MissLog,
    stats: RobotStats,
    commanders: CommanderStats,
    last: LinkOutput,
    gate: CommandGate,
    /// commands refused since the last `robot/commanders` message
    refused_unpublished: bool,
    /// a hot standby answers on slot 1 ([`RobotLink::set_standby`])
    standby: bool,
    /// the cycle of the last `robot/commanders` message
    commanders_cycle: u64,
}

/// Number of command slots ([`RobotLink::cycle_slots`]).
pub const SLOTS: usize = 2;

/// The largest joint difference between two torques \[Nm\].
fn largest_difference(a: &[f64], b: &[f64]) -> f64 {
    a.iter()
        .zip(b)
        .fold(0.0f64, |m, (x, y)| m.max((x - y).abs()))
}

impl RobotLink {
    /// A link for a `dof`-joint arm with control period `period_ns` \[ns\],
    /// braked until a controller answers.
    pub fn new(dof: usize, period_ns: u64) -> Result<RobotLink, LinkError> {
        if dof == 0 || dof > MAX_DOF {
            return Err(LinkError::Joints { dof, max: MAX_DOF });
        }
        if period_ns == 0 {
            return Err(LinkError::Period);
        }
        let consecutive_missed = MAX_MISSED + 1;
        Ok(RobotLink {
            dof,
            period_ns,
            consecutive_missed,
            loop_established: false,
            misses: MissLog::default(),
            stats: RobotStats::zeroed(),
            commanders: CommanderStats::zeroed(),
            last: LinkOutput {
                tau: [0.0; MAX_DOF],
                dof,
                brake: true,
                fresh: false,
                status: robot_status::BRAKING,
                command_seq: 0,
                missed: consecutive_missed,
                brake_engaged: false,
                miss_run: None,
                publish_stats: false,
                in_charge: 0,
                takeover: false,
                refused: false,
            },
            gate: CommandGate::unchecked(),
            refused_unpublished: false,
            standby: true,
            commanders_cycle: 0,
        })
    }

    /// Take commands only from the senders `gate` admits (the default:
    /// every sender, [`CommandGate::unchecked`]).
    pub fn set_gate(&mut self, gate: CommandGate) {
        self.gate = gate;
    }

    /// Whether a hot standby answers on slot 1 (the default: yes). Without
    /// one, nobody is asked for a missing answer ([`RobotLink::standby_wanted`]).
    pub fn set_standby(&mut self, standby: bool) {
        self.standby = standby;
    }

    /// Judge command sample `cmd` for `slot`, sent by process `pid`: taken
    /// only from the slot's controller ([`CommandGate`]) and only when
    /// valid ([`RobotLink::valid`]); a refused one is counted by kind.
    /// Allocates nothing, locks nothing.
    pub fn admit(&mut self, slot: usize, pid: i32, cmd: &TorqueCommand) -> bool {
        if slot >= SLOTS {
            return false;
        }
        let stranger = !self.gate.admits(slot, pid);
        let malformed = !stranger && !self.valid(cmd);
        let c = &mut self.commanders;
        if stranger {
            c.refused_stranger[slot] = c.refused_stranger[slot].saturating_add(1);
            c.stranger_pid = pid;
        } else if malformed {
            c.refused_malformed[slot] = c.refused_malformed[slot].saturating_add(1);
        }
        self.refused_unpublished |= stranger || malformed;
        !(stranger || malformed)
    }

    /// Take every queued command sample of each slot's channel, keeping in
    /// `newest` the newest one [`RobotLink::admit`] takes (a slot without
    /// one keeps its last); true when some slot's answers state
    /// `state_seq`. What the adapters poll between a state and their
    /// decision. Allocates nothing.
    pub fn poll(
        &mut self,
        channels: [&phri_ipc::Subscriber<TorqueCommand>; SLOTS],
        newest: &mut [Option<TorqueCommand>; SLOTS],
        state_seq: u64,
    ) -> Result<bool, phri_ipc::IpcError> {
        for (slot, (kept, channel)) in newest.iter_mut().zip(channels).enumerate() {
            while let Some((pid, c)) = channel.receive_from()? {
                if self.admit(slot, pid, &c) {
                    *kept = Some(c);
                }
            }
        }
        Ok(newest
            .iter()
            .flatten()
            .any(|c| RobotLink::answers(c, state_seq)))
    }

    /// The control period \[ns\].
    pub fn period_ns(&self) -> u64 {
        self.period_ns
    }

    /// Does `cmd` answer state `state_seq`?
    pub fn answers(cmd: &TorqueCommand, state_seq: u64) -> bool {
        cmd.state_seq == state_seq
    }

    /// A command this arm can apply: one torque per joint, all finite.
    pub fn valid(&self, cmd: &TorqueCommand) -> bool {
        cmd.dof as usize == self.dof && cmd.tau[..self.dof].iter().all(|t| t.is_finite())
    }

    /// Measurement time \[ns\] of state `seq` (1, 2, …) on the robot's clock:
    /// `epoch_ns` for the first, then exactly one period per state, however
    /// late this process ran.
    pub fn state_stamp_ns(&self, epoch_ns: u64, seq: u64) -> u64 {
        epoch_ns + seq.saturating_sub(1) * self.period_ns
    }

    /// This process woke at `woke_ns` for the cycle due at `deadline_ns`:
    /// more than half a period late is an overrun, and the schedule slips.
    pub fn wake(&mut self, deadline_ns: u64, woke_ns: u64) -> Wake {
        let late = woke_ns > deadline_ns + self.period_ns / 2;
        if late {
            self.stats.overruns += 1;
        }
        Wake {
            woke_ns,
            deadline_ns: if late { woke_ns } else { deadline_ns },
            late,
        }
    }

    /// Ask the standby (slot 1) for the answer to state `state_seq` at this
    /// period's deadline? With a standby, when slot 0 is in charge of a
    /// running loop (not braked) and `newest[0]` does not answer it: slot 0
    /// is late or gone.
    /// (While slot 1 is in charge, it is woken by every state instead:
    /// [`LinkOutput::in_charge`].)
    pub fn standby_wanted(&self, newest: &[Option<TorqueCommand>; SLOTS], state_seq: u64) -> bool {
        let answered = newest[0]
            .as_ref()
            .is_some_and(|c| self.valid(c) && Self::answers(c, state_seq));
        self.standby
            && self.last.in_charge == 0
            && self.loop_established
            && !self.last.brake
            && !answered
    }

    /// At the deadline (`now_ns`), having polled `newest`: ask the standby
    /// ([`RobotLink::standby_wanted`]) and wait for an answer to state
    /// `state_seq` until the later of a late cycle's grace
    /// ([`Wake::grace_until_any`]) and, the standby asked,
    /// [`STANDBY_GRACE_NS`] from now.
    pub fn grace(
        &self,
        wake: &Wake,
        newest: &[Option<TorqueCommand>; SLOTS],
        state_seq: u64,
        now_ns: u64,
    ) -> Grace {
        let standby_asked = self.standby_wanted(newest, state_seq);
        let late = wake.grace_until_any(&newest.each_ref().map(Option::as_ref), state_seq);
        let asked = standby_asked.then_some(now_ns + STANDBY_GRACE_NS);
        Grace {
            standby_asked,
            until_ns: late.max(asked),
        }
    }

    /// Decide this period: `newest` is the newest command received (if any),
    /// `state_seq` the last state published, which a fresh command answers.
    /// Allocates nothing.
    pub fn cycle(
        &mut self,
        newest: Option<&TorqueCommand>,
        state_seq: u64,
        timing: &CycleTiming,
    ) -> LinkOutput {
        self.cycle_slots([newest, None], state_seq, timing)
    }

    /// How long a link that has never applied a fresh command (the arm
    /// braked since its start) waits for slot 0, in charge at the start,
    /// before the other slot's answers may start the arm \[ns\]: a standby
    /// that answers first does not take charge of a start the first
    /// controller is about to make, and a first controller that never
    /// answers does not keep the arm braked for good.
    pub const FIRST_START_WAIT_NS: u64 = 3_000_000_000;

    /// Decide this period with a hot standby: `newest[s]` is slot `s`'s newest
    /// command. The slot in charge's fresh command is applied; without it the
    /// other slot's fresh one, which then takes charge (before the link's
    /// first fresh command only after [`RobotLink::FIRST_START_WAIT_NS`]:
    /// slot 0 starts the arm). Allocates nothing.
    pub fn cycle_slots(
        &mut self,
        newest: [Option<&TorqueCommand>; SLOTS],
        state_seq: u64,
        timing: &CycleTiming,
    ) -> LinkOutput {
        let n = self.dof;
        let valid = newest.map(|c| c.filter(|c| self.valid(c)));
        let answer = valid.map(|c| c.filter(|c| Self::answers(c, state_seq)));
        let primary = self.last.in_charge;
        // compared while the loop runs (from the brakes both start afresh)
        if let ([Some(a), Some(b)], false) = (answer, self.last.brake) {
            let c = &mut self.commanders;
            c.both_answered += 1;
            c.max_answer_diff_nm = c
                .max_answer_diff_nm
                .max(largest_difference(&a.tau[..n], &b.tau[..n]));
        }
        // the first start is slot 0's (braked meanwhile), unless it keeps silent
        let other_may = self.loop_established
            || self.stats.cycles.saturating_mul(self.period_ns) >= Self::FIRST_START_WAIT_NS;
        let applied = match (answer[primary], answer[1 - primary]) {
            (Some(cmd), _) => Some((primary, cmd)),
            (None, Some(cmd)) if other_may => Some((1 - primary, cmd)),
            // a late answer to an older state is still the newest torque: reuse it
            (None, _) => valid[primary].map(|c| (primary, c)),
        };
        let mut answered = false;
        let mut takeover = false;
        if let Some((slot, cmd)) = applied {
            if Self::answers(cmd, state_seq) {
                answered = true;
                let received = timing.command_event_ns.max(cmd.stamp_ns);
                let latency = received.saturating_sub(timing.state_published_ns);
                let bin = ((latency / 1000) as usize).min(LATENCY_BINS - 1);
                self.stats.latency_hist[bin] = self.stats.latency_hist[bin].saturating_add(1);
                self.stats.latency_max_ns = self.stats.latency_max_ns.max(latency);
                let c = &mut self.commanders;
                c.periods[slot] += 1;
                // what one period changes, where no takeover is involved
                if slot == primary && self.last.fresh && !self.last.brake {
                    let step = largest_difference(&cmd.tau[..n], &self.last.tau[..n]);
                    c.max_step_nm = c.max_step_nm.max(step as f32);
                }
                if slot != primary {
                    self.last.in_charge = slot;
                    c.in_charge = slot as u32;
                    // from a running loop: a takeover (from the brakes: a start)
                    if !self.last.brake {
                        takeover = true;
                        let diff = largest_difference(&cmd.tau[..n], &self.last.tau[..n]);
                        c.takeovers += 1;
                        c.last_takeover_state_stamp_ns = cmd.state_stamp_ns;
                        c.last_takeover_state_seq = state_seq;
                        c.last_takeover_to = slot as u32;
                        c.last_takeover_diff_nm = diff;
                        c.max_takeover_diff_nm = c.max_takeover_diff_nm.max(diff);
                    }
                }
            }
            self.last.tau[..n].copy_from_slice(&cmd.tau[..n]);
            self.last.command_seq = cmd.seq;
        }
        // an answer given after the standby was asked is applied, but late
        let fresh = answered && !timing.standby_asked;
        let mut miss_run = None;
        if fresh {
            self.consecutive_missed = 0;
            self.loop_established = true;
            miss_run = self.misses.end();
        } else {
            self.consecutive_missed = self.consecutive_missed.saturating_add(1);
            if self.loop_established {
                self.stats.missed_deadlines += 1;
                self.misses.miss(
                    self.stats.missed_deadlines,
                    self.stats.cycles,
                    timing.now_ns.saturating_sub(timing.state_published_ns) / 1000,
                    timing.behind_schedule_ns / 1000,
                );
            }
        }
        let brake = self.consecutive_missed > MAX_MISSED;
        let brake_engaged = brake && !self.last.brake;
        if brake_engaged {
            self.stats.brake_events += 1;
        }
        if brake {
            self.stats.braked_cycles += 1;
        }
        self.stats.cycles += 1;
        let out = &mut self.last;
        out.brake = brake;
        out.fresh = fresh;
        out.status = if brake { robot_status::BRAKING } else { 0 }
            | if fresh {
                robot_status::COMMAND_FRESH
            } else {
                0
            }
            | if out.in_charge == 1 {
                robot_status::STANDBY_IN_CHARGE
            } else {
                0
            };
        out.takeover = takeover;
        out.missed = self.consecutive_missed;
        out.brake_engaged = brake_engaged;
        out.miss_run = miss_run;
        out.publish_stats = self.stats.cycles.is_multiple_of(STATS_EVERY);
        out.refused = self.refused_unpublished
            && self.stats.cycles >= self.commanders_cycle + REFUSED_PUBLISH_EVERY;
        *out
    }

    /// The last decision (before the first cycle: braked, no command).
    pub fn output(&self) -> &LinkOutput {
        &self.last
    }

    /// The loop statistics so far.
    pub fn stats(&self) -> &RobotStats {
        &self.stats
    }

    /// The statistics as the next `robot/stats` message, stamped `stamp_ns`.
    pub fn stats_message(&mut self, stamp_ns: u64) -> &RobotStats {
        self.stats.seq += 1;
        self.stats.stamp_ns = stamp_ns;
        &self.stats
    }

    /// Which controller commanded, as the next `robot/commanders` message,
    /// stamped `stamp_ns`.
    pub fn commanders_message(&mut self, stamp_ns: u64) -> &CommanderStats {
        self.refused_unpublished = false;
        self.commanders_cycle = self.stats.cycles;
        self.commanders.seq += 1;
        self.commanders.stamp_ns = stamp_ns;
        &self.commanders
    }

    /// The command slots' figures so far.
    pub fn commanders(&self) -> &CommanderStats {
        &self.commanders
    }

    /// End the run of missed deadlines in progress, if any (at shutdown):
    /// the run, if it is to be logged.
    pub fn finish(&mut self) -> Option<MissRun> {
        self.misses.end()
    }
}
