//! `phri-camera-ros2` against a ROS 2 depth camera nobody here wrote: a
//! Cyclone DDS publisher (`deploy/ros2/depth_pub.py`, Eclipse Cyclone DDS's
//! Python binding) of `sensor_msgs/Image` and `sensor_msgs/CameraInfo`
//! playing the real Kinect frames of `../shared/data/kinect-person` at
//! 30 Hz. On this host's loopback (ROS_AUTOMATIC_DISCOVERY_RANGE=LOCALHOST,
//! the publisher on `lo` only, a ROS domain of the test's own): 640×480
//! 16UC1 frames arrive on `camera/depth` pixel for pixel with the
//! recording's intrinsics; 1280×720 32FC1 frames arrive resampled by the
//! nearest-valid rule, their intrinsics scaled back. Across a veth between
//! two network namespaces (as root), the camera with `ros2.discovery =
//! "subnet"`: frames cross. Bad inputs (rgb8, a short step, fx = 0, stamps
//! 5 s old) are dropped, counted on `camera/status` by cause and logged at
//! most once a second. The tests run one at a time (their rates and
//! latencies are measured; they go to BENCHMARKS).

use std::io::{BufRead, BufReader};
use std::path::PathBuf;
use std::process::{Child, Command, Stdio};
use std::sync::{Arc, Mutex};
use std::time::{Duration, Instant};

use phri_ipc::{CameraStatus, FrameHeader, Queue};
use serde_json::Value;

#[path = "../../../tests/support/workspace.rs"]
mod workspace;
use workspace::repo;
#[allow(dead_code)]
mod netns;
use netns::{peer_python, veth, wait_at_most, NETNS_SETUP};

/// One test at a time: each measures rates and latencies on 2 shared cores.
static ONE_AT_A_TIME: Mutex<()> = Mutex::new(());

/// Cyclone DDS on this host's loopback only: no multicast, unicast
/// discovery of 127.0.0.1, participant announcements every 0.5 s.
const LOOPBACK_PEER: &str = "<CycloneDDS><Domain id=\"any\"><General><Interfaces>\
    <NetworkInterface name=\"lo\"/></Interfaces><AllowMulticast>false</AllowMulticast>\
    </General><Discovery><ParticipantIndex>auto</ParticipantIndex>\
    <Peers><Peer address=\"127.0.0.1\"/></Peers><SPDPInterval>0.5s</SPDPInterval>\
    </Discovery></Domain></CycloneDDS>";

const W: usize = 640;
const H: usize = 480;
const IMAGE_TOPIC: &str = "/camera/camera/depth/image_rect_raw";

/// The recorded Kinect frames (640×480 millimetres), in name order.
fn source_frames() -> (PathBuf, Vec<Vec<u16>>) {
    let dir = repo().join("../shared/data/kinect-person");
    let mut names: Vec<PathBuf> = std::fs::read_dir(&dir)
        .unwrap_or_else(|e| panic!("{}: {e}", dir.display()))
        .flatten()
        .map(|e| e.path())
        .filter(|p| {
            p.file_name()
                .is_some_and(|n| n.to_string_lossy().starts_with("depth-data-"))
        })
        .collect();
    names.sort();
    let frames: Vec<Vec<u16>> = names
        .iter()
        .map(|p| {
            let b = std::fs::read(p).unwrap();
            assert_eq!(b.len(), W * H * 2, "{}", p.display());
            b.chunks_exact(2)
                .map(|c| u16::from_le_bytes([c[0], c[1]]))
                .collect()
        })
        .collect();
    assert_eq!(frames.len(), 12, "{}", dir.display());
    (dir, frames)
}

/// A ROS domain of this test's own (parallel test processes do not cross).
fn domain(case: u32) -> u32 {
    10 + (std::process::id() * 4 + case) % 90
}

/// A child killed (if still running) when dropped: no leftovers on a panic.
struct Reaped(Option<Child>);

impl Reaped {
    fn child(&mut self) -> &mut Child {
        self.0.as_mut().unwrap()
    }

