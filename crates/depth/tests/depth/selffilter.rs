//! Removing the robot's own pixels from rendered robot + human frames.

use crate::common;

use nalgebra::Point3;
use phri_depth::{
    CameraPose, Capsule, DepthError, Intrinsics, RenderOptions, Renderer, SelfFilter,
    SelfFilterParams,
};

const K: Intrinsics = Intrinsics::KINECT;

struct Labelled {
    frame: Vec<u16>,
    labels: Vec<u16>,
}

fn render(scene: &common::Scene, options: RenderOptions) -> Labelled {
    let mut r = Renderer::new(K, CameraPose::paper_default(), options).unwrap();
    let mut frame = vec![0; K.pixel_count()];
    let mut labels = vec![0; K.pixel_count()];
    r.render_labeled(
        &scene.all,
        &scene.boxes,
        scene.floor_z,
        &mut frame,
        &mut labels,
    )
    .unwrap();
    Labelled { frame, labels }
}

fn is_robot(scene: &common::Scene, label: u16) -> bool {
    label >= 1 && usize::from(label) <= scene.robot.len()
}

fn is_human(scene: &common::Scene, label: u16) -> bool {
    usize::from(label) > scene.robot.len() && usize::from(label) <= scene.all.len()
}

#[test]
fn every_robot_pixel_goes_and_every_human_pixel_stays() {
    let scene = common::scene();
    let mut filter =
        SelfFilter::new(K, CameraPose::paper_default(), SelfFilterParams::default()).unwrap();
    for seed in 0..5 {
        let options = RenderOptions {
            seed,
            ..RenderOptions::default()
        };
        let Labelled { mut frame, labels } = render(&scene, options);
        let before = frame.clone();
        let robot_before = (0..frame.len())
            .filter(|&i| is_robot(&scene, labels[i]) && before[i] > 0)
            .count();
        let human_before = (0..frame.len())
            .filter(|&i| is_human(&scene, labels[i]) && before[i] > 0)
            .count();
        assert!(robot_before > 5000 && human_before > 20_000);

        let removed = filter.apply(&scene.robot, &mut frame).unwrap();

        let robot_left = (0..frame.len())
            .filter(|&i| is_robot(&scene, labels[i]) && frame[i] > 0)
            .count();
        let human_after = (0..frame.len())
            .filter(|&i| is_human(&scene, labels[i]) && frame[i] > 0)
            .count();
        let zeroed = (0..frame.len())
            .filter(|&i| before[i] > 0 && frame[i] == 0)
            .count();
        assert_eq!(robot_left, 0, "seed {seed}: robot pixels left");
        assert_eq!(
            human_after, human_before,
            "seed {seed}: human pixels removed"
        );
        assert_eq!(
            removed, zeroed,
            "the count is the number of pixels set to 0"
        );
        // besides the robot only background touching it goes (the floor around
        // the base column, within margin + tolerance)
        assert!(removed >= robot_before && removed < robot_before + 2000);
        // nothing else changed
        assert!((0..frame.len()).all(|i| frame[i] == 0 || frame[i] == before[i]));
        // a second pass finds nothing more
        assert_eq!(filter.apply(&scene.robot, &mut frame).unwrap(), 0);
    }
}

#[test]
fn without_margin_and_tolerance_noisy_robot_pixels_survive() {
    // why the inflation matters: noise pushes readings out of the exact surface interval
    let scene = common::scene();
    let Labelled { mut frame, labels } = render(&scene, RenderOptions::default());
    let bare = SelfFilterParams {
        margin_m: 0.0,
        depth_tolerance_m: 0.0,
        noise_sigmas: 0.0,
        ..SelfFilterParams::default()
    };
    let mut filter = SelfFilter::new(K, CameraPose::paper_default(), bare).unwrap();
    filter.apply(&scene.robot, &mut frame).unwrap();
    let left = (0..frame.len())
        .filter(|&i| is_robot(&scene, labels[i]) && frame[i] > 0)
        .count();
    assert!(left > 100, "{left} robot pixels survive a bare filter");
}

#[test]
fn the_filter_follows_the_joint_state() {
    // robot capsules of another posture leave this posture's pixels in place
    let scene = common::scene();
    let Labelled { mut frame, labels } = render(&scene, RenderOptions::ideal());
    let other = common::lwr_capsules(&[1.6, -0.6, 0.0, 1.2, 0.0, -0.8, 0.0]);
    let mut filter =
        SelfFilter::new(K, CameraPose::paper_default(), SelfFilterParams::default()).unwrap();
    filter.apply(&other[2..], &mut frame).unwrap();
    let forearm = (0..frame.len())
        .filter(|&i| usize::from(labels[i]) == 6 && frame[i] > 0)
        .count();
    assert!(forearm > 200, "this posture's forearm is still there");
}

#[test]
fn bad_input_is_an_error() {
    let mut filter =
        SelfFilter::new(K, CameraPose::paper_default(), SelfFilterParams::default()).unwrap();
    let mut small = vec![0u16; 10];
    assert!(matches!(
        filter.apply(&[], &mut small),
        Err(DepthError::FrameSize { .. })
    ));
    let mut frame = vec![1000u16; K.pixel_count()];
    let nan = Capsule::sphere(Point3::new(0.0, f64::NAN, 0.0), 0.1);
    assert!(matches!(
        filter.apply(&[nan], &mut frame),
        Err(DepthError::Primitive { index: 0, .. })
    ));
    assert!(frame.iter().all(|&d| d == 1000), "untouched on error");
    let bad = SelfFilterParams {
        margin_m: -0.01,
        ..SelfFilterParams::default()
    };
    assert!(SelfFilter::new(K, CameraPose::paper_default(), bad).is_err());
}

#[test]
fn a_hand_ten_centimetres_from_the_arm_survives() {
    let mut scene = common::scene();
    // a hand (sphere, r = 4.5 cm) 10 cm above the forearm's surface (the
    // inflated forearm reaches 3 cm, the depth tolerance 2 cm + 3σ ≈ 4 cm)
    let forearm = scene.robot[4];
    let mid = forearm.a + (forearm.b - forearm.a) * 0.5;
    let axis = (forearm.b - forearm.a).normalize();
    let z = nalgebra::Vector3::z();
    let up = (z - axis * z.dot(&axis)).normalize(); // perpendicular to the axis
    let hand = Capsule::sphere(mid + up * (forearm.radius + 0.10 + 0.045), 0.045);
    assert!((forearm.distance_to_point(&hand.a) - 0.145).abs() < 1e-9);
    scene.all.push(hand);
    let hand_label = scene.all.len() as u16;
    let mut filter =
        SelfFilter::new(K, CameraPose::paper_default(), SelfFilterParams::default()).unwrap();
    for seed in 0..5 {
        let Labelled { mut frame, labels } = render(
            &scene,
            RenderOptions {
                seed,
                ..RenderOptions::default()
            },
        );
        let hand_pixels = |f: &[u16]| {
            (0..f.len())
                .filter(|&i| labels[i] == hand_label && f[i] > 0)
                .count()
        };
        let before = hand_pixels(&frame);
        assert!(before > 200);
        filter.apply(&scene.robot, &mut frame).unwrap();
        assert_eq!(hand_pixels(&frame), before, "seed {seed}");
        let robot_left = (0..frame.len())
            .filter(|&i| is_robot(&scene, labels[i]) && frame[i] > 0)
            .count();
        assert_eq!(robot_left, 0);
    }
}
