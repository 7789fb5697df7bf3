//! The supervised services' bookkeeping, as plain data and decisions: which
//! runs (by pid), when to restart what died (exponential back-off), which
//! service is frozen (silent on its liveness service beyond its deadline
//! while what it depends on is not), and the views of it all: the health message, the state files,
//! the report's `services`. Pure: the clock comes in as `now_ns`
//! (CLOCK_MONOTONIC), processes are started, signalled and reaped by the
//! caller, which tells the roster what happened.

use std::collections::BTreeMap;

use phri_config::{ServiceSpec, SupervisorConfig};
use phri_ipc::{Health, Zeroed};

use crate::report::ServiceReport;
use crate::restart::RestartPolicy;
use crate::state::{ServiceJson, ServiceState, StateJson, SupervisorState, STATE_VERSION};

/// One supervised service.
#[derive(Clone, Debug)]
pub struct Supervised {
    /// its key under `[services]`
    pub name: String,
    /// its configuration (`[services.NAME]`)
    pub spec: ServiceSpec,
    /// process id while it runs (started or adopted); `None` while it is down
    pub pid: Option<u32>,
    /// its restarts and back-off
    pub policy: RestartPolicy,
    /// when to start it again \[ns\], while a restart is pending
    pub restart_at: Option<u64>,
    /// last beat on its liveness service (`liveness/<name>`), or since
    /// when its silence is judged afresh ((re)start, a dependency silent,
    /// killed frozen) \[ns\]
    pub last_heartbeat_ns: u64,
    /// its liveness deadline passed without a beat (iceoryx2's WaitSet
    /// said so); cleared by a beat or a fresh judgement
    pub missed: bool,
    /// last (re)start \[ns\]
    pub started_ns: u64,
    /// its heartbeat was heard since its last (re)start
    pub heard_since_start: bool,
    /// the supervisor killed it as frozen since its last (re)start: its
    /// exit is that verdict's, not a start that failed
    pub killed_frozen: bool,
    /// when it exited, over the last `crash_loop_window_s` [ns]
    exits_ns: Vec<u64>,
}

impl Supervised {
    /// restarts so far
    pub fn restarts(&self) -> u32 {
        self.policy.restarts
    }

    /// it was started (or adopted) before in this cell: its next start is a restart
    pub fn started_before(&self) -> bool {
        self.started_ns > 0
    }

    /// running (started or adopted, not yet reaped)
    pub fn alive(&self) -> bool {
        self.pid.is_some()
    }
}

/// A service found frozen by [`Roster::frozen`]: kill it (it is then reaped
/// and restarted as any exit).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct Frozen {
    /// index in the roster
    pub index: usize,
    /// how long its heartbeat channel had been silent \[ns\]
    pub silent_ns: u64,
}

/// Every supervised service, in start order (the index is the same everywhere).
#[derive(Clone, Debug)]
pub struct Roster {
    sup: SupervisorConfig,
    services: Vec<Supervised>,
    /// per service: silent beyond its heartbeat timeout (scratch of [`Roster::frozen`])
    silent: Vec<bool>,
    /// the dead-man stopped the cell: nothing is restarted until an
    /// operator resumes it ([`Roster::resume`])
    held: bool,
}

impl Roster {
    /// `services` in start order ([`crate::spec::in_start_order`]), all down until started.
    pub fn new(sup: SupervisorConfig, services: Vec<(String, ServiceSpec)>) -> Roster {
        let services: Vec<Supervised> = services
            .into_iter()
            .map(|(name, spec)| Supervised {
                name,
                spec,
                pid: None,
                policy: RestartPolicy::default(),
                restart_at: None,
                last_heartbeat_ns: 0,
                missed: false,
                started_ns: 0,
                heard_since_start: false,
                killed_frozen: false,
                exits_ns: Vec::new(),
            })
            .collect();
        Roster {
            sup,
            silent: vec![false; services.len()],
            services,
            held: false,
        }
    }