    /// SIGINT, then its exit within 10 s.
    fn stop(&mut self, what: &str) -> std::process::ExitStatus {
        let c = self.child();
        // SAFETY: kill(2) of our own child
        unsafe { libc::kill(c.id() as i32, libc::SIGINT) };
        let s = wait_at_most(c, Duration::from_secs(10), what);
        self.0 = None;
        s
    }
}

impl Drop for Reaped {
    fn drop(&mut self) {
        if let Some(c) = self.0.as_mut() {
            let _ = c.kill();
            let _ = c.wait();
        }
    }
}

/// phri-camera-ros2 running, its stderr lines kept (and shown).
struct Camera {
    proc: Reaped,
    lines: Arc<Mutex<Vec<String>>>,
    reader: Option<std::thread::JoinHandle<()>>,
    prefix: String,
}

impl Camera {
    /// Starts `cmd` (phri-camera-ros2, maybe behind unshare).
    fn start(mut cmd: Command, prefix: &str) -> Camera {
        let mut child = cmd
            .stderr(Stdio::piped())
            .spawn()
            .expect("the camera starts");
        let stderr = child.stderr.take().unwrap();
        let lines = Arc::new(Mutex::new(Vec::new()));
        let kept = Arc::clone(&lines);
        let reader = std::thread::spawn(move || {
            for line in BufReader::new(stderr).lines().map_while(Result::ok) {
                eprintln!("{line}");
                kept.lock().unwrap().push(line);
            }
        });
        Camera {
            proc: Reaped(Some(child)),
            lines,
            reader: Some(reader),
            prefix: prefix.to_string(),
        }
    }

    fn lines(&self) -> Vec<String> {
        self.lines.lock().unwrap().clone()
    }

    /// Waits for its start line (DDS up, camera/depth open).
    fn wait_started(&mut self) {
        let t0 = Instant::now();
        while !self.lines().iter().any(|l| l.contains("from ROS 2 domain")) {
            if let Some(s) = self.proc.child().try_wait().unwrap() {
                panic!(
                    "phri-camera-ros2 exited ({s}):\n{}",
                    self.lines().join("\n")
                );
            }
            assert!(t0.elapsed() < Duration::from_secs(30), "no start line");
            std::thread::sleep(Duration::from_millis(20));
        }
    }

    /// Stops it (SIGINT): it must exit cleanly; its stderr lines.
    fn stop(mut self) -> Vec<String> {
        let s = self.proc.stop("phri-camera-ros2");
        if let Some(r) = self.reader.take() {
            r.join().unwrap();
        }
        let lines = self.lines();
        let _ = phri_ipc::remove_leftovers(&self.prefix);
        assert!(s.success(), "phri-camera-ros2: {s}\n{}", lines.join("\n"));
        lines
    }
}

/// phri-camera-ros2 on the test's prefix, the deployed configuration with
/// a ROS 2 camera.
fn camera_command(prefix: &str) -> Command {
    let mut c = Command::new(env!("CARGO_BIN_EXE_phri-camera-ros2"));
    camera_args(&mut c, prefix);
    c
}

fn camera_args(c: &mut Command, prefix: &str) {
    c.current_dir(repo())
        .arg("--config")
        .arg(repo().join("deploy/phri.toml"))
        .args(["--prefix", prefix])
        .args(["--set", "camera.source=\"ros2\""])
        .stdout(Stdio::null());
}

/// depth_pub.py with `args`, on the loopback, ROS domain `domain`.
fn publisher(python: &PathBuf, frames: &PathBuf, domain: u32, args: &[&str]) -> Reaped {
    let child = Command::new(python)
        .arg(repo().join("deploy/ros2/depth_pub.py"))
        .arg("--frames")
        .arg(frames)
        .args(["--domain", &domain.to_string()])
        .args(args)
        .env("CYCLONEDDS_URI", LOOPBACK_PEER)
        .stdout(Stdio::piped())
        .spawn()
        .expect("depth_pub.py starts");
    Reaped(Some(child))
}

