//! The perception steps in one process: camera → ingestion → repulsion worker,
//! checked against geometry (and so the binaries of this package are built by
//! `cargo test --workspace` for the system tests).

use nalgebra::Vector3;
use phri_config::{CameraConfig, Config, IngestConfig, PointConfig, RepulsionConfig};
use phri_depth::RenderOptions;
use phri_ipc::{FrameHeader, WorldState, Zeroed};
use phri_model::{Data, Model};
use phri_perception::{CameraSim, FrameError, Ingest, IngestOutcome, StateHistory, Worker};

const Q0: [f64; 7] = [0.0, -0.4, 0.0, 1.8, 0.0, -0.6, 0.0];

fn model() -> Model {
    phri_config::Loaded::defaults().model().unwrap()
}

/// `[perception]` as deployed.
fn ingest_config() -> IngestConfig {
    Config::defaults().perception
}

/// `[repulsion]` as deployed, with one control point: the flange, radius
/// 0.05 m (what the geometry below measures against).
fn repulsion_config() -> RepulsionConfig {
    RepulsionConfig {
        workers: 1,
        points: vec![PointConfig {
            name: "end_effector".into(),
            link: "lwr_flange".into(),
            xyz: [0.0; 3],
            radius: 0.05,
            law: None,
        }],
        ..Config::defaults().repulsion
    }
}

fn ee(model: &Model) -> Vector3<f64> {
    let mut d = Data::new(model);
    phri_model::forward_kinematics(model, &mut d, &Q0).unwrap();
    phri_model::frame_placement(model, &d, model.frame_id("lwr_flange").unwrap()).p
}

/// The arm at Q0 and a ball of radius 0.08 m at `centre`.
fn world(centre: Vector3<f64>) -> WorldState {
    let mut w = WorldState::zeroed();
    w.seq = 1;
    w.stamp_ns = 1_000_000_000;
    w.dof = 7;
    w.q[..7].copy_from_slice(&Q0);
    w.n_human = 1;
    w.human[0].a = [centre.x, centre.y, centre.z];
    w.human[0].b = [centre.x, centre.y, centre.z];
    w.human[0].radius = 0.08;
    w
}

fn pipeline(centre: Vector3<f64>) -> (phri_ipc::PointRepulsion, u32) {
    let w = world(centre);
    let azimuth = Config::defaults().camera.azimuth_rad;
    let (_, header, filtered, removed) = filtered_view(azimuth, &w);
    assert_eq!(header.capture_ns, w.stamp_ns);
    let model = model();
    let mut worker = Worker::new(model, &repulsion_config(), 0).unwrap();
    let results = worker.step(&header, &filtered).unwrap().to_vec();
    let ee_result = results.iter().find(|r| r.point == 0).copied().unwrap();
    // the message carries the same results, for this frame
    let msg = *worker.respond(&header, &filtered).unwrap();
    assert_eq!(msg.n_points as usize, results.len());
    assert_eq!(
        (msg.frame_seq, msg.capture_ns),
        (header.seq, header.capture_ns)
    );
    assert_eq!((msg.worker, msg.workers, msg.seq), (0, 1, 1));
    assert_eq!(msg.points[0].min_distance, ee_result.min_distance);
    (ee_result, removed)
}

#[test]
fn a_ball_near_the_end_effector_is_seen_at_its_distance_and_repels_it() {
    let model = model();
    let p = ee(&model);
    // beside the end effector, across the camera's line of sight (same depth: nothing occluded)
    let camera = Config::defaults().camera.pose().unwrap().position().coords;
    let across = (p - camera).cross(&Vector3::z()).normalize();
    let centre = p + across * 0.25;
    let (r, removed) = pipeline(centre);
    assert!(
        removed > 1000,
        "the robot's own pixels were not removed ({removed})"
    );
    // surface-to-surface: centre distance − ball radius − control point radius (0.05)
    let truth = (centre - p).norm() - 0.08 - 0.05;
    assert_eq!(r.active, 1);
    assert!(
        (r.min_distance - truth).abs() < 0.03,
        "depth-space {} vs geometric {truth}",
        r.min_distance
    );
    let away = (p - centre).normalize();
    let v = Vector3::from(r.v_call);
    assert!(
        v.norm() > 0.0 && v.normalize().dot(&away) > 0.5,
        "repulsion {v:?} does not point away from the ball"
    );
}