    /// The dead-man stopped the cell (the services stopped themselves when
    /// no supervisor was heard): hold it stopped, restarting nothing, until
    /// [`Roster::resume`].
    pub fn hold(&mut self) {
        self.held = true;
        for s in &mut self.services {
            s.restart_at = None;
        }
    }

    /// Held stopped by the dead-man.
    pub fn held(&self) -> bool {
        self.held
    }

    /// An operator resumed a held cell at `now_ns`: every service that is
    /// down (and restarts) starts again now. `false`: it was not held.
    pub fn resume(&mut self, now_ns: u64) -> bool {
        if !self.held {
            return false;
        }
        self.held = false;
        for s in &mut self.services {
            if s.pid.is_none() && s.spec.restart {
                s.restart_at = Some(now_ns);
            }
        }
        true
    }

    /// Service `index` stopped by its dead-man at `now_ns`: down, not a
    /// crash (no back-off, no crash-loop count), restarted only on resume.
    pub fn stopped_by_deadman(&mut self, index: usize) {
        let s = &mut self.services[index];
        s.pid = None;
        s.restart_at = None;
    }

    /// How many services are supervised.
    pub fn len(&self) -> usize {
        self.services.len()
    }

    /// No service is supervised.
    pub fn is_empty(&self) -> bool {
        self.services.is_empty()
    }

    /// Service `index` (in start order); panics when there is no such service.
    pub fn get(&self, index: usize) -> &Supervised {
        &self.services[index]
    }

    /// Every service, in start order (its position is its index).
    pub fn iter(&self) -> impl Iterator<Item = &Supervised> {
        self.services.iter()
    }

    /// How the supervisor behaves (`[supervisor]` of the configuration).
    pub fn config(&self) -> &SupervisorConfig {
        &self.sup
    }

    /// Service `index` was (re)started at `now_ns` as process `pid`.
    pub fn started(&mut self, index: usize, now_ns: u64, pid: u32) {
        let s = &mut self.services[index];
        s.pid = Some(pid);
        s.restart_at = None;
        s.policy.started(now_ns);
        s.started_ns = now_ns;
        s.last_heartbeat_ns = now_ns;
        s.missed = false;
        s.heard_since_start = false;
        s.killed_frozen = false;
    }

    /// Service `index` is being killed as frozen.
    pub fn killing_frozen(&mut self, index: usize) {
        self.services[index].killed_frozen = true;
    }

    /// The index of service `name`.
    pub fn index_of(&self, name: &str) -> Option<usize> {
        self.services.iter().position(|s| s.name == name)
    }

    /// Whether `pid` is a process this supervisor runs (started or adopted).
    pub fn runs(&self, pid: u32) -> bool {
        self.services.iter().any(|s| s.pid == Some(pid))
    }

    /// Service `index` was adopted at `now_ns` from a supervisor that died,
    /// which had restarted it `restarts` times.
    pub fn adopted(&mut self, index: usize, now_ns: u64, pid: u32, restarts: u32) {
        self.started(index, now_ns, pid);
        self.services[index].policy.restarts = restarts;
    }

    /// Service `index` ended at `now_ns`: when it will be started again \[ns\]
    /// (`None`: it is not restarted, `restart = false`).
    pub fn exited(&mut self, index: usize, now_ns: u64) -> Option<u64> {
        let sup = &self.sup;
        let s = &mut self.services[index];
        s.pid = None;
        let window_ns = (sup.crash_loop_window_s * 1e9) as u64;
        s.exits_ns
            .retain(|&t| now_ns.saturating_sub(t) <= window_ns);
        s.exits_ns.push(now_ns);
        s.restart_at = s.spec.restart.then(|| {
            s.policy.exited(
                now_ns,
                sup.restart_backoff_min_ms,
                sup.restart_backoff_max_ms,
                sup.stable_after_s,
            )
        });
        s.restart_at
    }

