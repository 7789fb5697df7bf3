//! The recorder's side of the JSON views (shared with `phri-monitor` in
//! `phri-ipc-json`): log times, and `from_json` for the types `phri-replay`
//! publishes.

use phri_ipc::*;
use serde_json::Value;

pub use phri_ipc_json::Msg;

/// The time a message is logged at: its publish time when it carries one,
/// else its `stamp_ns`, else `recv_ns` (receive time).
pub fn log_ns<T: Msg>(m: &T, v: &Value, recv_ns: u64) -> u64 {
    m.published_ns()
        .or_else(|| v.get("stamp_ns").and_then(Value::as_u64))
        .filter(|&t| t > 0)
        .unwrap_or(recv_ns)
}

// ---- JSON back to messages (phri-replay) ----

fn field<'a>(v: &'a Value, k: &str) -> Result<&'a Value, String> {
    v.get(k).ok_or_else(|| format!("field '{k}' missing"))
}

fn u64_of(v: &Value, k: &str) -> Result<u64, String> {
    field(v, k)?
        .as_u64()
        .ok_or_else(|| format!("field '{k}' is not an unsigned integer"))
}

fn u32_of(v: &Value, k: &str) -> Result<u32, String> {
    u32::try_from(u64_of(v, k)?).map_err(|_| format!("field '{k}' out of range"))
}

fn i32_of(v: &Value, k: &str) -> Result<i32, String> {
    field(v, k)?
        .as_i64()
        .and_then(|x| i32::try_from(x).ok())
        .ok_or_else(|| format!("field '{k}' is not a 32-bit integer"))
}

/// A number; `null` (a non-finite value on recording) becomes `none`.
fn f64_or(v: &Value, none: f64) -> Result<f64, String> {
    match v {
        Value::Null => Ok(none),
        x => x.as_f64().ok_or_else(|| format!("'{x}' is not a number")),
    }
}

fn f64_of(v: &Value, k: &str, none: f64) -> Result<f64, String> {
    f64_or(field(v, k)?, none).map_err(|e| format!("field '{k}': {e}"))
}

/// `ns` or `null` (u64::MAX).
fn opt_ns_of(v: &Value, k: &str) -> Result<u64, String> {
    match field(v, k)? {
        Value::Null => Ok(u64::MAX),
        x => x
            .as_u64()
            .ok_or_else(|| format!("field '{k}' is not an unsigned integer")),
    }
}

/// Fill the front of `out` from the array `k` (the rest stays zero).
fn arr_of(v: &Value, k: &str, out: &mut [f64], none: f64) -> Result<(), String> {
    let a = field(v, k)?
        .as_array()
        .ok_or_else(|| format!("field '{k}' is not an array"))?;
    if a.len() > out.len() {
        return Err(format!(
            "field '{k}': {} entries, at most {}",
            a.len(),
            out.len()
        ));
    }
    for (o, x) in out.iter_mut().zip(a) {
        *o = f64_or(x, none).map_err(|e| format!("field '{k}': {e}"))?;
    }
    Ok(())
}

fn mode_of(v: &Value, k: &str) -> Result<u32, String> {
    let name = field(v, k)?
        .as_str()
        .ok_or_else(|| format!("field '{k}' is not a string"))?;
    (0..16)
        .find(|&m| control_mode::name(m) == name)
        .ok_or_else(|| format!("field '{k}': unknown mode '{name}'"))
}

/// A message `phri-replay` can rebuild from its JSON.
pub trait FromJson: Msg + Zeroed {
    fn from_json(v: &Value) -> Result<Self, String>;
}

impl FromJson for JointState {
    fn from_json(v: &Value) -> Result<Self, String> {
        let mut m = JointState::zeroed();
        m.seq = u64_of(v, "seq")?;
        m.stamp_ns = u64_of(v, "stamp_ns")?;
        m.published_ns = u64_of(v, "published_ns")?;
        m.dof = u32_of(v, "dof")?;
        m.status = u32_of(v, "status")?;
        arr_of(v, "q", &mut m.q, f64::NAN)?;
        arr_of(v, "tau", &mut m.tau, f64::NAN)?;
        arr_of(v, "wrench", &mut m.wrench, f64::NAN)?;
        m.command_seq = u64_of(v, "command_seq")?;
        m.missed_commands = u32_of(v, "missed_commands")?;
        Ok(m)
    }
}

