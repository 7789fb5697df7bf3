//! Hard cases rendered by phri-depth's renderer (Kinect-like noise and edge
//! drop-outs, the floor in view, found by RANSAC) from capsule people of the
//! simulator's proportions, measured against the capsules' truth: the head at
//! the head capsule's centre, a hand at its hand capsule's middle.

use nalgebra::{Point3, Vector3};
use phri_depth::{Aabb, CameraPose, Capsule, Intrinsics, RenderOptions, Renderer};
use phri_people::{FloorMode, Joint, Person, Tracker, TrackerConfig, MAX_PEOPLE};

const K: Intrinsics = Intrinsics::KINECT;
const TOLERANCE_M: f64 = 0.10;

/// An arm's pose.
#[derive(Clone, Copy)]
enum Arm {
    /// hanging, a little away from the body
    Down,
    /// raised above the shoulder, the hand above the head
    Raised,
    /// held out sideways at 45°
    Out,
    /// the forearm forward at the belly, the hand ~0.2 m in front of the torso
    Front,
}

/// A capsule person standing on the floor (base frame z up, metres).
struct Body {
    capsules: Vec<Capsule>,
    head: Point3<f64>,
    /// the person's own left and right hands
    left_hand: Point3<f64>,
    right_hand: Point3<f64>,
}

/// A person at `(x, y)` on the floor facing the direction `yaw` \[rad\].
fn person(x: f64, y: f64, yaw: f64, left: Arm, right: Arm) -> Body {
    let fwd = Vector3::new(yaw.cos(), yaw.sin(), 0.0);
    let lft = Vector3::new(-yaw.sin(), yaw.cos(), 0.0);
    let p = |f: f64, l: f64, u: f64| Point3::new(x, y, 0.0) + fwd * f + lft * l + Vector3::z() * u;
    let mut caps = vec![
        Capsule::new(p(0.0, 0.0, 1.56), p(0.0, 0.0, 1.65), 0.10),
        Capsule::new(p(0.0, 0.0, 1.08), p(0.0, 0.0, 1.33), 0.15),
        Capsule::new(p(0.0, -0.08, 0.95), p(0.0, 0.08, 0.95), 0.12),
    ];
    for s in [1.0, -1.0] {
        caps.push(Capsule::new(
            p(0.0, s * 0.1, 0.88),
            p(0.0, s * 0.1, 0.5),
            0.075,
        ));
        caps.push(Capsule::new(
            p(0.0, s * 0.1, 0.5),
            p(0.0, s * 0.1, 0.1),
            0.055,
        ));
    }
    let mut hands = [Point3::origin(); 2];
    for (k, (s, arm)) in [(1.0, left), (-1.0, right)].into_iter().enumerate() {
        let shoulder = p(0.0, s * 0.19, 1.45);
        let (elbow, wrist) = match arm {
            Arm::Down => (p(0.0, s * 0.26, 1.16), p(0.02, s * 0.33, 0.89)),
            Arm::Raised => (p(0.0, s * 0.42, 1.62), p(0.03, s * 0.44, 1.9)),
            Arm::Out => (p(0.0, s * 0.4, 1.25), p(0.0, s * 0.6, 1.06)),
            Arm::Front => (p(0.05, s * 0.24, 1.17), p(0.33, s * 0.1, 1.15)),
        };
        let dir = (wrist - elbow).normalize();
        caps.push(Capsule::new(shoulder, elbow, 0.05));
        caps.push(Capsule::new(elbow, wrist, 0.04));
        caps.push(Capsule::new(wrist, wrist + dir * 0.1, 0.045));
        hands[k] = wrist + dir * 0.05;
    }
    Body {
        capsules: caps,
        head: p(0.0, 0.0, 1.605),
        left_hand: hands[0],
        right_hand: hands[1],
    }
}

/// The camera 1.3 m above the floor at the origin, looking along +x, a little down.
fn camera() -> CameraPose {
    CameraPose::look_at(
        &Point3::new(0.0, 0.0, 1.3),
        &Point3::new(3.0, 0.0, 1.0),
        &Vector3::z(),
    )
    .unwrap()
}

