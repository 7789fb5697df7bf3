//! Real-time scheduling as the cell gets it, not as it was asked for: a
//! probe before the start (is SCHED_FIFO at the configured priority, and the
//! configured pinning, permitted here?), and, once each service of the
//! torque loop or perception (`rt_priority > 0`) runs, what the kernel says
//! it runs under (its threads' policy and priority, its CPUs, its locked
//! memory), judged against its `[services.*]` entry. A run that did not get
//! what it asked for is a degraded run: the report's `realtime` and
//! `degraded` name each service and what it lacked.

use std::collections::BTreeMap;
use std::fmt;

use serde::Serialize;

/// What a service is configured to get (`[services.*] rt_priority`, `cpus`).
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct Wanted {
    /// SCHED_FIFO priority (1-99; 0: the normal scheduler, nothing to judge)
    pub priority: i32,
    /// CPUs to pin it to (empty: not pinned)
    pub cpus: Vec<usize>,
}

/// What a running service has, as the kernel reports it.
#[derive(Clone, Debug, Default, PartialEq, Eq)]
pub struct Observed {
    /// the highest real-time priority among its threads (`None`: every
    /// thread under the normal scheduler)
    pub priority: Option<i32>,
    /// the CPUs its main thread may run on
    pub cpus: Vec<usize>,
    /// memory locked into RAM \[kB\] (`VmLck`)
    pub locked_kb: u64,
}

/// One thing a service did not get.
#[derive(Clone, Debug, PartialEq, Eq)]
pub enum Shortfall {
    /// not under SCHED_FIFO at the configured priority
    Scheduler {
        /// the configured priority (at most 99)
        wanted: i32,
        /// the highest real-time priority among its threads (`None`: the
        /// normal scheduler)
        got: Option<i32>,
    },
    /// CPUs configured that this machine does not have online
    MissingCpus {
        /// the configured CPUs, sorted
        wanted: Vec<usize>,
        /// how many CPUs this machine has online
        online: usize,
    },
    /// pinned elsewhere than configured (or not pinned)
    Cpus {
        /// the configured CPUs, sorted
        wanted: Vec<usize>,
        /// the CPUs its main thread may run on
        got: Vec<usize>,
    },
    /// real-time, but its memory is not locked (page faults can stall it)
    Unlocked,
}

impl Shortfall {
    /// The summary line's words for this kind of shortfall.
    pub fn kind(&self) -> &'static str {
        match self {
            Shortfall::Scheduler { .. } => "no real-time scheduling",
            Shortfall::MissingCpus { .. } | Shortfall::Cpus { .. } => "no CPU pinning",
            Shortfall::Unlocked => "memory not locked",
        }
    }
}

fn cpu_list(cpus: &[usize]) -> String {
    if cpus.is_empty() {
        return "none".into();
    }
    cpus.iter()
        .map(usize::to_string)
        .collect::<Vec<_>>()
        .join(",")
}

impl fmt::Display for Shortfall {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        match self {
            Shortfall::Scheduler { wanted, got: None } => {
                write!(f, "SCHED_OTHER instead of SCHED_FIFO {wanted}")
            }
            Shortfall::Scheduler {
                wanted,
                got: Some(p),
            } => write!(f, "real-time priority {p} instead of {wanted}"),
            Shortfall::MissingCpus { wanted, online } => write!(
                f,
                "pinned to CPUs {} configured, {online} CPU(s) online",
                cpu_list(wanted)
            ),
            Shortfall::Cpus { wanted, got } => write!(
                f,
                "runs on CPUs {} instead of {}",
                cpu_list(got),
                cpu_list(wanted)
            ),
            Shortfall::Unlocked => write!(f, "memory not locked (mlockall refused)"),
        }
    }
}

