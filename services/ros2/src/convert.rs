//! phri's messages as ROS 2 messages: pure functions, no I/O. Frames follow
//! REP 105: [`BASE_FRAME`] is the robot's base (phri's base frame, z up);
//! each moving link is a child of it in `/tf` under its model name; the
//! depth camera's optical frame is [`CAMERA_FRAME`] (+z along the optical
//! axis, +x right, +y down, REP 103's `_optical` convention).

use nalgebra::{Matrix3, UnitQuaternion, Vector3 as V3};
use phri_ipc::{CollabState, FrameHeader, RepulsionResult};
use phri_model::Placement;

use crate::msgs::{
    ColorRgba, Header, Image, JointState, Marker, MarkerArray, PointCloud2, PointField, Quaternion,
    Time, Transform, TransformStamped, Vector3, Wrench, WrenchStamped,
};

/// The robot's base frame (REP 105).
pub const BASE_FRAME: &str = "base_link";
/// The first depth camera's optical frame.
pub const CAMERA_FRAME: &str = "camera_depth_optical_frame";
/// Bytes per point of `/phri/points`: x, y, z as little-endian f32 \[m\].
pub const POINT_STEP: usize = phri_view::depth::POINT_STRIDE;

/// phri's clock (CLOCK_MONOTONIC) to ROS time (the system clock): the
/// offset between the two, read when the bridge samples them.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub struct Clock {
    /// realtime − monotonic \[ns\]
    pub offset_ns: i128,
}

impl Clock {
    /// From a reading of both clocks \[ns\].
    pub fn new(monotonic_ns: u64, realtime_ns: u64) -> Clock {
        Clock {
            offset_ns: i128::from(realtime_ns) - i128::from(monotonic_ns),
        }
    }

    /// A CLOCK_MONOTONIC time as ROS time.
    pub fn ros(&self, monotonic_ns: u64) -> Time {
        let t = (i128::from(monotonic_ns) + self.offset_ns).clamp(0, i128::from(u64::MAX));
        Time::from_ns(t as u64)
    }
}

fn header(stamp: Time, frame: &str) -> Header {
    Header {
        stamp,
        frame_id: frame.to_string(),
    }
}

fn quaternion(r: &Matrix3<f64>) -> Quaternion {
    let q = UnitQuaternion::from_matrix(r);
    Quaternion {
        x: q.i,
        y: q.j,
        z: q.k,
        w: q.w,
    }
}

fn vector(v: &V3<f64>) -> Vector3 {
    Vector3 {
        x: v.x,
        y: v.y,
        z: v.z,
    }
}

/// `robot/state` into `out` (its names set once by the caller): positions
/// [rad or m] and the torque applied in the last period as effort \[Nm\];
/// no velocities (the robot measures positions only). `dof` values, at
/// most as many as names.
pub fn joint_state(s: &phri_ipc::JointState, stamp: Time, out: &mut JointState) {
    let n = (s.dof as usize).min(s.q.len()).min(out.name.len());
    out.header.stamp = stamp;
    out.position.clear();
    out.position.extend_from_slice(&s.q[..n]);
    out.effort.clear();
    out.effort.extend_from_slice(&s.tau[..n]);
    out.velocity.clear();
}

/// One transform from `parent` to `child` at `placement` (the child's
/// frame in the parent's).
pub fn transform(stamp: Time, parent: &str, child: &str, p: &Placement) -> TransformStamped {
    TransformStamped {
        header: header(stamp, parent),
        child_frame_id: child.to_string(),
        transform: Transform {
            translation: vector(&p.p),
            rotation: quaternion(&p.r),
        },
    }
}

/// The camera's optical frame in [`BASE_FRAME`], from a frame's header
/// (its pose: rotation row-major, translation \[m\]).
pub fn camera_transform(stamp: Time, h: &FrameHeader) -> TransformStamped {
    let (r, p) = phri_view::depth::camera_pose(h);
    transform(stamp, BASE_FRAME, CAMERA_FRAME, &Placement { r, p })
}