    /// Service `index` crash-loops at `now_ns`: it ended more than
    /// `crash_loop_restarts` times within the last `crash_loop_window_s`
    /// (a restart each). Returns how often.
    pub fn crash_looping(&self, index: usize, now_ns: u64) -> Option<usize> {
        let window_ns = (self.sup.crash_loop_window_s * 1e9) as u64;
        let n = self.services[index]
            .exits_ns
            .iter()
            .filter(|&&t| now_ns.saturating_sub(t) <= window_ns)
            .count();
        (n > self.sup.crash_loop_restarts as usize).then_some(n)
    }

    /// The hot standby's partner of service `index`: `X` for `X_standby`,
    /// `X_standby` for `X`, when both are in the roster (the controllers,
    /// the residuals).
    pub fn partner(&self, index: usize) -> Option<usize> {
        let name = self.services.get(index)?.name.as_str();
        let other = match name.strip_suffix("_standby") {
            Some(first) => first.to_string(),
            None => format!("{name}_standby"),
        };
        self.index_of(&other).filter(|&i| i != index)
    }

    /// Service `index` runs and has been heard since its start, within its
    /// liveness deadline: it does its part.
    pub fn healthy(&self, index: usize) -> bool {
        self.services.get(index).is_some_and(|s| {
            s.pid.is_some() && !s.missed && (s.spec.heartbeat.is_none() || s.heard_since_start)
        })
    }

    /// Whether service `index` is to be started now; the pending restart is
    /// taken (a failed start is [`Roster::restart_failed`]).
    pub fn restart_due(&mut self, index: usize, now_ns: u64) -> bool {
        if self.held {
            return false;
        }
        let s = &mut self.services[index];
        if s.restart_at.is_some_and(|at| now_ns >= at) {
            s.restart_at = None;
            true
        } else {
            false
        }
    }

    /// Starting service `index` failed at `now_ns`: try again after the next
    /// back-off (counted as a restart); returns when \[ns\].
    pub fn restart_failed(&mut self, index: usize, now_ns: u64) -> u64 {
        let sup = &self.sup;
        let s = &mut self.services[index];
        // a start that fails counts towards a crash loop as an exit does
        let window_ns = (sup.crash_loop_window_s * 1e9) as u64;
        s.exits_ns
            .retain(|&t| now_ns.saturating_sub(t) <= window_ns);
        s.exits_ns.push(now_ns);
        let at = s.policy.exited(
            now_ns,
            sup.restart_backoff_min_ms,
            sup.restart_backoff_max_ms,
            sup.stable_after_s,
        );
        s.restart_at = Some(at);
        at
    }

    /// Service `index` beat on its liveness service: alive at `now_ns`.
    pub fn heard(&mut self, index: usize, now_ns: u64) {
        let s = &mut self.services[index];
        s.last_heartbeat_ns = now_ns;
        s.missed = false;
        s.heard_since_start = s.pid.is_some();
    }

    /// Service `index` was silent for its whole liveness deadline (the
    /// WaitSet woke the supervisor for it): silent now, whatever the clocks
    /// say to the microsecond.
    pub fn deadline_missed(&mut self, index: usize) {
        self.services[index].missed = true;
    }

    /// The liveness deadline of each watched service (those with a
    /// `heartbeat`), by index: its `heartbeat_timeout_ms`, else the supervisor's.
    pub fn deadlines(&self) -> Vec<(usize, std::time::Duration)> {
        self.services
            .iter()
            .enumerate()
            .filter(|(_, s)| s.spec.heartbeat.is_some())
            .map(|(i, s)| (i, std::time::Duration::from_nanos(self.timeout_ns(s))))
            .collect()
    }

    /// The supervisor itself was stalled until `now_ns` (it could not hear
    /// anyone): every service's silence is judged afresh from now, so that
    /// its own stall is not taken for theirs.
    pub fn judge_afresh(&mut self, now_ns: u64) {
        for s in &mut self.services {
            s.last_heartbeat_ns = s.last_heartbeat_ns.max(now_ns);
            s.missed = false;
        }
    }

    /// The cell is whole: every service runs, and every one with a
    /// heartbeat channel has been heard on it since it started.
    pub fn whole(&self) -> bool {
        self.services
            .iter()
            .all(|s| s.pid.is_some() && (s.spec.heartbeat.is_none() || s.heard_since_start))
    }