/// Its JSON summary once it is done.
fn finished(mut p: Reaped) -> Value {
    let c = p.0.take().unwrap();
    let out = c.wait_with_output().unwrap();
    assert!(out.status.success(), "depth_pub.py: {}", out.status);
    serde_json::from_slice(&out.stdout).expect("depth_pub.py prints JSON")
}

/// What the test saw on `camera/depth` and `camera/status`.
#[derive(Default)]
struct Seen {
    frames: usize,
    /// frames the camera numbered that never reached this reader: its
    /// queue (two deep) overflowed while the test's thread was away (gaps
    /// in the headers' `seq`, which counts every frame published)
    lost: usize,
    /// the last frame's `seq`
    last_seq: u64,
    /// published_ns of each frame
    published: Vec<u64>,
    /// published − capture_wall [ns]
    latency: Vec<u64>,
    status: Option<CameraStatus>,
}

impl Seen {
    fn rate_hz(&self) -> f64 {
        let p = &self.published;
        if p.len() < 2 {
            return 0.0;
        }
        (p.len() - 1) as f64 / ((p[p.len() - 1] - p[0]) as f64 * 1e-9)
    }

    fn percentile_ms(&self, q: f64) -> f64 {
        let mut l = self.latency.clone();
        l.sort_unstable();
        if l.is_empty() {
            return f64::NAN;
        }
        l[((l.len() as f64 * q) as usize).min(l.len() - 1)] as f64 * 1e-6
    }

    fn report(&self, what: &str, published: &Value) {
        eprintln!(
            "BENCH camera-ros2 {what}: received {} of {} images, {:.1} Hz on camera/depth \
             (published at {:.1} Hz); capture→published p50 {:.2} ms p99 {:.2} ms max {:.2} ms; \
             dropped old {} behind {} (load average {})",
            self.frames,
            published["published"],
            self.rate_hz(),
            published["rate_hz"].as_f64().unwrap_or(0.0),
            self.percentile_ms(0.5),
            self.percentile_ms(0.99),
            self.latency.iter().max().copied().unwrap_or(0) as f64 * 1e-6,
            self.status.map_or(0, |s| s.dropped_old),
            self.status.map_or(0, |s| s.dropped_behind),
            std::fs::read_to_string("/proc/loadavg")
                .unwrap_or_default()
                .split_whitespace()
                .next()
                .unwrap_or("?"),
        );
    }
}

/// Reads `camera/depth` (each frame given to `check`) and `camera/status`
/// (the newest kept) on `prefix` while `running` says so, then 1 s more
/// (the status after the last frame).
fn watch(
    prefix: &str,
    mut running: impl FnMut() -> bool,
    mut check: impl FnMut(&FrameHeader, &[u16]),
) -> Seen {
    let node = phri_ipc::node("test-camera-ros2", prefix).unwrap();
    let frames = phri_ipc::camera(0)
        .unwrap()
        .depth
        .frame_subscriber(&node, Queue::Drain)
        .unwrap();
    let status = phri_ipc::CAMERA_STATUS
        .subscriber(&node, Queue::Latest)
        .unwrap();
    let mut seen = Seen::default();
    let mut after: Option<Instant> = None;
    loop {
        while let Some(f) = frames.receive().unwrap() {
            let h = f.user_header();
            seen.frames += 1;
            seen.lost += h.seq.saturating_sub(seen.last_seq + 1) as usize;
            seen.last_seq = h.seq;
            seen.published.push(h.published_ns);
            seen.latency
                .push(h.published_ns.saturating_sub(h.capture_wall_ns));
            check(h, f.payload());
        }
        if let Some(s) = status.latest().unwrap() {
            seen.status = Some(s);
        }
        match after {
            None if !running() => after = Some(Instant::now()),
            Some(t) if t.elapsed() > Duration::from_millis(1200) => break,
            _ => {}
        }
        std::thread::sleep(Duration::from_millis(2));
    }
    seen
}

/// Is a child still running?
fn alive(p: &mut Reaped) -> bool {
    p.child().try_wait().unwrap().is_none()
}

fn header_intrinsics(h: &FrameHeader) -> [f64; 4] {
    [h.fx, h.fy, h.cx, h.cy]
}