/// The estimated contact forces F̂ of the collaboration as one wrench in
/// [`BASE_FRAME`]: their sum \[N\], and their moment about the frame's origin
/// Σ p × F̂ \[Nm\] (so one contact's point is recoverable from the two). A
/// non-finite force or point counts as none.
pub fn contact_wrench(c: &CollabState, stamp: Time) -> WrenchStamped {
    let mut force = V3::zeros();
    let mut torque = V3::zeros();
    let n = (c.n_forces as usize).min(c.forces.len());
    for f in &c.forces[..n] {
        let (p, v) = (V3::from(f.point), V3::from(f.force));
        if p.iter().chain(v.iter()).all(|x| x.is_finite()) {
            force += v;
            torque += p.cross(&v);
        }
    }
    WrenchStamped {
        header: header(stamp, BASE_FRAME),
        wrench: Wrench {
            force: vector(&force),
            torque: vector(&torque),
        },
    }
}

/// A depth frame as `sensor_msgs/Image`, `16UC1` (millimetres, little
/// endian, 0: no reading) in [`CAMERA_FRAME`], at full resolution, into
/// `out` (its buffer reused). `false` when the payload is short.
pub fn depth_image(h: &FrameHeader, depth: &[u16], stamp: Time, out: &mut Image) -> bool {
    if !phri_view::depth::complete(h, depth) {
        return false;
    }
    let (w, ht) = (h.width as usize, h.height as usize);
    let scale_mm = h.depth_scale * 1000.0;
    out.header = header(stamp, CAMERA_FRAME);
    out.width = w as u32;
    out.height = ht as u32;
    out.encoding = "16UC1".to_string();
    out.is_bigendian = 0;
    out.step = (w * 2) as u32;
    out.data.clear();
    out.data.reserve(w * ht * 2);
    // phri's depths are in units of depth_scale [m]; 16UC1 is millimetres
    let exact_mm = (scale_mm - 1.0).abs() < 1e-9;
    for &d in &depth[..w * ht] {
        let mm = if exact_mm {
            d
        } else {
            (f64::from(d) * scale_mm).round().min(f64::from(u16::MAX)) as u16
        };
        out.data.extend_from_slice(&mm.to_le_bytes());
    }
    true
}

/// A depth frame's valid pixels as `sensor_msgs/PointCloud2` in
/// [`CAMERA_FRAME`] (x, y, z float32 \[m\]), one pixel in `k` per axis,
/// unorganised (height 1). `false` when the payload is short, `k` is 0 or
/// the intrinsics are unusable.
pub fn points(
    h: &FrameHeader,
    depth: &[u16],
    k: usize,
    stamp: Time,
    out: &mut PointCloud2,
) -> bool {
    out.data.clear();
    if !phri_view::depth::optical_points(h, depth, k, &mut out.data) {
        return false;
    }
    let n = out.data.len() / POINT_STEP;
    let field = |name: &str, offset: u32| PointField {
        name: name.to_string(),
        offset,
        datatype: PointField::FLOAT32,
        count: 1,
    };
    out.header = header(stamp, CAMERA_FRAME);
    out.height = 1;
    out.width = n as u32;
    out.fields = vec![field("x", 0), field("y", 4), field("z", 8)];
    out.is_bigendian = false;
    out.point_step = POINT_STEP as u32;
    out.row_step = (n * POINT_STEP) as u32;
    out.is_dense = true;
    true
}

/// Length of a repulsion arrow per m/s of `V_Call` \[s\].
pub const VELOCITY_ARROW_S: f64 = 0.5;

/// The repulsion workers' latest results as arrows in [`BASE_FRAME`]: one
/// per control point (namespace `repulsion`, id = the point's index) from
/// the point along its repulsive velocity `V_Call` ([`VELOCITY_ARROW_S`]
/// long per m/s), deleted while nothing is in its surveillance region.
pub fn repulsion_markers(results: &[RepulsionResult], stamp: Time) -> MarkerArray {
    let mut markers = Vec::new();
    for r in results {
        let n = (r.n_points as usize).min(r.points.len());
        for p in &r.points[..n] {
            let pos = V3::from(p.position);
            let v = V3::from(p.v_call);
            let shown = p.active != 0
                && pos.iter().chain(v.iter()).all(|x| x.is_finite())
                && v.norm() > 0.0;
            let mut m = Marker {
                header: header(stamp, BASE_FRAME),
                ns: "repulsion".to_string(),
                id: p.point as i32,
                kind: Marker::ARROW,
                action: if shown { Marker::ADD } else { Marker::DELETE },
                ..Marker::default()
            };
            if shown {
                m.points = vec![vector(&pos), vector(&(pos + v * VELOCITY_ARROW_S))];
                // shaft and head diameters, head length [m]
                m.scale = Vector3 {
                    x: 0.01,
                    y: 0.02,
                    z: 0.03,
                };
                m.color = ColorRgba {
                    r: 1.0,
                    g: 0.4,
                    b: 0.0,
                    a: 1.0,
                };
            }
            markers.push(m);
        }
    }
    MarkerArray { markers }
}