fn tracker(pose: &CameraPose) -> Tracker {
    // the world's up in the camera frame, from the camera's pose
    let up = pose.rotation().transpose() * Vector3::z();
    let cfg = TrackerConfig {
        up_camera: [up.x, up.y, up.z],
        floor: FloorMode::Ransac,
        ..TrackerConfig::default()
    };
    Tracker::new(K, cfg).unwrap()
}

fn render(r: &mut Renderer, caps: &[Capsule], boxes: &[Aabb]) -> Vec<u16> {
    let mut out = vec![0u16; K.pixel_count()];
    r.render(caps, boxes, Some(0.0), &mut out).unwrap();
    out
}

fn cam(pose: &CameraPose, p: &Point3<f64>) -> [f64; 3] {
    let c = pose.to_camera(p);
    [c.x, c.y, c.z]
}

fn dist(a: [f64; 3], b: [f64; 3]) -> f64 {
    ((a[0] - b[0]).powi(2) + (a[1] - b[1]).powi(2) + (a[2] - b[2]).powi(2)).sqrt()
}

/// The reported person nearest `body`'s head, if any.
fn nearest<'a>(people: &'a [Person], pose: &CameraPose, body: &Body) -> Option<&'a Person> {
    let head = cam(pose, &body.head);
    people.iter().min_by(|a, b| {
        dist(a.joints[Joint::Head as usize], head)
            .total_cmp(&dist(b.joints[Joint::Head as usize], head))
    })
}

/// Error \[m\] of joint `j` against the truth `t` (base frame); infinite when not found.
fn error(p: &Person, pose: &CameraPose, j: Joint, t: &Point3<f64>) -> f64 {
    if p.confidence[j as usize] > 0.0 {
        dist(p.joints[j as usize], cam(pose, t))
    } else {
        f64::INFINITY
    }
}

/// Tracks `frames` frames of one scene alone; checks `checks` (joint, truth) of `body`.
fn check_scene(name: &str, bodies: &[Body], boxes: &[Aabb], checks: &[(usize, Joint)]) {
    let pose = camera();
    let mut r = Renderer::new(K, pose, RenderOptions::default()).unwrap();
    let caps: Vec<Capsule> = bodies
        .iter()
        .flat_map(|b| b.capsules.iter().copied())
        .collect();
    let mut t = tracker(&pose);
    let mut out = [Person::default(); MAX_PEOPLE];
    let mut failures = Vec::new();
    // a few frames of the same scene (fresh noise each): the first alone, then tracked
    for frame in 0..5 {
        r.reseed(frame);
        let depth = render(&mut r, &caps, boxes);
        let n = t.step(&depth, 1.0 / 30.0, &mut out).unwrap();
        assert_eq!(
            n,
            bodies.len(),
            "{name} frame {frame}: {n} people for {}",
            bodies.len()
        );
        for &(b, j) in checks {
            let body = &bodies[b];
            let truth = match j {
                Joint::Head => body.head,
                Joint::LeftHand => body.left_hand,
                Joint::RightHand => body.right_hand,
                _ => unreachable!(),
            };
            let p = nearest(&out[..n], &pose, body).unwrap();
            let e = error(p, &pose, j, &truth);
            eprintln!("{name} frame {frame} body {b} {j:?}: {:.1} cm", e * 100.0);
            if !(e <= TOLERANCE_M) {
                failures.push(format!("frame {frame} body {b} {j:?}: {:.1} cm", e * 100.0));
            }
        }
    }
    assert!(failures.is_empty(), "{name}: {failures:#?}");
}

const FACING_CAMERA: f64 = std::f64::consts::PI;

#[test]
fn a_person_with_a_raised_hand() {
    let b = person(2.4, 0.0, FACING_CAMERA, Arm::Down, Arm::Raised);
    check_scene(
        "raised hand",
        &[b],
        &[],
        &[
            (0, Joint::Head),
            (0, Joint::LeftHand),
            (0, Joint::RightHand),
        ],
    );
}

