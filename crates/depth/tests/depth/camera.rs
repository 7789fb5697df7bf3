//! Pinhole projection and the camera pose.

use nalgebra::{Point3, Vector3};
use phri_depth::{CameraPose, DepthError, Intrinsics};
use rand::rngs::SmallRng;
use rand::{Rng, SeedableRng};

#[test]
fn default_intrinsics_are_the_kinect() {
    let k = Intrinsics::default();
    assert_eq!((k.width, k.height), (640, 480));
    assert_eq!((k.fx, k.fy, k.cx, k.cy), (525.0, 525.0, 319.5, 239.5));
    assert_eq!(k.pixel_count(), 640 * 480);
    k.validate().unwrap();
}

#[test]
fn projection_round_trip() {
    let k = Intrinsics::default();
    let mut rng = SmallRng::seed_from_u64(1);
    for _ in 0..1000 {
        let p = Point3::new(
            rng.gen_range(-2.0..2.0),
            rng.gen_range(-2.0..2.0),
            rng.gen_range(0.3..5.0),
        );
        let px = k.project(&p).unwrap();
        assert_eq!(px.depth, p.z, "depth is the camera z");
        // REFERENCE §3: p_x = f_x x/z + c_x
        assert!((px.px - (525.0 * p.x / p.z + 319.5)).abs() < 1e-12);
        assert!((px.py - (525.0 * p.y / p.z + 239.5)).abs() < 1e-12);
        let back = k.back_project(px.px, px.py, px.depth);
        assert!((back - p).norm() < 1e-12, "{back} vs {p}");
        // the ray through the pixel, scaled by the depth, is the point
        assert!((k.ray(px.px, px.py) * p.z - p.coords).norm() < 1e-12);
    }
    assert!(k.project(&Point3::new(0.1, 0.1, 0.0)).is_none());
    assert!(k.project(&Point3::new(0.1, 0.1, -1.0)).is_none());
    assert!(k.project(&Point3::new(f64::NAN, 0.1, 1.0)).is_none());
}

#[test]
fn principal_point_is_on_the_optical_axis() {
    let k = Intrinsics::default();
    let p = k.back_project(319.5, 239.5, 2.0);
    assert_eq!(p, Point3::new(0.0, 0.0, 2.0));
    // image x right, y down
    let right = k.project(&Point3::new(0.1, 0.0, 1.0)).unwrap();
    let below = k.project(&Point3::new(0.0, 0.1, 1.0)).unwrap();
    assert!(right.px > 319.5 && below.py > 239.5);
}

#[test]
fn column_and_row_factors_back_project_pixel_centres() {
    let k = Intrinsics::default();
    let xs = k.column_factors();
    let ys = k.row_factors();
    assert_eq!((xs.len(), ys.len()), (640, 480));
    let p = k.back_project(17.0, 401.0, 1.7);
    assert!((xs[17] * 1.7 - p.x).abs() < 1e-15 && (ys[401] * 1.7 - p.y).abs() < 1e-15);
}

fn check_look_at(eye: Point3<f64>, target: Point3<f64>, up: Vector3<f64>) {
    let pose = CameraPose::look_at(&eye, &target, &up).unwrap();
    let r = pose.rotation();
    let m = r.matrix();
    // orthonormal, right-handed
    assert!((m.transpose() * m - nalgebra::Matrix3::identity()).norm() < 1e-12);
    assert!((m.determinant() - 1.0).abs() < 1e-12);
    // camera z points at the target
    let z = m.column(2).into_owned();
    let dir = (target - eye).normalize();
    assert!((z - dir).norm() < 1e-12, "z = {z}, towards target {dir}");
    assert!((pose.position() - eye).norm() < 1e-12);
    // the target is on the optical axis at its distance
    let t = pose.to_camera(&target);
    assert!(t.x.abs() < 1e-12 && t.y.abs() < 1e-12);
    assert!((t.z - (target - eye).norm()).abs() < 1e-12);
    // image "up" (camera −y) leans towards `up`; camera x is horizontal w.r.t. up
    let y = m.column(1).into_owned();
    assert!(y.dot(&up) < 0.0);
    assert!(m.column(0).dot(&up).abs() < 1e-12);
    // to_base inverts to_camera
    let q = Point3::new(0.3, -0.2, 0.9);
    assert!((pose.to_base(&pose.to_camera(&q)) - q).norm() < 1e-12);
    let v = Vector3::new(0.1, 0.7, -0.3);
    assert!((pose.vector_to_base(&pose.vector_to_camera(&v)) - v).norm() < 1e-12);
}