fn close(a: [f64; 4], b: [f64; 4]) -> bool {
    a.iter().zip(b).all(|(x, y)| (x - y).abs() < 1e-9)
}

#[test]
fn loopback_640x480_16uc1_frames_arrive_pixel_for_pixel() {
    let _one = ONE_AT_A_TIME.lock().unwrap_or_else(|e| e.into_inner());
    let python = peer_python(&repo());
    let (dir, sources) = source_frames();
    let prefix = format!("camros2a{}_", std::process::id());
    let d = domain(0);
    let mut cam = camera_command(&prefix);
    cam.env("ROS_AUTOMATIC_DISCOVERY_RANGE", "LOCALHOST")
        .env("ROS_DOMAIN_ID", d.to_string());
    let mut camera = Camera::start(cam, &prefix);
    camera.wait_started();
    let mut p = publisher(&python, &dir, d, &["--duration", "5", "--start-after", "1"]);
    let (mut unequal, mut bad_k) = (0, Vec::new());
    let seen = watch(
        &prefix,
        || alive(&mut p),
        |h, px| {
            if !sources.iter().any(|s| s.as_slice() == px) {
                unequal += 1;
            }
            let k = header_intrinsics(h);
            if (h.width, h.height) != (640, 480) || k != [580.0, 580.0, 320.0, 240.0] {
                bad_k.push((h.width, h.height, k));
            }
        },
    );
    let published = finished(p);
    let lines = camera.stop();
    seen.report("loopback 640x480 16UC1", &published);
    let n = published["published"].as_u64().unwrap() as usize;
    assert!(
        seen.frames as f64 >= 0.8 * n as f64,
        "{} of {n} frames arrived\n{}",
        seen.frames,
        lines.join("\n")
    );
    assert_eq!(unequal, 0, "frames not equal to any recorded frame");
    assert!(bad_k.is_empty(), "{:?}", &bad_k[..bad_k.len().min(3)]);
    let s = seen.status.expect("camera/status");
    assert_eq!((s.source, s.camera), (2, 0));
    // every frame it counts reached this reader or was lost from its queue
    assert_eq!(
        s.frames as usize,
        seen.frames + seen.lost,
        "{} lost",
        seen.lost
    );
    assert_eq!(
        (s.dropped_malformed, s.dropped_no_info, s.dropped_future),
        (0, 0, 0),
        "{s:?}"
    );
    // a frame delayed past camera.max_age_s by a stall of the loaded
    // machine is dropped (counted): legitimate, and rare
    assert!(s.dropped_old as f64 <= 0.1 * n as f64, "{s:?}");
    assert!(seen.percentile_ms(0.5) < 100.0);
}

/// The nearest valid reading of each output pixel's footprint in a `w`×`h`
/// frame, written out from the definition (floating point footprints).
fn nearest_valid(src: &[u16], w: usize, h: usize) -> Vec<u16> {
    let mut out = vec![0u16; W * H];
    for v in 0..H {
        let y0 = (v as f64 * h as f64 / H as f64).floor() as usize;
        let y1 = (((v + 1) as f64 * h as f64 / H as f64).ceil() as usize).min(h);
        for u in 0..W {
            let x0 = (u as f64 * w as f64 / W as f64).floor() as usize;
            let x1 = (((u + 1) as f64 * w as f64 / W as f64).ceil() as usize).min(w);
            let mut best = 0u16;
            for y in y0..y1 {
                for &d in &src[y * w + x0..y * w + x1] {
                    if d != 0 && (best == 0 || d < best) {
                        best = d;
                    }
                }
            }
            out[v * W + u] = best;
        }
    }
    out
}

/// depth_pub.py's nearest-neighbour resize of a recorded frame, and its
/// 32FC1 metres back to millimetres.
fn published_mm(src: &[u16], w: usize, h: usize) -> Vec<u16> {
    let mut out = Vec::with_capacity(w * h);
    for y in 0..h {
        let sy = y * H / h;
        for x in 0..w {
            let mm = src[sy * W + x * W / w];
            // metres as a float32 (NaN for none), read back
            let m = if mm == 0 {
                f32::NAN
            } else {
                (f64::from(mm) / 1000.0) as f32
            };
            out.push(if m.is_finite() && m > 0.0 {
                (f64::from(m) * 1000.0).round() as u16
            } else {
                0
            });
        }
    }
    out
}

