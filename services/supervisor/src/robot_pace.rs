//! Did the robot's own loop keep its pace? From `robot/stats` (cumulative
//! counts since the robot process started, about every 100 periods, stamped
//! on CLOCK_MONOTONIC): the cycles it ran against the cycles the time it ran
//! held, its overruns and its braked cycles, each apart from start-up's
//! braked wait for the first command (the arm held by its brakes while the
//! other services start: a late wake-up then commands nothing), and its
//! overruns apart from the ordered shutdown's (the controllers stopped
//! before it). A robot that slips is a robot whose control box stops it:
//! any of these makes the run degraded.

use phri_ipc::RobotStats;
use serde::Serialize;

/// The robot loop's pace in the report (`torque_loop`).
#[derive(Clone, Copy, Debug, Default, PartialEq, Serialize)]
pub struct PaceReport {
    /// periods the time between the robot's first and last statistics held
    /// (every robot process's own span, added up)
    pub cycles_expected: u64,
    /// of them, periods the robot's loop did not run (it woke too late and
    /// its schedule slipped)
    pub cycles_short: u64,
    /// braked periods before the first robot process first ran unbraked:
    /// the wait for the first command, not a slip (to the statistics'
    /// resolution, 100 periods)
    pub startup_braked_cycles: u64,
    /// overruns (of `overruns`) in that wait, while the cell's services
    /// were starting: not a slip. To the statistics' resolution, on the
    /// safe side: those of the last statistics before the loop first ran
    /// unbraked
    pub startup_overruns: u64,
    /// overruns (of `overruns`) after the run ended, while the supervisor
    /// stopped the services (the controllers before the robot): not a
    /// slip. On the safe side: the statistics window the run ended in
    /// counts as the run's
    pub shutdown_overruns: u64,
}

/// One robot process's statistics: the first and the newest (stamp [ns],
/// cycles), and its newest overrun count.
#[derive(Clone, Copy, Debug)]
struct Span {
    first: (u64, u64),
    last: (u64, u64),
    overruns: u64,
}

impl Span {
    fn expected(&self, period_ns: u64) -> u64 {
        self.last.0.saturating_sub(self.first.0) / period_ns.max(1)
    }

    fn ran(&self) -> u64 {
        self.last.1.saturating_sub(self.first.1)
    }
}

/// The running account. Allocates nothing.
#[derive(Clone, Copy, Debug)]
pub struct RobotPace {
    period_ns: u64,
    /// the current robot process's span, its statistics' last seq
    span: Option<Span>,
    last_seq: u64,
    /// the spans of the robot processes before it: expected, ran, overruns
    before: (u64, u64, u64),
    /// start-up's braked wait, once the loop first ran unbraked
    startup_braked: Option<u64>,
    /// braked cycles so far (the first process's, until it ran unbraked)
    braked_so_far: u64,
    /// start-up's overruns, once the loop first ran unbraked
    startup_overruns: Option<u64>,
    /// overruns so far (the first process's, until it ran unbraked)
    overruns_so_far: u64,
    /// when the run ended \[ns, CLOCK_MONOTONIC\], and the overruns (all
    /// processes) of the first statistics stamped after it
    stopped: Option<(u64, Option<u64>)>,
}

impl RobotPace {
    /// For a robot whose loop runs every `period_s` \[s\].
    pub fn new(period_s: f64) -> RobotPace {
        RobotPace {
            period_ns: (period_s * 1e9).round().max(1.0) as u64,
            span: None,
            last_seq: 0,
            before: (0, 0, 0),
            startup_braked: None,
            braked_so_far: 0,
            startup_overruns: None,
            overruns_so_far: 0,
            stopped: None,
        }
    }

    /// The run ended at `now_ns` \[CLOCK_MONOTONIC\]: the services are about
    /// to be stopped.
    pub fn on_stop(&mut self, now_ns: u64) {
        self.stopped.get_or_insert((now_ns, None));
    }

    /// A `robot/stats` message.
    pub fn on_stats(&mut self, m: &RobotStats) {
        if m.seq < self.last_seq {
            // a restarted robot counts from 0
            if let Some(s) = self.span.take() {
                self.before.0 += s.expected(self.period_ns);
                self.before.1 += s.ran();
                self.before.2 += s.overruns;
            }
            // a restart is no start-up: its braked wait is the restart's
            self.startup_braked.get_or_insert(self.braked_so_far);
            self.startup_overruns.get_or_insert(self.overruns_so_far);
        }
        self.last_seq = m.seq;
        let now = (m.stamp_ns, m.cycles);
        let span = self.span.get_or_insert(Span {
            first: now,
            last: now,
            overruns: 0,
        });
        (span.last, span.overruns) = (now, m.overruns);
        let total = self.overruns();
        if let Some((at, first @ None)) = self.stopped.as_mut() {
            if m.stamp_ns > *at {
                *first = Some(total);
            }
        }
        if self.startup_braked.is_none() {
            self.braked_so_far = m.braked_cycles;
            if m.cycles > m.braked_cycles {
                self.startup_braked = Some(m.braked_cycles);
                // this message's window held unbraked periods: its
                // overruns count as the run's
                self.startup_overruns = Some(self.overruns_so_far);
            } else {
                self.overruns_so_far = m.overruns;
            }
        }
    }

