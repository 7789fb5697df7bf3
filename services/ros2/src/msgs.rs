//! The ROS 2 messages the bridge speaks, as serde structs whose field order
//! is the `.msg` definitions' (CDR encodes fields in declaration order, with
//! no names): `builtin_interfaces`, `std_msgs`, `sensor_msgs`,
//! `geometry_msgs`, `tf2_msgs`, `diagnostic_msgs` and `visualization_msgs`
//! of ROS 2 Humble and later, and ROS4HRI's `hri_msgs` (REP 155). Each type names its ROS package and type
//! ([`RosType`]); on the wire the DDS type is
//! `<package>::msg::dds_::<Type>_`. Units and frames follow REP 103/105:
//! SI units, right-handed frames, `base_link` the robot's base.

use serde::{Deserialize, Serialize};

/// A ROS 2 message type: its package and name (`sensor_msgs`, `JointState`).
pub trait RosType {
    /// the ROS package (`sensor_msgs`)
    const PACKAGE: &'static str;
    /// the type's name in its package (`JointState`)
    const NAME: &'static str;
}

macro_rules! ros_type {
    ($t:ty, $pkg:literal, $name:literal) => {
        impl RosType for $t {
            const PACKAGE: &'static str = $pkg;
            const NAME: &'static str = $name;
        }
    };
}

/// A sequence of octets (`uint8[]`), encoded as one block rather than
/// byte by byte (CDR: a 32-bit length, then the bytes).
pub mod octets {
    use serde::de::{Deserializer, SeqAccess, Visitor};
    use serde::Serializer;

    /// Serialises `v` as one block of bytes.
    pub fn serialize<S: Serializer>(v: &[u8], s: S) -> Result<S::Ok, S::Error> {
        s.serialize_bytes(v)
    }

    /// Deserialises a block of bytes (or a sequence of them, byte by byte).
    pub fn deserialize<'de, D: Deserializer<'de>>(d: D) -> Result<Vec<u8>, D::Error> {
        struct Octets;
        impl<'de> Visitor<'de> for Octets {
            type Value = Vec<u8>;
            fn expecting(&self, f: &mut std::fmt::Formatter) -> std::fmt::Result {
                f.write_str("a sequence of octets")
            }
            fn visit_bytes<E>(self, v: &[u8]) -> Result<Vec<u8>, E> {
                Ok(v.to_vec())
            }
            fn visit_byte_buf<E>(self, v: Vec<u8>) -> Result<Vec<u8>, E> {
                Ok(v)
            }
            fn visit_seq<A: SeqAccess<'de>>(self, mut a: A) -> Result<Vec<u8>, A::Error> {
                let mut v = Vec::with_capacity(a.size_hint().unwrap_or(0).min(1 << 24));
                while let Some(b) = a.next_element()? {
                    v.push(b);
                }
                Ok(v)
            }
        }
        d.deserialize_bytes(Octets)
    }
}

/// `builtin_interfaces/Time`: seconds and nanoseconds since the Unix epoch
/// (ROS time: the system clock).
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Serialize, Deserialize)]
pub struct Time {
    /// seconds since the Unix epoch
    pub sec: i32,
    /// nanoseconds within the second (below 10⁹)
    pub nanosec: u32,
}
ros_type!(Time, "builtin_interfaces", "Time");

impl Time {
    /// From nanoseconds since the Unix epoch (saturating at the i32 range).
    pub fn from_ns(ns: u64) -> Time {
        let sec = (ns / 1_000_000_000).min(i32::MAX as u64) as i32;
        Time {
            sec,
            nanosec: (ns % 1_000_000_000) as u32,
        }
    }

    /// Nanoseconds since the Unix epoch (0 before it).
    pub fn to_ns(self) -> u64 {
        u64::try_from(self.sec).unwrap_or(0) * 1_000_000_000 + u64::from(self.nanosec)
    }
}

/// `builtin_interfaces/Duration`.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Serialize, Deserialize)]
pub struct Duration {
    /// whole seconds
    pub sec: i32,
    /// nanoseconds to add (below 10⁹)
    pub nanosec: u32,
}