    /// The running services not yet heard on their heartbeat channel since they started.
    pub fn unheard(&self) -> Vec<&str> {
        self.services
            .iter()
            .filter(|s| s.pid.is_some() && s.spec.heartbeat.is_some() && !s.heard_since_start)
            .map(|s| s.name.as_str())
            .collect()
    }

    /// Silence on its heartbeat longer than this is frozen [ns]: the
    /// service's own `heartbeat_timeout_ms`, else the supervisor's.
    fn timeout_ns(&self, s: &Supervised) -> u64 {
        s.spec
            .heartbeat_timeout_ms
            .unwrap_or(self.sup.heartbeat_timeout_ms)
            * 1_000_000
    }

    /// A (re)started service is not judged before this [ns].
    fn grace_ns(&self) -> u64 {
        4 * (self.sup.heartbeat_timeout_ms * 1_000_000).max(500_000_000)
    }

    /// The services frozen at `now_ns`: running, out of their start-up
    /// grace, every service they depend on heard from, yet silent on their
    /// own heartbeat beyond its timeout. A service whose dependencies are
    /// silent, not yet heard since they started, or unknown is not judged: its silence is explained by
    /// theirs, and it is judged afresh once they are back. A frozen
    /// service's silence is also counted afresh (it is killed meanwhile).
    pub fn frozen(&mut self, now_ns: u64) -> Vec<Frozen> {
        for i in 0..self.services.len() {
            let s = &self.services[i];
            self.silent[i] = s.spec.heartbeat.is_some()
                && (s.missed || now_ns.saturating_sub(s.last_heartbeat_ns) > self.timeout_ns(s));
        }
        let grace = self.grace_ns();
        let mut frozen = Vec::new();
        for i in 0..self.services.len() {
            // a dependency that is down (restarting) or not yet heard since
            // it started (connecting to a robot, loading) explains the
            // silence too, before its own (maybe longer) timeout says so
            let deps_ok = self.services[i].spec.depends_on.iter().all(|d| {
                self.services.iter().zip(&self.silent).any(|(o, &silent)| {
                    &o.name == d
                        && o.pid.is_some()
                        && !silent
                        && (o.heard_since_start || o.spec.heartbeat.is_none())
                })
            });
            let s = &mut self.services[i];
            if !deps_ok {
                s.last_heartbeat_ns = now_ns;
                s.missed = false;
                continue;
            }
            let past_grace = now_ns.saturating_sub(s.started_ns) > grace;
            if s.pid.is_some() && past_grace && self.silent[i] {
                frozen.push(Frozen {
                    index: i,
                    silent_ns: now_ns.saturating_sub(s.last_heartbeat_ns),
                });
                s.last_heartbeat_ns = now_ns;
                s.missed = false;
            }
        }
        frozen
    }

    /// Fill `health` (`supervisor/health`) at `now_ns`: the next sequence
    /// number, and per service (as many as the message holds) its name, pid
    /// (0: down), whether it runs, restarts and last start.
    pub fn fill_health(&self, health: &mut Health, now_ns: u64) {
        self.fill_health_from(health, now_ns, 0);
    }

    /// Fill `health` as `supervisor/health/more`: the services past the
    /// first [`phri_ipc::MAX_SERVICES`]. False (nothing to publish) when
    /// the roster holds no more.
    pub fn fill_health_more(&self, health: &mut Health, now_ns: u64) -> bool {
        if self.services.len() <= phri_ipc::MAX_SERVICES {
            return false;
        }
        self.fill_health_from(health, now_ns, phri_ipc::MAX_SERVICES);
        true
    }

