//! The cell's state as plottable series: the controller's mode, the
//! collaboration phase, the momentum residual and the thresholds it is
//! judged against, the obstacle distance and the force the intended contacts
//! do not explain. One serialisable sample ([`Status`]) with its JSON schema
//! ([`Status::json_schema`]); each viewer sends it its own way (phri-viz as
//! `phri.viz.Status` JSON, phri-ros2 as a `diagnostic_msgs/DiagnosticStatus`).

use phri_ipc::{
    residual_flags, CollabPart, CollabPhase, CollabReason, CollabState, ControlMode, ControlStatus,
    Residual,
};
use serde::Serialize;
use serde_json::json;

/// Schema name of [`Status`].
pub const SCHEMA_NAME: &str = "phri.viz.Status";

/// The thresholds of the collision detector (`[dynamics]`), per joint \[Nm\].
#[derive(Clone, Debug, Default, PartialEq, Serialize)]
pub struct Thresholds {
    /// |r_i| above: contact \[Nm\]
    pub contact: Vec<f64>,
    /// |r_i| above: collision \[Nm\]
    pub collision: Vec<f64>,
    /// ‖r‖ above: collision \[Nm\]
    pub collision_norm: f64,
}

/// One status sample. Absent inputs leave their fields at "none"/empty/null.
#[derive(Clone, Debug, Default, PartialEq, Serialize)]
pub struct Status {
    /// [`ControlMode`] name (`none` before the controller reported)
    pub mode: &'static str,
    /// [`ControlMode`] wire value (−1: none), for plots
    pub mode_id: i64,
    /// [`CollabPhase`] name (`none` before the controller reported)
    pub phase: &'static str,
    /// [`CollabPhase`] wire value (−1: none)
    pub phase_id: i64,
    /// why the phase last changed ([`CollabReason`] name)
    pub phase_reason: &'static str,
    /// the collaborative human part ([`CollabPart`] name)
    pub human_part: &'static str,
    /// momentum residual r ≈ τ_ext per joint \[Nm\]
    pub residual: Vec<f64>,
    /// ‖r‖ \[Nm\]
    pub residual_norm: Option<f64>,
    /// the residual's contact flag: some |r_i| above its contact threshold
    pub contact: bool,
    /// the residual's collision flag: some |r_i| or ‖r‖ above its collision threshold
    pub collision: bool,
    /// the residual's valid flag: the observer is initialised and the value meaningful
    pub residual_valid: bool,
    /// last joint past its contact threshold (−1: none)
    pub isolated_joint: i32,
    /// per-joint contact thresholds the residual is judged against \[Nm\]
    pub contact_threshold: Vec<f64>,
    /// per-joint collision thresholds \[Nm\]
    pub collision_threshold: Vec<f64>,
    /// collision threshold on ‖r‖ \[Nm\]
    pub collision_norm_threshold: f64,
    /// smallest obstacle distance of the control points \[m\] (null: none seen)
    pub min_distance: Option<f64>,
    /// largest repulsion risk ‖V_Call‖/V_max [0, 1]
    pub risk: Option<f64>,
    /// SNS task scale [0, 1]
    pub task_scale: Option<f64>,
    /// ‖r − Σ J_kᵀ F̂_k‖: residual the intended contacts do not explain \[Nm\]
    pub unexplained_norm: Option<f64>,
    /// no robot state for longer than phri-viz's `--stale-after`: the cell
    /// stopped (or stalled); the scene is not being sent
    pub stale: bool,
    /// age of the newest robot state when this status was sent \[s\] (0: it came
    /// with this status; null: none yet)
    pub input_age: Option<f64>,
}

/// `x` when finite, else `None` (JSON has no infinity).
fn finite(x: f64) -> Option<f64> {
    x.is_finite().then_some(x)
}

