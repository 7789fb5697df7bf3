//! The supervision driven step by step with synthetic events, no process:
//! every verdict of the supervisor (restart with back-off, crash loop,
//! failed start, dead-man hold, stall, frozen and starved services,
//! intruders), its start-up and its health.

use super::*;
use crate::process::DEADMAN_TEXT;

const MS: u64 = 1_000_000;
const S: u64 = 1_000_000_000;

/// sim (watched), control (watched, depends on sim), worker (not watched).
fn setup() -> Setup {
    let defaults = phri_config::Config::defaults();
    let spec = |binary: &str, heartbeat: Option<&str>, deps: &[&str]| ServiceSpec {
        binary: binary.into(),
        heartbeat: heartbeat.map(str::to_string),
        depends_on: deps.iter().map(|d| d.to_string()).collect(),
        start_delay_ms: 0,
        cpus: vec![1],
        ..defaults.services["sim"].clone()
    };
    let services = vec![
        ("sim".to_string(), spec("phri-sim", Some("sim/truth"), &[])),
        (
            "control".to_string(),
            spec("phri-control", Some("control/status"), &["sim"]),
        ),
        ("worker".to_string(), spec("phri-worker", None, &[])),
    ];
    Setup::unscheduled(defaults.supervisor.clone(), services)
}

/// A test's cell: the machine and the pids it handed out.
struct Cell {
    sup: Supervision,
    next_pid: u32,
    /// CPU time so far per service [ns] (`None`: not sampled)
    cpu_ns: Vec<Option<u64>>,
    /// CPU share per service while sampled (of one CPU)
    cpu_share: Vec<f64>,
    last_sample: u64,
}

impl Cell {
    fn new(setup: Setup) -> Cell {
        let n = setup.services.len();
        Cell {
            sup: Supervision::new(setup),
            next_pid: 100,
            cpu_ns: vec![Some(0); n],
            cpu_share: vec![0.0; n],
            last_sample: 0,
        }
    }

    fn step(&mut self, now: u64, event: Event) -> Vec<Action> {
        let mut out = Vec::new();
        self.sup.step(now, event, &mut out);
        out
    }

    /// Step `event` and answer every action as a cell would (each start
    /// succeeds, `exits` are reaped), through the sequence it begins; every
    /// action returned, the answers' among them.
    fn run(&mut self, now: u64, event: Event, exits: &[(usize, &str)]) -> Vec<Action> {
        let mut all = Vec::new();
        let mut pending = self.step(now, event);
        loop {
            let mut answers = Vec::new();
            for action in &pending {
                answers.extend(self.answer(now, action, exits));
            }
            all.extend(pending);
            all.extend(answers);
            if !self.sup.awaits() {
                return all;
            }
            pending = self.step(now, Event::Done);
        }
    }

    /// A cell's answer to `action`: its follow-up actions.
    fn answer(&mut self, now: u64, action: &Action, exits: &[(usize, &str)]) -> Vec<Action> {
        match *action {
            Action::Launch(index) | Action::Start(index) => {
                self.next_pid += 1;
                let pid = self.next_pid;
                self.step(now, Event::Started { index, pid })
            }
            Action::SampleCpu => {
                let dt = now.saturating_sub(self.last_sample);
                self.last_sample = now;
                let mut out = Vec::new();
                for index in 0..self.cpu_ns.len() {
                    let used = (dt as f64 * self.cpu_share[index]) as u64;
                    let cpu_ns = self.cpu_ns[index].map(|c| c + used);
                    self.cpu_ns[index] = cpu_ns;
                    out.extend(self.step(now, Event::CpuTime { index, cpu_ns }));
                }
                out
            }
            Action::Reap => {
                let mut out = Vec::new();
                for &(index, detail) in exits {
                    if self.sup.reaping() {
                        let detail = detail.to_string();
                        out.extend(self.step(now, Event::Exited { index, detail }));
                    }
                }
                out
            }
            _ => Vec::new(),
        }
    }

    /// Start every service at `now`, all succeeding.
    fn start(&mut self, now: u64) -> Vec<Action> {
        self.run(now, Event::Start, &[])
    }