#[test]
fn loopback_1280x720_32fc1_frames_are_resampled_never_thinner() {
    let _one = ONE_AT_A_TIME.lock().unwrap_or_else(|e| e.into_inner());
    let python = peer_python(&repo());
    let (dir, sources) = source_frames();
    let (w, h) = (1280, 720);
    let inputs: Vec<Vec<u16>> = sources.iter().map(|s| published_mm(s, w, h)).collect();
    let expected: Vec<Vec<u16>> = inputs.iter().map(|s| nearest_valid(s, w, h)).collect();
    // the pole test of the real data: the recorded frames' valid pixels
    // survive a 2 × 1.5 downscale
    let prefix = format!("camros2b{}_", std::process::id());
    let d = domain(1);
    let mut cam = camera_command(&prefix);
    cam.env("ROS_AUTOMATIC_DISCOVERY_RANGE", "LOCALHOST")
        .env("ROS_DOMAIN_ID", d.to_string());
    let mut camera = Camera::start(cam, &prefix);
    camera.wait_started();
    let mut p = publisher(
        &python,
        &dir,
        d,
        &[
            "--duration",
            "5",
            "--start-after",
            "1",
            "--width",
            "1280",
            "--height",
            "720",
            "--encoding",
            "32FC1",
        ],
    );
    let (mut unmatched, mut thinner, mut bad_k) = (0usize, 0usize, Vec::new());
    let seen = watch(
        &prefix,
        || alive(&mut p),
        |hd, px| {
            match expected.iter().position(|e| e.as_slice() == px) {
                Some(i) => {
                    // never thinner, said once more pixel by pixel: every
                    // input reading (each in some footprint) leaves an
                    // output reading no farther than it
                    let input = &inputs[i];
                    for y in (0..h).step_by(2) {
                        for x in 0..w {
                            let d = input[y * w + x];
                            let o = px[(y * H / h) * W + x * W / w];
                            if d != 0 && (o == 0 || o > d) {
                                thinner += 1;
                            }
                        }
                    }
                }
                None => unmatched += 1,
            }
            let k = header_intrinsics(hd);
            if (hd.width, hd.height) != (640, 480) || !close(k, [580.0, 580.0, 320.0, 240.0]) {
                bad_k.push(k);
            }
        },
    );
    let published = finished(p);
    let lines = camera.stop();
    seen.report("loopback 1280x720 32FC1", &published);
    assert_eq!(
        published["k"],
        serde_json::json!([1160.0, 0.0, 640.5, 0.0, 870.0, 360.25, 0.0, 0.0, 1.0])
    );
    let n = published["published"].as_u64().unwrap() as usize;
    // 110 MB/s of images through Python, Cyclone DDS and RustDDS on 2
    // shared cores: under others' load, frames are lost (best effort) or
    // arrive older than camera.max_age_s (dropped, counted): enough arrive
    // to check the resampling
    assert!(
        seen.frames as f64 >= 0.3 * n as f64,
        "{} of {n} frames arrived\n{}",
        seen.frames,
        lines.join("\n")
    );
    assert_eq!(
        unmatched, 0,
        "frames not the nearest-valid resampling of a recorded one"
    );
    assert_eq!(
        thinner, 0,
        "pixels thinned or farther than their footprint's reading"
    );
    assert!(bad_k.is_empty(), "{:?}", &bad_k[..bad_k.len().min(3)]);
    let s = seen.status.expect("camera/status");
    // every frame it counts reached this reader or was lost from its queue
    assert_eq!(
        s.frames as usize,
        seen.frames + seen.lost,
        "{} lost",
        seen.lost
    );
    // a frame delayed past camera.max_age_s by a stall of the loaded
    // machine is dropped (counted): legitimate, and rare
    assert_eq!((s.dropped_malformed, s.dropped_no_info), (0, 0), "{s:?}");
    assert!(s.dropped_old as f64 <= 0.1 * n as f64, "{s:?}");
}