    /// `health` listing the services from number `first` on.
    fn fill_health_from(&self, health: &mut Health, now_ns: u64, first: usize) {
        health.seq += 1;
        health.stamp_ns = now_ns;
        health.count = self.services.len() as u32;
        let listed = self.services.get(first..).unwrap_or(&[]);
        for h in health.services.iter_mut().skip(listed.len()) {
            *h = phri_ipc::ServiceHealth::zeroed();
        }
        for (h, s) in health.services.iter_mut().zip(listed) {
            h.name = phri_ipc::json::to_c_str(&s.name);
            h.pid = s.pid.map_or(0, |p| p as i32);
            h.alive = s.pid.is_some() as u32;
            h.restarts = s.policy.restarts;
            h.started_ns = s.started_ns;
        }
    }

    /// `state.json` of this supervisor (`supervisor_pid`) and run (`prefix`).
    pub fn state_json(&self, prefix: &str, supervisor_pid: u32) -> StateJson {
        StateJson {
            prefix: prefix.to_string(),
            services: self
                .services
                .iter()
                .map(|s| {
                    (
                        s.name.clone(),
                        ServiceJson {
                            pid: s.pid,
                            restarts: s.policy.restarts,
                        },
                    )
                })
                .collect(),
            supervisor_pid,
        }
    }

    /// `supervisor.state`: what a supervisor that takes over needs.
    pub fn state(&self, prefix: &str, supervisor_pid: u32, cell_start_ns: u64) -> SupervisorState {
        SupervisorState {
            version: STATE_VERSION,
            supervisor_pid,
            prefix: prefix.to_string(),
            cell_start_ns,
            services: self
                .services
                .iter()
                .map(|s| ServiceState {
                    name: s.name.clone(),
                    pid: s.pid.unwrap_or(0),
                    restarts: s.policy.restarts,
                })
                .collect(),
        }
    }

