//! The owned channels (those a safety decision reads, see
//! [`phri_ipc::owners`]) as the supervisor watches them: which of their
//! publishers are strangers (not a service it started for that channel),
//! and what their readers refused (`audit/inputs`), for the report.

use std::collections::BTreeMap;

use phri_ipc::owners::{PUBLISHERS, REFUSALS};
use phri_ipc::InputAudit;
use serde::Serialize;

use crate::roster::Roster;

/// The channel on which any process of the cell's user may publish: the
/// operator's requests (`phri-hri`, a script) speak as `cli` there.
pub const OPERATOR_CHANNEL: &str = "hri/request";

/// Publishers of `channel` (their pids) that are not a running service of
/// `roster` whose binary publishes it. `me` (the supervisor) and unknown
/// pids (≤ 0) are never strangers; on [`OPERATOR_CHANNEL`] nobody is.
pub fn strangers(channel: &str, publishers: &[i32], roster: &Roster, me: i32) -> Vec<i32> {
    // a further camera's channel is owned as the first camera's
    let Some(owned) = phri_ipc::Owned::of(channel) else {
        return Vec::new();
    };
    let Some((_, binaries)) = PUBLISHERS.iter().find(|(c, _)| *c == owned.name()) else {
        return Vec::new();
    };
    if channel == OPERATOR_CHANNEL {
        return Vec::new();
    }
    let owners: Vec<i32> = roster
        .iter()
        .filter(|s| binaries.contains(&s.spec.binary.as_str()))
        .filter_map(|s| s.pid.map(|p| p as i32))
        .collect();
    publishers
        .iter()
        .copied()
        .filter(|&p| p > 0 && p != me && !owners.contains(&p))
        .collect()
}

/// `inputs.READER.CHANNEL` in the report: what one reader refused there.
#[derive(Clone, Debug, Default, PartialEq, Eq, Serialize)]
pub struct Refused {
    /// from a process the supervisor did not start for the channel
    pub stranger: u64,
    /// stamped in the future
    pub future: u64,
    /// older than the input's staleness bound
    pub stale: u64,
    /// a repulsion result for a point its worker does not own
    pub not_its_point: u64,
    /// the newest stranger's pid (null: none)
    pub stranger_pid: Option<i32>,
}

/// `inputs` in the report: per reader (controller, residual, voice
/// recogniser), per owned channel, what it refused (channels with nothing
/// refused are left out).
#[derive(Clone, Debug, Default, PartialEq, Serialize)]
pub struct InputsReport(pub BTreeMap<String, BTreeMap<String, Refused>>);

impl InputsReport {
    /// The report's `degraded` lines: strangers and stamps from the future
    /// (a forged sender or a broken clock), per reader and channel. Stale
    /// inputs are counted only (a late frame is the staleness rule at work).
    pub fn degraded(&self) -> Vec<String> {
        let mut out = Vec::new();
        for (reader, channels) in &self.0 {
            for (channel, r) in channels {
                if r.stranger > 0 {
                    out.push(format!(
                        "inputs: {reader} refused {} message(s) on {channel} from a process the supervisor did not start for it{}",
                        r.stranger,
                        r.stranger_pid.map_or(String::new(), |p| format!(" (pid {p})"))
                    ));
                }
                if r.future > 0 {
                    out.push(format!(
                        "inputs: {reader} refused {} message(s) on {channel} stamped in the future",
                        r.future
                    ));
                }
            }
        }
        out
    }
}

/// The readers' audits over the run; a restarted reader's counts start at
/// 0 again and are added to its predecessor's.
#[derive(Clone, Debug, Default)]
pub struct AuditLog {
    /// per reader: the newest audit's seq, its counts, and the counts of
    /// its predecessors
    readers: BTreeMap<String, (u64, Counts, Counts)>,
    /// per reader: the newest stranger's pid per owned channel
    last_pids: BTreeMap<String, Vec<i32>>,
}

type Counts = [[u64; REFUSALS]; PUBLISHERS.len()];