/// `std_msgs/Header`: when the data was measured and in which frame.
#[derive(Clone, Debug, Default, PartialEq, Serialize, Deserialize)]
pub struct Header {
    /// when the data was measured (ROS time)
    pub stamp: Time,
    /// the frame the data is in
    pub frame_id: String,
}

/// `std_msgs/String`.
#[derive(Clone, Debug, Default, PartialEq, Eq, Serialize, Deserialize)]
pub struct StringMsg {
    /// the text
    pub data: String,
}
ros_type!(StringMsg, "std_msgs", "String");

/// `sensor_msgs/JointState`: positions [rad or m], velocities [rad/s or m/s],
/// efforts [Nm or N]; an array may be empty when not measured.
#[derive(Clone, Debug, Default, PartialEq, Serialize, Deserialize)]
pub struct JointState {
    /// when the joints were measured
    pub header: Header,
    /// the joints' names; the other arrays are in this order
    pub name: Vec<String>,
    /// per joint \[rad or m\]
    pub position: Vec<f64>,
    /// per joint \[rad/s or m/s\]; empty when not measured
    pub velocity: Vec<f64>,
    /// per joint \[Nm or N\]; empty when not measured
    pub effort: Vec<f64>,
}
ros_type!(JointState, "sensor_msgs", "JointState");

/// `geometry_msgs/Vector3`.
#[derive(Clone, Copy, Debug, Default, PartialEq, Serialize, Deserialize)]
pub struct Vector3 {
    /// x component
    pub x: f64,
    /// y component
    pub y: f64,
    /// z component
    pub z: f64,
}

impl From<[f64; 3]> for Vector3 {
    fn from(v: [f64; 3]) -> Vector3 {
        Vector3 {
            x: v[0],
            y: v[1],
            z: v[2],
        }
    }
}

/// `geometry_msgs/Point` \[m\].
pub type Point = Vector3;

/// `geometry_msgs/Quaternion` (x, y, z, w).
#[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize)]
pub struct Quaternion {
    /// vector part, x
    pub x: f64,
    /// vector part, y
    pub y: f64,
    /// vector part, z
    pub z: f64,
    /// scalar part
    pub w: f64,
}

impl Default for Quaternion {
    fn default() -> Quaternion {
        Quaternion {
            x: 0.0,
            y: 0.0,
            z: 0.0,
            w: 1.0,
        }
    }
}

/// `geometry_msgs/Pose`.
#[derive(Clone, Copy, Debug, Default, PartialEq, Serialize, Deserialize)]
pub struct Pose {
    /// origin \[m\]
    pub position: Point,
    /// orientation, a unit quaternion
    pub orientation: Quaternion,
}

/// `geometry_msgs/Wrench`: force \[N\] and torque \[Nm\].
#[derive(Clone, Copy, Debug, Default, PartialEq, Serialize, Deserialize)]
pub struct Wrench {
    /// force \[N\]
    pub force: Vector3,
    /// torque \[Nm\]
    pub torque: Vector3,
}

/// `geometry_msgs/WrenchStamped`.
#[derive(Clone, Debug, Default, PartialEq, Serialize, Deserialize)]
pub struct WrenchStamped {
    /// when, and the frame the wrench is in
    pub header: Header,
    /// the force and torque
    pub wrench: Wrench,
}
ros_type!(WrenchStamped, "geometry_msgs", "WrenchStamped");

/// `geometry_msgs/Transform`: the child frame's origin \[m\] and orientation in the parent's.
#[derive(Clone, Copy, Debug, Default, PartialEq, Serialize, Deserialize)]
pub struct Transform {
    /// the child frame's origin in the parent's \[m\]
    pub translation: Vector3,
    /// the child frame's orientation in the parent's
    pub rotation: Quaternion,
}

/// `geometry_msgs/TransformStamped`.
#[derive(Clone, Debug, Default, PartialEq, Serialize, Deserialize)]
pub struct TransformStamped {
    /// when, and the parent frame
    pub header: Header,
    /// the child frame
    pub child_frame_id: String,
    /// the child frame in the parent's
    pub transform: Transform,
}

