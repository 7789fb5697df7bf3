//! The cell's state as plottable series ([`Status`], `phri.viz.Status`, JSON;
//! built by `phri-view`): the controller's mode, the collaboration phase, the
//! momentum residual and the thresholds it is judged against, the obstacle
//! distance and the force the intended contacts do not explain. Foxglove has
//! no built-in schema for these, so the message is JSON with a JSON schema
//! (its Plot, State Transitions and Indicator panels read JSON as they read
//! protobuf): [`StatusMessage`].

use foxglove::{Encode, Schema};

pub use phri_view::status::{Status, Thresholds, SCHEMA_NAME};

/// A [`Status`] as a Foxglove message: JSON, with [`Status::json_schema`]
/// as its schema ([`SCHEMA_NAME`], `jsonschema`).
#[derive(Clone, Copy, Debug)]
pub struct StatusMessage<'a>(pub &'a Status);

impl Encode for StatusMessage<'_> {
    type Error = serde_json::Error;

    fn get_schema() -> Option<Schema> {
        let schema = serde_json::to_vec(&Status::json_schema()).unwrap_or_default();
        Some(Schema::new(SCHEMA_NAME, "jsonschema", schema))
    }

    fn get_message_encoding() -> String {
        "json".to_string()
    }

    fn encode(&self, buf: &mut impl foxglove::bytes::BufMut) -> Result<(), serde_json::Error> {
        let bytes = serde_json::to_vec(self.0)?;
        buf.put_slice(&bytes);
        Ok(())
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use phri_ipc::{residual_flags, ControlMode, ControlStatus, Residual, Zeroed};

    #[test]
    fn the_status_is_json_with_its_schema() {
        let mut c = ControlStatus::zeroed();
        c.mode = ControlMode::Reaction as u32;
        let mut r = Residual::zeroed();
        r.dof = 3;
        r.r[..3].copy_from_slice(&[1.0, -2.0, 3.0]);
        r.flags = residual_flags::VALID;
        let th = Thresholds {
            contact: vec![4.0, 4.0, 3.0],
            collision: vec![8.0, 8.0, 6.0],
            collision_norm: 12.0,
        };
        let s = Status::from_latest(Some(&c), None, Some(&r), &th);
        let mut buf = Vec::new();
        StatusMessage(&s).encode(&mut buf).unwrap();
        let v: serde_json::Value = serde_json::from_slice(&buf).unwrap();
        assert_eq!(v["mode"], "reaction");
        assert_eq!(v["residual"][2], 3.0);
        assert_eq!(v["collision_norm_threshold"], 12.0);
        assert_eq!(v, serde_json::to_value(&s).unwrap());
        assert_eq!(StatusMessage::get_message_encoding(), "json");
        let schema = StatusMessage::get_schema().unwrap();
        assert_eq!(
            (schema.name.as_str(), schema.encoding.as_str()),
            (SCHEMA_NAME, "jsonschema")
        );
        let parsed: serde_json::Value = serde_json::from_slice(&schema.data).unwrap();
        assert_eq!(parsed, Status::json_schema());
    }
}
