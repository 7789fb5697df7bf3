//! Who starves whom. A service spinning at real-time priority takes its CPU
//! from every lower-priority service pinned there, and they fall silent on
//! their heartbeat channels: killing them restarts the victims and leaves the
//! culprit. So before a silent service is killed, the CPU time of the
//! services that share its CPUs over the last second is looked at
//! ([`CpuUse`]), and one that used most of a CPU is killed instead
//! ([`judge`]). Pure: samples come in with their time, read by the caller
//! from `/proc` ([`crate::process::cpu_time_ns`]).

use std::collections::VecDeque;

use crate::roster::Roster;

/// CPU use is judged over at most this window \[ns\] (the caller gives the
/// window: the later half of the silent service's silence, when the
/// starvation surely had begun, bounded by this).
pub const WINDOW_NS: u64 = 1_000_000_000;
/// A service that used more than this share of one CPU over the window
/// starves what shares its CPUs: a share of what the machine had of it, a
/// hypervisor's steal left out ([`CpuUse::available`]).
pub const STARVING_SHARE: f64 = 0.9;
/// Samples spanning less than this are no judgement [ns].
const MIN_SPAN_NS: u64 = 50_000_000;

/// Recent CPU-time samples of every supervised service (roster indices),
/// and what each used over the whole run.
#[derive(Clone, Debug)]
pub struct CpuUse {
    /// per service: (time [ns], CPU time so far [ns]) over the last window
    samples: Vec<Counter>,
    /// per service: its processes' CPU time and running time before the
    /// current process [ns], and the current one's first and newest sample
    totals: Vec<Total>,
    /// (time, the machine's stolen time so far per CPU) [ns] over the last window
    steal: Counter,
}

/// A growing count of nanoseconds (a process's CPU time, the machine's
/// stolen time), sampled over the last [`WINDOW_NS`]: (time, count) \[ns\].
#[derive(Clone, Debug, Default)]
struct Counter(VecDeque<(u64, u64)>);

impl Counter {
    /// The count was `count` at `now_ns` (`None`: unknown, the history is
    /// dropped); a count that went back (another process) starts a new one.
    fn record(&mut self, now_ns: u64, count: Option<u64>) {
        let Some(c) = count else {
            self.0.clear();
            return;
        };
        if self.0.back().is_some_and(|&(_, last)| c < last) {
            self.0.clear();
        }
        self.0.push_back((now_ns, c));
        while self
            .0
            .front()
            .is_some_and(|&(at, _)| now_ns.saturating_sub(at) > WINDOW_NS)
        {
            self.0.pop_front();
        }
    }

    /// How fast the count grew over the last `window_ns` of samples, in ns
    /// per ns; `None` when the samples span less than half of that window
    /// (or 50 ms).
    fn rate(&self, window_ns: u64) -> Option<f64> {
        let &(t1, c1) = self.0.back()?;
        let &(t0, c0) = self
            .0
            .iter()
            .find(|&&(t, _)| t1.saturating_sub(t) <= window_ns)?;
        let span = t1.saturating_sub(t0);
        if span < MIN_SPAN_NS.max(window_ns / 2) {
            return None;
        }
        Some(c1.saturating_sub(c0) as f64 / span as f64)
    }
}

/// A process's start-up (loading its configuration, model, files) is left
/// out of the share judged against its budget \[ns\].
pub const STARTUP_NS: u64 = 1_000_000_000;

/// One service's CPU time over the run [ns]: all of it, and past each
/// process's start-up ([`STARTUP_NS`]).
#[derive(Clone, Copy, Debug, Default)]
struct Total {
    cpu_ns: u64,
    ran_ns: u64,
    steady_cpu_ns: u64,
    steady_ran_ns: u64,
    current: Option<Process>,
}

/// The current process's samples: (time, CPU time since it started) [ns].
#[derive(Clone, Copy, Debug)]
struct Process {
    first: (u64, u64),
    /// the first sample past its start-up
    settled: Option<(u64, u64)>,
    last: (u64, u64),
}

