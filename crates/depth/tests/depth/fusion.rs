//! Distances fused across two cameras against Cartesian geometry: a person
//! only one camera sees is still bounded from below, because what the other
//! camera does not watch counts as occupied for it.

use crate::common::{human_capsules, lwr_points_of_interest, Q_REACH};
use nalgebra::Vector3;
use phri_depth::{
    fuse, CameraPose, CameraView, Capsule, DepthSpaceDistance, Intrinsics, PointOfInterest,
    RenderOptions, Renderer, Repulsion, RepulsionParams,
};

/// A narrow camera (about 11° by 9°) above the robot's hand, looking down:
/// it watches the hand, not the person reaching towards it.
const NARROW: Intrinsics = Intrinsics {
    width: 160,
    height: 120,
    fx: 800.0,
    fy: 800.0,
    cx: 79.5,
    cy: 59.5,
};

/// The depth-space scan's reach [m].
const RHO: f64 = 0.4;
/// How far a bound may exceed the Cartesian truth [m]: millimetre depths,
/// a pixel 4 mm across at 2 m, the occlusion rule's hidden space placed at
/// the point's depth.
const TOLERANCE: f64 = 0.01;

struct Camera {
    view: CameraView,
    distance: DepthSpaceDistance,
    frame: Vec<u16>,
}

impl Camera {
    fn new(intrinsics: Intrinsics, pose: CameraPose, person: &[Capsule]) -> Camera {
        let options = RenderOptions::ideal();
        let mut renderer = Renderer::new(intrinsics, pose, options).unwrap();
        let mut frame = vec![0; intrinsics.pixel_count()];
        // the person alone: the robot's own pixels are what the self-filter removes
        renderer.render(person, &[], None, &mut frame).unwrap();
        Camera {
            view: CameraView::new(&intrinsics, pose, options.min_range_m, options.max_range_m)
                .unwrap(),
            distance: DepthSpaceDistance::new(intrinsics, pose, RepulsionParams::default(), 0.001)
                .unwrap(),
            frame,
        }
    }

    fn repulsion(&self, point: &PointOfInterest) -> Repulsion {
        self.distance.repulsion(&self.frame, point).unwrap()
    }
}

fn truth(person: &[Capsule], point: &PointOfInterest) -> f64 {
    person
        .iter()
        .map(|c| c.distance_to_point(&point.position) - point.radius)
        .fold(f64::INFINITY, f64::min)
        .max(0.0)
}

#[test]
fn a_person_only_one_camera_sees_is_still_bounded_from_below() {
    // the person in front of the robot, reaching towards its hand
    let person = human_capsules(0.9, -0.35, 2.0);
    let front = CameraPose::paper_default();
    let points = lwr_points_of_interest(&Q_REACH);
    let hand = points[points.len() - 1].0;
    let above =
        CameraPose::look_at(&(hand + Vector3::new(0.0, 0.0, 1.5)), &hand, &Vector3::x()).unwrap();
    let cameras = [
        Camera::new(Intrinsics::KINECT, front, &person),
        Camera::new(NARROW, above, &person),
    ];
    assert!(
        cameras[0].frame.iter().any(|&d| d > 0),
        "the front camera sees the person"
    );
    assert!(
        cameras[1].frame.iter().all(|&d| d == 0),
        "the narrow camera must not see the person"
    );
    let params = RepulsionParams::default();
    let (mut watched_by_narrow, mut unseen_nearer) = (0, 0);
    for &(position, radius) in &points {
        let point = PointOfInterest::new(position, radius);
        let truth = truth(&person, &point);
        let answers: Vec<(f64, Repulsion)> = cameras
            .iter()
            .map(|c| {
                let r = c.repulsion(&point);
                (c.view.bound(&point, &r, RHO), r)
            })
            .collect();
        // each camera's bound, and so the fused one, is a lower bound of the
        // truth (to TOLERANCE)
        for (i, (bound, _)) in answers.iter().enumerate() {
            assert!(
                *bound <= truth + TOLERANCE,
                "camera {i}: bound {bound} over the truth {truth} at {position}"
            );
        }
        let fused = fuse(answers.iter().map(|(b, r)| (*b, r)), &params);
        let d = fused.repulsion.min_distance;
        assert!(
            d <= truth + TOLERANCE,
            "fused {d} over the truth {truth} at {position}"
        );
        let best = answers.iter().map(|a| a.0).fold(0.0, f64::max);
        assert_eq!(d, best, "the fused distance is the largest bound");
        // the narrow camera saw nothing: its depth-space distance alone
        // would have called the person ρ away or farther
        if cameras[1].view.clearance(&position) > radius {
            watched_by_narrow += 1;
            assert_eq!(answers[1].1.min_distance, f64::INFINITY);
            if answers[1].1.min_distance.min(RHO) > truth + TOLERANCE {
                unseen_nearer += 1;
            }
        }
    }
    assert!(
        watched_by_narrow > 0,
        "the narrow camera watches none of the arm's points"
    );
    assert!(
        unseen_nearer > 0,
        "the person is nowhere nearer than ρ to a point the narrow camera watches"
    );
}

#[test]
fn a_second_camera_that_sees_past_the_shadow_raises_the_distance() {
    // the person between the front camera and the arm: its shadow covers
    // every point of the arm for that camera (distance 0, the paper's
    // rule); the camera across the cell sees the person from the side of
    // the arm and measures the gap
    let person = human_capsules(1.1, 0.5, -2.7); // TRY
    let front = CameraPose::paper_default();
    let behind = CameraPose::paper_setup(0.6 + std::f64::consts::PI).unwrap();
    let cameras = [
        Camera::new(Intrinsics::KINECT, front, &person),
        Camera::new(Intrinsics::KINECT, behind, &person),
    ];
    let params = RepulsionParams::default();
    let mut measured = 0;
    for (position, radius) in lwr_points_of_interest(&Q_REACH) {
        let point = PointOfInterest::new(position, radius);
        let truth = truth(&person, &point);
        let bounds: Vec<(f64, Repulsion)> = cameras
            .iter()
            .map(|c| {
                let r = c.repulsion(&point);
                (c.view.bound(&point, &r, RHO), r)
            })
            .collect();
        let fused = fuse(bounds.iter().map(|(b, r)| (*b, r)), &params);
        let d = fused.repulsion.min_distance;
        assert!(d <= truth + TOLERANCE, "fused {d} over the truth {truth}");
        assert!(d >= bounds[0].0 && d >= bounds[1].0);
        assert!(
            bounds[0].0 < 0.01,
            "the front camera sees past the person: {}",
            bounds[0].0
        );
        if d >= truth.min(RHO) - 0.02 {
            measured += 1;
        }
    }
    assert!(
        measured >= 6,
        "the second camera measured {measured} of 8 points"
    );
}