    /// The report's `services`.
    pub fn reports(&self) -> BTreeMap<String, ServiceReport> {
        self.services
            .iter()
            .map(|s| {
                (
                    s.name.clone(),
                    ServiceReport {
                        restarts: s.policy.restarts,
                        alive_at_end: s.pid.is_some(),
                    },
                )
            })
            .collect()
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use phri_ipc::Zeroed;

    const MS: u64 = 1_000_000;

    /// sim ← dynamics (heartbeat sim/truth ← dynamics/residual); a worker
    /// without heartbeat; a service that depends on one that is not supervised.
    fn roster() -> Roster {
        let config = phri_config::Config::defaults();
        let mut sup = config.supervisor.clone();
        sup.heartbeat_timeout_ms = 200;
        sup.restart_backoff_min_ms = 50;
        sup.restart_backoff_max_ms = 400;
        sup.stable_after_s = 5.0;
        let spec = |heartbeat: Option<&str>, deps: &[&str]| ServiceSpec {
            heartbeat: heartbeat.map(str::to_string),
            depends_on: deps.iter().map(|d| d.to_string()).collect(),
            ..config.services["sim"].clone()
        };
        let mut r = Roster::new(
            sup,
            vec![
                ("sim".into(), spec(Some("sim/truth"), &[])),
                ("dynamics".into(), spec(Some("dynamics/residual"), &["sim"])),
                ("worker".into(), spec(None, &[])),
                ("orphan".into(), spec(Some("control/status"), &["nobody"])),
            ],
        );
        for i in 0..r.len() {
            r.started(i, 0, 100 + i as u32);
        }
        r
    }

    /// Every service with heartbeat `channel` beat at `t_ns`.
    fn hear(r: &mut Roster, channel: &str, t_ns: u64) {
        for i in 0..r.len() {
            if r.get(i).spec.heartbeat.as_deref() == Some(channel) {
                r.heard(i, t_ns);
            }
        }
    }

    /// Both heartbeats heard every 10 ms until `until_ms`, except `mute`'s.
    fn run(r: &mut Roster, from_ms: u64, until_ms: u64, mute: &[&str]) -> Vec<(u64, usize)> {
        let mut frozen = Vec::new();
        for t in (from_ms..until_ms).step_by(10) {
            for ch in ["sim/truth", "dynamics/residual", "control/status"] {
                if !mute.contains(&ch) {
                    hear(r, ch, t * MS);
                }
            }
            frozen.extend(r.frozen(t * MS).into_iter().map(|f| (t, f.index)));
        }
        frozen
    }

    #[test]
    fn a_silent_service_is_frozen_after_its_timeout_once_out_of_grace() {
        let mut r = roster();
        assert!(run(&mut r, 0, 2100, &[]).is_empty());
        // dynamics falls silent at 2100 ms: frozen once silent > 200 ms
        let f = run(&mut r, 2100, 2400, &["dynamics/residual"]);
        assert_eq!(f, [(2300, 1)]);
        // counted afresh after the verdict (it is being killed)
        assert!(run(&mut r, 2400, 2490, &["dynamics/residual"]).is_empty());
    }

    /// The WaitSet's word that a deadline passed is the verdict: frozen at
    /// once, even a microsecond short of the timeout by this clock; a beat
    /// before the judgement clears it, and so does the start-up grace.
    #[test]
    fn a_missed_deadline_is_silence_until_a_beat() {
        let mut r = roster();
        run(&mut r, 0, 2100, &[]);
        // 1 µs before the 200 ms timeout; the others beat on, dynamics (1) does not
        let t = 2090 * MS + 200 * MS - 1_000;
        hear(&mut r, "sim/truth", t);
        hear(&mut r, "control/status", t);
        r.deadline_missed(1);
        assert_eq!(
            r.frozen(t),
            [Frozen {
                index: 1,
                silent_ns: 200 * MS - 1_000
            }]
        );
        assert!(r.frozen(t + MS).is_empty(), "judged once");
        r.deadline_missed(1);
        r.heard(1, t + 2 * MS);
        assert!(r.frozen(t + 3 * MS).is_empty(), "a beat clears it");
        r.started(1, t + 4 * MS, 9);
        r.deadline_missed(1);
        assert!(r.frozen(t + 5 * MS).is_empty(), "in its grace");
        let w = r.deadlines();
        assert_eq!(w.iter().map(|(i, _)| *i).collect::<Vec<_>>(), [0, 1, 3]);
        assert!(w
            .iter()
            .all(|(_, d)| *d == std::time::Duration::from_millis(200)));
    }

    #[test]
    fn silence_during_the_start_up_grace_is_not_frozen() {
        let mut r = roster();
        // grace: 4 × max(200 ms, 500 ms) = 2 s after the start
        let f = run(&mut r, 0, 2100, &["dynamics/residual"]);
        assert_eq!(f, [(2010, 1)]);
        // a restart grants the grace again
        r.started(1, 2100 * MS, 300);
        assert!(run(&mut r, 2100, 4100, &["dynamics/residual"]).is_empty());
    }

    #[test]
    fn after_a_stall_of_the_supervisor_silence_is_judged_afresh() {
        let mut r = roster();
        run(&mut r, 0, 3000, &[]);
        // the supervisor heard nothing from 3000 to 3500 ms (it was stalled)
        r.judge_afresh(3500 * MS);
        assert!(run(&mut r, 3500, 3700, &["dynamics/residual"]).is_empty());
        assert_eq!(run(&mut r, 3700, 3800, &["dynamics/residual"]), [(3710, 1)]);
    }

    #[test]
    fn silence_explained_by_a_silent_dependency_is_not_frozen() {
        let mut r = roster();
        run(&mut r, 0, 3000, &[]);
        // the simulator dies: it and dynamics fall silent, neither is frozen
        // (a dead service is restarting, and it explains dynamics' silence)
        r.exited(0, 3000 * MS);
        let f = run(&mut r, 3000, 4000, &["sim/truth", "dynamics/residual"]);
        assert!(f.is_empty(), "{f:?}");
        // the simulator is back, dynamics still silent: judged from then on,
        // not from its last message at 2990 ms
        r.started(0, 4000 * MS, 200);
        let f = run(&mut r, 4000, 4400, &["dynamics/residual"]);
        assert_eq!(f, [(4200, 1)]);
    }

    #[test]
    fn a_dead_dependency_with_a_long_timeout_explains_the_silence_at_once() {
        let mut r = roster();
        // the robot adapter: 3 s to connect to its box, so a long timeout
        r.services[0].spec.heartbeat_timeout_ms = Some(3000);
        run(&mut r, 0, 3000, &[]);
        // killed: its dependant falls silent at once, long before the
        // adapter's own timeout would call it silent
        r.exited(0, 3000 * MS);
        let f = run(&mut r, 3000, 3500, &["sim/truth", "dynamics/residual"]);
        assert!(f.is_empty(), "{f:?}");
    }

    #[test]
    fn without_heartbeat_or_process_or_known_dependencies_nothing_is_frozen() {
        let mut r = roster();
        // the orphan depends on a service that is not supervised: never judged
        let f = run(&mut r, 0, 5000, &["control/status"]);
        assert!(f.is_empty(), "{f:?}");
        // a dead service is silent but not frozen (it is restarting)
        r.exited(0, 5000 * MS);
        let f = run(&mut r, 5000, 6000, &["sim/truth"]);
        assert!(f.is_empty(), "{f:?}");
        // ... and explains its dependants' silence
        assert!(run(&mut r, 6000, 7000, &["sim/truth", "dynamics/residual"]).is_empty());
    }

    #[test]
    fn a_service_timeout_overrides_the_supervisors() {
        let mut r = roster();
        r.services[1].spec.heartbeat_timeout_ms = Some(1500);
        run(&mut r, 0, 2500, &[]);
        let f = run(&mut r, 2500, 4500, &["dynamics/residual"]);
        // last heard at 2490 ms: silent beyond 1.5 s from 4000 ms (not 2700 ms)
        assert_eq!(f, [(4000, 1)]);
    }

    #[test]
    fn exits_schedule_restarts_with_back_off_unless_restart_is_off() {
        let mut r = roster();
        assert_eq!(r.exited(0, 100 * MS), Some(150 * MS));
        assert!(!r.restart_due(0, 149 * MS));
        assert!(r.restart_due(0, 150 * MS));
        assert!(!r.restart_due(0, 150 * MS), "taken once");
        // the start failed: the next back-off, counted
        assert_eq!(r.restart_failed(0, 150 * MS), 250 * MS);
        assert!(r.restart_due(0, 250 * MS));
        r.started(0, 250 * MS, 500);
        assert_eq!(r.get(0).restarts(), 2);
        r.services[2].spec.restart = false;
        assert_eq!(r.exited(2, 300 * MS), None);
        assert!(!r.restart_due(2, 10_000 * MS));
        let reports = r.reports();
        assert_eq!(reports["sim"].restarts, 2);
        assert!(reports["sim"].alive_at_end);
        assert!(!reports["worker"].alive_at_end);
    }

    #[test]
    fn a_service_restarted_too_often_within_the_window_crash_loops() {
        let mut r = roster();
        r.sup.crash_loop_restarts = 3;
        r.sup.crash_loop_window_s = 1.0;
        // 3 exits within a second: restarted each time, not yet a loop
        for t in [100, 300, 500] {
            r.exited(0, t * MS);
            assert_eq!(r.crash_looping(0, t * MS), None, "{t}");
            r.started(0, t * MS + MS, 7);
        }
        // the 4th within the window: more than 3
        r.exited(0, 900 * MS);
        assert_eq!(r.crash_looping(0, 900 * MS), Some(4));
        // spread out over more than the window: never a loop
        let mut r = roster();
        r.sup.crash_loop_restarts = 3;
        r.sup.crash_loop_window_s = 1.0;
        for k in 0..10u64 {
            r.exited(1, k * 400 * MS);
            assert_eq!(r.crash_looping(1, k * 400 * MS), None, "{k}");
            r.started(1, k * 400 * MS + MS, 7);
        }
    }

    #[test]
    fn the_cell_is_whole_once_every_heartbeat_was_heard_since_its_start() {
        let mut r = roster();
        assert!(!r.whole());
        assert_eq!(r.unheard(), ["sim", "dynamics", "orphan"]);
        hear(&mut r, "sim/truth", 10 * MS);
        hear(&mut r, "dynamics/residual", 10 * MS);
        hear(&mut r, "control/status", 10 * MS);
        assert!(r.whole(), "{:?}", r.unheard());
        // a restart must be heard again; a dead service is not whole
        r.started(1, 20 * MS, 300);
        assert_eq!(r.unheard(), ["dynamics"]);
        r.exited(1, 30 * MS);
        assert!(!r.whole());
        assert!(r.unheard().is_empty());
        assert!(r.runs(100) && !r.runs(300));
        assert_eq!(r.index_of("worker"), Some(2));
    }

    /// A roster past the first health message's [`phri_ipc::MAX_SERVICES`]
    /// lists the rest on `supervisor/health/more`: every service's pid
    /// reaches the services (the owners of their inputs).
    #[test]
    fn services_past_the_first_health_message_are_listed_on_the_second() {
        let r = roster();
        let mut h = Health::zeroed();
        assert!(!r.fill_health_more(&mut h, 0), "4 services fit one message");
        let config = phri_config::Config::defaults();
        let specs: Vec<(String, ServiceSpec)> = (0..phri_ipc::MAX_SERVICES + 3)
            .map(|i| (format!("s{i}"), config.services["sim"].clone()))
            .collect();
        let mut r = Roster::new(config.supervisor.clone(), specs);
        for i in 0..r.len() {
            r.started(i, 0, 1000 + i as u32);
        }
        let (mut first, mut more) = (Health::zeroed(), Health::zeroed());
        r.fill_health(&mut first, 5);
        assert!(r.fill_health_more(&mut more, 5));
        let n = phri_ipc::MAX_SERVICES;
        assert_eq!((first.count, more.count), (n as u32 + 3, n as u32 + 3));
        assert_eq!(first.services[n - 1].pid, 1000 + n as i32 - 1);
        assert_eq!(more.services[0].name_str(), format!("s{n}"));
        assert_eq!(more.services[2].pid, 1000 + n as i32 + 2);
        assert_eq!(more.services[3].pid, 0);
        assert_eq!(more.services[3].name_str(), "");
    }

    #[test]
    fn health_and_state_show_every_service() {
        let mut r = roster();
        r.exited(1, 10 * MS);
        r.adopted(2, 20 * MS, 77, 4);
        let mut h = Health::zeroed();
        r.fill_health(&mut h, 30 * MS);
        r.fill_health(&mut h, 40 * MS);
        assert_eq!((h.seq, h.stamp_ns, h.count), (2, 40 * MS, 4));
        assert_eq!(&h.services[0].name[..4], b"sim\0");
        assert_eq!((h.services[0].pid, h.services[0].alive), (100, 1));
        assert_eq!(
            (
                h.services[1].pid,
                h.services[1].alive,
                h.services[1].restarts
            ),
            (0, 0, 1)
        );
        assert_eq!(
            (
                h.services[2].pid,
                h.services[2].restarts,
                h.services[2].started_ns
            ),
            (77, 4, 20 * MS)
        );
        let j = r.state_json("p_", 9);
        assert_eq!(j.services["dynamics"].pid, None);
        assert_eq!(j.services["worker"].pid, Some(77));
        let s = r.state("p_", 9, 5);
        assert_eq!(s.services[1].pid, 0);
        assert_eq!(
            s.service("worker").map(|w| (w.pid, w.restarts)),
            Some((77, 4))
        );
        assert_eq!(s.cell_start_ns, 5);
    }

    #[test]
    fn long_names_are_cut_to_the_message_field() {
        let config = phri_config::Config::defaults();
        let long = "a".repeat(40);
        let mut r = Roster::new(
            config.supervisor.clone(),
            vec![(long, config.services["sim"].clone())],
        );
        r.started(0, 0, 1);
        let mut h = Health::zeroed();
        r.fill_health(&mut h, 0);
        assert_eq!(h.services[0].name[..31], [b'a'; 31]);
        assert_eq!(h.services[0].name[31], 0);
    }
}