impl Total {
    /// The current process ended (or was replaced): its use counts.
    fn fold(&mut self) {
        if let Some(p) = self.current.take() {
            self.cpu_ns += p.last.1;
            self.ran_ns += p.last.0.saturating_sub(p.first.0);
            if let Some(s) = p.settled {
                self.steady_cpu_ns += p.last.1.saturating_sub(s.1);
                self.steady_ran_ns += p.last.0.saturating_sub(s.0);
            }
        }
    }
}

/// One service's CPU use over the run (`cpu` in the report).
#[derive(Clone, Copy, Debug, Default, PartialEq, serde::Serialize)]
pub struct CpuReport {
    /// CPU time its processes used \[s\]
    pub cpu_s: f64,
    /// of one core, over the time they ran past their start-up (their
    /// first second; over all of it for a process that ran no longer)
    pub share: f64,
    /// `[services.NAME] cpu_budget` (null: not judged)
    pub budget: Option<f64>,
}

impl CpuReport {
    /// `cpu_ns` of CPU time over a run of `duration_s`, no budget (the
    /// supervisor's own): its share of one core over the run (0 for a run
    /// of no duration).
    pub fn of_run(cpu_ns: u64, duration_s: f64) -> CpuReport {
        let cpu_s = cpu_ns as f64 * 1e-9;
        let share = match duration_s > 0.0 {
            true => cpu_s / duration_s,
            false => 0.0,
        };
        CpuReport {
            cpu_s,
            share,
            budget: None,
        }
    }
}

impl CpuUse {
    /// For `services` services.
    pub fn new(services: usize) -> CpuUse {
        CpuUse {
            samples: vec![Counter::default(); services],
            totals: vec![Total::default(); services],
            steal: Counter::default(),
        }
    }

    /// The machine had lost `steal_ns` per CPU to its hypervisor at `now_ns`
    /// (`None`: unknown, the history is dropped).
    pub fn record_steal(&mut self, now_ns: u64, steal_ns: Option<u64>) {
        self.steal.record(now_ns, steal_ns);
    }

    /// The share of each CPU the hypervisor left the machine over the last
    /// `window_ns` \[0.25, 1\]: 1 without samples (not a virtual machine,
    /// or not known). A process that had all of a CPU the machine had shows
    /// this share of the wall clock in its CPU time.
    pub fn available(&self, window_ns: u64) -> f64 {
        self.steal
            .rate(window_ns)
            .map_or(1.0, |stolen| (1.0 - stolen).clamp(0.25, 1.0))
    }

    /// What service `index` used over the run so far, with its `budget`.
    /// `None` before two samples of a process of it.
    pub fn over_the_run(&self, index: usize, budget: Option<f64>) -> Option<CpuReport> {
        let mut t = *self.totals.get(index)?;
        t.fold();
        if t.ran_ns == 0 {
            return None;
        }
        let share = match t.steady_ran_ns {
            0 => t.cpu_ns as f64 / t.ran_ns as f64,
            ran => t.steady_cpu_ns as f64 / ran as f64,
        };
        Some(CpuReport {
            cpu_s: t.cpu_ns as f64 * 1e-9,
            share,
            budget,
        })
    }

    /// Every service of `roster` with what it used over the run, against
    /// its `cpu_budget` (`cpu` in the report); services never sampled are
    /// left out.
    pub fn report(&self, roster: &Roster) -> std::collections::BTreeMap<String, CpuReport> {
        roster
            .iter()
            .enumerate()
            .filter_map(|(i, s)| Some((s.name.clone(), self.over_the_run(i, s.spec.cpu_budget)?)))
            .collect()
    }

    fn total(&mut self, index: usize, now_ns: u64, cpu_ns: Option<u64>) {
        let Some(t) = self.totals.get_mut(index) else {
            return;
        };
        match (cpu_ns, t.current.as_mut()) {
            (None, _) => t.fold(),
            (Some(c), Some(p)) if c >= p.last.1 => {
                p.last = (now_ns, c);
                if p.settled.is_none() && now_ns.saturating_sub(p.first.0) >= STARTUP_NS {
                    p.settled = Some(p.last);
                }
            }
            (Some(c), _) => {
                // a new process (a restart): the one before counts
                t.fold();
                t.current = Some(Process {
                    first: (now_ns, c),
                    settled: None,
                    last: (now_ns, c),
                });
            }
        }
    }