#[test]
fn look_at_gives_an_orthonormal_pose_aimed_at_the_target() {
    check_look_at(
        Point3::new(2.0, 1.0, 1.2),
        Point3::new(0.3, 0.0, 0.4),
        Vector3::z(),
    );
    check_look_at(
        Point3::new(-1.0, 3.0, 0.2),
        Point3::new(0.0, 0.0, 1.0),
        Vector3::z(),
    );
    check_look_at(
        Point3::new(0.0, 0.0, 3.0),
        Point3::new(0.1, 0.0, 0.0),
        Vector3::z() * 5.0,
    );
    check_look_at(
        Point3::new(0.0, 0.0, 3.0),
        Point3::new(0.0, 0.0, 0.0),
        Vector3::x(),
    );
}

#[test]
fn looking_along_base_x_with_z_up_puts_base_y_on_the_left() {
    let pose = CameraPose::look_at(
        &Point3::new(0.0, 0.0, 1.0),
        &Point3::new(1.0, 0.0, 1.0),
        &Vector3::z(),
    )
    .unwrap();
    let k = Intrinsics::default();
    let left = pose.project(&k, &Point3::new(2.0, 0.5, 1.0)).unwrap();
    let up = pose.project(&k, &Point3::new(2.0, 0.0, 1.5)).unwrap();
    assert!(left.px < k.cx, "base +y appears left");
    assert!(up.py < k.cy, "base +z appears up");
    assert!((left.depth - 2.0).abs() < 1e-12);
}

#[test]
fn paper_default_camera() {
    let pose = CameraPose::paper_default();
    let eye = pose.position();
    // 2 m radial distance, 1.2 m height, azimuth 0.6 rad (front-left)
    assert!((eye.x.hypot(eye.y) - 2.0).abs() < 1e-12);
    assert!((eye.z - 1.2).abs() < 1e-12);
    assert!((eye.y.atan2(eye.x) - 0.6).abs() < 1e-12);
    assert!(eye.x > 0.0 && eye.y > 0.0);
    let k = Intrinsics::default();
    let target = pose
        .project(&k, &Point3::new(0.3, 0.0, 0.4))
        .expect("target in front");
    assert!((target.px - k.cx).abs() < 1e-9 && (target.py - k.cy).abs() < 1e-9);
    // the robot base and a raised end effector are in view
    for p in [Point3::new(0.0, 0.0, 0.0), Point3::new(0.5, 0.2, 1.0)] {
        let px = pose.project(&k, &p).unwrap();
        assert!(
            px.px > 0.0 && px.px < 639.0 && px.py > 0.0 && px.py < 479.0,
            "{p} at {px:?}"
        );
    }
    assert_eq!(CameraPose::paper_setup(0.6).unwrap(), pose);
    assert_eq!(CameraPose::default(), pose);
}

#[test]
fn degenerate_look_at_and_intrinsics_are_refused() {
    let e = Point3::new(1.0, 0.0, 1.0);
    assert!(matches!(
        CameraPose::look_at(&e, &e, &Vector3::z()),
        Err(DepthError::Pose(_))
    ));
    assert!(matches!(
        CameraPose::look_at(&e, &Point3::new(1.0, 0.0, 0.0), &Vector3::z()),
        Err(DepthError::Pose(_))
    ));
    assert!(CameraPose::look_at(&e, &Point3::origin(), &Vector3::zeros()).is_err());
    assert!(CameraPose::look_at(&e, &Point3::new(f64::NAN, 0.0, 0.0), &Vector3::z()).is_err());
    let bad = [
        Intrinsics {
            width: 0,
            ..Intrinsics::default()
        },
        Intrinsics {
            fx: 0.0,
            ..Intrinsics::default()
        },
        Intrinsics {
            fy: f64::NAN,
            ..Intrinsics::default()
        },
        Intrinsics {
            cx: f64::INFINITY,
            ..Intrinsics::default()
        },
    ];
    for k in bad {
        assert!(
            matches!(k.validate(), Err(DepthError::Intrinsics(_))),
            "{k:?}"
        );
    }
}
