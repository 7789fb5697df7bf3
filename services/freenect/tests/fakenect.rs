//! The real `phri-freenect` process under fakenect (Debian's
//! `libfreenect-bin`), playing a recording written from the 12 real Kinect
//! frames of `../shared/data/kinect-person`: every frame comes out on
//! `camera/depth` as it went in, within the quantisation of the disparity
//! conversion at each pixel's depth, with the Kinect's intrinsics and
//! consistent stamps; past the recording's end the service keeps running.
//! And without fakenect or a Kinect it fails at once, in one line naming
//! the device.

use std::io::{BufRead, BufReader};
use std::path::{Path, PathBuf};
use std::process::{Child, Command, Stdio};
use std::time::{Duration, Instant};

use phri_freenect::{Disparity, PIXELS};
use phri_ipc::{Queue, CAMERA_DEPTH};

const DATA: &str = concat!(
    env!("CARGO_MANIFEST_DIR"),
    "/../../../shared/data/kinect-person"
);

fn repo() -> PathBuf {
    Path::new(concat!(env!("CARGO_MANIFEST_DIR"), "/../..")).to_path_buf()
}

/// The 12 frames [mm], in file-name order.
fn person_frames() -> Vec<Vec<u16>> {
    let mut paths: Vec<PathBuf> = std::fs::read_dir(DATA)
        .unwrap()
        .map(|e| e.unwrap().path())
        .filter(|p| {
            p.file_name()
                .and_then(|n| n.to_str())
                .is_some_and(|n| n.starts_with("depth-data-"))
        })
        .collect();
    paths.sort();
    paths
        .iter()
        .map(|p| {
            let bytes = std::fs::read(p).unwrap();
            assert_eq!(bytes.len(), 2 * PIXELS, "{}", p.display());
            bytes
                .chunks_exact(2)
                .map(|b| u16::from_le_bytes([b[0], b[1]]))
                .collect()
        })
        .collect()
}

/// `phri-freenect` under its own prefix, in its own process group (the
/// `fakenect` wrapper is a shell script: its child must go with it).
fn start(fakenect_dir: Option<&Path>, prefix: &str) -> Child {
    let bin = env!("CARGO_BIN_EXE_phri-freenect");
    let mut cmd = match fakenect_dir {
        Some(dir) => {
            let mut c = Command::new("fakenect");
            c.arg(dir).arg(bin);
            c
        }
        None => Command::new(bin),
    };
    cmd.current_dir(repo())
        .arg("--config")
        .arg(repo().join("deploy/phri.toml"))
        .args(["--prefix", prefix])
        .args(["--set", "camera.source=\"freenect\""])
        .stdin(Stdio::null())
        .stdout(Stdio::null())
        .stderr(Stdio::piped());
    std::os::unix::process::CommandExt::process_group(&mut cmd, 0);
    cmd.spawn().unwrap()
}

/// Stop the service with SIGTERM (under the `fakenect` shell wrapper: its
/// child, the service, which the shell reaps before it exits itself), the
/// whole process group with SIGKILL after 5 s; clean the prefix.
fn stop(child: &mut Child, prefix: &str) {
    let pid = child.id();
    let children =
        std::fs::read_to_string(format!("/proc/{pid}/task/{pid}/children")).unwrap_or_default();
    let mut targets: Vec<String> = children.split_whitespace().map(str::to_string).collect();
    if targets.is_empty() {
        targets.push(pid.to_string());
    }
    for t in &targets {
        let _ = Command::new("kill")
            .args(["-TERM", t])
            .stderr(Stdio::null())
            .status();
    }
    let deadline = Instant::now() + Duration::from_secs(5);
    while child.try_wait().unwrap().is_none() {
        if Instant::now() > deadline {
            let _ = Command::new("kill")
                .args(["-KILL", "--", &format!("-{pid}")])
                .stderr(Stdio::null())
                .status();
            let _ = child.wait();
            break;
        }
        std::thread::sleep(Duration::from_millis(20));
    }
    let _ = phri_ipc::remove_leftovers(prefix);
}

/// A received frame: its header and depths [mm].
struct Got {
    header: phri_ipc::FrameHeader,
    depths: Vec<u16>,
}

