//! JSON views of the message types (they do not derive `Serialize`): fields by
//! name, joint arrays truncated to `dof`, frames summarised. Shared by the
//! tools that print or record channels (`phri-monitor`, `phri-record`).

use phri_ipc::*;
use serde_json::{json, Value};

/// A message a tool can open, count and convert to JSON.
pub trait Msg: std::fmt::Debug + iceoryx2::prelude::ZeroCopySend + Copy + 'static {
    fn seq(&self) -> u64;
    /// independent sequence streams on one channel (one per publisher)
    fn stream(&self) -> u64 {
        0
    }
    /// publish time [ns, CLOCK_MONOTONIC] when the message carries one
    fn published_ns(&self) -> Option<u64>;
    fn to_json(&self) -> Value;
}

fn joints(a: &[f64], dof: u32) -> Value {
    json!(&a[..(dof as usize).min(a.len())])
}

fn opt_ns(ns: u64) -> Value {
    if ns == u64::MAX {
        Value::Null
    } else {
        json!(ns)
    }
}

fn num(x: f64) -> Value {
    // JSON has no inf/NaN
    if x.is_finite() {
        json!(x)
    } else {
        Value::Null
    }
}

impl Msg for JointState {
    fn seq(&self) -> u64 {
        self.seq
    }
    fn published_ns(&self) -> Option<u64> {
        Some(self.published_ns)
    }
    fn to_json(&self) -> Value {
        json!({
            "seq": self.seq, "stamp_ns": self.stamp_ns, "published_ns": self.published_ns,
            "dof": self.dof, "status": self.status,
            "q": joints(&self.q, self.dof), "tau": joints(&self.tau, self.dof),
            "wrench": self.wrench, "command_seq": self.command_seq,
            "missed_commands": self.missed_commands,
        })
    }
}

impl Msg for TorqueCommand {
    fn seq(&self) -> u64 {
        self.seq
    }
    fn published_ns(&self) -> Option<u64> {
        Some(self.stamp_ns)
    }
    fn to_json(&self) -> Value {
        json!({
            "seq": self.seq, "stamp_ns": self.stamp_ns, "state_seq": self.state_seq,
            "state_stamp_ns": self.state_stamp_ns, "dof": self.dof,
            "mode": control_mode::name(self.mode), "tau": joints(&self.tau, self.dof),
        })
    }
}

impl Msg for Residual {
    fn seq(&self) -> u64 {
        self.seq
    }
    fn published_ns(&self) -> Option<u64> {
        Some(self.stamp_ns)
    }
    fn to_json(&self) -> Value {
        json!({
            "seq": self.seq, "stamp_ns": self.stamp_ns, "state_seq": self.state_seq,
            "state_stamp_ns": self.state_stamp_ns, "dof": self.dof, "flags": self.flags,
            "isolated_joint": self.isolated_joint,
            "r": joints(&self.r, self.dof), "qd": joints(&self.qd, self.dof),
            "norm": num(self.norm), "compute_ns": self.compute_ns,
        })
    }
}

impl Msg for ControlStatus {
    fn seq(&self) -> u64 {
        self.seq
    }
    fn published_ns(&self) -> Option<u64> {
        Some(self.stamp_ns)
    }
    fn to_json(&self) -> Value {
        json!({
            "seq": self.seq, "stamp_ns": self.stamp_ns, "state_seq": self.state_seq,
            "state_stamp_ns": self.state_stamp_ns, "mode": control_mode::name(self.mode),
            "reaction": self.reaction, "waypoints_reached": self.waypoints_reached,
            "detections": self.detections, "protective_stops": self.protective_stops,
            "resumes": self.resumes, "residual_age_ns": opt_ns(self.residual_age_ns),
            "q_ref": self.q_ref.iter().copied().map(num).collect::<Vec<_>>(),
            "ee": self.ee, "compute_ns": self.compute_ns,
            "wake_latency_ns": self.wake_latency_ns,
            "perception_age_ns": opt_ns(self.perception_age_ns),
            "min_distance": num(self.min_distance), "risk": num(self.risk),
            "task_scale": num(self.task_scale),
        })
    }
}

impl Msg for Truth {
    fn seq(&self) -> u64 {
        self.seq
    }
    fn published_ns(&self) -> Option<u64> {
        None
    }
    fn to_json(&self) -> Value {
        let n = (self.n_contacts as usize).min(MAX_CONTACTS);
        let contacts: Vec<Value> = self.contacts[..n]
            .iter()
            .map(|c| {
                json!({"robot_object": c.robot_object, "human_part": c.human_part,
                       "intended": c.intended != 0, "force": c.force, "point": c.point,
                       "depth": c.depth})
            })
            .collect();
        json!({
            "seq": self.seq, "stamp_ns": self.stamp_ns, "state_seq": self.state_seq,
            "n_contacts": self.n_contacts, "dof": self.dof,
            "tau_ext": joints(&self.tau_ext, self.dof), "q": joints(&self.q, self.dof),
            "qd": joints(&self.qd, self.dof), "min_distance": num(self.min_distance),
            "contacts": contacts,
        })
    }
}