    /// A round at `now` after the wakes `woke`, with `exits` reaped.
    fn round(&mut self, now: u64, woke: &[Event], exits: &[(usize, &str)]) -> Vec<Action> {
        for w in woke {
            assert!(self.step(now, w.clone()).is_empty());
        }
        self.run(now, Event::Round, exits)
    }

    /// Every watched service beats at `now`, but `mute`.
    fn beat(&mut self, now: u64, mute: &[usize]) {
        for i in [0, 1] {
            if !mute.contains(&i) {
                assert!(self.step(now, Event::Beat(i)).is_empty());
            }
        }
    }

    /// Rounds every 10 ms from `from` to `until` [ns], all beating but
    /// `mute`; every action.
    fn rounds(&mut self, from: u64, until: u64, mute: &[usize]) -> Vec<Action> {
        let mut all = Vec::new();
        let mut t = from;
        while t < until {
            self.beat(t, mute);
            all.extend(self.round(t, &[Event::Tick], &[]));
            t += TICK_NS;
        }
        all
    }
}

fn warns(actions: &[Action]) -> Vec<&str> {
    actions
        .iter()
        .filter_map(|a| match a {
            Action::Warn(w) => Some(w.as_str()),
            _ => None,
        })
        .collect()
}

fn records(actions: &[Action]) -> Vec<(&'static str, &str)> {
    actions
        .iter()
        .filter_map(|a| match a {
            Action::Record { kind, service, .. } => Some((*kind, service.as_str())),
            _ => None,
        })
        .collect()
}

fn kills(actions: &[Action]) -> Vec<usize> {
    actions
        .iter()
        .filter_map(|a| match a {
            Action::Kill(i) => Some(*i),
            _ => None,
        })
        .collect()
}

fn starts(actions: &[Action]) -> Vec<usize> {
    actions
        .iter()
        .filter_map(|a| match a {
            Action::Start(i) => Some(*i),
            _ => None,
        })
        .collect()
}

/// A cell started at 1 s, whole (every watched service heard), past its
/// start-up, its last round at 4 s − 10 ms.
fn running() -> Cell {
    let mut c = Cell::new(setup());
    c.start(S);
    c.rounds(S, 4 * S, &[]);
    c
}

#[test]
fn the_start_up_starts_each_service_in_order_and_tells_the_cell() {
    let mut s = setup();
    s.services[1].1.start_delay_ms = 300;
    let mut c = Cell::new(s);
    assert_eq!(c.step(S, Event::Start), [Action::Launch(0)]);
    let started = c.step(S, Event::Started { index: 0, pid: 7 });
    assert_eq!(
        started,
        [
            Action::Info("started sim (pid 7)".into()),
            Action::WriteState,
            Action::PublishHealth { now_ns: S },
            Action::CheckStart,
        ]
    );
    assert!(c.sup.awaits());
    assert_eq!(c.step(S, Event::Done), [Action::Launch(1)]);
    let started = c.step(S, Event::Started { index: 1, pid: 8 });
    assert!(started.contains(&Action::Pause(std::time::Duration::from_millis(300))));
    assert_eq!(c.step(S, Event::Done), [Action::Launch(2)]);
    c.step(S, Event::Started { index: 2, pid: 9 });
    // the last one started: supervision begins
    assert_eq!(c.step(2 * S, Event::Done), [Action::WriteState]);
    assert!(!c.sup.awaits());
    assert!(c.sup.running(2 * S));
    assert!(c.sup.roster().runs(8));
}

#[test]
fn a_takeover_adopts_and_says_so() {
    let mut c = Cell::new(setup());
    c.step(S, Event::Start);
    let adopted = c.step(
        S,
        Event::Adopted {
            index: 0,
            pid: 40,
            restarts: 3,
        },
    );
    assert_eq!(
        adopted[0],
        Action::Info("adopted sim (pid 40) from the previous supervisor".into())
    );
    // a takeover looks for no early exit: the adopted ran already
    assert!(!adopted.contains(&Action::CheckStart));
    c.step(S, Event::Done);
    c.step(S, Event::Started { index: 1, pid: 41 });
    c.step(S, Event::Done);
    c.step(S, Event::Started { index: 2, pid: 42 });
    let begun = c.step(S, Event::Done);
    assert_eq!(records(&begun), [("takeover", "supervisor")]);
    assert_eq!(c.sup.roster().get(0).restarts(), 3);
    // no start-up window: an exit now is a crash, restarted
    let exit = c.round(S + 10 * MS, &[Event::Tick], &[(1, "exit status 1")]);
    assert!(c.sup.running(S + 10 * MS));
    assert!(warns(&exit)
        .iter()
        .any(|w| w.starts_with("control exit status 1; restarting in")));
}