#[test]
fn a_recording_of_the_real_frames_comes_out_as_recorded() {
    let frames = person_frames();
    assert_eq!(frames.len(), 12);
    let dir = std::env::temp_dir().join(format!("phri-freenect-fakenect-{}", std::process::id()));
    let _ = std::fs::remove_dir_all(&dir);
    // device timestamps from just before a wrap of the 32-bit counter
    let names = phri_freenect::write_recording(&dir, &frames, 30.0, u32::MAX - 7_000_000).unwrap();
    assert_eq!(names.len(), 12);

    let prefix = format!("fnk{}_", std::process::id());
    // subscribed before the service starts: no frame missed
    let node = phri_ipc::node("freenect-test", &prefix).unwrap();
    let sub = CAMERA_DEPTH.frame_subscriber(&node, Queue::Drain).unwrap();
    let mut child = start(Some(&dir), &prefix);
    let stderr = child.stderr.take().unwrap();
    let reader = std::thread::spawn(move || {
        BufReader::new(stderr)
            .lines()
            .map_while(Result::ok)
            .collect::<Vec<String>>()
    });

    let mut got: Vec<Got> = Vec::new();
    let deadline = Instant::now() + Duration::from_secs(20);
    while got.len() < frames.len() && Instant::now() < deadline {
        match sub.receive().unwrap() {
            Some(f) => got.push(Got {
                header: *f.user_header(),
                depths: f.payload().to_vec(),
            }),
            None => {
                if child.try_wait().unwrap().is_some() {
                    break;
                }
                std::thread::sleep(Duration::from_millis(2));
            }
        }
    }
    // past the recording's end (fakenect fails every later event
    // processing): still running, nothing more published
    std::thread::sleep(Duration::from_millis(1500));
    let alive = child.try_wait().unwrap().is_none();
    let extra = std::iter::from_fn(|| sub.receive().unwrap()).count();
    stop(&mut child, &prefix);
    // the prefix's files go once no node of it is left, ours included
    drop(sub);
    drop(node);
    let _ = phri_ipc::remove_leftovers(&prefix);
    let lines = reader.join().unwrap();
    let _ = std::fs::remove_dir_all(&dir);
    assert!(alive, "exited after the recording: {lines:#?}");
    assert_eq!(extra, 0);
    assert_eq!(got.len(), frames.len(), "{lines:#?}");

    let table = Disparity::new();
    let (mut compared, mut max_diff, mut bound_at_max) = (0usize, 0u32, 0u16);
    let mut worst_ratio = 0.0f64;
    for (i, (g, want)) in got.iter().zip(&frames).enumerate() {
        let h = &g.header;
        assert_eq!(h.seq, i as u64 + 1);
        assert_eq!((h.width, h.height), (640, 480));
        assert_eq!((h.fx, h.fy, h.cx, h.cy), (580.0, 580.0, 320.0, 240.0));
        assert!(h.capture_wall_ns > 0);
        assert!(h.capture_wall_ns <= h.published_ns, "frame {i}");
        assert_eq!(g.depths.len(), PIXELS);
        for (p, (&d, &w)) in g.depths.iter().zip(want).enumerate() {
            if w == 0 {
                assert_eq!(d, 0, "frame {i} pixel {p}: no reading became {d} mm");
                continue;
            }
            // half the depth difference of the raws bracketing the depth
            let step = table.step_mm(w);
            let diff = (d as i32 - w as i32).unsigned_abs();
            assert!(
                2 * diff <= step as u32,
                "frame {i} pixel {p}: {w} mm came out {d} mm (raw step there {step} mm)"
            );
            compared += 1;
            if diff > max_diff {
                (max_diff, bound_at_max) = (diff, step);
            }
            if step > 0 {
                worst_ratio = worst_ratio.max(2.0 * diff as f64 / step as f64);
            }
        }
        assert_eq!(
            h.valid_pixels as usize,
            want.iter().filter(|&&w| w > 0).count()
        );
    }
    let first = got[0].header.capture_wall_ns;
    let last = got[got.len() - 1].header.capture_wall_ns;
    let rate = (got.len() - 1) as f64 / ((last - first) as f64 * 1e-9);
    let latency_ms = got
        .iter()
        .map(|g| (g.header.published_ns - g.header.capture_wall_ns) as f64 * 1e-6)
        .fold(0.0, f64::max);
    eprintln!(
        "{} frames, {compared} pixels with a reading compared: max |Δ| {max_diff} mm \
         (bound there: half of a {bound_at_max} mm raw step), worst Δ/(step/2) {worst_ratio:.2}; \
         {rate:.1} Hz by capture stamps, capture → published ≤ {latency_ms:.2} ms",
        got.len()
    );
    assert!((25.0..35.0).contains(&rate), "{rate} Hz");
}