#[cfg(test)]
mod tests {
    use super::*;
    use phri_ipc::{ContactForce, Zeroed};

    #[test]
    fn the_clock_maps_monotonic_to_realtime() {
        let c = Clock::new(5_000_000_000, 1_764_000_000_000_000_000);
        assert_eq!(c.ros(6_500_000_000).to_ns(), 1_764_000_001_500_000_000);
    }

    #[test]
    fn a_rotation_becomes_its_unit_quaternion() {
        // 90° about z
        let r = Matrix3::new(0.0, -1.0, 0.0, 1.0, 0.0, 0.0, 0.0, 0.0, 1.0);
        let q = quaternion(&r);
        let h = std::f64::consts::FRAC_1_SQRT_2;
        assert!((q.z - h).abs() < 1e-12 && (q.w - h).abs() < 1e-12, "{q:?}");
        assert!(q.x.abs() < 1e-12 && q.y.abs() < 1e-12);
    }

    #[test]
    fn the_contact_wrench_is_the_forces_sum_and_moment_about_the_base() {
        let mut c = CollabState::zeroed();
        c.n_forces = 2;
        c.forces[0] = ContactForce {
            point: [0.5, 0.0, 0.4],
            force: [0.0, 0.0, -10.0],
            frame: 7,
            observable: 1,
        };
        c.forces[1] = ContactForce {
            point: [f64::NAN, 0.0, 0.0],
            force: [1.0, 0.0, 0.0],
            frame: 5,
            observable: 1,
        };
        let w = contact_wrench(&c, Time::default()).wrench;
        assert_eq!((w.force.x, w.force.y, w.force.z), (0.0, 0.0, -10.0));
        // p × F = (0.5, 0, 0.4) × (0, 0, −10) = (0, 5, 0)
        assert!((w.torque.y - 5.0).abs() < 1e-12 && w.torque.x.abs() < 1e-12);
    }

    fn frame(w: u32, h: u32) -> FrameHeader {
        let mut f = FrameHeader::zeroed();
        f.width = w;
        f.height = h;
        f.fx = 500.0;
        f.fy = 500.0;
        f.cx = f64::from(w) / 2.0;
        f.cy = f64::from(h) / 2.0;
        f.depth_scale = 0.001;
        f
    }

    #[test]
    fn an_image_keeps_millimetres_and_a_short_payload_is_refused() {
        let h = frame(4, 2);
        let depth = [1000, 0, 2000, 65535, 1, 2, 3, 4];
        let mut img = Image::default();
        assert!(depth_image(&h, &depth, Time::default(), &mut img));
        assert_eq!((img.width, img.height, img.step), (4, 2, 8));
        assert_eq!(&img.data[..4], &[0xe8, 0x03, 0, 0]);
        assert!(!depth_image(&h, &depth[..7], Time::default(), &mut img));
    }

    #[test]
    fn points_are_the_valid_pixels_back_projected() {
        let h = frame(4, 2);
        // pixel (u 2, v 1) at 2 m lies on the optical axis: (0, 0, 2)
        let mut depth = [0u16; 8];
        depth[6] = 2000;
        let mut pc = PointCloud2::default();
        assert!(points(&h, &depth, 1, Time::default(), &mut pc));
        assert_eq!(pc.width, 1);
        let f = |i: usize| f32::from_le_bytes(pc.data[i * 4..i * 4 + 4].try_into().unwrap());
        assert_eq!((f(0), f(1), f(2)), (0.0, 0.0, 2.0));
        assert!(!points(&h, &depth, 0, Time::default(), &mut pc));
    }
}