#[test]
fn a_service_that_cannot_be_started_fails_the_start() {
    let mut c = Cell::new(setup());
    c.step(S, Event::Start);
    c.step(S, Event::Started { index: 0, pid: 7 });
    c.step(S, Event::Done);
    let failed = c.step(
        S,
        Event::SpawnFailed {
            index: 1,
            error: "[services.control]: cannot start phri-control: gone".into(),
        },
    );
    assert!(failed.is_empty());
    assert!(c.step(S, Event::Done).is_empty(), "nothing more is started");
    assert!(!c.sup.awaits());
    assert!(!c.sup.running(S));
    assert_eq!(
        c.sup.ending(),
        Ending::StartFailed("[services.control]: cannot start phri-control: gone".into())
    );
}

#[test]
fn an_exit_during_the_start_up_fails_the_start() {
    // before the last service started
    let mut c = Cell::new(setup());
    c.step(S, Event::Start);
    c.step(S, Event::Started { index: 0, pid: 7 });
    let detail = "exit status 2".to_string();
    assert!(c.step(S, Event::Exited { index: 0, detail }).is_empty());
    assert!(c.step(S, Event::Done).is_empty());
    assert_eq!(
        c.sup.ending(),
        Ending::StartFailed("sim exit status 2 during start-up".into())
    );
    // within startup_s after the last start: reaped in a round
    let mut c = Cell::new(setup());
    c.start(S);
    let startup_ns = (c.sup.roster().config().startup_s * 1e9) as u64;
    c.round(
        S + startup_ns / 2,
        &[Event::Gone(1)],
        &[(1, "exit status 2"), (0, "exit status 3")],
    );
    assert!(!c.sup.running(S + startup_ns / 2));
    assert_eq!(
        c.sup.ending(),
        Ending::StartFailed("control exit status 2 during start-up".into())
    );
}

#[test]
fn a_service_killed_frozen_within_the_start_up_is_restarted_not_a_failed_start() {
    // a start-up window longer than a service's grace (a slow last
    // service on a loaded machine): control, silent past its grace in it,
    // is killed as frozen; its exit is that verdict's, and it is restarted
    let mut setup = setup();
    setup.sup.startup_s = 10.0;
    let mut c = Cell::new(setup);
    c.start(S);
    let t = 4 * S;
    c.rounds(S, t, &[]);
    let out = c.rounds(t, t + S, &[1]);
    assert_eq!(kills(&out).first(), Some(&1), "{out:?}");
    let now = t + S;
    c.beat(now, &[1]);
    let exit = c.round(now, &[Event::Gone(1)], &[(1, "killed by signal 9")]);
    assert!(c.sup.running(now), "{:?}", c.sup.ending());
    assert_eq!(records(&exit), [("exit", "control")]);
    assert!(
        warns(&exit)
            .iter()
            .any(|w| w.starts_with("control killed by signal 9; restarting in")),
        "{exit:?}"
    );
    // an exit of its own in the window still fails the start
    let later = now + 10 * MS;
    c.round(later, &[Event::Gone(0)], &[(0, "exit status 2")]);
    assert_eq!(
        c.sup.ending(),
        Ending::StartFailed("sim exit status 2 during start-up".into())
    );
}

/// A running cell whose controller (index 1) was killed at 4 s: the cell,
/// the restart back-off [ms], the kill's time [ns] and the actions of its round.
fn control_killed() -> (Cell, u64, u64, Vec<Action>) {
    let mut c = running();
    let min_ms = c.sup.roster().config().restart_backoff_min_ms;
    let t = 4 * S;
    c.beat(t, &[]);
    let exit = c.round(t, &[Event::Gone(1)], &[(1, "killed by signal 9")]);
    (c, min_ms, t, exit)
}

