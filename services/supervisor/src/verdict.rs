//! The supervisor's verdicts on what happened to the cell, as decisions on
//! the roster and the clock alone: a service that ended (a crash to
//! restart, a start that failed, a crash loop that ends the run, a crash
//! loop of one of a hot-standby pair whose partner carries on, or a
//! dead-man stop that holds the cell until an operator resumes it), and a
//! stall of the supervisor itself. The main loop logs, records and acts on
//! them.

use crate::process::DEADMAN_TEXT;
use crate::roster::Roster;

/// What became of a service that ended.
#[derive(Clone, Debug, PartialEq, Eq)]
pub enum ExitVerdict {
    /// it stopped itself for want of a supervisor (its dead-man): not a
    /// crash, and the cell stays stopped until an operator resumes it;
    /// `Some(reason)` when this exit put the cell on hold
    DeadmanHold(Option<String>),
    /// it ended during the start-up: the start fails
    StartFailed(String),
    /// it ended too often: the run ends
    CrashLoop(String),
    /// one of a hot-standby pair (`control_standby`, `dynamics_standby`,
    /// or the first of a pair) ended too often while its partner runs
    /// healthy: the cell is whole without it, so the run goes on; it is
    /// reported (the reason) and started again after its back-off (the time
    /// \[ns\], or never with `restart = false`)
    PartnerCrashLoop(String, Option<u64>),
    /// a crash: started again at this time \[ns\], or never (`restart = false`)
    Restart(Option<u64>),
}

/// Service `index` of `roster` ended at `now_ns` as `detail` says (its exit
/// status in words); `starting`: the cell's start-up is not over (an exit
/// then fails the start, unless the supervisor killed it as frozen);
/// `deadman_s` and `crash_window_s` name the settings in the reasons.
pub fn on_exit(
    roster: &mut Roster,
    index: usize,
    now_ns: u64,
    detail: &str,
    starting: bool,
) -> ExitVerdict {
    let name = roster.get(index).name.clone();
    let sup = roster.config().clone();
    if detail.starts_with(DEADMAN_TEXT) {
        roster.stopped_by_deadman(index);
        if roster.held() {
            return ExitVerdict::DeadmanHold(None);
        }
        roster.hold();
        return ExitVerdict::DeadmanHold(Some(format!(
            "dead-man: {name} heard no supervisor for {} s and stopped the cell; it stays stopped until an operator resumes it (phri-hri resume)",
            sup.deadman_s
        )));
    }
    // killed frozen (starved on a loaded machine, or hung) in the
    // start-up's window: restarted like any frozen service, not a start
    // that failed (a service that ends by itself then is one)
    if starting && !roster.get(index).killed_frozen {
        return ExitVerdict::StartFailed(format!("{name} {detail} during start-up"));
    }
    let at = roster.exited(index, now_ns);
    if let Some(n) = roster.crash_looping(index, now_ns) {
        if let Some(p) = roster.partner(index).filter(|&p| roster.healthy(p)) {
            // the reason is the same at every further exit: reported once
            return ExitVerdict::PartnerCrashLoop(
                format!(
                    "{name} crash-loops (ended more than {} times within {} s): restarted with back-off while {} carries the cell",
                    sup.crash_loop_restarts,
                    sup.crash_loop_window_s,
                    roster.get(p).name
                ),
                at,
            );
        }
        return ExitVerdict::CrashLoop(format!(
            "{name} ended {n} times within {} s (last: {detail}): the cell is not whole",
            sup.crash_loop_window_s
        ));
    }
    ExitVerdict::Restart(at)
}

/// The supervisor did not run for `stalled_ns` (stopped, starved) until
/// `now_ns`: the services' silence meanwhile is not theirs to answer for,
/// and a stall past the dead-man's time (`deadman_ns`) means the services
/// stopped the cell themselves: it holds. `Some(reason)` when this stall put
/// the cell on hold.
pub fn on_stall(
    roster: &mut Roster,
    stalled_ns: u64,
    deadman_ns: u64,
    now_ns: u64,
) -> Option<String> {
    roster.judge_afresh(now_ns);
    if stalled_ns <= deadman_ns || roster.held() {
        return None;
    }
    roster.hold();
    Some(format!(
        "dead-man: no supervisor for {:.1} s (this supervisor was stalled); the cell stopped itself and stays stopped until an operator resumes it (phri-hri resume)",
        stalled_ns as f64 * 1e-9
    ))
}

#[cfg(test)]
mod tests {
    use super::*;
    use phri_config::ServiceSpec;

    const S: u64 = 1_000_000_000;

    fn roster() -> Roster {
        let defaults = phri_config::Config::defaults();
        let spec = |binary: &str| ServiceSpec {
            binary: binary.into(),
            ..defaults.services["sim"].clone()
        };
        let mut r = Roster::new(
            defaults.supervisor.clone(),
            vec![
                ("sim".into(), spec("phri-sim")),
                ("control".into(), spec("phri-control")),
            ],
        );
        r.started(0, S, 100);
        r.started(1, S, 101);
        r
    }

    #[test]
    fn a_crash_restarts_with_back_off_and_too_many_end_the_run() {
        let mut r = roster();
        let min_ms = r.config().restart_backoff_min_ms;
        let v = on_exit(&mut r, 1, 10 * S, "killed by signal 9", false);
        assert_eq!(v, ExitVerdict::Restart(Some(10 * S + min_ms * 1_000_000)));
        let limit = r.config().crash_loop_restarts as u64;
        let mut last = v;
        for k in 1..=limit {
            r.started(1, 10 * S + k * 1_000_000, 200 + k as u32);
            last = on_exit(&mut r, 1, 10 * S + k * 2_000_000, "exit status 101", false);
        }
        match last {
            ExitVerdict::CrashLoop(why) => {
                assert!(
                    why.starts_with("control ended") && why.contains("exit status 101"),
                    "{why}"
                )
            }
            other => panic!("{other:?}"),
        }
    }