impl FromJson for Residual {
    fn from_json(v: &Value) -> Result<Self, String> {
        let mut m = Residual::zeroed();
        m.seq = u64_of(v, "seq")?;
        m.stamp_ns = u64_of(v, "stamp_ns")?;
        m.state_seq = u64_of(v, "state_seq")?;
        m.state_stamp_ns = u64_of(v, "state_stamp_ns")?;
        m.dof = u32_of(v, "dof")?;
        m.flags = u32_of(v, "flags")?;
        m.isolated_joint = i32_of(v, "isolated_joint")?;
        arr_of(v, "r", &mut m.r, f64::NAN)?;
        arr_of(v, "qd", &mut m.qd, f64::NAN)?;
        m.norm = f64_of(v, "norm", f64::NAN)?;
        m.compute_ns = u64_of(v, "compute_ns")?;
        Ok(m)
    }
}

impl FromJson for ControlStatus {
    fn from_json(v: &Value) -> Result<Self, String> {
        let mut m = ControlStatus::zeroed();
        m.seq = u64_of(v, "seq")?;
        m.stamp_ns = u64_of(v, "stamp_ns")?;
        m.state_seq = u64_of(v, "state_seq")?;
        m.state_stamp_ns = u64_of(v, "state_stamp_ns")?;
        m.mode = mode_of(v, "mode")?;
        m.reaction = u32_of(v, "reaction")?;
        m.waypoints_reached = u64_of(v, "waypoints_reached")?;
        m.detections = u64_of(v, "detections")?;
        m.protective_stops = u64_of(v, "protective_stops")?;
        m.resumes = u64_of(v, "resumes")?;
        m.residual_age_ns = opt_ns_of(v, "residual_age_ns")?;
        arr_of(v, "q_ref", &mut m.q_ref, f64::NAN)?;
        arr_of(v, "ee", &mut m.ee, f64::NAN)?;
        m.compute_ns = u64_of(v, "compute_ns")?;
        m.wake_latency_ns = u64_of(v, "wake_latency_ns")?;
        m.perception_age_ns = opt_ns_of(v, "perception_age_ns")?;
        // non-finite on recording: no obstacle seen
        m.min_distance = f64_of(v, "min_distance", f64::INFINITY)?;
        m.risk = f64_of(v, "risk", f64::NAN)?;
        m.task_scale = f64_of(v, "task_scale", f64::NAN)?;
        Ok(m)
    }
}

impl FromJson for Truth {
    fn from_json(v: &Value) -> Result<Self, String> {
        let mut m = Truth::zeroed();
        m.seq = u64_of(v, "seq")?;
        m.stamp_ns = u64_of(v, "stamp_ns")?;
        m.state_seq = u64_of(v, "state_seq")?;
        m.n_contacts = u32_of(v, "n_contacts")?;
        m.dof = u32_of(v, "dof")?;
        arr_of(v, "tau_ext", &mut m.tau_ext, f64::NAN)?;
        arr_of(v, "q", &mut m.q, f64::NAN)?;
        arr_of(v, "qd", &mut m.qd, f64::NAN)?;
        // +inf: no human
        m.min_distance = f64_of(v, "min_distance", f64::INFINITY)?;
        let contacts = field(v, "contacts")?
            .as_array()
            .ok_or("field 'contacts' is not an array")?;
        if contacts.len() > MAX_CONTACTS {
            return Err(format!(
                "{} contacts, at most {MAX_CONTACTS}",
                contacts.len()
            ));
        }
        for (c, j) in m.contacts.iter_mut().zip(contacts) {
            c.robot_object = i32_of(j, "robot_object")?;
            c.human_part = i32_of(j, "human_part")?;
            c.intended = field(j, "intended")?.as_bool().unwrap_or(false) as u32;
            arr_of(j, "force", &mut c.force, f64::NAN)?;
            arr_of(j, "point", &mut c.point, f64::NAN)?;
            c.depth = f64_of(j, "depth", f64::NAN)?;
        }
        m.n_contacts = m.n_contacts.min(contacts.len() as u32);
        Ok(m)
    }
}