#[test]
fn a_crash_is_restarted_after_its_back_off() {
    let (mut c, min_ms, t, exit) = control_killed();
    assert_eq!(records(&exit), [("exit", "control")]);
    assert_eq!(
        warns(&exit),
        [format!("control killed by signal 9; restarting in {min_ms} ms").as_str()]
    );
    // the state and the health tell the cell at once
    let told = [
        Action::WriteState,
        Action::PublishHealth { now_ns: t },
        Action::CheckNodeCounter,
    ];
    assert!(exit.windows(3).any(|w| w == told), "{exit:?}");
    // not before its back-off
    let early = c.round(t + min_ms * MS - MS, &[Event::Tick], &[]);
    assert!(starts(&early).is_empty());
    let due = t + min_ms * MS;
    let restart = c.round(due, &[Event::Tick], &[]);
    assert_eq!(starts(&restart), [1]);
    assert!(restart.contains(&Action::Info(format!(
        "restarted control (pid {})",
        c.next_pid
    ))));
    assert!(restart.contains(&Action::Record {
        at_ns: due,
        kind: "restart",
        service: "control".into(),
        detail: "restart 1".into()
    }));
    assert!(c.sup.roster().get(1).alive());
    // a quick second crash: the back-off doubles
    let again = c.round(due + 20 * MS, &[Event::Tick], &[(1, "exit status 101")]);
    let doubled = 2 * min_ms;
    assert_eq!(
        warns(&again),
        [format!("control exit status 101; restarting in {doubled} ms").as_str()]
    );
    assert!(c.sup.running(due + 20 * MS));
}

#[test]
fn a_due_restart_waits_for_the_dead_process_s_resources_to_be_removed_at_most_a_while() {
    let (mut c, min_ms, t, _) = control_killed();
    let due = t + min_ms * MS;
    // the removal runs past the back-off: no start while it does
    let mut now = due;
    for _ in 0..10 {
        c.beat(now, &[1]);
        let r = c.round(now, &[Event::Tick, Event::Cleaning(true)], &[]);
        assert!(starts(&r).is_empty(), "at {now}: {r:?}");
        now += 100 * MS;
    }
    // done: started in the next round
    c.beat(now, &[1]);
    let done = c.round(now, &[Event::Tick, Event::Cleaning(false)], &[]);
    assert_eq!(starts(&done), [1]);
    // a removal that never ends delays the next restart by CLEANUP_WAIT_NS at most
    now += 100 * MS;
    c.beat(now, &[]);
    let exit = c.round(now, &[Event::Gone(1)], &[(1, "killed by signal 9")]);
    assert_eq!(records(&exit), [("exit", "control")]);
    let since = now;
    let mut started_at = None;
    while started_at.is_none() && now < since + CLEANUP_WAIT_NS + 2 * S {
        now += 100 * MS;
        c.beat(now, &[1]);
        let r = c.round(now, &[Event::Tick, Event::Cleaning(true)], &[]);
        if starts(&r) == [1] {
            started_at = Some(now);
        }
    }
    let at = started_at.expect("started while the removal still ran");
    assert!(at >= since + 100 * MS + CLEANUP_WAIT_NS, "{at} {since}");
}

#[test]
fn a_restart_that_cannot_start_is_tried_again_and_too_many_end_the_run() {
    let mut c = running();
    let limit = c.sup.roster().config().crash_loop_restarts as u64;
    let mut t = 4 * S;
    c.round(t, &[Event::Tick], &[(2, "exit status 1")]);
    for _ in 0..=limit {
        // the next start that is due fails
        while c.sup.roster().get(2).restart_at.is_none_or(|at| at > t) {
            t += TICK_NS;
        }
        let mut out = c.step(t, Event::Round);
        for _ in 0..2 {
            out = c.step(t, Event::Done);
        }
        assert_eq!(starts(&out), [2]);
        let error = "[services.worker]: cannot start phri-worker: no such file".to_string();
        let failed = c.step(
            t,
            Event::SpawnFailed {
                index: 2,
                error: error.clone(),
            },
        );
        assert_eq!(warns(&failed)[0], error);
        c.step(t, Event::Done);
        if !c.sup.running(t) {
            break;
        }
    }
    let window = c.sup.roster().config().crash_loop_window_s;
    let why = format!(
        "worker could not be started {} times within {window} s ([services.worker]: cannot start phri-worker: no such file)",
        limit + 1
    );
    assert_eq!(c.sup.ending(), Ending::Stopped(Some(why)));
}

