//! The recorder's side of the JSON views (shared with `phri-monitor` and
//! `phri-replay` in `phri-ipc-json`): log times; `phri-replay` rebuilds
//! messages with [`from_json`].

use phri_ipc::Message;
use serde_json::Value;

pub use phri_ipc_json::{from_json, to_json, JsonError};

/// The time a message is logged at: its publish time when it carries one,
/// else its `stamp_ns`, else `recv_ns` (receive time).
pub fn log_ns<T: Message>(m: &T, v: &Value, recv_ns: u64) -> u64 {
    m.published_ns()
        .or_else(|| v.get("stamp_ns").and_then(Value::as_u64))
        .filter(|&t| t > 0)
        .unwrap_or(recv_ns)
}

#[cfg(test)]
mod tests {
    use super::*;
    use phri_ipc::*;

    #[test]
    fn replayable_messages_survive_json() {
        let mut s = JointState::zeroed();
        s.seq = 7;
        s.published_ns = 123;
        s.dof = 7;
        s.q[6] = 0.5;
        s.wrench[5] = -1.0;
        let back: JointState = from_json(&to_json(&s)).unwrap();
        assert_eq!(to_json(&back), to_json(&s));

        let mut r = Residual::zeroed();
        r.dof = 7;
        r.flags = residual_flags::COLLISION;
        r.isolated_joint = -1;
        r.norm = f64::NAN;
        let back: Residual = from_json(&to_json(&r)).unwrap();
        assert_eq!(back.isolated_joint, -1);
        assert!(back.norm.is_nan());
        assert_eq!(to_json(&back), to_json(&r));

        let mut c = ControlStatus::zeroed();
        c.mode = ControlMode::Reaction as u32;
        c.ee = [0.1, 0.2, 0.3];
        c.residual_age_ns = u64::MAX;
        c.min_distance = f64::INFINITY;
        let back: ControlStatus = from_json(&to_json(&c)).unwrap();
        assert_eq!(back.mode, ControlMode::Reaction as u32);
        assert_eq!(back.residual_age_ns, u64::MAX);
        assert_eq!(back.min_distance, f64::INFINITY);
        assert_eq!(to_json(&back), to_json(&c));

        let mut t = Truth::zeroed();
        t.dof = 7;
        t.n_contacts = 1;
        t.contacts[0].intended = 1;
        t.contacts[0].force = [1.0, 2.0, 3.0];
        let back: Truth = from_json(&to_json(&t)).unwrap();
        assert_eq!(to_json(&back), to_json(&t));
    }

    #[test]
    fn log_time_prefers_the_publish_time() {
        let mut s = JointState::zeroed();
        s.published_ns = 5;
        s.stamp_ns = 3;
        assert_eq!(log_ns(&s, &to_json(&s), 9), 5);
        let mut t = Truth::zeroed();
        t.stamp_ns = 3;
        assert_eq!(log_ns(&t, &to_json(&t), 9), 3);
        assert_eq!(log_ns(&Truth::zeroed(), &to_json(&Truth::zeroed()), 9), 9);
    }
}