    /// Service `index` had used `cpu_ns` of CPU time at `now_ns` (`None`: it
    /// is not running; its history is dropped).
    pub fn record(&mut self, index: usize, now_ns: u64, cpu_ns: Option<u64>) {
        self.total(index, now_ns, cpu_ns);
        if let Some(s) = self.samples.get_mut(index) {
            s.record(now_ns, cpu_ns);
        }
    }

    /// Service `index` was (re)started: its history is another process's.
    pub fn restarted(&mut self, index: usize) {
        if let Some(s) = self.samples.get_mut(index) {
            s.0.clear();
        }
        if let Some(t) = self.totals.get_mut(index) {
            t.fold();
        }
    }

    /// Share of one CPU service `index` used over the last `window_ns` of
    /// samples (1.0: a whole CPU); `None` when its samples span less than
    /// half of that window (or 50 ms).
    pub fn share(&self, index: usize, window_ns: u64) -> Option<f64> {
        self.samples.get(index)?.rate(window_ns)
    }
}

/// The services that used more than their CPU budget, as (a `degraded`
/// line, its words in the summary), by name.
pub fn over_budget(cpu: &std::collections::BTreeMap<String, CpuReport>) -> Vec<(String, String)> {
    let over: Vec<(&String, &CpuReport, f64)> = cpu
        .iter()
        .filter_map(|(n, c)| Some((n, c, c.budget?)))
        .filter(|(_, c, b)| c.share > *b)
        .collect();
    if over.is_empty() {
        return Vec::new();
    }
    let each: Vec<String> = over
        .iter()
        .map(|(n, c, b)| format!("{n} {:.0} % of {:.0} %", 100.0 * c.share, 100.0 * b))
        .collect();
    vec![(
        format!(
            "CPU over budget (share of one core over the time each ran, against [services.NAME] cpu_budget): {}",
            each.join(", ")
        ),
        format!("CPU over budget: {}", each.join(", ")),
    )]
}

/// Two CPU sets overlap (an empty set is any CPU).
pub fn share_cpus(a: &[usize], b: &[usize]) -> bool {
    a.is_empty() || b.is_empty() || a.iter().any(|c| b.contains(c))
}

/// What the CPU use of the services sharing a silent service's CPUs says of
/// its silence.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum Verdict {
    /// another service used more than [`STARVING_SHARE`] of a CPU they
    /// share: it starved the silent one (its index and share)
    Starved {
        /// roster index of the service that starved it
        culprit: usize,
        /// the share of one CPU it used over the window (1.0: a whole CPU)
        share: f64,
    },
    /// nobody starved it: frozen by itself (the busiest service on its
    /// CPUs, itself included, and its share)
    Frozen {
        /// roster index of the busiest service on its CPUs (maybe itself)
        busiest: usize,
        /// the share of one CPU it used over the window (1.0: a whole CPU)
        share: f64,
    },
}

/// Judge a silence of `silent_ns` on `frozen`'s heartbeat over its later
/// half (the starvation had surely begun by then) or, when that half holds
/// too few CPU samples because the supervisor itself was held up for part
/// of it, over the whole silence (windows clamped to 0.1-1 × [`WINDOW_NS`]).
/// Shares are of what the machine had of a CPU ([`CpuUse::available`]).
/// `None` without samples over either: no verdict without evidence.
pub fn judge(roster: &Roster, cpu: &CpuUse, frozen: usize, silent_ns: u64) -> Option<Verdict> {
    let clamp = |w: u64| w.clamp(WINDOW_NS / 10, WINDOW_NS);
    [clamp(silent_ns / 2), clamp(silent_ns)]
        .into_iter()
        .find_map(|window| {
            let (index, share) = busiest(roster, cpu, frozen, window)?;
            Some((index, share / cpu.available(window)))
        })
        .map(|(index, share)| {
            if share > STARVING_SHARE && index != frozen {
                Verdict::Starved {
                    culprit: index,
                    share,
                }
            } else {
                Verdict::Frozen {
                    busiest: index,
                    share,
                }
            }
        })
}