#[test]
fn a_crash_loop_ends_the_run() {
    let mut c = running();
    let limit = c.sup.roster().config().crash_loop_restarts as u64;
    let mut t = 4 * S;
    let mut last = Vec::new();
    for _ in 0..=limit {
        // crashed, restarted once due, crashed again 1 ms later
        last = c.round(
            t,
            &[Event::Gone(1)],
            &[(1, "exit status 101"), (0, "exit status 1")],
        );
        if !c.sup.running(t) {
            break;
        }
        let at = c.sup.roster().get(1).restart_at.expect("a restart pending");
        c.round(at, &[Event::Tick], &[]);
        t = at + MS;
    }
    assert!(!c.sup.running(t));
    let why = match c.sup.ending() {
        Ending::Stopped(Some(why)) => why,
        other => panic!("{other:?}"),
    };
    assert!(
        why.starts_with("control ended") && why.contains("exit status 101"),
        "{why}"
    );
    assert_eq!(
        warns(&last).last().copied(),
        Some(format!("{why}; stopping the cell").as_str())
    );
    assert!(last.contains(&Action::Degrade(why)));
    // the verdict ended the reaping: sim's exit in that round was left
    assert!(!c.sup.reaping());
    assert!(c.sup.roster().get(0).alive());
    // nothing restarted or published after the verdict
    assert!(starts(&last).is_empty());
    assert!(!last.contains(&Action::WriteState));
}

#[test]
fn a_dead_man_stop_holds_the_cell_until_an_operator_resumes_it() {
    let mut c = running();
    let t = 4 * S;
    let detail = format!("{DEADMAN_TEXT} (no supervisor heard; status 3)");
    let held = c.round(
        t,
        &[Event::Gone(0)],
        &[(0, detail.as_str()), (1, detail.as_str())],
    );
    let w = warns(&held);
    assert_eq!(w.len(), 1, "{w:?}");
    assert!(
        w[0].starts_with("dead-man: sim heard no supervisor"),
        "{}",
        w[0]
    );
    assert_eq!(
        records(&held),
        [("exit", "sim"), ("deadman", "sim"), ("exit", "control")]
    );
    assert!(c.sup.running(t), "a hold does not end the run");
    // nothing restarts, however long
    let later = c.rounds(t + 10 * MS, t + 3 * S, &[0, 1]);
    assert!(starts(&later).is_empty());
    // the operator resumes: both start again at the next round
    let t = t + 3 * S;
    let mut out = c.step(t, Event::Round);
    assert_eq!(out, [Action::Drain]);
    out = c.step(t, Event::Resume);
    assert_eq!(
        warns(&out),
        ["resumed by the operator: starting the services the dead-man stopped"]
    );
    assert_eq!(records(&out), [("resume", "supervisor")]);
    c.step(t, Event::Done);
    let acting = c.step(t, Event::Done);
    assert_eq!(starts(&acting), [0, 1]);
    // a resume without a hold does nothing
    assert!(c.step(t, Event::Resume).is_empty());
}

