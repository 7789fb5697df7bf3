//! Shared test scene: a KUKA LWR-IV as capsules (standard DH of REFERENCE §5),
//! a standing human as capsules, a table and the floor, seen by the paper's
//! default camera.
#![allow(dead_code)]

use nalgebra::{Isometry3, Point3, Translation3, UnitQuaternion, Vector3};
use phri_depth::{Aabb, Capsule};

/// Standard DH of the LWR-IV (REFERENCE §5): a_i = 0.
const ALPHA: [f64; 7] = [
    std::f64::consts::FRAC_PI_2,
    -std::f64::consts::FRAC_PI_2,
    -std::f64::consts::FRAC_PI_2,
    std::f64::consts::FRAC_PI_2,
    std::f64::consts::FRAC_PI_2,
    -std::f64::consts::FRAC_PI_2,
    0.0,
];
const D: [f64; 7] = [0.3105, 0.0, 0.40, 0.0, 0.39, 0.0, 0.078];

/// Origins of DH frames 0..=7 in the base frame for joint angles `q` \[rad\].
pub fn lwr_frame_origins(q: &[f64; 7]) -> [Point3<f64>; 8] {
    let mut t = Isometry3::identity();
    let mut out = [Point3::origin(); 8];
    for i in 0..7 {
        let rz = UnitQuaternion::from_axis_angle(&Vector3::z_axis(), q[i]);
        let rx = UnitQuaternion::from_axis_angle(&Vector3::x_axis(), ALPHA[i]);
        t = t
            * Isometry3::from_parts(Translation3::identity(), rz)
            * Isometry3::from_parts(Translation3::new(0.0, 0.0, D[i]), rx);
        out[i + 1] = Point3::from(t.translation.vector);
    }
    out
}

/// A typical reaching posture \[rad\].
pub const Q_REACH: [f64; 7] = [0.3, -0.6, 0.0, 1.2, 0.0, -0.8, 0.0];

/// The robot's collision capsules at `q` (base frame): base column, shoulder,
/// upper arm, elbow, forearm, wrist, hand; 8 capsules.
pub fn lwr_capsules(q: &[f64; 7]) -> Vec<Capsule> {
    let p = lwr_frame_origins(q);
    let lerp = |a: Point3<f64>, b: Point3<f64>, s: f64| a + (b - a) * s;
    vec![
        Capsule::new(
            Point3::new(0.0, 0.0, 0.02),
            Point3::new(0.0, 0.0, 0.2),
            0.08,
        ),
        Capsule::new(Point3::new(0.0, 0.0, 0.2), p[2], 0.07),
        Capsule::new(p[2], lerp(p[2], p[3], 0.6), 0.065),
        Capsule::new(lerp(p[2], p[3], 0.6), p[4], 0.065),
        Capsule::new(p[4], lerp(p[4], p[5], 0.6), 0.06),
        Capsule::new(lerp(p[4], p[5], 0.6), p[5], 0.055),
        Capsule::new(p[5], p[6], 0.055),
        Capsule::new(p[6], p[7], 0.045),
    ]
}

/// Points of interest along the arm at `q`: (position, link radius); 8 points.
pub fn lwr_points_of_interest(q: &[f64; 7]) -> Vec<(Point3<f64>, f64)> {
    let p = lwr_frame_origins(q);
    let lerp = |a: Point3<f64>, b: Point3<f64>, s: f64| a + (b - a) * s;
    vec![
        (p[2], 0.07),
        (lerp(p[2], p[3], 0.5), 0.065),
        (p[3], 0.065),
        (lerp(p[4], p[5], 0.33), 0.06),
        (lerp(p[4], p[5], 0.66), 0.055),
        (p[5], 0.055),
        (lerp(p[6], p[7], 0.5), 0.05),
        (p[7], 0.045),
    ]
}