impl AuditLog {
    /// A reader's `audit/inputs`: its counts since it started (a lower `seq`
    /// is a new process of it: its predecessor's counts are kept).
    pub fn on_audit(&mut self, m: &InputAudit) {
        let entry = self.readers.entry(m.service_str().to_string()).or_insert((
            0,
            [[0; REFUSALS]; PUBLISHERS.len()],
            [[0; REFUSALS]; PUBLISHERS.len()],
        ));
        if m.seq < entry.0 {
            // a new process of this reader: keep what the last one counted
            for (b, l) in entry.2.iter_mut().zip(entry.1.iter()) {
                for (x, y) in b.iter_mut().zip(l) {
                    *x += y;
                }
            }
        }
        entry.0 = m.seq;
        for (k, counts) in entry.1.iter_mut().enumerate() {
            *counts = m.refused[k];
        }
        let pids = self
            .last_pids
            .entry(m.service_str().to_string())
            .or_default();
        pids.clear();
        pids.extend_from_slice(&m.stranger_pid[..PUBLISHERS.len()]);
    }

    /// `inputs` in the report: each reader's counts summed over its
    /// processes, with the newest stranger's pid.
    pub fn report(&self) -> InputsReport {
        let mut out = BTreeMap::new();
        for (reader, (_, last, base)) in &self.readers {
            let pids = self.last_pids.get(reader);
            let mut channels = BTreeMap::new();
            for (k, (channel, _)) in PUBLISHERS.iter().enumerate() {
                let c = |i: usize| last[k][i] + base[k][i];
                let r = Refused {
                    stranger: c(0),
                    future: c(1),
                    stale: c(2),
                    not_its_point: c(3),
                    stranger_pid: pids.and_then(|p| p.get(k).copied()).filter(|&p| p > 0),
                };
                if r != Refused::default() {
                    channels.insert(channel.to_string(), r);
                }
            }
            if !channels.is_empty() {
                out.insert(reader.clone(), channels);
            }
        }
        InputsReport(out)
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use phri_config::ServiceSpec;
    use phri_ipc::Zeroed;

    fn roster() -> Roster {
        let spec = |binary: &str| ServiceSpec {
            binary: binary.into(),
            ..phri_config::Config::defaults().services["sim"].clone()
        };
        let mut r = Roster::new(
            phri_config::Config::defaults().supervisor,
            vec![
                ("sim".into(), spec("phri-sim")),
                ("repulsion0".into(), spec("phri-repulsion")),
                ("repulsion1".into(), spec("phri-repulsion")),
            ],
        );
        r.started(0, 0, 100);
        r.started(1, 0, 101);
        r.started(2, 0, 102);
        r
    }

    #[test]
    fn strangers_are_publishers_no_service_was_started_for() {
        let r = roster();
        assert!(strangers("perception/repulsion", &[101, 102], &r, 1).is_empty());
        assert_eq!(
            strangers("perception/repulsion", &[101, 4242, 0, 1], &r, 1),
            [4242]
        );
        // the simulator may publish the state, not repulsion results
        assert_eq!(strangers("perception/repulsion", &[100], &r, 1), [100]);
        assert!(strangers("robot/state", &[100], &r, 1).is_empty());
        // the operator's channel and channels nobody owns
        assert!(strangers("hri/request", &[4242], &r, 1).is_empty());
        assert!(strangers("camera/depth", &[4242], &r, 1).is_empty());
    }

    #[test]
    fn audits_add_up_over_reader_restarts_and_name_what_degrades_the_run() {
        let mut log = AuditLog::default();
        let audit = |seq: u64, future: u64, stranger: u64| {
            let mut m = InputAudit::zeroed();
            m.seq = seq;
            m.service = phri_ipc::json::to_c_str("control");
            m.refused[2] = [stranger, future, 0, 0];
            m.stranger_pid[2] = if stranger > 0 { 4242 } else { 0 };
            m
        };
        log.on_audit(&audit(1, 0, 0));
        assert!(log.report().0.is_empty());
        log.on_audit(&audit(2, 4, 0));
        // the controller restarted: its counts begin again
        log.on_audit(&audit(1, 1, 2));
        let r = log.report();
        let c = &r.0["control"]["perception/repulsion"];
        assert_eq!((c.future, c.stranger, c.stranger_pid), (5, 2, Some(4242)));
        let d = r.degraded();
        assert_eq!(d.len(), 2, "{d:?}");
        assert!(
            d[0].contains("pid 4242") && d[1].contains("5 message(s)"),
            "{d:?}"
        );
    }
}