/// `tf2_msgs/TFMessage` (`/tf`).
#[derive(Clone, Debug, Default, PartialEq, Serialize, Deserialize)]
pub struct TfMessage {
    /// the transforms, each stamped
    pub transforms: Vec<TransformStamped>,
}
ros_type!(TfMessage, "tf2_msgs", "TFMessage");

/// `sensor_msgs/Image`.
#[derive(Clone, Debug, Default, PartialEq, Serialize, Deserialize)]
pub struct Image {
    /// the capture time and the camera's optical frame
    pub header: Header,
    /// rows \[px\]
    pub height: u32,
    /// columns \[px\]
    pub width: u32,
    /// the pixels' encoding (REP 118: `16UC1`, `mono16`, `32FC1`, ...)
    pub encoding: String,
    /// 1 when the pixels are big-endian, else 0
    pub is_bigendian: u8,
    /// bytes per row
    pub step: u32,
    /// the pixels, row after row: `step` × `height` bytes
    #[serde(with = "octets")]
    pub data: Vec<u8>,
}
ros_type!(Image, "sensor_msgs", "Image");

/// `sensor_msgs/PointField`.
#[derive(Clone, Debug, Default, PartialEq, Serialize, Deserialize)]
pub struct PointField {
    /// the field's name (`x`, `y`, `z`, ...)
    pub name: String,
    /// its offset in a point \[bytes\]
    pub offset: u32,
    /// its type ([`PointField::FLOAT32`], ...)
    pub datatype: u8,
    /// elements per point
    pub count: u32,
}

impl PointField {
    /// `datatype` of a 32-bit float.
    pub const FLOAT32: u8 = 7;
}

/// `sensor_msgs/PointCloud2`.
#[derive(Clone, Debug, Default, PartialEq, Serialize, Deserialize)]
pub struct PointCloud2 {
    /// the capture time and the points' frame
    pub header: Header,
    /// rows (1: an unorganised cloud)
    pub height: u32,
    /// points per row
    pub width: u32,
    /// each point's layout
    pub fields: Vec<PointField>,
    /// whether the data is big-endian
    pub is_bigendian: bool,
    /// bytes per point
    pub point_step: u32,
    /// bytes per row
    pub row_step: u32,
    /// the points, row after row: `row_step` × `height` bytes
    #[serde(with = "octets")]
    pub data: Vec<u8>,
    /// whether every point is valid (no NaN)
    pub is_dense: bool,
}
ros_type!(PointCloud2, "sensor_msgs", "PointCloud2");

/// `diagnostic_msgs/KeyValue`.
#[derive(Clone, Debug, Default, PartialEq, Eq, Serialize, Deserialize)]
pub struct KeyValue {
    /// the value's name
    pub key: String,
    /// the value, as text
    pub value: String,
}

/// `diagnostic_msgs/DiagnosticStatus`.
#[derive(Clone, Debug, Default, PartialEq, Eq, Serialize, Deserialize)]
pub struct DiagnosticStatus {
    /// [`DiagnosticStatus::OK`], `WARN`, `ERROR` or `STALE`
    pub level: u8,
    /// what it is the status of
    pub name: String,
    /// the status, in a few words
    pub message: String,
    /// the hardware it is about
    pub hardware_id: String,
    /// named values
    pub values: Vec<KeyValue>,
}

impl DiagnosticStatus {
    /// `level`: all is well.
    pub const OK: u8 = 0;
    /// `level`: a warning.
    pub const WARN: u8 = 1;
    /// `level`: an error.
    pub const ERROR: u8 = 2;
    /// `level`: no recent data.
    pub const STALE: u8 = 3;
}

/// `diagnostic_msgs/DiagnosticArray`.
#[derive(Clone, Debug, Default, PartialEq, Serialize, Deserialize)]
pub struct DiagnosticArray {
    /// when
    pub header: Header,
    /// one per component
    pub status: Vec<DiagnosticStatus>,
}
ros_type!(DiagnosticArray, "diagnostic_msgs", "DiagnosticArray");

/// `std_msgs/ColorRGBA` [0, 1].
#[derive(Clone, Copy, Debug, Default, PartialEq, Serialize, Deserialize)]
pub struct ColorRgba {
    /// red
    pub r: f32,
    /// green
    pub g: f32,
    /// blue
    pub b: f32,
    /// opacity (1: opaque)
    pub a: f32,
}