    /// A hot standby killed six times (one more than the crash loop's
    /// limit) while the controller in charge runs healthy: reported and
    /// restarted with back-off, the run goes on; the same crash loop with
    /// its partner down ends the run as any other.
    #[test]
    fn a_standby_s_crash_loop_is_reported_and_restarted_while_its_partner_carries_the_cell() {
        let defaults = phri_config::Config::defaults();
        let spec = |binary: &str| ServiceSpec {
            binary: binary.into(),
            ..defaults.services["sim"].clone()
        };
        let mut r = Roster::new(
            defaults.supervisor.clone(),
            vec![
                ("sim".into(), spec("phri-sim")),
                ("control".into(), spec("phri-control")),
                ("control_standby".into(), spec("phri-control")),
            ],
        );
        for i in 0..3 {
            r.started(i, S, 100 + i as u32);
            r.heard(i, S);
        }
        assert_eq!(
            (r.partner(1), r.partner(2), r.partner(0)),
            (Some(2), Some(1), None)
        );
        let limit = r.config().crash_loop_restarts as u64;
        let min_ms = r.config().restart_backoff_min_ms;
        let max_ms = r.config().restart_backoff_max_ms;
        let mut t = 10 * S;
        let mut verdicts = Vec::new();
        for k in 0..=limit {
            let v = on_exit(&mut r, 2, t, "killed by signal 9", false);
            // started again once its back-off passed, killed 1 ms later
            let at = match &v {
                ExitVerdict::Restart(Some(at)) | ExitVerdict::PartnerCrashLoop(_, Some(at)) => *at,
                other => panic!("exit {k}: {other:?}"),
            };
            verdicts.push((t, v));
            assert!(!r.restart_due(2, at - 1), "exit {k} restarted early");
            assert!(r.restart_due(2, at), "exit {k} not restarted");
            r.started(2, at, 300 + k as u32);
            t = at + 1_000_000;
        }
        assert!(
            verdicts[..limit as usize]
                .iter()
                .all(|(_, v)| matches!(v, ExitVerdict::Restart(Some(_)))),
            "{verdicts:?}"
        );
        match verdicts.last().unwrap() {
            (exit_t, ExitVerdict::PartnerCrashLoop(why, Some(at))) => {
                assert!(
                    why.starts_with("control_standby crash-loops")
                        && why.ends_with("while control carries the cell"),
                    "{why}"
                );
                // with back-off: grown past the shortest by the quick exits
                assert!(*at >= exit_t + 2 * min_ms * 1_000_000, "{at} {exit_t}");
                assert!(*at <= exit_t + max_ms * 1_000_000, "{at} {exit_t}");
            }
            other => panic!("{other:?}"),
        }
        assert_eq!(r.get(2).restarts(), limit as u32 + 1);
        // the controller in charge killed now: its partner, the standby, is
        // just restarted and not heard yet: the cell is not whole, the run ends
        let mut last = ExitVerdict::Restart(None);
        for k in 0..=limit {
            last = on_exit(&mut r, 1, t, "killed by signal 9", false);
            if let ExitVerdict::Restart(Some(at)) = last {
                assert!(r.restart_due(1, at));
                r.started(1, at, 400 + k as u32);
                t = at + 1_000_000;
            }
        }
        assert!(matches!(last, ExitVerdict::CrashLoop(_)), "{last:?}");
    }

    #[test]
    fn an_exit_during_the_start_fails_the_start() {
        let mut r = roster();
        match on_exit(&mut r, 0, 2 * S, "exit status 2", true) {
            ExitVerdict::StartFailed(why) => assert_eq!(why, "sim exit status 2 during start-up"),
            other => panic!("{other:?}"),
        }
    }

    #[test]
    fn a_dead_man_stop_holds_the_cell_once_and_restarts_nothing() {
        let mut r = roster();
        let detail = format!("{DEADMAN_TEXT} (exit status 3)");
        let first = on_exit(&mut r, 0, 20 * S, &detail, false);
        assert!(
            matches!(&first, ExitVerdict::DeadmanHold(Some(why)) if why.contains("sim heard no supervisor"))
        );
        assert!(r.held());
        // the next one finds the cell held already
        assert_eq!(
            on_exit(&mut r, 1, 20 * S, &detail, false),
            ExitVerdict::DeadmanHold(None)
        );
        assert!(
            (0..2).all(|i| !r.restart_due(i, 60 * S)),
            "restarted without an operator"
        );
        // an operator resumes: both start again
        assert!(r.resume(61 * S));
        assert!((0..2).all(|i| r.restart_due(i, 61 * S)));
    }

    #[test]
    fn a_stall_past_the_dead_man_holds_the_cell() {
        let mut r = roster();
        let deadman = (r.config().deadman_s * 1e9) as u64;
        assert_eq!(on_stall(&mut r, 200_000_000, deadman, 5 * S), None);
        assert!(!r.held());
        let why = on_stall(&mut r, deadman + S, deadman, 30 * S).expect("held");
        assert!(why.starts_with("dead-man: no supervisor for"), "{why}");
        assert!(r.held());
        assert_eq!(
            on_stall(&mut r, deadman + S, deadman, 40 * S),
            None,
            "held once"
        );
    }
}