/// Two network namespaces joined by a veth (as two hosts of a /24 of their
/// own): the camera in one with `ros2.discovery = "subnet"`, the publisher
/// (Cyclone DDS's defaults: the veth) in the other. Needs root.
#[test]
fn across_a_veth_the_frames_cross_and_arrive() {
    let _one = ONE_AT_A_TIME.lock().unwrap_or_else(|e| e.into_inner());
    assert!(
        // SAFETY: geteuid(2) has no preconditions
        unsafe { libc::geteuid() } == 0,
        "this test needs root: network namespaces (unshare --net) and a veth pair (ip link)"
    );
    let python = peer_python(&repo());
    let (dir, sources) = source_frames();
    let prefix = format!("camros2c{}_", std::process::id());
    let mut cam = Command::new("unshare");
    cam.env("PHRI_VETH", "cam0")
        .env("PHRI_ADDR", "10.231.2.1/24")
        .env_remove("PHRI_AFTER")
        .env_remove("PHRI_NO_IPV6")
        .env_remove("ROS_AUTOMATIC_DISCOVERY_RANGE")
        .env_remove("ROS_LOCALHOST_ONLY")
        .env("ROS_DOMAIN_ID", "0")
        .args(["--net", "--", "sh", "-c", NETNS_SETUP])
        .arg(env!("CARGO_BIN_EXE_phri-camera-ros2"));
    camera_args(&mut cam, &prefix);
    cam.args(["--set", "ros2.discovery=\"subnet\""]);
    let mut camera = Camera::start(cam, &prefix);
    let publisher = Command::new("unshare")
        .env("PHRI_VETH", "pub0")
        .env("PHRI_ADDR", "10.231.2.2/24")
        .env_remove("PHRI_AFTER")
        .env_remove("PHRI_NO_IPV6")
        .env_remove("CYCLONEDDS_URI")
        .args(["--net", "--", "sh", "-c", NETNS_SETUP])
        .arg(&python)
        .arg(repo().join("deploy/ros2/depth_pub.py"))
        .arg("--frames")
        .arg(&dir)
        .args(["--domain", "0", "--duration", "5", "--start-after", "2"])
        .stdout(Stdio::piped())
        .spawn()
        .expect("unshare starts the publisher");
    let mut p = Reaped(Some(publisher));
    veth(camera.proc.child(), "cam0", p.child(), "pub0");
    // the publisher's namespace (and with it the veth) outlives the
    // publisher until the camera has stopped: a clean shutdown of its DDS
    let holder = Command::new("nsenter")
        .arg(format!("--net=/proc/{}/ns/net", p.child().id()))
        .args(["sleep", "120"])
        .spawn()
        .expect("nsenter holds the publisher's namespace");
    let holder = Reaped(Some(holder));
    camera.wait_started();
    assert!(
        camera
            .lines()
            .iter()
            .any(|l| l.contains("every interface (subnet)")),
        "the camera is not on the subnet"
    );
    let mut unequal = 0;
    let seen = watch(
        &prefix,
        || alive(&mut p),
        |h, px| {
            if !sources.iter().any(|s| s.as_slice() == px)
                || header_intrinsics(h) != [580.0, 580.0, 320.0, 240.0]
            {
                unequal += 1;
            }
        },
    );
    let published = finished(p);
    let lines = camera.stop();
    drop(holder);
    seen.report("veth 640x480 16UC1", &published);
    let n = published["published"].as_u64().unwrap() as usize;
    assert!(
        seen.frames as f64 >= 0.7 * n as f64,
        "{} of {n} frames crossed the veth\n{}",
        seen.frames,
        lines.join("\n")
    );
    assert_eq!(unequal, 0);
}