/// A standing human, 1.75 m, feet at `(x, y)` on the floor z = 0, facing
/// `heading` \[rad\] (direction of the chest normal), right forearm reaching
/// forwards and down; 17 capsules.
pub fn human_capsules(x: f64, y: f64, heading: f64) -> Vec<Capsule> {
    let f = Vector3::new(heading.cos(), heading.sin(), 0.0); // forward
    let l = Vector3::new(-heading.sin(), heading.cos(), 0.0); // left
    let o = Point3::new(x, y, 0.0);
    let at = |fw: f64, lf: f64, up: f64| o + f * fw + l * lf + Vector3::z() * up;
    vec![
        Capsule::sphere(at(0.0, 0.0, 1.63), 0.10), // head
        Capsule::new(at(0.0, 0.0, 1.45), at(0.0, 0.0, 1.52), 0.06), // neck
        Capsule::new(at(0.0, 0.0, 1.10), at(0.0, 0.0, 1.35), 0.17), // chest
        Capsule::new(at(0.0, 0.0, 0.92), at(0.0, 0.0, 1.10), 0.15), // abdomen
        Capsule::new(at(0.0, 0.1, 0.88), at(0.0, -0.1, 0.88), 0.13), // pelvis
        Capsule::new(at(0.0, 0.21, 1.38), at(0.05, 0.24, 1.10), 0.055), // left upper arm
        Capsule::new(at(0.05, 0.24, 1.10), at(0.10, 0.24, 0.86), 0.045), // left forearm
        Capsule::new(at(0.10, 0.24, 0.86), at(0.12, 0.24, 0.76), 0.045), // left hand
        Capsule::new(at(0.0, -0.21, 1.38), at(0.08, -0.24, 1.12), 0.055), // right upper arm
        Capsule::new(at(0.08, -0.24, 1.12), at(0.32, -0.20, 0.80), 0.045), // right forearm
        Capsule::new(at(0.32, -0.20, 0.80), at(0.40, -0.19, 0.72), 0.045), // right hand
        Capsule::new(at(0.0, 0.1, 0.85), at(0.0, 0.1, 0.47), 0.08), // left thigh
        Capsule::new(at(0.0, 0.1, 0.47), at(0.0, 0.1, 0.08), 0.06), // left shin
        Capsule::new(at(0.0, -0.1, 0.85), at(0.0, -0.1, 0.47), 0.08), // right thigh
        Capsule::new(at(0.0, -0.1, 0.47), at(0.0, -0.1, 0.08), 0.06), // right shin
        Capsule::new(at(0.0, 0.1, 0.04), at(0.18, 0.1, 0.04), 0.04), // left foot
        Capsule::new(at(0.0, -0.1, 0.04), at(0.18, -0.1, 0.04), 0.04), // right foot
    ]
}

/// A low table (top at 0.4 m) to the robot's left, base frame.
pub fn table() -> Aabb {
    Aabb::new(Point3::new(-0.3, 0.4, 0.0), Point3::new(0.3, 0.9, 0.4))
}

/// The whole scene: robot capsules first, then the human's.
pub struct Scene {
    pub robot: Vec<Capsule>,
    pub human: Vec<Capsule>,
    pub all: Vec<Capsule>,
    pub boxes: Vec<Aabb>,
    pub floor_z: Option<f64>,
}

/// Robot at [`Q_REACH`], the human in front of it reaching towards the end
/// effector (hand about 0.3 m from it), a table, the floor.
pub fn scene() -> Scene {
    let robot = lwr_capsules(&Q_REACH);
    let human = human_capsules(0.9, -0.35, 2.0);
    let mut all = robot.clone();
    all.extend_from_slice(&human);
    Scene {
        robot,
        human,
        all,
        boxes: vec![table()],
        floor_z: Some(0.0),
    }
}

/// First ray parameter at which the line `o + t dir` reaches the capsule, by
/// sphere tracing on the analytic distance (an independent check of the
/// renderer's closed form), and the closest approach seen on the way \[m\].
pub fn sphere_trace(
    o: &Point3<f64>,
    dir: &Vector3<f64>,
    c: &Capsule,
    t_max: f64,
) -> (Option<f64>, f64) {
    let mut t = 0.0;
    let mut closest = f64::INFINITY;
    for _ in 0..100_000 {
        let d = c.distance_to_point(&(o + dir * t));
        closest = closest.min(d);
        if d < 1e-11 {
            return (Some(t), closest);
        }
        t += d / dir.norm();
        if t > t_max {
            break;
        }
    }
    (None, closest)
}

/// A camera at 1 m height looking along base +x (image right = base −y).
pub fn front_camera() -> phri_depth::CameraPose {
    phri_depth::CameraPose::look_at(
        &Point3::new(0.0, 0.0, 1.0),
        &Point3::new(1.0, 0.0, 1.0),
        &Vector3::z(),
    )
    .expect("valid pose")
}

/// Base-frame direction of the ray through pixel `(u, v)`, scaled so that the
/// ray parameter is the depth.
pub fn pixel_ray(
    k: &phri_depth::Intrinsics,
    pose: &phri_depth::CameraPose,
    u: usize,
    v: usize,
) -> Vector3<f64> {
    pose.vector_to_base(&k.ray(u as f64, v as f64))
}