#[test]
fn without_a_kinect_it_fails_at_once_naming_the_device() {
    let prefix = format!("fnn{}_", std::process::id());
    let t = Instant::now();
    let mut child = start(None, &prefix);
    let mut exited = None;
    while t.elapsed() < Duration::from_secs(10) {
        if let Some(status) = child.try_wait().unwrap() {
            exited = Some(status);
            break;
        }
        std::thread::sleep(Duration::from_millis(20));
    }
    let mut err = String::new();
    if exited.is_none() {
        stop(&mut child, &prefix);
    } else {
        let _ = phri_ipc::remove_leftovers(&prefix);
    }
    // reaped already (try_wait or stop): returns at once
    let _ = child.wait();
    if let Some(mut e) = child.stderr.take() {
        let _ = std::io::Read::read_to_string(&mut e, &mut err);
    }
    let status = exited.unwrap_or_else(|| panic!("still running after 10 s: {err}"));
    assert!(!status.success(), "{err}");
    assert_eq!(status.code(), Some(2), "{err}");
    assert_eq!(err.trim_end().lines().count(), 1, "{err}");
    assert!(err.contains("freenect device 0"), "{err}");
    eprintln!("{:.2} s: {}", t.elapsed().as_secs_f64(), err.trim_end());
}

#[test]
fn a_check_run_needs_no_device() {
    let out = Command::new(env!("CARGO_BIN_EXE_phri-freenect"))
        .current_dir(repo())
        .arg("--config")
        .arg(repo().join("deploy/phri.toml"))
        .args(["--prefix", &format!("fnc{}_", std::process::id())])
        .args(["--set", "camera.source=\"freenect\"", "--check"])
        .output()
        .unwrap();
    assert!(
        out.status.success(),
        "{}",
        String::from_utf8_lossy(&out.stderr)
    );
}

#[test]
fn a_device_that_never_sends_a_frame_is_an_error_after_5_s() {
    // fakenect with an empty recording: a device that answers no frame
    let dir = std::env::temp_dir().join(format!("phri-freenect-empty-{}", std::process::id()));
    let _ = std::fs::remove_dir_all(&dir);
    std::fs::create_dir_all(&dir).unwrap();
    std::fs::write(dir.join("INDEX.txt"), "").unwrap();
    let prefix = format!("fne{}_", std::process::id());
    let t = Instant::now();
    let mut child = start(Some(&dir), &prefix);
    let mut exited = None;
    while t.elapsed() < Duration::from_secs(10) {
        if let Some(status) = child.try_wait().unwrap() {
            exited = Some(status);
            break;
        }
        std::thread::sleep(Duration::from_millis(20));
    }
    if exited.is_none() {
        stop(&mut child, &prefix);
    }
    let _ = child.wait();
    let _ = phri_ipc::remove_leftovers(&prefix);
    let mut err = String::new();
    if let Some(mut e) = child.stderr.take() {
        let _ = std::io::Read::read_to_string(&mut e, &mut err);
    }
    let _ = std::fs::remove_dir_all(&dir);
    let took = t.elapsed().as_secs_f64();
    let status = exited.unwrap_or_else(|| panic!("still running after 10 s: {err}"));
    assert_eq!(status.code(), Some(2), "{err}");
    // the warnings of failed event processing before it, then the error
    let last = err.trim_end().lines().last().unwrap_or_default();
    assert_eq!(
        last, "phri-freenect: freenect device 0: no depth frame within 5 s",
        "{err}"
    );
    assert!((5.0..8.0).contains(&took), "{took} s");
    eprintln!("{took:.2} s: {last}");
}