/// One bad publisher after another against one camera: each input's drops
/// counted under its cause, nothing published.
#[test]
fn bad_inputs_are_dropped_counted_and_logged_once_a_second() {
    let _one = ONE_AT_A_TIME.lock().unwrap_or_else(|e| e.into_inner());
    let python = peer_python(&repo());
    let (dir, _) = source_frames();
    let prefix = format!("camros2d{}_", std::process::id());
    let d = domain(3);
    let mut cam = camera_command(&prefix);
    cam.env("ROS_AUTOMATIC_DISCOVERY_RANGE", "LOCALHOST")
        .env("ROS_DOMAIN_ID", d.to_string());
    let mut camera = Camera::start(cam, &prefix);
    camera.wait_started();
    let phases: [(&str, &[&str]); 4] = [
        ("rgb8", &["--encoding", "rgb8"]),
        ("short step", &["--step-delta", "-2"]),
        ("fx = 0", &["--fx", "0"]),
        ("5 s old", &["--age", "5"]),
    ];
    let mut before = CameraStatus::default();
    for (what, args) in phases {
        let lines_before = camera.lines().len();
        let mut all = vec!["--duration", "2.5", "--start-after", "1"];
        all.extend_from_slice(args);
        let mut p = publisher(&python, &dir, d, &all);
        let seen = watch(&prefix, || alive(&mut p), |_, _| {});
        let published = finished(p);
        let n = published["published"].as_u64().unwrap();
        let s = seen
            .status
            .unwrap_or_else(|| panic!("{what}: no camera/status"));
        let new_lines: Vec<String> = camera.lines()[lines_before..].to_vec();
        eprintln!("{what}: {n} published, status {s:?}");
        assert_eq!(seen.frames, 0, "{what}: frames published");
        assert_eq!(s.frames, 0, "{what}: {s:?}");
        let grew = |now: u64, was: u64| now - was;
        let (malformed, no_info, old) = (
            grew(s.dropped_malformed, before.dropped_malformed),
            grew(s.dropped_no_info, before.dropped_no_info),
            grew(s.dropped_old, before.dropped_old),
        );
        // most images arrive (best effort on the loopback; the first ones
        // may come before discovery ends)
        let most = (n as f64 * 0.7) as u64;
        let warned: Vec<&String> = new_lines.iter().filter(|l| l.contains("WARN")).collect();
        match what {
            "rgb8" => {
                assert!(malformed >= most, "{what}: {malformed} of {n}: {s:?}");
                let about: Vec<&&String> = warned
                    .iter()
                    .filter(|l| l.contains(IMAGE_TOPIC) && l.contains("rgb8"))
                    .collect();
                // one line a second at most, over 2.5 s
                assert!((1..=4).contains(&about.len()), "{what}: {warned:#?}");
                assert!(about.iter().all(|l| l.contains("encoding")), "{about:#?}");
            }
            "short step" => {
                assert!(malformed >= most, "{what}: {malformed} of {n}: {s:?}");
                let about = warned
                    .iter()
                    .filter(|l| l.contains(IMAGE_TOPIC) && l.contains("step"))
                    .count();
                assert!((1..=4).contains(&about), "{what}: {warned:#?}");
            }
            "fx = 0" => {
                assert!(no_info >= most, "{what}: {no_info} of {n}: {s:?}");
                assert!(
                    warned.iter().any(|l| l.contains("camera info refused")),
                    "{what}: {warned:#?}"
                );
                assert!(warned.len() <= 8, "{what}: {warned:#?}");
            }
            _ => {
                assert!(old >= most, "{what}: {old} of {n}: {s:?}");
            }
        }
        assert!(s.dropped_future == 0, "{what}: {s:?}");
        before = s;
    }
    let lines = camera.stop();
    let summary = lines
        .iter()
        .rfind(|l| l.contains("images: published 0"))
        .unwrap_or_else(|| panic!("no summary in\n{}", lines.join("\n")));
    eprintln!("{summary}");
}