#[test]
fn a_stall_of_the_supervisor_is_not_the_services_and_past_the_dead_man_holds() {
    let mut c = running();
    // 300 ms without a round: warned, silence judged afresh, nobody frozen
    let t = 4 * S;
    c.rounds(t, t + 10 * MS, &[]);
    let stalled = c.round(t + 310 * MS, &[Event::Tick], &[]);
    assert_eq!(
        warns(&stalled),
        ["stalled for 300 ms: heartbeats judged afresh"]
    );
    assert!(kills(&stalled).is_empty());
    assert_eq!(records(&stalled), [("stall", "supervisor")]);
    // longer than the dead-man's time: the cell stopped itself, and holds
    let deadman_ns = (c.sup.roster().config().deadman_s * 1e9) as u64;
    let t = t + 310 * MS + deadman_ns + S;
    let held = c.round(t, &[Event::Tick], &[]);
    let w = warns(&held);
    assert!(w[0].starts_with("stalled for"), "{w:?}");
    assert!(w[1].starts_with("dead-man: no supervisor for"), "{w:?}");
    assert_eq!(
        records(&held),
        [("stall", "supervisor"), ("deadman", "supervisor")]
    );
    assert!(c.sup.roster().held());
    assert!(c.sup.running(t));
}

#[test]
fn a_frozen_service_is_killed_and_one_that_starves_it_instead() {
    // control silent, the CPUs idle: control is frozen and killed
    let mut c = running();
    let t = 4 * S;
    let out = c.rounds(t, t + S, &[1]);
    let killed = kills(&out);
    assert!(
        !killed.is_empty() && killed.iter().all(|&k| k == 1),
        "{killed:?}"
    );
    let w = warns(&out);
    assert!(
        w.iter()
            .any(|w| w.starts_with("control silent on liveness/control for")
                && w.contains("frozen, killing it")),
        "{w:?}"
    );
    assert!(records(&out).contains(&("frozen", "control")));
    // control silent while the worker spins on their CPU: the worker dies
    let mut c = running();
    c.cpu_share[2] = 1.0;
    let out = c.rounds(t, t + S, &[1]);
    let killed = kills(&out);
    assert!(
        !killed.is_empty() && killed.iter().all(|&k| k == 2),
        "{killed:?}"
    );
    assert!(warns(&out)
        .iter()
        .any(|w| w.ends_with("killing worker instead")));
    assert!(records(&out).contains(&("blame", "worker")));
}

#[test]
fn a_silence_without_cpu_samples_is_judged_again() {
    let mut c = running();
    // no CPU time readable: no verdict without evidence
    c.cpu_ns = vec![None; 3];
    let t = 4 * S;
    let out = c.rounds(t, t + S, &[1]);
    assert!(kills(&out).is_empty());
    assert!(warns(&out)
        .iter()
        .any(|w| w.ends_with("no CPU samples over that time: judged again")));
}

#[test]
fn intruders_end_the_run_and_strangers_are_reported_once() {
    let mut c = running();
    let t = 4 * S;
    let stranger = Event::Stranger {
        channel: "robot/state",
        pid: 666,
        who: "evil".into(),
    };
    let first = c.step(t, stranger.clone());
    assert_eq!(records(&first), [("intruder", "supervisor")]);
    assert!(c.step(t, stranger).is_empty(), "reported once");
    assert!(c.sup.stranger_known("robot/state", 666));
    assert!(
        c.sup.running(t),
        "a stranger's messages are refused: the run goes on"
    );
    let refused = c.step(t, Event::RobotIntruder("the robot refused pid 9".into()));
    assert_eq!(records(&refused), [("intruder", "robot")]);
    assert!(c.sup.running(t));
    let out = c.step(
        t,
        Event::CommandIntruder {
            pid: 667,
            who: "rogue".into(),
            channel: "robot/command",
        },
    );
    let why = "pid 667 (rogue) published on robot/command instead of the supervised controller";
    assert!(out.contains(&Action::Degrade(why.into())));
    assert!(!c.sup.running(t));
    assert_eq!(c.sup.ending(), Ending::Stopped(Some(why.into())));
}

#[test]
fn a_signal_or_the_run_s_length_ends_the_run_cleanly() {
    let mut c = running();
    c.step(5 * S, Event::Signal);
    assert!(!c.sup.running(5 * S));
    assert_eq!(c.sup.ending(), Ending::Stopped(None));
    let mut s = setup();
    s.t0_ns = S;
    s.duration_s = Some(2.0);
    let c = Cell::new(s);
    assert!(c.sup.running(3 * S - 1));
    assert!(!c.sup.running(3 * S));
    assert_eq!(c.sup.ending(), Ending::Stopped(None));
}

