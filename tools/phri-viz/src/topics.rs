//! The topics phri-viz serves and phri-record writes: one place for their
//! names, schemas and encodings (the layout in `deploy/foxglove/` names the same).

use foxglove::messages::{FrameTransforms, JointStates, PointCloud, RawImage, SceneUpdate};
use foxglove::{Encode, Schema};

use crate::status::StatusMessage;

/// `foxglove.SceneUpdate`: the robot's link capsules, posed from `robot/state`.
pub const ROBOT: &str = "/viz/robot";
/// `foxglove.SceneUpdate`: the person's capsules from `sim/world`.
pub const PERSON: &str = "/viz/person";
/// `foxglove.SceneUpdate`: per control point, the repulsive velocity (arrow)
/// and the minimum-distance line to the closest obstacle point (`perception/repulsion`).
pub const REPULSION: &str = "/viz/repulsion";
/// `foxglove.SceneUpdate`: the collaborative hand and the estimated contact
/// forces (`collab/state`, `perception/hand`).
pub const COLLAB: &str = "/viz/collab";
/// `foxglove.FrameTransforms`: `base` → each link, `base` → `camera`.
pub const TF: &str = "/viz/tf";
/// `foxglove.PointCloud`: the filtered depth (`perception/depth`), base frame.
pub const POINTS: &str = "/viz/depth/points";
/// `foxglove.RawImage`: the filtered depth as a 16UC1 image \[mm\].
pub const IMAGE: &str = "/viz/depth/image";
/// `foxglove.JointStates`: position \[rad\] and applied torque \[Nm\] of every joint (`robot/state`).
pub const JOINTS: &str = "/viz/joints";
/// `phri.viz.Status` (JSON): mode, phase, residual and thresholds ([`crate::status::Status`]).
pub const STATUS: &str = "/viz/status";

/// One topic: its name, schema and message encoding.
#[derive(Clone, Debug)]
pub struct Topic {
    pub name: &'static str,
    pub schema: Schema,
    /// `protobuf` (Foxglove's schemas) or `json` ([`crate::status::Status`])
    pub encoding: String,
}

fn topic<T: Encode>(name: &'static str) -> Topic {
    Topic {
        name,
        // every type used here has a schema (Foxglove's built-ins, Status)
        schema: T::get_schema().unwrap_or_else(|| Schema::new(name, "", Vec::new())),
        encoding: T::get_message_encoding(),
    }
}

/// The scene's topics (the SceneUpdates), published at the scene rate.
pub const SCENE: &[&str] = &[ROBOT, PERSON, REPULSION, COLLAB];

/// Every topic, in a stable order.
pub const ALL: &[&str] = &[
    ROBOT, PERSON, REPULSION, COLLAB, TF, POINTS, IMAGE, JOINTS, STATUS,
];

/// Every topic with its schema, in [`ALL`]'s order.
pub fn all() -> Vec<Topic> {
    ALL.iter()
        .map(|&name| match name {
            TF => topic::<FrameTransforms>(name),
            POINTS => topic::<PointCloud>(name),
            IMAGE => topic::<RawImage>(name),
            JOINTS => topic::<JointStates>(name),
            STATUS => topic::<StatusMessage<'static>>(name),
            _ => topic::<SceneUpdate>(name),
        })
        .collect()
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn every_topic_has_its_foxglove_schema() {
        let t = all();
        assert_eq!(t.len(), ALL.len());
        let schema = |name: &str| {
            let t = t.iter().find(|t| t.name == name).unwrap();
            (
                t.schema.name.clone(),
                t.schema.encoding.clone(),
                t.encoding.clone(),
            )
        };
        let pb = |s: &str| {
            (
                s.to_string(),
                "protobuf".to_string(),
                "protobuf".to_string(),
            )
        };
        for s in SCENE {
            assert_eq!(schema(s), pb("foxglove.SceneUpdate"));
        }
        assert_eq!(schema(TF), pb("foxglove.FrameTransforms"));
        assert_eq!(schema(POINTS), pb("foxglove.PointCloud"));
        assert_eq!(schema(IMAGE), pb("foxglove.RawImage"));
        assert_eq!(schema(JOINTS), pb("foxglove.JointStates"));
        assert_eq!(
            schema(STATUS),
            (
                "phri.viz.Status".to_string(),
                "jsonschema".to_string(),
                "json".to_string()
            )
        );
        assert!(t.iter().all(|t| !t.schema.data.is_empty()));
    }
}