/// `sensor_msgs/CompressedImage` (in a marker: its texture; empty here).
#[derive(Clone, Debug, Default, PartialEq, Serialize, Deserialize)]
pub struct CompressedImage {
    /// when, and the camera's frame
    pub header: Header,
    /// the compression (`jpeg`, `png`, ...)
    pub format: String,
    /// the compressed image
    #[serde(with = "octets")]
    pub data: Vec<u8>,
}

/// `visualization_msgs/UVCoordinate`.
#[derive(Clone, Copy, Debug, Default, PartialEq, Serialize, Deserialize)]
pub struct UvCoordinate {
    /// horizontal texture coordinate
    pub u: f32,
    /// vertical texture coordinate
    pub v: f32,
}

/// `visualization_msgs/MeshFile`.
#[derive(Clone, Debug, Default, PartialEq, Serialize, Deserialize)]
pub struct MeshFile {
    /// the mesh file's name (its extension gives its format)
    pub filename: String,
    /// the file's contents
    #[serde(with = "octets")]
    pub data: Vec<u8>,
}

/// `visualization_msgs/Marker` (ROS 2 Humble and later).
#[derive(Clone, Debug, Default, PartialEq, Serialize, Deserialize)]
pub struct Marker {
    /// when, and the frame of `pose` and `points`
    pub header: Header,
    /// namespace: with `id`, the marker's name
    pub ns: String,
    /// the marker's id in `ns`
    pub id: i32,
    /// [`Marker::ARROW`], …
    #[serde(rename = "type")]
    pub kind: i32,
    /// [`Marker::ADD`] or [`Marker::DELETE`]
    pub action: i32,
    /// the marker's pose in the header's frame
    pub pose: Pose,
    /// size \[m\]; an arrow by points: shaft diameter, head diameter, head length
    pub scale: Vector3,
    /// colour
    pub color: ColorRgba,
    /// how long the marker lasts (0: until replaced or deleted)
    pub lifetime: Duration,
    /// whether the marker moves with its frame
    pub frame_locked: bool,
    /// points of the marker \[m\] (an arrow: its start and end)
    pub points: Vec<Point>,
    /// a colour per point (empty: `color`)
    pub colors: Vec<ColorRgba>,
    /// the texture's resource (URI)
    pub texture_resource: String,
    /// the texture's image
    pub texture: CompressedImage,
    /// texture coordinates, one per point
    pub uv_coordinates: Vec<UvCoordinate>,
    /// a text marker's text
    pub text: String,
    /// a mesh marker's mesh (URI)
    pub mesh_resource: String,
    /// a mesh marker's mesh, embedded
    pub mesh_file: MeshFile,
    /// whether the mesh's own materials are used
    pub mesh_use_embedded_materials: bool,
}

impl Marker {
    /// `kind`: an arrow.
    pub const ARROW: i32 = 0;
    /// `action`: add or modify.
    pub const ADD: i32 = 0;
    /// `action`: delete.
    pub const DELETE: i32 = 2;
}

/// `visualization_msgs/MarkerArray`.
#[derive(Clone, Debug, Default, PartialEq, Serialize, Deserialize)]
pub struct MarkerArray {
    /// the markers
    pub markers: Vec<Marker>,
}
ros_type!(MarkerArray, "visualization_msgs", "MarkerArray");

/// `hri_msgs/IdsList` (ROS4HRI, REP 155): the ids of the faces, bodies,
/// voices or persons tracked now (`/humans/bodies/tracked`).
#[derive(Clone, Debug, Default, PartialEq, Serialize, Deserialize)]
pub struct IdsList {
    /// when, and the frame
    pub header: Header,
    /// the ids tracked now
    pub ids: Vec<String>,
}
ros_type!(IdsList, "hri_msgs", "IdsList");

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn time_round_trips_through_nanoseconds() {
        let t = Time::from_ns(1_764_000_000_123_456_789);
        assert_eq!(t.sec, 1_764_000_000);
        assert_eq!(t.nanosec, 123_456_789);
        assert_eq!(t.to_ns(), 1_764_000_000_123_456_789);
    }
}