/// The whole cell in one network namespace, run by the supervisor with
/// `--camera ros2` beside the simulated arm; the camera's publisher on the
/// far end of a veth, in another (another host, as far as DDS can tell).
/// The report names the source and counts what crossed.
#[test]
fn a_whole_cell_takes_its_camera_from_another_host() {
    let _one = ONE_AT_A_TIME.lock().unwrap_or_else(|e| e.into_inner());
    assert!(
        // SAFETY: geteuid(2) has no preconditions
        unsafe { libc::geteuid() } == 0,
        "this test needs root: network namespaces (unshare --net) and a veth pair (ip link)"
    );
    let python = peer_python(&repo());
    let (dir, _) = source_frames();
    let prefix = format!("camros2w{}_", std::process::id());
    let run_dir = std::env::temp_dir().join(format!("phri-test-{prefix}"));
    let _ = std::fs::remove_dir_all(&run_dir);
    let report = run_dir.join("report.json");
    let cell = Command::new("unshare")
        .current_dir(repo())
        .env("PHRI_VETH", "cell0")
        .env("PHRI_ADDR", "10.231.3.1/24")
        .env_remove("PHRI_AFTER")
        .env_remove("PHRI_NO_IPV6")
        .env_remove("ROS_AUTOMATIC_DISCOVERY_RANGE")
        .env_remove("ROS_LOCALHOST_ONLY")
        .env("ROS_DOMAIN_ID", "0")
        .args(["--net", "--", "sh", "-c", NETNS_SETUP])
        .arg(workspace::bin("phri-supervisor"))
        .arg("--config")
        .arg(repo().join("deploy/phri.toml"))
        .args(["--scenario", "coexistence", "--duration", "12"])
        .args(["--prefix", &prefix])
        .arg("--run-dir")
        .arg(&run_dir)
        .arg("--report")
        .arg(&report)
        .args(["--camera", "ros2"])
        .args(["--set", "ros2.discovery=\"subnet\""])
        // the bridge is not what this test is about
        .args(["--set", "services.ros2.enabled=false"])
        .stdout(Stdio::null())
        .spawn()
        .expect("unshare starts the cell");
    let mut cell = Reaped(Some(cell));
    let publisher = Command::new("unshare")
        .env("PHRI_VETH", "far0")
        .env("PHRI_ADDR", "10.231.3.2/24")
        .env_remove("PHRI_AFTER")
        .env_remove("PHRI_NO_IPV6")
        .env_remove("CYCLONEDDS_URI")
        .args(["--net", "--", "sh", "-c", NETNS_SETUP])
        .arg(&python)
        .arg(repo().join("deploy/ros2/depth_pub.py"))
        .arg("--frames")
        .arg(&dir)
        .args(["--domain", "0", "--duration", "14"])
        .stdout(Stdio::piped())
        .spawn()
        .expect("unshare starts the publisher");
    let mut p = Reaped(Some(publisher));
    veth(cell.child(), "cell0", p.child(), "far0");
    let status = wait_at_most(cell.child(), Duration::from_secs(60), "the cell");
    cell.0 = None;
    let published = finished(p);
    assert!(status.success(), "the supervisor: {status}");
    let r: Value = serde_json::from_str(&std::fs::read_to_string(&report).unwrap()).unwrap();
    let _ = std::fs::remove_dir_all(&run_dir);
    let cam = &r["perception"]["cameras"][0];
    eprintln!(
        "published: {published}\ncamera 0: {cam}\nsummary: {}",
        r["summary"]
    );
    assert_eq!(cam["source"], "ros2");
    // 12 s of the cell, its camera starting a second or two in, at 30 Hz
    let frames = cam["frames"].as_u64().unwrap();
    assert!(frames >= 200, "{frames} frames crossed into the cell");
    let rate = cam["rate_hz"].as_f64().unwrap();
    assert!((27.0..=33.0).contains(&rate), "{rate} Hz");
    let k = &cam["intrinsics"];
    assert_eq!(
        (k["fx"].as_f64(), k["cx"].as_f64()),
        (Some(580.0), Some(320.0))
    );
    assert_eq!(cam["drop_causes"]["malformed"], 0);
    // the frames from the other host reached the repulsion workers
    assert!(cam["frame_to_repulsion_ms"]["p50"].as_f64().unwrap() > 0.0);
    assert_eq!(r["torque_loop"]["missed_deadlines"], 0);
    // the camera's loop ran at its real-time priority
    let rt = &r["realtime"]["services"]["camera"];
    assert_eq!(rt["shortfalls"], serde_json::json!([]), "{rt}");
}