/// Judge what a service got against what it was configured to get, on a
/// machine with `online` CPUs. Services without a real-time priority are
/// not judged.
pub fn judge(wanted: &Wanted, observed: &Observed, online: usize) -> Vec<Shortfall> {
    let mut out = Vec::new();
    if wanted.priority <= 0 {
        return out;
    }
    let want_p = wanted.priority.min(99);
    let fifo = observed.priority.is_some_and(|p| p >= want_p);
    if !fifo {
        out.push(Shortfall::Scheduler {
            wanted: want_p,
            got: observed.priority,
        });
    }
    let mut want_cpus = wanted.cpus.clone();
    want_cpus.sort_unstable();
    want_cpus.dedup();
    if !want_cpus.is_empty() {
        if want_cpus.iter().any(|&c| c >= online) {
            out.push(Shortfall::MissingCpus {
                wanted: want_cpus,
                online,
            });
        } else if observed.cpus != want_cpus {
            out.push(Shortfall::Cpus {
                wanted: want_cpus,
                got: observed.cpus.clone(),
            });
        }
    }
    // mlockall follows SCHED_FIFO: without the one the other was not tried
    if fifo && observed.locked_kb == 0 {
        out.push(Shortfall::Unlocked);
    }
    out
}

/// `realtime.services.NAME` in the report.
#[derive(Clone, Debug, Default, PartialEq, Serialize)]
pub struct ServiceRt {
    /// configured SCHED_FIFO priority
    pub wanted_priority: i32,
    /// the highest real-time priority its threads ran at (null: SCHED_OTHER),
    /// the lowest over its processes (restarts)
    pub priority: Option<i32>,
    /// configured CPUs
    pub wanted_cpus: Vec<usize>,
    /// the CPUs it ran on (its last process)
    pub cpus: Vec<usize>,
    /// every process of it had its memory locked
    pub memory_locked: bool,
    /// processes observed (1 + restarts seen)
    pub processes: u32,
    /// what it lacked, in words (empty: it got everything)
    pub shortfalls: Vec<String>,
    /// the summary's words for what it lacked ([`Shortfall::kind`])
    #[serde(skip)]
    pub kinds: Vec<&'static str>,
}

/// `realtime` in the report.
#[derive(Clone, Debug, Default, PartialEq, Serialize)]
pub struct RealtimeReport {
    /// SCHED_FIFO at the highest configured priority was permitted when the
    /// cell started (the probe)
    pub permitted: bool,
    /// why not, when it was not
    pub refusal: Option<String>,
    /// the services with a real-time priority, as they ran
    pub services: BTreeMap<String, ServiceRt>,
}

impl RealtimeReport {
    /// The report's `degraded` lines: one per service that lacked something.
    pub fn degraded(&self) -> Vec<String> {
        self.services
            .iter()
            .filter(|(_, s)| !s.shortfalls.is_empty())
            .map(|(name, s)| format!("real-time: {name} {}", s.shortfalls.join("; ")))
            .collect()
    }

    /// The summary line's words (`no real-time scheduling`, `no CPU
    /// pinning`, `memory not locked`), each once, in that order.
    pub fn kinds(&self) -> Vec<&'static str> {
        let mut kinds: Vec<&'static str> = Vec::new();
        if !self.permitted {
            kinds.push("no real-time scheduling");
        }
        for k in [
            "no real-time scheduling",
            "no CPU pinning",
            "memory not locked",
        ] {
            let seen = self.services.values().any(|s| s.kinds.contains(&k));
            if seen && !kinds.contains(&k) {
                kinds.push(k);
            }
        }
        kinds
    }
}

/// The services' real-time state over the run: which process of each was
/// judged, and what each got.
#[derive(Clone, Debug, Default)]
pub struct RealtimeWatch {
    report: RealtimeReport,
    /// per service: the pid last judged
    judged: BTreeMap<String, u32>,
    /// per service: the kinds of shortfall found (kept across restarts)
    found: BTreeMap<String, Vec<Shortfall>>,
}

impl RealtimeWatch {
    /// A watch after the start's probe (`refusal`: why SCHED_FIFO was refused).
    pub fn new(refusal: Option<String>) -> RealtimeWatch {
        RealtimeWatch {
            report: RealtimeReport {
                permitted: refusal.is_none(),
                refusal,
                services: BTreeMap::new(),
            },
            ..Default::default()
        }
    }

    /// SCHED_FIFO was permitted when the run started.
    pub fn permitted(&self) -> bool {
        self.report.permitted
    }

    /// Process `pid` of service `name` is not judged yet.
    pub fn due(&self, name: &str, pid: u32) -> bool {
        self.judged.get(name) != Some(&pid)
    }