#[test]
fn placing_the_points_only_gives_the_scan_s_positions_and_no_obstacle() {
    // a ball beside the end effector: the full answer sees it
    let model = model();
    let p = ee(&model);
    let w = world(p + Vector3::new(0.0, 0.2, 0.0));
    let azimuth = Config::defaults().camera.azimuth_rad;
    let (_, header, filtered, _) = filtered_view(azimuth, &w);
    let mut worker = Worker::new(model, &repulsion_config(), 0).unwrap();
    let full = worker.step(&header, &filtered).unwrap().to_vec();
    assert!(full.iter().any(|r| r.active == 1));
    worker.set_positions_only(true);
    let placed = worker.step(&header, &filtered).unwrap().to_vec();
    assert_eq!(placed.len(), full.len());
    let rho = repulsion_config().params.rho;
    for (a, b) in placed.iter().zip(&full) {
        assert_eq!((a.point, a.position), (b.point, b.position));
        assert_eq!((a.active, a.v_call, a.min_distance), (0, [0.0; 3], rho));
    }
    // and back: the scan again
    worker.set_positions_only(false);
    let again = worker.step(&header, &filtered).unwrap();
    assert_eq!(again[0].min_distance, full[0].min_distance);
}

#[test]
fn an_obstacle_in_front_of_the_point_is_never_farther_than_it_is() {
    // the occlusion rule: what hides the space behind it may be as near as the point's own depth
    let model = model();
    let p = ee(&model);
    let camera = Config::defaults().camera.pose().unwrap().position().coords;
    let centre = p + (camera - p).normalize() * 0.3;
    let (r, _) = pipeline(centre);
    let truth = (centre - p).norm() - 0.08 - 0.05;
    assert_eq!(r.active, 1);
    assert!(
        r.min_distance <= truth + 0.01,
        "depth-space {} must not exceed the geometric {truth}",
        r.min_distance
    );
}

#[test]
fn nothing_near_means_no_repulsion_and_robot_pixels_are_not_obstacles() {
    let model = model();
    let far = ee(&model) + Vector3::new(0.0, 1.5, 0.0);
    let (r, _) = pipeline(far);
    // only the filtered robot and the far ball: nothing within ρ except the table top far below
    assert!(Vector3::from(r.v_call).norm() < 0.02, "{:?}", r);
}

#[test]
fn malformed_frames_are_refused() {
    let model = model();
    let mut ingest = Ingest::new(model, &ingest_config()).unwrap();
    let mut history = StateHistory::new(7, 10);
    history.push(1_000_000_000, &Q0);
    let mut h = FrameHeader::zeroed();
    phri_perception::camera::fill_camera_header(
        &mut h,
        1,
        &Config::defaults().camera.intrinsics,
        &Config::defaults().camera.pose().unwrap(),
    );
    h.capture_ns = 1_000_000_000;
    let mut out = vec![0u16; 640 * 480];
    let frame = vec![1000u16; 640 * 480];
    assert!(matches!(
        ingest.step(
            &mut h.clone(),
            &frame[..100],
            &history,
            1_000_000_000,
            &mut out
        ),
        Err(FrameError::Size { .. })
    ));
    let mut future = h;
    future.capture_ns = 2_000_000_000;
    assert!(matches!(
        ingest.step(&mut future, &frame, &history, 1_000_000_000, &mut out),
        Err(FrameError::Future { .. })
    ));
    let mut old = h;
    old.capture_ns = 500_000_000;
    assert!(matches!(
        ingest.step(&mut old, &frame, &history, 1_000_000_000, &mut out),
        Err(FrameError::Stale { .. })
    ));
    assert!(matches!(
        ingest.step(
            &mut h.clone(),
            &vec![0u16; 640 * 480],
            &history,
            1_000_000_000,
            &mut out
        ),
        Err(FrameError::Empty { .. })
    ));
    let mut bad = h;
    bad.fx = f64::NAN;
    assert!(matches!(
        ingest.step(&mut bad, &frame, &history, 1_000_000_000, &mut out),
        Err(FrameError::Camera { .. })
    ));
    let mut scale = h;
    scale.depth_scale = 0.0002;
    assert!(matches!(
        ingest.step(&mut scale, &frame, &history, 1_000_000_000, &mut out),
        Err(FrameError::Scale { .. })
    ));
    let empty = StateHistory::new(7, 10);
    assert!(matches!(
        ingest.step(&mut h.clone(), &frame, &empty, 1_000_000_000, &mut out),
        Err(FrameError::NoJointState { .. })
    ));
    // a service before its first state (now: the newest state's stamp, 0):
    // no state to match, not a frame from the future
    assert!(matches!(
        ingest.step(&mut h.clone(), &frame, &empty, empty.newest_ns(), &mut out),
        Err(FrameError::NoJointState { .. })
    ));
    // a good frame passes, then the same sequence again is refused
    let mut h5 = h;
    h5.seq = 5;
    assert!(ingest
        .step(&mut h5.clone(), &frame, &history, 1_000_000_000, &mut out)
        .is_ok());
    assert!(matches!(
        ingest.step(&mut h5.clone(), &frame, &history, 1_000_000_000, &mut out),
        Err(FrameError::Sequence { .. })
    ));
    // a camera that restarted starts over at 1: accepted
    assert!(ingest
        .step(&mut h.clone(), &frame, &history, 1_000_000_000, &mut out)
        .is_ok());
}