impl Msg for RobotStats {
    fn seq(&self) -> u64 {
        self.seq
    }
    fn published_ns(&self) -> Option<u64> {
        None
    }
    fn to_json(&self) -> Value {
        // the histogram is summarised: its non-empty range and total
        let first = self.latency_hist.iter().position(|&c| c > 0);
        let last = self.latency_hist.iter().rposition(|&c| c > 0);
        let total: u64 = self.latency_hist.iter().map(|&c| c as u64).sum();
        json!({
            "seq": self.seq, "stamp_ns": self.stamp_ns, "cycles": self.cycles,
            "missed_deadlines": self.missed_deadlines, "braked_cycles": self.braked_cycles,
            "brake_events": self.brake_events, "overruns": self.overruns,
            "latency_max_ns": self.latency_max_ns,
            "latency_hist": {"bin_us": 1, "count": total, "first_bin": first, "last_bin": last},
        })
    }
}

impl Msg for Health {
    fn seq(&self) -> u64 {
        self.seq
    }
    fn published_ns(&self) -> Option<u64> {
        Some(self.stamp_ns)
    }
    fn to_json(&self) -> Value {
        let n = (self.count as usize).min(MAX_SERVICES);
        let services: Vec<Value> = self.services[..n]
            .iter()
            .map(|s| {
                json!({"name": s.name_str(), "pid": s.pid, "alive": s.alive != 0,
                       "restarts": s.restarts, "started_ns": s.started_ns})
            })
            .collect();
        json!({"seq": self.seq, "stamp_ns": self.stamp_ns, "count": self.count, "services": services})
    }
}

impl Msg for WorldState {
    fn seq(&self) -> u64 {
        self.seq
    }
    fn published_ns(&self) -> Option<u64> {
        None
    }
    fn to_json(&self) -> Value {
        let n = (self.n_human as usize).min(MAX_HUMAN_CAPSULES);
        let human: Vec<Value> = self.human[..n]
            .iter()
            .map(|c| json!({"a": c.a, "b": c.b, "radius": c.radius, "part": c.part}))
            .collect();
        json!({
            "seq": self.seq, "stamp_ns": self.stamp_ns, "dof": self.dof,
            "n_human": self.n_human, "q": joints(&self.q, self.dof), "human": human,
        })
    }
}

impl Msg for RepulsionResult {
    fn seq(&self) -> u64 {
        self.seq
    }
    fn stream(&self) -> u64 {
        self.worker as u64
    }
    fn published_ns(&self) -> Option<u64> {
        Some(self.published_ns)
    }
    fn to_json(&self) -> Value {
        let n = (self.n_points as usize).min(MAX_POINTS_PER_WORKER);
        let points: Vec<Value> = self.points[..n]
            .iter()
            .map(|p| {
                json!({"point": p.point, "active": p.active != 0, "v_call": p.v_call,
                       "min_distance": num(p.min_distance), "obstacle": p.obstacle,
                       "position": p.position})
            })
            .collect();
        json!({
            "seq": self.seq, "frame_seq": self.frame_seq, "capture_ns": self.capture_ns,
            "published_ns": self.published_ns,
            "frame_capture_wall_ns": self.frame_capture_wall_ns, "worker": self.worker,
            "workers": self.workers, "n_points": self.n_points, "compute_ns": self.compute_ns,
            "points": points,
        })
    }
}

/// Summary of a depth frame: seq, size, valid pixels, depth range, latency.
pub fn frame_json(h: &FrameHeader, d: &[u16]) -> Value {
    let (mut valid, mut mn, mut mx) = (0usize, u16::MAX, 0u16);
    for &x in d.iter().filter(|&&x| x > 0) {
        valid += 1;
        mn = mn.min(x);
        mx = mx.max(x);
    }
    json!({
        "seq": h.seq, "width": h.width, "height": h.height, "pixels": d.len(),
        "bytes": d.len() * 2 + std::mem::size_of::<FrameHeader>(),
        "valid_pixels": valid, "removed_pixels": h.removed_pixels,
        "min_depth_mm": if valid > 0 { json!(mn) } else { Value::Null },
        "max_depth_mm": if valid > 0 { json!(mx) } else { Value::Null },
        "capture_to_published_ms": h.published_ns.saturating_sub(h.capture_wall_ns) as f64 * 1e-6,
    })
}

impl Msg for DepthFault {
    fn seq(&self) -> u64 {
        self.seq
    }
    fn published_ns(&self) -> Option<u64> {
        Some(self.stamp_ns)
    }
    fn to_json(&self) -> Value {
        json!({
            "seq": self.seq, "stamp_ns": self.stamp_ns, "kind": depth_fault::name(self.kind),
            "frames": self.frames, "delay_ms": num(self.delay_ms), "duration_s": num(self.duration_s),
        })
    }
}