    /// Record what process `pid` of `name` got; returns what it lacked.
    pub fn record(
        &mut self,
        name: &str,
        pid: u32,
        wanted: &Wanted,
        observed: &Observed,
        online: usize,
    ) -> Vec<Shortfall> {
        self.judged.insert(name.to_string(), pid);
        let short = judge(wanted, observed, online);
        let found = self.found.entry(name.to_string()).or_default();
        for s in &short {
            if !found.contains(s) {
                found.push(s.clone());
            }
        }
        let entry = self.report.services.entry(name.to_string()).or_default();
        let first = entry.processes == 0;
        entry.wanted_priority = wanted.priority;
        entry.wanted_cpus = wanted.cpus.clone();
        entry.priority = if first {
            observed.priority
        } else {
            entry.priority.min(observed.priority)
        };
        entry.cpus = observed.cpus.clone();
        entry.memory_locked = (first || entry.memory_locked) && observed.locked_kb > 0;
        entry.processes += 1;
        entry.shortfalls = found.iter().map(Shortfall::to_string).collect();
        entry.kinds = found.iter().map(Shortfall::kind).collect();
        short
    }

    /// `realtime` in the report, as judged so far.
    pub fn report(&self) -> RealtimeReport {
        self.report.clone()
    }
}

/// The two controllers of a hot standby swap priorities with their role
/// (the one in charge runs at the higher of their `rt_priority`, the
/// other at the lower: `phri_control::standby::RolePriority`): each is
/// judged against the lower.
pub fn role_ranked(wanted: &mut [(String, Wanted)]) {
    let prio = |w: &[(String, Wanted)], n: &str| {
        w.iter()
            .find(|(name, _)| name == n)
            .map(|(_, w)| w.priority)
    };
    let (Some(a), Some(b)) = (prio(wanted, "control"), prio(wanted, "control_standby")) else {
        return;
    };
    for (name, w) in wanted.iter_mut() {
        if name == "control" || name == "control_standby" {
            w.priority = a.min(b);
        }
    }
}

/// Why SCHED_FIFO at a priority would not be granted.
#[derive(Debug, thiserror::Error)]
pub enum ProbeError {
    /// the kernel refused it (no CAP_SYS_NICE, an rtprio limit)
    #[error("SCHED_FIFO {priority} refused: {source}")]
    Refused {
        /// the SCHED_FIFO priority asked for
        priority: i32,
        /// the kernel's error
        source: std::io::Error,
    },
    /// the scratch thread that asked did not come back
    #[error("SCHED_FIFO {priority}: the probe failed")]
    Failed {
        /// the SCHED_FIFO priority asked for
        priority: i32,
    },
}

/// What the services of a run ask for that this machine refuses.
#[derive(Debug, thiserror::Error)]
#[error("{}", self.describe())]
pub struct Refused {
    /// the highest priority asked for, refused, and the service asking
    pub scheduler: Option<(ProbeError, String)>,
    /// services pinned to CPUs this process may not use: (service, CPUs)
    pub pinning: Vec<(String, Vec<usize>)>,
    /// the CPUs this process may run on
    pub allowed: Vec<usize>,
}

impl Refused {
    /// One line: the refused scheduler, then the refused pinning.
    fn describe(&self) -> String {
        let mut parts = Vec::new();
        if let Some((e, name)) = &self.scheduler {
            parts.push(format!("{e} ({name})"));
        }
        if !self.pinning.is_empty() {
            let each: Vec<String> = self
                .pinning
                .iter()
                .map(|(name, cpus)| format!("{name} on CPU {}", cpu_list(cpus)))
                .collect();
            parts.push(format!(
                "pinning refused: {} (this process may run on CPUs {})",
                each.join(", "),
                cpu_list(&self.allowed)
            ));
        }
        parts.join("; ")
    }
}