#[test]
fn two_people_side_by_side() {
    let a = person(2.8, 0.55, FACING_CAMERA, Arm::Out, Arm::Down);
    let b = person(2.8, -0.55, FACING_CAMERA, Arm::Down, Arm::Raised);
    check_scene(
        "two people",
        &[a, b],
        &[],
        &[
            (0, Joint::Head),
            (0, Joint::LeftHand),
            (0, Joint::RightHand),
            (1, Joint::Head),
            (1, Joint::LeftHand),
            (1, Joint::RightHand),
        ],
    );
}

#[test]
fn a_person_partly_out_of_view() {
    // the image's right edge (base −y) cuts the person's left side
    let half_width = K.cx / K.fx * 2.2;
    let b = person(2.2, -(half_width - 0.05), FACING_CAMERA, Arm::Out, Arm::Out);
    check_scene(
        "partly out of view",
        &[b],
        &[],
        &[(0, Joint::Head), (0, Joint::RightHand)],
    );
}

#[test]
fn a_hand_in_front_of_the_torso() {
    let b = person(2.0, 0.1, FACING_CAMERA, Arm::Raised, Arm::Front);
    check_scene(
        "hand near torso",
        &[b],
        &[],
        &[
            (0, Joint::Head),
            (0, Joint::LeftHand),
            (0, Joint::RightHand),
        ],
    );
}

#[test]
fn nobody_in_an_empty_room() {
    let pose = camera();
    let mut r = Renderer::new(K, pose, RenderOptions::default()).unwrap();
    let boxes = [
        // a table, a cabinet, a back wall and a side wall
        Aabb::new(Point3::new(2.0, -0.8, 0.0), Point3::new(2.6, 0.2, 0.75)),
        Aabb::new(Point3::new(2.5, 0.6, 0.0), Point3::new(2.9, 1.0, 1.9)),
        Aabb::new(Point3::new(4.0, -3.0, 0.0), Point3::new(4.1, 3.0, 2.6)),
        Aabb::new(Point3::new(0.5, 1.6, 0.0), Point3::new(4.0, 1.7, 2.6)),
    ];
    let mut t = tracker(&pose);
    let mut out = [Person::default(); MAX_PEOPLE];
    for frame in 0..10 {
        r.reseed(frame);
        let depth = render(&mut r, &[], &boxes);
        let n = t.step(&depth, 1.0 / 30.0, &mut out).unwrap();
        assert_eq!(n, 0, "frame {frame}: {:?}", &out[..n]);
        // nothing at all in view but the floor
        let depth = render(&mut r, &[], &[]);
        assert_eq!(t.step(&depth, 1.0 / 30.0, &mut out).unwrap(), 0);
    }
}

#[test]
fn a_learned_background_leaves_only_the_person() {
    let pose = camera();
    let mut r = Renderer::new(K, pose, RenderOptions::default()).unwrap();
    let boxes = [Aabb::new(
        Point3::new(2.6, -0.8, 0.0),
        Point3::new(3.2, 0.2, 0.75),
    )];
    let up = pose.rotation().transpose() * Vector3::z();
    let cfg = TrackerConfig {
        up_camera: [up.x, up.y, up.z],
        ..TrackerConfig::default()
    };
    let mut t = Tracker::new(K, cfg).unwrap();
    for frame in 0..10 {
        r.reseed(100 + frame);
        t.learn_background(&render(&mut r, &[], &boxes)).unwrap();
    }
    let mut out = [Person::default(); MAX_PEOPLE];
    r.reseed(7);
    assert_eq!(
        t.step(&render(&mut r, &[], &boxes), 0.033, &mut out)
            .unwrap(),
        0
    );
    let b = person(2.3, 0.0, FACING_CAMERA, Arm::Out, Arm::Raised);
    let n = t
        .step(&render(&mut r, &b.capsules, &boxes), 0.033, &mut out)
        .unwrap();
    assert_eq!(n, 1);
    for (j, truth) in [
        (Joint::Head, b.head),
        (Joint::LeftHand, b.left_hand),
        (Joint::RightHand, b.right_hand),
    ] {
        let e = error(&out[0], &pose, j, &truth);
        assert!(e <= TOLERANCE_M, "{j:?}: {:.1} cm", e * 100.0);
    }
}