    /// Overruns so far, every robot process's.
    fn overruns(&self) -> u64 {
        self.before.2 + self.span.map_or(0, |s| s.overruns)
    }

    /// The pace so far.
    pub fn report(&self) -> PaceReport {
        let (mut expected, mut ran, _) = self.before;
        if let Some(s) = &self.span {
            expected += s.expected(self.period_ns);
            ran += s.ran();
        }
        PaceReport {
            cycles_expected: expected,
            cycles_short: expected.saturating_sub(ran),
            startup_braked_cycles: self.startup_braked.unwrap_or(self.braked_so_far),
            startup_overruns: self.startup_overruns.unwrap_or(self.overruns_so_far),
            shutdown_overruns: match self.stopped {
                Some((_, Some(at_stop))) => self.overruns().saturating_sub(at_stop),
                _ => 0,
            },
        }
    }
}

/// `n` with its thousands apart (`4 621`).
pub fn grouped(n: u64) -> String {
    let digits = n.to_string();
    let mut out = String::with_capacity(digits.len() + digits.len() / 3);
    for (i, c) in digits.chars().enumerate() {
        if i > 0 && (digits.len() - i).is_multiple_of(3) {
            out.push(' ');
        }
        out.push(c);
    }
    out
}

/// `n` `what`s, grouped (`1 overrun`, `4 621 overruns`).
fn counted(n: u64, what: &str) -> String {
    match n {
        1 => format!("1 {what}"),
        n => format!("{} {what}s", grouped(n)),
    }
}

/// What the robot's loop did wrong, as (a `degraded` line, its words in the
/// summary): overruns (woke more than half a period late) between start-up's
/// wait and the shutdown, with their share of the periods run and the
/// cycles short of the run's length; braked cycles after start-up's wait.
/// Empty when it kept its pace.
pub fn finding(
    cycles: u64,
    overruns: u64,
    braked_cycles: u64,
    pace: &PaceReport,
) -> Vec<(String, String)> {
    let mut out = Vec::new();
    let overruns = overruns.saturating_sub(pace.startup_overruns + pace.shutdown_overruns);
    if overruns > 0 || pace.cycles_short > 0 {
        let share = 100.0 * overruns as f64 / cycles.max(1) as f64;
        let short = 100.0 * pace.cycles_short as f64 / pace.cycles_expected.max(1) as f64;
        let over = counted(overruns, "overrun");
        out.push((
            format!(
                "robot loop behind: {over} ({share:.1} % of periods), {} cycles short of the run's {} ({short:.1} %)",
                grouped(pace.cycles_short),
                grouped(pace.cycles_expected)
            ),
            match overruns {
                // the periods not run are the finding
                0 => format!(
                    "robot loop behind: {} cycles short of the run's {}",
                    grouped(pace.cycles_short),
                    grouped(pace.cycles_expected)
                ),
                _ => format!("robot loop behind: {over}, {share:.0} % of periods"),
            },
        ));
    }
    let braked = braked_cycles.saturating_sub(pace.startup_braked_cycles);
    if braked > 0 {
        let w = counted(braked, "braked cycle");
        out.push((format!("robot braked: {w} after start-up"), w));
    }
    out
}

#[cfg(test)]
mod tests {
    use super::*;
    use phri_ipc::Zeroed;

    const MS: u64 = 1_000_000;

    fn stats(seq: u64, stamp_ms: u64, cycles: u64, braked: u64) -> RobotStats {
        let mut m = RobotStats::zeroed();
        m.seq = seq;
        m.stamp_ns = stamp_ms * MS;
        m.cycles = cycles;
        m.braked_cycles = braked;
        m
    }

    fn late(mut m: RobotStats, overruns: u64) -> RobotStats {
        m.overruns = overruns;
        m
    }

    #[test]
    fn a_loop_that_slipped_runs_fewer_cycles_than_its_time_held() {
        let mut p = RobotPace::new(0.001);
        // 300 braked periods waiting for the first command, then on time
        p.on_stats(&stats(1, 1_100, 100, 100));
        p.on_stats(&stats(2, 1_200, 200, 200));
        p.on_stats(&stats(3, 1_300, 300, 300));
        p.on_stats(&stats(4, 1_400, 400, 300));
        p.on_stats(&stats(5, 61_000, 60_000, 300));
        let r = p.report();
        assert_eq!(r.cycles_expected, 59_900);
        assert_eq!(r.cycles_short, 0);
        assert_eq!(r.startup_braked_cycles, 300);
        assert!(finding(60_000, 0, 300, &r).is_empty());
        // the same minute with 6 900 periods lost to late wake-ups
        let mut p = RobotPace::new(0.001);
        p.on_stats(&stats(1, 1_100, 100, 100));
        p.on_stats(&stats(2, 1_400, 400, 300));
        p.on_stats(&stats(3, 61_000, 53_100, 300));
        let r = p.report();
        assert_eq!((r.cycles_expected, r.cycles_short), (59_900, 6_900));
        let f = finding(53_100, 4_621, 300, &r);
        assert_eq!(f.len(), 1, "{f:?}");
        assert_eq!(f[0].1, "robot loop behind: 4 621 overruns, 9 % of periods");
        assert!(
            f[0].0
                .contains("6 900 cycles short of the run's 59 900 (11.5 %)"),
            "{}",
            f[0].0
        );
    }