/// Try SCHED_FIFO at `priority` on a scratch thread (then back to the
/// normal scheduler): would a service be granted it? `Err` says why not.
pub fn probe(priority: i32) -> Result<(), ProbeError> {
    if priority <= 0 {
        return Ok(());
    }
    let priority = priority.min(99);
    let probe = std::thread::spawn(move || {
        let param = libc::sched_param {
            sched_priority: priority,
        };
        // SAFETY: plain syscalls on the calling thread with valid arguments
        let rc = unsafe { libc::sched_setscheduler(0, libc::SCHED_FIFO, &param) };
        if rc != 0 {
            return Err(std::io::Error::last_os_error());
        }
        let normal = libc::sched_param { sched_priority: 0 };
        // SAFETY: as above
        unsafe { libc::sched_setscheduler(0, libc::SCHED_OTHER, &normal) };
        Ok(())
    });
    match probe.join() {
        Ok(Ok(())) => Ok(()),
        Ok(Err(source)) => Err(ProbeError::Refused { priority, source }),
        Err(_) => Err(ProbeError::Failed { priority }),
    }
}

/// The CPUs this process may run on (its affinity mask).
pub fn own_cpus() -> Vec<usize> {
    affinity(0)
}

/// The CPUs that thread or process `pid` may run on (0: the caller).
fn affinity(pid: i32) -> Vec<usize> {
    // SAFETY: a zeroed cpu_set_t is valid; sched_getaffinity fills it
    let mut set: libc::cpu_set_t = unsafe { std::mem::zeroed() };
    // SAFETY: valid pointer and size
    let rc =
        unsafe { libc::sched_getaffinity(pid, std::mem::size_of::<libc::cpu_set_t>(), &mut set) };
    if rc != 0 {
        return Vec::new();
    }
    (0..libc::CPU_SETSIZE as usize)
        // SAFETY: c is within the set's size
        .filter(|&c| unsafe { libc::CPU_ISSET(c, &set) })
        .collect()
}

/// What process `pid` runs under now (`None`: it is gone).
pub fn observe(pid: u32) -> Option<Observed> {
    let tasks = std::fs::read_dir(format!("/proc/{pid}/task")).ok()?;
    let mut priority: Option<i32> = None;
    for t in tasks.flatten() {
        let Some(tid) = t.file_name().to_str().and_then(|s| s.parse::<i32>().ok()) else {
            continue;
        };
        // SAFETY: plain syscalls on a thread id; failures are checked
        let policy = unsafe { libc::sched_getscheduler(tid) };
        if policy != libc::SCHED_FIFO && policy != libc::SCHED_RR {
            continue;
        }
        let mut param = libc::sched_param { sched_priority: 0 };
        // SAFETY: valid pointer
        if unsafe { libc::sched_getparam(tid, &mut param) } == 0 {
            priority = Some(priority.map_or(param.sched_priority, |p| p.max(param.sched_priority)));
        }
    }
    let status = std::fs::read_to_string(format!("/proc/{pid}/status")).ok()?;
    let locked_kb = status
        .lines()
        .find_map(|l| l.strip_prefix("VmLck:"))
        .and_then(|v| v.split_whitespace().next()?.parse().ok())
        .unwrap_or(0);
    Some(Observed {
        priority,
        cpus: affinity(pid as i32),
        locked_kb,
    })
}