#[test]
fn injected_faults_reach_ingestion_as_the_frames_they_describe() {
    use phri_ipc::{DepthFault, DepthFaultKind};
    use phri_perception::FaultState;
    let model = model();
    let mut camera = CameraSim::new(model.clone(), &Config::defaults().camera).unwrap();
    let mut ingest = Ingest::new(model, &ingest_config()).unwrap();
    let mut frame = vec![0u16; camera.pixels()];
    let mut filtered = vec![0u16; camera.pixels()];
    let mut history = StateHistory::new(7, 10);
    let mut faults = FaultState::default();
    let w = world(Vector3::new(0.5, 0.5, 0.5));
    history.push(w.stamp_ns, &Q0);
    let mut capture = |kind: Option<DepthFaultKind>, seq: u64| {
        if let Some(kind) = kind {
            let mut f = DepthFault::zeroed();
            f.seq = seq;
            f.kind = kind as u32;
            f.frames = 1;
            faults.accept(&f, 0).unwrap();
        }
        let mut header = FrameHeader::zeroed();
        camera.step(&w, 0, &mut frame, &mut header).unwrap();
        assert_eq!(faults.apply(&mut frame, &mut header, 0), 0);
        ingest.step(
            &mut header,
            &frame,
            &history,
            w.stamp_ns + 5_000_000,
            &mut filtered,
        )
    };
    assert!(capture(None, 0).is_ok());
    assert!(matches!(
        capture(Some(DepthFaultKind::Zeros), 1),
        Err(FrameError::Empty { .. })
    ));
    assert!(matches!(
        capture(Some(DepthFaultKind::Size), 2),
        Err(FrameError::Size { .. })
    ));
    assert!(matches!(
        capture(Some(DepthFaultKind::Stale), 3),
        Err(FrameError::Stale { .. })
    ));
    // flying pixels are plausible depths: they pass, as a real sensor's would
    assert!(capture(Some(DepthFaultKind::Noise), 4).is_ok());
    assert!(capture(None, 5).is_ok());
}

/// A camera's frame of the ball world at Q0 as ingestion filters it, with
/// its configuration, header and the robot's pixels removed: `azimuth`
/// \[rad\] around the base as `[camera]` places it.
fn filtered_view(azimuth: f64, w: &WorldState) -> (CameraConfig, FrameHeader, Vec<u16>, u32) {
    let model = model();
    let cfg = CameraConfig {
        render: RenderOptions::ideal(),
        azimuth_rad: azimuth,
        ..Config::defaults().camera
    };
    let (mut header, frame) = camera_frame(&model, &cfg, w);
    let mut ingest = Ingest::new(model, &ingest_config()).unwrap();
    let (filtered, out) = ingest_at_q0(&mut ingest, &mut header, &frame, w);
    (cfg, header, filtered, out.removed)
}

/// `frame` of `w` (header `header`) through `ingest`, the arm at Q0 when
/// it was taken, 5 ms before now: the filtered depths and the outcome.
fn ingest_at_q0(
    ingest: &mut Ingest,
    header: &mut FrameHeader,
    frame: &[u16],
    w: &WorldState,
) -> (Vec<u16>, IngestOutcome) {
    let mut history = StateHistory::new(7, 10);
    history.push(w.stamp_ns, &Q0);
    let mut filtered = vec![0u16; frame.len()];
    let out = ingest
        .step(
            header,
            frame,
            &history,
            w.stamp_ns + 5_000_000,
            &mut filtered,
        )
        .unwrap();
    (filtered, out)
}