#[test]
fn a_signal_during_the_start_up_starts_nothing_more() {
    let mut c = Cell::new(setup());
    c.step(S, Event::Start);
    c.step(S, Event::Started { index: 0, pid: 7 });
    c.step(S, Event::Signal);
    assert_eq!(c.step(S, Event::Done), [Action::WriteState]);
    assert!(!c.sup.awaits());
    assert!(!c.sup.running(S));
    assert_eq!(c.sup.ending(), Ending::Stopped(None));
}

#[test]
fn health_goes_out_every_tick_after_a_start_then_at_its_rate() {
    let mut c = Cell::new(setup());
    c.start(S);
    let health = |out: &[Action]| {
        out.iter()
            .filter(|a| matches!(a, Action::PublishHealth { .. }))
            .count()
    };
    // the first second: every round
    let out = c.rounds(S, 2 * S, &[]);
    assert_eq!(health(&out), 100);
    // then at health_hz
    let hz = c.sup.roster().config().health_hz;
    let out = c.rounds(2 * S, 3 * S, &[]);
    assert_eq!(health(&out) as f64, hz);
}

#[test]
fn a_round_is_due_with_a_wake_or_a_tick_s_time() {
    let mut c = running();
    let t = 4 * S;
    c.rounds(t, t + TICK_NS, &[]);
    // 1 ms after the last round, nothing woke it: no round
    assert!(c.step(t + MS, Event::Round).is_empty());
    // a missed deadline asks for one at once
    c.step(t + 2 * MS, Event::Missed(1));
    assert_eq!(c.step(t + 2 * MS, Event::Round), [Action::Drain]);
}

#[test]
fn each_real_time_service_is_observed_once_per_process_after_it_settled() {
    let mut s = setup();
    s.wanted[1].priority = 40;
    s.require_rt = true;
    let mut c = Cell::new(s);
    c.start(S);
    let observe = |out: &[Action]| {
        out.iter()
            .filter_map(|a| match a {
                Action::Observe { index, pid } => Some((*index, *pid)),
                _ => None,
            })
            .collect::<Vec<_>>()
    };
    // not before it settled
    let out = c.rounds(S, S + 150 * MS, &[]);
    assert!(observe(&out).is_empty());
    let out = c.rounds(S + 150 * MS, S + 250 * MS, &[]);
    let pid = c.sup.roster().get(1).pid.expect("control runs");
    assert_eq!(observe(&out)[0], (1, pid));
    // what it got falls short: with --require-rt the run ends
    let observed = crate::realtime::Observed {
        priority: None,
        cpus: vec![0, 1],
        locked_kb: 0,
    };
    let out = c.step(
        S + 250 * MS,
        Event::Realtime {
            index: 1,
            pid,
            observed,
        },
    );
    assert!(warns(&out)[0].starts_with(&format!("control (pid {pid}): ")));
    assert!(!c.sup.running(S + 250 * MS));
    // judged once per process
    let out = c.rounds(S + 260 * MS, S + 300 * MS, &[]);
    assert!(observe(&out).is_empty());
}

#[test]
fn a_run_whose_simulated_robot_fell_behind_goes_on_by_as_much_up_to_its_length_again() {
    let s = |robot_clock| Setup {
        duration_s: Some(10.0),
        robot_clock,
        ..setup()
    };
    let mut sim = Supervision::new(s(true));
    let mut out = Vec::new();
    assert!(sim.running(9_999_000_000) && !sim.running(10_000_000_000));
    // 3 s of periods not run: 3 s more
    sim.step(1, Event::RobotBehind(3_000_000_000), &mut out);
    assert!(out.is_empty());
    assert!(sim.running(12_999_000_000) && !sim.running(13_000_000_000));
    // never more than the length again
    sim.step(2, Event::RobotBehind(30_000_000_000), &mut out);
    assert!(sim.running(19_999_000_000) && !sim.running(20_000_000_000));
    // a real arm's run ends on the wall clock
    let mut real = Supervision::new(s(false));
    real.step(1, Event::RobotBehind(3_000_000_000), &mut out);
    assert!(!real.running(10_000_000_000));
}