/// Before the start: is what `services` ask for permitted here? The
/// highest configured priority is probed, and every configured CPU must be
/// online and in this process's own affinity (a container's cpuset). `Err`
/// says what is refused (in one line, displayed).
pub fn probe_services<'a>(
    services: impl Iterator<Item = (&'a str, &'a Wanted)>,
    online: usize,
) -> Result<(), Refused> {
    let mut highest: Option<(i32, &str)> = None;
    let mut missing: Vec<(String, Vec<usize>)> = Vec::new();
    let allowed = own_cpus();
    for (name, w) in services.filter(|(_, w)| w.priority > 0) {
        if highest.is_none_or(|(p, _)| w.priority > p) {
            highest = Some((w.priority, name));
        }
        let absent: Vec<usize> = w
            .cpus
            .iter()
            .copied()
            .filter(|&c| c >= online || !allowed.contains(&c))
            .collect();
        if !absent.is_empty() {
            missing.push((name.to_string(), absent));
        }
    }
    let scheduler = highest.and_then(|(p, name)| Some((probe(p).err()?, name.to_string())));
    if scheduler.is_none() && missing.is_empty() {
        return Ok(());
    }
    Err(Refused {
        scheduler,
        pinning: missing,
        allowed,
    })
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn the_two_controllers_are_judged_against_the_lower_priority() {
        let mut w = vec![
            ("sim".to_string(), want(80, &[1])),
            ("control".to_string(), want(79, &[1])),
            ("control_standby".to_string(), want(77, &[1])),
        ];
        role_ranked(&mut w);
        let p: Vec<i32> = w.iter().map(|(_, w)| w.priority).collect();
        assert_eq!(p, [80, 77, 77]);
        // one controller alone keeps its own
        let mut one = vec![("control".to_string(), want(79, &[1]))];
        role_ranked(&mut one);
        assert_eq!(one[0].1.priority, 79);
    }

    fn want(p: i32, cpus: &[usize]) -> Wanted {
        Wanted {
            priority: p,
            cpus: cpus.to_vec(),
        }
    }

    fn got(p: Option<i32>, cpus: &[usize], kb: u64) -> Observed {
        Observed {
            priority: p,
            cpus: cpus.to_vec(),
            locked_kb: kb,
        }
    }

    #[test]
    fn a_service_that_got_what_it_asked_for_lacks_nothing() {
        assert!(judge(&want(79, &[1]), &got(Some(79), &[1], 4000), 2).is_empty());
        // no priority configured: not judged whatever it runs under
        assert!(judge(&want(0, &[0]), &got(None, &[0, 1], 0), 2).is_empty());
    }

    #[test]
    fn each_refusal_is_named() {
        let s = judge(&want(79, &[1]), &got(None, &[1], 0), 2);
        assert_eq!(
            s,
            [Shortfall::Scheduler {
                wanted: 79,
                got: None
            }]
        );
        assert_eq!(s[0].to_string(), "SCHED_OTHER instead of SCHED_FIFO 79");
        assert_eq!(s[0].kind(), "no real-time scheduling");
        // a lower priority than configured (an rtprio limit)
        let s = judge(&want(79, &[1]), &got(Some(50), &[1], 10), 2);
        assert_eq!(s[0].to_string(), "real-time priority 50 instead of 79");
        // pinning lost: runs anywhere
        let s = judge(&want(79, &[1]), &got(Some(79), &[0, 1], 10), 2);
        assert_eq!(s[0].to_string(), "runs on CPUs 0,1 instead of 1");
        assert_eq!(s[0].kind(), "no CPU pinning");
        // a CPU the machine lacks
        let s = judge(&want(79, &[1]), &got(Some(79), &[0], 10), 1);
        assert_eq!(
            s,
            [Shortfall::MissingCpus {
                wanted: vec![1],
                online: 1
            }]
        );
        // real-time but unlocked
        let s = judge(&want(79, &[]), &got(Some(79), &[0, 1], 0), 2);
        assert_eq!(s, [Shortfall::Unlocked]);
    }

    #[test]
    fn the_watch_judges_each_process_once_and_keeps_what_any_lacked() {
        let mut w = RealtimeWatch::new(None);
        let wanted = want(79, &[1]);
        assert!(w.due("control", 10));
        assert!(w
            .record("control", 10, &wanted, &got(Some(79), &[1], 8), 2)
            .is_empty());
        assert!(!w.due("control", 10));
        // its restart got SCHED_OTHER: the service lacked it, for the whole run
        assert!(w.due("control", 11));
        w.record("control", 11, &wanted, &got(None, &[1], 0), 2);
        w.record("sim", 12, &want(78, &[1]), &got(Some(78), &[1], 8), 2);
        let r = w.report();
        assert!(r.permitted);
        assert_eq!(r.services["control"].processes, 2);
        assert_eq!(r.services["control"].priority, None);
        assert!(!r.services["control"].memory_locked);
        assert_eq!(
            r.degraded(),
            ["real-time: control SCHED_OTHER instead of SCHED_FIFO 79"]
        );
        assert_eq!(r.kinds(), ["no real-time scheduling"]);
        // a refused probe is the same verdict even before any service is judged
        let r = RealtimeWatch::new(Some("SCHED_FIFO 80 refused".into())).report();
        assert!(!r.permitted && r.kinds() == ["no real-time scheduling"]);
    }

    #[test]
    fn this_process_is_observed_as_the_kernel_runs_it() {
        let me = observe(std::process::id()).expect("this process exists");
        assert_eq!(me.cpus, own_cpus());
        assert!(!me.cpus.is_empty());
        assert!(observe(u32::MAX).is_none());
    }
}