    #[test]
    fn braked_cycles_after_start_up_are_a_finding_start_up_s_wait_is_not() {
        let mut p = RobotPace::new(0.001);
        p.on_stats(&stats(1, 100, 100, 100));
        p.on_stats(&stats(2, 200, 200, 150));
        // 25 braked periods in mid-run
        p.on_stats(&stats(3, 300, 300, 175));
        let r = p.report();
        assert_eq!(r.startup_braked_cycles, 150);
        let f = finding(300, 0, 175, &r);
        assert_eq!(f.len(), 1);
        assert_eq!(f[0].1, "25 braked cycles");
    }

    #[test]
    fn overruns_in_start_up_s_braked_wait_are_apart_the_run_s_are_a_finding() {
        let mut p = RobotPace::new(0.001);
        // 3 late wake-ups while the services start, the arm braked
        p.on_stats(&late(stats(1, 100, 100, 100), 2));
        p.on_stats(&late(stats(2, 200, 200, 200), 3));
        assert_eq!(p.report().startup_overruns, 3);
        // the first unbraked periods: a late wake-up in their window is the run's
        p.on_stats(&late(stats(3, 300, 300, 250), 4));
        p.on_stats(&late(stats(4, 60_000, 60_000, 250), 4));
        let r = p.report();
        assert_eq!(r.startup_overruns, 3);
        let f = finding(60_000, 4, 250, &r);
        assert_eq!(f.len(), 1, "{f:?}");
        assert_eq!(f[0].1, "robot loop behind: 1 overrun, 0 % of periods");
        // none after start-up: no finding
        assert!(finding(60_000, 3, 250, &r).is_empty());
        // a restarted robot's late wake-ups are the run's, braked or not
        p.on_stats(&late(stats(1, 60_100, 100, 100), 5));
        assert_eq!(p.report().startup_overruns, 3);
        let f = finding(60_100, 4 + 5, 350, &p.report());
        assert!(f[0].1.starts_with("robot loop behind: 6 overruns"), "{f:?}");
    }

    #[test]
    fn periods_short_without_an_overrun_are_named_as_such() {
        let r = PaceReport {
            cycles_expected: 4_605,
            cycles_short: 5,
            startup_braked_cycles: 0,
            startup_overruns: 1,
            shutdown_overruns: 0,
        };
        let f = finding(4_700, 1, 0, &r);
        assert_eq!(f.len(), 1, "{f:?}");
        assert_eq!(
            f[0].1,
            "robot loop behind: 5 cycles short of the run's 4 605"
        );
    }

    #[test]
    fn overruns_after_the_run_ended_are_the_shutdown_s() {
        let mut p = RobotPace::new(0.001);
        p.on_stats(&late(stats(1, 100, 100, 100), 1));
        p.on_stats(&late(stats(2, 1_000, 1_000, 200), 2));
        // the run ends at 1.05 s: the window it ends in is the run's
        p.on_stop(1_050 * MS);
        p.on_stats(&late(stats(3, 1_100, 1_100, 200), 4));
        p.on_stats(&late(stats(4, 1_200, 1_200, 300), 7));
        let r = p.report();
        assert_eq!((r.startup_overruns, r.shutdown_overruns), (1, 3));
        let f = finding(1_200, 7, 300, &r);
        assert_eq!(f.len(), 2, "{f:?}");
        assert!(f[0].1.starts_with("robot loop behind: 3 overruns"), "{f:?}");
        // no statistics after the stop: none is the shutdown's
        let mut p = RobotPace::new(0.001);
        p.on_stats(&late(stats(1, 100, 100, 50), 1));
        p.on_stop(150 * MS);
        assert_eq!(p.report().shutdown_overruns, 0);
    }

    #[test]
    fn a_restarted_robot_adds_its_own_span() {
        let mut p = RobotPace::new(0.001);
        p.on_stats(&stats(5, 1_000, 1_000, 100));
        p.on_stats(&stats(6, 2_000, 2_000, 100));
        // restarted 0.5 s later: its own count from 0; its braked wait is the restart's
        p.on_stats(&stats(1, 2_600, 100, 100));
        p.on_stats(&stats(2, 3_600, 1_000, 100));
        let r = p.report();
        assert_eq!(r.cycles_expected, 1_000 + 1_000);
        assert_eq!(r.cycles_short, 100);
        assert_eq!(r.startup_braked_cycles, 100);
    }

    #[test]
    fn thousands_are_grouped() {
        assert_eq!(grouped(0), "0");
        assert_eq!(grouped(999), "999");
        assert_eq!(grouped(4_621), "4 621");
        assert_eq!(grouped(1_234_567), "1 234 567");
    }
}
