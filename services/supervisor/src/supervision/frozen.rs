//! Frozen services: alive, their dependencies heard from, but silent
//! themselves beyond their deadline. One is killed (then reaped and
//! restarted as any exit), unless another service starved it on the CPUs
//! they share: that one is killed instead. Without CPU samples over the
//! silence (the supervisor was held up too) there is no verdict yet.

use super::{Action, Supervision};
use crate::cpu;
use phri_ipc::liveness;

impl Supervision {
    /// Judge the frozen at `now_ns`: each victim killed once.
    pub(super) fn kill_frozen(&mut self, now_ns: u64, out: &mut Vec<Action>) {
        let mut killed: Vec<usize> = Vec::new();
        for f in self.roster.frozen(now_ns) {
            let name = self.roster.get(f.index).name.clone();
            let heartbeat = liveness::liveness_name(&name);
            let silent_ms = f.silent_ns / 1_000_000;
            let victim = match cpu::judge(&self.roster, &self.cpu, f.index, f.silent_ns) {
                Some(cpu::Verdict::Starved { culprit: c, share }) => {
                    let culprit = self.roster.get(c).name.clone();
                    let percent = share.min(1.0) * 100.0;
                    out.push(Action::Warn(format!(
                        "{name} silent on {heartbeat} for {silent_ms} ms while {culprit} used {percent:.0} % of a CPU they share: killing {culprit} instead"
                    )));
                    let starved =
                        format!("no beat on {heartbeat} for {silent_ms} ms; starved by {culprit}");
                    self.record(out, now_ns, "frozen", &name, &starved);
                    let blame =
                        format!("used {percent:.0} % of a CPU while {name} starved: killed");
                    self.record(out, now_ns, "blame", &culprit, &blame);
                    c
                }
                Some(cpu::Verdict::Frozen { busiest: b, share }) => {
                    out.push(Action::Warn(format!(
                        "{name} silent on {heartbeat} for {silent_ms} ms: frozen, killing it (busiest on its CPUs: {} at {:.0} %)",
                        self.roster.get(b).name,
                        share.min(1.0) * 100.0
                    )));
                    let detail = format!("no beat on {heartbeat} for {silent_ms} ms");
                    self.record(out, now_ns, "frozen", &name, &detail);
                    f.index
                }
                // no CPU samples over its silence (this process was held
                // up too): no verdict without evidence, judged again
                None => {
                    out.push(Action::Warn(format!(
                        "{name} silent on {heartbeat} for {silent_ms} ms; no CPU samples over that time: judged again"
                    )));
                    continue;
                }
            };
            if !killed.contains(&victim) {
                killed.push(victim);
                self.roster.killing_frozen(victim);
                out.push(Action::Kill(victim));
            }
        }
    }
}