/// The running service sharing `frozen`'s CPUs (itself included) that used
/// the largest share of a CPU over the last `window_ns`, and that share.
pub fn busiest(
    roster: &Roster,
    cpu: &CpuUse,
    frozen: usize,
    window_ns: u64,
) -> Option<(usize, f64)> {
    let cpus = &roster.get(frozen).spec.cpus;
    roster
        .iter()
        .enumerate()
        .filter(|(_, s)| s.alive() && share_cpus(cpus, &s.spec.cpus))
        .filter_map(|(i, _)| Some((i, cpu.share(i, window_ns)?)))
        .max_by(|a, b| a.1.total_cmp(&b.1))
}

#[cfg(test)]
mod tests {
    use super::*;

    const MS: u64 = 1_000_000;

    #[test]
    fn the_supervisor_s_own_share_is_its_time_over_the_run() {
        let r = CpuReport::of_run(1_500 * MS, 60.0);
        assert!((r.cpu_s - 1.5).abs() < 1e-12 && (r.share - 0.025).abs() < 1e-12);
        assert_eq!(r.budget, None);
        assert_eq!(CpuReport::of_run(7, 0.0).share, 0.0);
    }

    /// camera and spinner on CPU 0, sim on CPU 1, all running.
    fn roster() -> Roster {
        let config = phri_config::Config::defaults();
        let spec = |cpus: &[usize]| phri_config::ServiceSpec {
            cpus: cpus.to_vec(),
            ..config.services["camera"].clone()
        };
        let mut r = Roster::new(
            config.supervisor.clone(),
            vec![
                ("sim".into(), spec(&[1])),
                ("camera".into(), spec(&[0])),
                ("spinner".into(), spec(&[0])),
            ],
        );
        for i in 0..3 {
            r.started(i, 0, 100 + i as u32);
        }
        r
    }

    /// Every 50 ms for `ms`: each service's share of a CPU.
    fn sample(cpu: &mut CpuUse, from_ms: u64, ms: u64, shares: &[f64]) {
        for t in (from_ms..=from_ms + ms).step_by(50) {
            for (i, s) in shares.iter().enumerate() {
                cpu.record(i, t * MS, Some((t as f64 * MS as f64 * s) as u64));
            }
        }
    }

    /// The service starving `frozen`, judged over the last `window_ns`
    /// (the later half of a silence twice as long), and its share.
    fn culprit(r: &Roster, cpu: &CpuUse, frozen: usize, window_ns: u64) -> Option<(usize, f64)> {
        match judge(r, cpu, frozen, 2 * window_ns) {
            Some(Verdict::Starved { culprit, share }) => Some((culprit, share)),
            _ => None,
        }
    }

    #[test]
    fn a_spinner_on_the_silent_services_cpu_is_the_culprit() {
        let r = roster();
        let mut cpu = CpuUse::new(3);
        // not enough history yet: no verdict
        sample(&mut cpu, 0, 300, &[0.3, 0.0, 1.0]);
        assert_eq!(judge(&r, &cpu, 1, 2 * WINDOW_NS), None);
        let mut cpu = CpuUse::new(3);
        sample(&mut cpu, 400, 2000, &[0.3, 0.0, 0.97]);
        let (i, share) = culprit(&r, &cpu, 1, WINDOW_NS).unwrap();
        assert_eq!(i, 2);
        assert!((share - 0.97).abs() < 0.02, "{share}");
        // the spinner began 200 ms ago: over the silence only, it is the culprit
        let mut cpu = CpuUse::new(3);
        sample(&mut cpu, 0, 1000, &[0.3, 0.2, 0.0]);
        for t in (1050..=1300).step_by(50) {
            cpu.record(2, t * MS, Some((t - 1000) * MS));
        }
        assert_eq!(culprit(&r, &cpu, 1, WINDOW_NS).map(|c| c.0), None);
        assert_eq!(culprit(&r, &cpu, 1, WINDOW_NS / 5).map(|c| c.0), Some(2));
        // the simulator shares no CPU with it: its own silence is its own
        assert_eq!(culprit(&r, &cpu, 0, WINDOW_NS), None);
    }