#[test]
fn a_person_walking_behind_another_keeps_two_ids() {
    let pose = camera();
    let mut r = Renderer::new(K, pose, RenderOptions::default()).unwrap();
    let mut t = tracker(&pose);
    let mut out = [Person::default(); MAX_PEOPLE];
    let still = person(2.2, 0.0, FACING_CAMERA, Arm::Down, Arm::Down);
    let mut ids: [Vec<u32>; 2] = [Vec::new(), Vec::new()];
    let dt = 1.0 / 30.0;
    // B walks at 1 m/s from y = 1.5 to y = −1.5, 1 m behind A, sideways to the camera
    for k in 0..90 {
        let y = 1.5 - k as f64 * dt;
        let walker = person(3.2, y, -std::f64::consts::FRAC_PI_2, Arm::Down, Arm::Down);
        r.reseed(k);
        let caps: Vec<Capsule> = still
            .capsules
            .iter()
            .chain(&walker.capsules)
            .copied()
            .collect();
        let depth = render(&mut r, &caps, &[]);
        let n = t.step(&depth, dt, &mut out).unwrap();
        for (i, body) in [&still, &walker].into_iter().enumerate() {
            let head = cam(&pose, &body.head);
            if let Some(p) = out[..n]
                .iter()
                .find(|p| dist(p.joints[Joint::Head as usize], head) < 0.3)
            {
                if !ids[i].contains(&p.id) {
                    ids[i].push(p.id);
                }
            }
        }
    }
    assert_eq!(ids[0].len(), 1, "the still person's ids: {:?}", ids[0]);
    assert_eq!(ids[1].len(), 1, "the walker's ids: {:?}", ids[1]);
    assert_ne!(ids[0], ids[1]);
}

#[test]
fn three_people_in_a_corridor_with_walls() {
    let walls = [
        Aabb::new(Point3::new(0.5, 1.5, 0.0), Point3::new(8.0, 1.6, 2.6)),
        Aabb::new(Point3::new(0.5, -1.6, 0.0), Point3::new(8.0, -1.5, 2.6)),
    ];
    let bodies = [
        person(2.6, 0.8, FACING_CAMERA, Arm::Down, Arm::Down),
        person(3.2, -0.7, FACING_CAMERA - 0.4, Arm::Raised, Arm::Down),
        person(3.9, 0.1, FACING_CAMERA + 0.3, Arm::Down, Arm::Out),
    ];
    check_scene(
        "corridor",
        &bodies,
        &walls,
        &[
            (0, Joint::Head),
            (1, Joint::Head),
            (1, Joint::LeftHand),
            (2, Joint::Head),
        ],
    );
}

#[test]
fn a_person_close_to_a_camera_at_head_height() {
    // the camera 1.6 m high looking straight ahead, the person 1.1 m away
    let pose = CameraPose::look_at(
        &Point3::new(0.0, 0.0, 1.6),
        &Point3::new(3.0, 0.0, 1.6),
        &Vector3::z(),
    )
    .unwrap();
    let mut r = Renderer::new(K, pose, RenderOptions::default()).unwrap();
    let b = person(1.1, 0.0, FACING_CAMERA, Arm::Down, Arm::Raised);
    let mut t = tracker(&pose);
    let mut out = [Person::default(); MAX_PEOPLE];
    let mut failures = Vec::new();
    for frame in 0..5 {
        r.reseed(frame);
        let depth = render(&mut r, &b.capsules, &[]);
        let n = t.step(&depth, 1.0 / 30.0, &mut out).unwrap();
        assert_eq!(n, 1, "frame {frame}");
        for (j, truth) in [(Joint::Head, b.head), (Joint::RightHand, b.right_hand)] {
            let e = error(&out[0], &pose, j, &truth);
            eprintln!("close frame {frame} {j:?}: {:.1} cm", e * 100.0);
            if !(e <= TOLERANCE_M) {
                failures.push(format!("frame {frame} {j:?}: {:.1} cm", e * 100.0));
            }
        }
    }
    assert!(failures.is_empty(), "{failures:#?}");
}