impl Status {
    /// The status from the latest messages (any may be missing), residual cut to `dof`.
    pub fn from_latest(
        control: Option<&ControlStatus>,
        collab: Option<&CollabState>,
        residual: Option<&Residual>,
        thresholds: &Thresholds,
    ) -> Status {
        let mut s = Status {
            mode: "none",
            mode_id: -1,
            phase: "none",
            phase_id: -1,
            phase_reason: "none",
            human_part: "none",
            isolated_joint: -1,
            contact_threshold: thresholds.contact.clone(),
            collision_threshold: thresholds.collision.clone(),
            collision_norm_threshold: thresholds.collision_norm,
            ..Status::default()
        };
        if let Some(c) = control {
            s.mode = ControlMode::name_of(c.mode);
            s.mode_id = i64::from(c.mode);
            s.min_distance = finite(c.min_distance);
            s.risk = finite(c.risk);
            s.task_scale = finite(c.task_scale);
        }
        if let Some(c) = collab {
            s.phase = CollabPhase::name_of(c.phase);
            s.phase_id = i64::from(c.phase);
            s.phase_reason = CollabReason::name_of(c.reason);
            s.human_part = CollabPart::name_of(c.human_part);
            s.unexplained_norm = finite(c.unexplained_norm);
        }
        if let Some(r) = residual {
            let n = (r.dof as usize).min(r.r.len());
            s.residual = r.r[..n]
                .iter()
                .map(|x| if x.is_finite() { *x } else { 0.0 })
                .collect();
            s.residual_norm = finite(r.norm);
            s.contact = r.flags & residual_flags::CONTACT != 0;
            s.collision = r.flags & residual_flags::COLLISION != 0;
            s.residual_valid = r.flags & residual_flags::VALID != 0;
            s.isolated_joint = r.isolated_joint;
        }
        s
    }

    /// The JSON schema of [`Status`] (draft 2020-12 subset Foxglove reads).
    pub fn json_schema() -> serde_json::Value {
        let num = json!({"type": "number"});
        let opt = json!({"type": ["number", "null"]});
        let nums = json!({"type": "array", "items": {"type": "number"}});
        let text = json!({"type": "string"});
        json!({
            "title": SCHEMA_NAME,
            "type": "object",
            "properties": {
                "mode": text, "mode_id": {"type": "integer"},
                "phase": text, "phase_id": {"type": "integer"},
                "phase_reason": text, "human_part": text,
                "residual": nums, "residual_norm": opt,
                "contact": {"type": "boolean"}, "collision": {"type": "boolean"},
                "residual_valid": {"type": "boolean"},
                "isolated_joint": {"type": "integer"},
                "contact_threshold": nums, "collision_threshold": nums,
                "collision_norm_threshold": num,
                "min_distance": opt, "risk": opt, "task_scale": opt,
                "unexplained_norm": opt,
                "stale": {"type": "boolean"}, "input_age": opt
            }
        })
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use phri_ipc::Zeroed;

    #[test]
    fn the_status_names_mode_phase_and_cuts_the_residual() {
        let mut c = ControlStatus::zeroed();
        c.mode = ControlMode::Reaction as u32;
        c.min_distance = f64::INFINITY;
        c.risk = 0.25;
        let mut k = CollabState::zeroed();
        k.phase = CollabPhase::Contact as u32;
        let mut r = Residual::zeroed();
        r.dof = 3;
        r.r[..4].copy_from_slice(&[1.0, -2.0, 3.0, 99.0]);
        r.norm = 14f64.sqrt();
        r.flags = residual_flags::COLLISION | residual_flags::VALID;
        r.isolated_joint = 2;
        let th = Thresholds {
            contact: vec![4.0, 4.0, 3.0],
            collision: vec![8.0, 8.0, 6.0],
            collision_norm: 12.0,
        };
        let s = Status::from_latest(Some(&c), Some(&k), Some(&r), &th);
        assert_eq!((s.mode, s.mode_id), ("reaction", 2));
        assert_eq!((s.phase, s.phase_id), ("contact", 2));
        assert_eq!(s.residual, vec![1.0, -2.0, 3.0]);
        assert!(s.collision && !s.contact && s.residual_valid);
        assert_eq!(s.min_distance, None, "no obstacle seen: null, not infinity");
        assert_eq!(s.risk, Some(0.25));
        assert_eq!(s.collision_threshold, th.collision);
        let v = serde_json::to_value(&s).unwrap();
        assert_eq!(v["mode"], "reaction");
        assert_eq!(v["residual"][2], 3.0);
        assert_eq!(v["collision_norm_threshold"], 12.0);
        // every field the message has, the schema names
        let schema = Status::json_schema();
        for key in v.as_object().unwrap().keys() {
            assert!(
                schema["properties"].get(key).is_some(),
                "{key} not in the schema"
            );
        }
    }

    #[test]
    fn nothing_received_is_none() {
        let s = Status::from_latest(None, None, None, &Thresholds::default());
        assert_eq!((s.mode, s.phase, s.mode_id), ("none", "none", -1));
        assert!(s.residual.is_empty());
    }
}