impl FromJson for WorldState {
    fn from_json(v: &Value) -> Result<Self, String> {
        let mut m = WorldState::zeroed();
        m.seq = u64_of(v, "seq")?;
        m.stamp_ns = u64_of(v, "stamp_ns")?;
        m.dof = u32_of(v, "dof")?;
        arr_of(v, "q", &mut m.q, f64::NAN)?;
        let human = field(v, "human")?
            .as_array()
            .ok_or("field 'human' is not an array")?;
        if human.len() > MAX_HUMAN_CAPSULES {
            return Err(format!(
                "field 'human': {} capsules, at most {MAX_HUMAN_CAPSULES}",
                human.len()
            ));
        }
        m.n_human = human.len() as u32;
        for (dst, h) in m.human.iter_mut().zip(human) {
            arr_of(h, "a", &mut dst.a, f64::NAN)?;
            arr_of(h, "b", &mut dst.b, f64::NAN)?;
            dst.radius = f64_of(h, "radius", f64::NAN)?;
            dst.part = i32_of(h, "part")?;
        }
        Ok(m)
    }
}

impl FromJson for RepulsionResult {
    fn from_json(v: &Value) -> Result<Self, String> {
        let mut m = RepulsionResult::zeroed();
        m.seq = u64_of(v, "seq")?;
        m.frame_seq = u64_of(v, "frame_seq")?;
        m.capture_ns = u64_of(v, "capture_ns")?;
        m.published_ns = u64_of(v, "published_ns")?;
        m.frame_capture_wall_ns = u64_of(v, "frame_capture_wall_ns")?;
        m.worker = u32_of(v, "worker")?;
        m.workers = u32_of(v, "workers")?;
        m.compute_ns = u64_of(v, "compute_ns")?;
        let points = field(v, "points")?
            .as_array()
            .ok_or("field 'points' is not an array")?;
        if points.len() > MAX_POINTS_PER_WORKER {
            return Err(format!(
                "field 'points': {} points, at most {MAX_POINTS_PER_WORKER}",
                points.len()
            ));
        }
        m.n_points = points.len() as u32;
        for (dst, p) in m.points.iter_mut().zip(points) {
            dst.point = u32_of(p, "point")?;
            dst.active = field(p, "active")?
                .as_bool()
                .ok_or("field 'active' is not a boolean")? as u32;
            arr_of(p, "v_call", &mut dst.v_call, f64::NAN)?;
            // non-finite on recording: nothing seen
            dst.min_distance = f64_of(p, "min_distance", f64::INFINITY)?;
            arr_of(p, "obstacle", &mut dst.obstacle, f64::NAN)?;
            arr_of(p, "position", &mut dst.position, f64::NAN)?;
        }
        Ok(m)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn replayable_messages_survive_json() {
        let mut s = JointState::zeroed();
        s.seq = 7;
        s.published_ns = 123;
        s.dof = 7;
        s.q[6] = 0.5;
        s.wrench[5] = -1.0;
        let back = JointState::from_json(&s.to_json()).unwrap();
        assert_eq!(back.to_json(), s.to_json());

        let mut r = Residual::zeroed();
        r.dof = 7;
        r.flags = residual_flags::COLLISION;
        r.isolated_joint = -1;
        r.norm = f64::NAN;
        let back = Residual::from_json(&r.to_json()).unwrap();
        assert_eq!(back.isolated_joint, -1);
        assert!(back.norm.is_nan());
        assert_eq!(back.to_json(), r.to_json());

        let mut c = ControlStatus::zeroed();
        c.mode = control_mode::REACTION;
        c.ee = [0.1, 0.2, 0.3];
        c.residual_age_ns = u64::MAX;
        c.min_distance = f64::INFINITY;
        let back = ControlStatus::from_json(&c.to_json()).unwrap();
        assert_eq!(back.mode, control_mode::REACTION);
        assert_eq!(back.residual_age_ns, u64::MAX);
        assert_eq!(back.to_json(), c.to_json());

        let mut t = Truth::zeroed();
        t.dof = 7;
        t.n_contacts = 1;
        t.contacts[0].intended = 1;
        t.contacts[0].force = [1.0, 2.0, 3.0];
        let back = Truth::from_json(&t.to_json()).unwrap();
        assert_eq!(back.to_json(), t.to_json());
    }
}