    #[test]
    fn each_service_s_cpu_over_the_run_adds_its_processes_and_is_judged_against_its_budget() {
        let mut cpu = CpuUse::new(2);
        assert_eq!(cpu.over_the_run(0, None), None);
        // 20 % of a core for 2 s, killed, restarted: 40 % for 2 s; the
        // share judged leaves each process's first second out
        for t in (0..=2000).step_by(50) {
            cpu.record(0, t * MS, Some(t * MS / 5));
        }
        cpu.record(0, 2050 * MS, None);
        for t in (2100..=4100).step_by(50) {
            cpu.record(0, t * MS, Some((t - 2100) * MS * 2 / 5));
        }
        let c = cpu.over_the_run(0, Some(0.25)).unwrap();
        assert!((c.cpu_s - 1.2).abs() < 1e-9, "{c:?}");
        assert!((c.share - 0.3).abs() < 1e-9, "{c:?}");
        // a restart seen only as CPU time going back counts the same
        let mut again = CpuUse::new(1);
        for t in (0..=2000).step_by(50) {
            again.record(0, t * MS, Some(t * MS / 5));
        }
        for t in (2100..=4100).step_by(50) {
            again.record(0, t * MS, Some((t - 2100) * MS * 2 / 5));
        }
        assert_eq!(again.over_the_run(0, Some(0.25)), Some(c));
        // a process shorter than its start-up: judged over all of it
        let mut short = CpuUse::new(1);
        for t in (0..=500).step_by(50) {
            short.record(0, t * MS, Some(t * MS / 2));
        }
        let s = short.over_the_run(0, None).unwrap();
        assert!((s.share - 0.5).abs() < 1e-9, "{s:?}");
        let mut report = std::collections::BTreeMap::new();
        report.insert("sim".to_string(), c);
        let under = CpuReport {
            budget: Some(0.35),
            ..c
        };
        report.insert("camera".to_string(), under);
        report.insert("free".to_string(), CpuReport { budget: None, ..c });
        let f = over_budget(&report);
        assert_eq!(f.len(), 1);
        assert_eq!(f[0].1, "CPU over budget: sim 30 % of 25 %");
        report.remove("sim");
        assert!(over_budget(&report).is_empty());
    }

    #[test]
    fn the_report_names_each_sampled_service_with_its_budget() {
        let r = roster();
        let mut cpu = CpuUse::new(3);
        // the spinner idle, then stopped: its run still counts
        sample(&mut cpu, 0, 2000, &[0.3, 0.1, 0.0]);
        cpu.record(2, 2050 * MS, None);
        let report = cpu.report(&r);
        let camera = r.get(1).spec.cpu_budget;
        assert_eq!(
            report.keys().map(String::as_str).collect::<Vec<_>>(),
            ["camera", "sim", "spinner"]
        );
        assert_eq!(report["camera"].budget, camera);
        assert!((report["sim"].share - 0.3).abs() < 1e-6, "{report:?}");
        assert!((report["camera"].share - 0.1).abs() < 1e-6, "{report:?}");
        assert_eq!(report["spinner"].share, 0.0);
        // a service never sampled is left out
        assert!(CpuUse::new(3).report(&r).is_empty());
    }

    #[test]
    fn a_spinner_short_of_the_threshold_only_by_a_hypervisor_s_steal_is_the_culprit() {
        let r = roster();
        let mut cpu = CpuUse::new(3);
        // the spinner's CPU time: 85 % of the wall clock
        sample(&mut cpu, 0, 2000, &[0.3, 0.0, 0.85]);
        assert_eq!(culprit(&r, &cpu, 1, WINDOW_NS), None);
        // the hypervisor took 15 % of each CPU meanwhile: the spinner had
        // all the machine had of its CPU
        for t in (0..=2000u64).step_by(50) {
            cpu.record_steal(t * MS, Some(t * MS * 15 / 100));
        }
        assert!((cpu.available(WINDOW_NS) - 0.85).abs() < 1e-9);
        let (who, share) = culprit(&r, &cpu, 1, WINDOW_NS).expect("the spinner");
        assert_eq!(who, 2);
        assert!((share - 1.0).abs() < 1e-9, "{share}");
        // steal unknown (a sample missing): judged on the wall clock again
        cpu.record_steal(2050 * MS, None);
        assert_eq!(cpu.available(WINDOW_NS), 1.0);
        assert_eq!(culprit(&r, &cpu, 1, WINDOW_NS), None);
    }