/// The frame (header, depths) camera `cfg` takes of `w`.
fn camera_frame(model: &Model, cfg: &CameraConfig, w: &WorldState) -> (FrameHeader, Vec<u16>) {
    let mut camera = CameraSim::new(model.clone(), cfg).unwrap();
    let mut frame = vec![0u16; camera.pixels()];
    let mut header = FrameHeader::zeroed();
    camera.step(w, 0, &mut frame, &mut header).unwrap();
    (header, frame)
}

/// One ingestion fed the frames of two cameras in turn, mirrored about the
/// base's x axis (the same x and height, another y and orientation), removes
/// the robot from each frame as a fresh ingestion of that camera does.
#[test]
fn ingestion_follows_the_camera_of_each_frame() {
    let w = world(Vector3::new(0.0, 0.0, 3.0));
    let az = Config::defaults().camera.azimuth_rad;
    let model = model();
    let mut ingest = Ingest::new(model.clone(), &ingest_config()).unwrap();
    for (i, a) in [az, -az, az, -az].into_iter().enumerate() {
        let (cfg, fresh, want, removed) = filtered_view(a, &w);
        let (mut header, frame) = camera_frame(&model, &cfg, &w);
        header.seq = 10 + i as u64;
        let (got, out) = ingest_at_q0(&mut ingest, &mut header, &frame, &w);
        assert!(removed > 1000, "camera at {a} rad: {removed} robot pixels");
        assert_eq!(out.removed, removed, "camera at {a} rad, frame {i}");
        assert!(got == want, "camera at {a} rad, frame {i}");
        assert_eq!(header.valid_pixels, fresh.valid_pixels);
    }
}

#[test]
fn what_one_camera_saw_caps_what_the_robot_hid_from_another() {
    let model = model();
    let p = ee(&model);
    let (cfg_a, ..) = filtered_view(0.6, &world(p));
    let camera = cfg_a.pose().unwrap().position().coords;
    let across = (p - camera).cross(&Vector3::z()).normalize();
    let w = world(p + across * 0.25);
    // the paper's camera sees the ball: 0.25 − 0.08 − 0.05 = 0.12 m
    let (cfg_a, header_a, frame_a, _) = filtered_view(0.6, &w);
    // the mirror sees nothing near (as if the arm hid the ball from it)
    let (cfg_b, header_b, frame_b, _) = filtered_view(-0.6, &w);
    let empty = vec![0u16; frame_b.len()];
    let worker = |cfg: &CameraConfig| {
        Worker::new(model.clone(), &repulsion_config(), 0)
            .unwrap()
            .bounded_by(cfg)
            .unwrap()
    };
    let (mut a, mut b) = (worker(&cfg_a), worker(&cfg_b));
    let alone = b.step(&header_b, &empty).unwrap()[0].min_distance;
    assert!(alone > 0.3, "{alone}");
    let mut seen = phri_perception::SeenSurfaces::new(2, 50_000_000);
    let by_a = a.step_among(&header_a, &frame_a, 0, &mut seen).unwrap()[0];
    assert!((by_a.min_distance - 0.12).abs() < 0.01, "{by_a:?}");
    let capped = b.step_among(&header_b, &empty, 1, &mut seen).unwrap()[0];
    assert!(
        (capped.min_distance - by_a.min_distance).abs() < 0.005,
        "{capped:?} against {by_a:?}"
    );
    // the answer is the surface the paper's camera saw: an obstacle point,
    // and a repulsion away from it at eq. 16's magnitude of that distance
    assert_eq!(capped.active, 1);
    let away = Vector3::from(capped.position) - Vector3::from(capped.obstacle);
    let v = Vector3::from(capped.v_call);
    let params = repulsion_config().params;
    assert!((v.norm() - params.magnitude(capped.min_distance)).abs() < 1e-9);
    assert!(v.normalize().dot(&away.normalize()) > 1.0 - 1e-9);
    assert!((away.norm() - 0.05 - capped.min_distance).abs() < 1e-9);
    // what the mirror saw itself still counts as it did
    let own = b.step_among(&header_b, &frame_b, 1, &mut seen).unwrap()[0];
    assert!(own.min_distance <= by_a.min_distance + 0.005, "{own:?}");
    // the paper's camera's surfaces from a frame too long before: not used
    let mut late = header_b;
    late.capture_ns += 60_000_000;
    let uncapped = b.step_among(&late, &empty, 1, &mut seen).unwrap()[0];
    assert_eq!(uncapped.min_distance, alone);
}