    #[test]
    fn a_busy_service_below_the_threshold_or_the_silent_one_itself_is_no_culprit() {
        let r = roster();
        let mut cpu = CpuUse::new(3);
        sample(&mut cpu, 0, 2000, &[0.3, 0.1, 0.8]);
        assert_eq!(culprit(&r, &cpu, 1, WINDOW_NS), None);
        // the silent service spins itself: kill it, as any frozen service
        let mut cpu = CpuUse::new(3);
        sample(&mut cpu, 0, 2000, &[0.3, 0.99, 0.0]);
        assert_eq!(culprit(&r, &cpu, 1, WINDOW_NS), None);
    }

    #[test]
    fn a_silence_the_supervisor_was_held_up_in_is_judged_over_all_of_it() {
        let r = roster();
        let mut cpu = CpuUse::new(3);
        // sampled every 20 ms, the camera (1) stopped at 903 ms; the
        // supervisor held up from 1000 to 1108 ms, then sampling again
        for t in (0..=1000).step_by(20).chain([1108, 1128]) {
            cpu.record(0, t * MS, Some(t * MS * 3 / 10));
            cpu.record(1, t * MS, Some(t.min(903) * MS / 5));
            cpu.record(2, t * MS, Some(t * MS / 10));
        }
        let silent = 225 * MS;
        // the later half of the silence holds 20 ms of samples: too few
        assert_eq!(busiest(&r, &cpu, 1, silent / 2), None);
        // the whole silence holds enough: nobody starved it, it is frozen
        match judge(&r, &cpu, 1, silent) {
            Some(Verdict::Frozen { busiest, share }) => {
                assert_eq!(busiest, 2);
                assert!((share - 0.1).abs() < 0.01, "{share}");
            }
            other => panic!("{other:?}"),
        }
        // a spinner over the whole silence is still the culprit
        let mut cpu = CpuUse::new(3);
        for t in (0..=1000).step_by(20).chain([1108, 1128]) {
            cpu.record(1, t * MS, Some(t.min(903) * MS / 5));
            cpu.record(2, t * MS, Some(t.saturating_sub(900) * MS));
        }
        assert!(matches!(
            judge(&r, &cpu, 1, silent),
            Some(Verdict::Starved { culprit: 2, .. })
        ));
        // no samples at all over the silence: no verdict
        let mut cpu = CpuUse::new(3);
        for t in [1108, 1128] {
            cpu.record(1, t * MS, Some(0));
            cpu.record(2, t * MS, Some(0));
        }
        assert_eq!(judge(&r, &cpu, 1, silent), None);
    }

    #[test]
    fn history_ends_with_the_process() {
        let mut r = roster();
        let mut cpu = CpuUse::new(3);
        sample(&mut cpu, 0, 2000, &[0.3, 0.0, 0.99]);
        // the spinner died: no longer running, no longer blamed
        r.exited(2, 2000 * MS);
        assert_eq!(culprit(&r, &cpu, 1, WINDOW_NS), None);
        // a new process: its CPU time starts again from 0
        r.started(2, 2050 * MS, 300);
        cpu.record(2, 2100 * MS, Some(MS));
        assert_eq!(cpu.share(2, WINDOW_NS), None);
        cpu.record(2, 2200 * MS, None);
        assert_eq!(cpu.share(2, WINDOW_NS), None);
        assert!(share_cpus(&[], &[3]) && share_cpus(&[0, 1], &[1]) && !share_cpus(&[0], &[1]));
    }
}
