//! Replaying a directory of recorded depth frames (`[camera] source =
//! "replay"`): name order, PNG and raw frames alike, notes skipped, any
//! other file or a frame of the wrong size refused when the directory is
//! opened, looping or stopping at the end, a file that went bad since
//! dropped; and the older `[perception] source = "png"` turned into the
//! same replay.

use std::path::PathBuf;

use phri_config::{CameraConfig, CameraSource, Config};
use phri_perception::replay::{FrameFormat, Replay, ReplayError};

fn dir(name: &str) -> PathBuf {
    let d = std::env::temp_dir().join(format!("phri-replay-{}-{name}", std::process::id()));
    let _ = std::fs::remove_dir_all(&d);
    std::fs::create_dir_all(&d).unwrap();
    d
}

fn config(dir: &std::path::Path, looping: bool) -> CameraConfig {
    CameraConfig {
        source: CameraSource::Replay,
        replay_dir: dir.display().to_string(),
        replay_loop: looping,
        ..Config::defaults().camera
    }
}

fn raw(frame: &[u16]) -> Vec<u8> {
    frame.iter().flat_map(|d| d.to_le_bytes()).collect()
}

#[test]
fn a_directory_replays_in_name_order_png_and_raw_alike() {
    let camera = Config::defaults().camera;
    let k = camera.intrinsics;
    let d = dir("order");
    // written out of order, PNG and raw mixed; notes among them
    for (name, mm) in [("b.png", 2000u16), ("a.png", 1000), ("c.PNG", 3000)] {
        let frame = vec![mm; k.pixel_count()];
        phri_depth::write_depth_png(d.join(name), k.width, k.height, &frame).unwrap();
    }
    let mut ramp: Vec<u16> = (0..k.pixel_count()).map(|i| (i % 5000) as u16).collect();
    ramp[7] = 0;
    std::fs::write(d.join("b5"), raw(&ramp)).unwrap();
    std::fs::write(d.join("notes.txt"), "not a frame").unwrap();
    std::fs::write(d.join("README.md"), "# a recording").unwrap();
    std::fs::write(d.join(".hidden"), "x").unwrap();
    let mut replay = Replay::open(&config(&d, true), &d.join("phri.toml")).unwrap();
    let names: Vec<(String, FrameFormat)> = replay
        .files()
        .iter()
        .map(|f| {
            (
                f.path.file_name().unwrap().to_string_lossy().into_owned(),
                f.format,
            )
        })
        .collect();
    assert_eq!(
        names,
        [
            ("a.png".to_string(), FrameFormat::Png),
            ("b.png".to_string(), FrameFormat::Png),
            ("b5".to_string(), FrameFormat::Raw),
            ("c.PNG".to_string(), FrameFormat::Png)
        ]
    );
    assert_eq!(replay.period_ns(), (1e9 / camera.rate_hz) as u64);
    let mut out = vec![0u16; k.pixel_count()];
    let mut seen = Vec::new();
    for _ in 0..8 {
        replay.next_into(&mut out).unwrap().unwrap();
        seen.push(out[0]);
        if seen.len() % 4 == 3 {
            assert_eq!(out, ramp, "a raw frame is its millimetres, 0 stays 0");
        }
    }
    assert_eq!(seen, [1000, 2000, 0, 3000, 1000, 2000, 0, 3000]);
    // without looping the replay ends
    let mut once = Replay::open(&config(&d, false), &d).unwrap();
    let frames = std::iter::from_fn(|| once.next_into(&mut out)).count();
    assert_eq!(frames, 4);
    assert!(once.done() && once.next_into(&mut out).is_none());
}

#[test]
fn a_png_directory_and_a_raw_directory_give_the_same_frames() {
    let k = Config::defaults().camera.intrinsics;
    let (p, r) = (dir("same-png"), dir("same-raw"));
    let mut state = 0x9e37_79b9_7f4a_7c15u64;
    let frames: Vec<Vec<u16>> = (0..3)
        .map(|_| {
            (0..k.pixel_count())
                .map(|_| {
                    state ^= state << 13;
                    state ^= state >> 7;
                    state ^= state << 17;
                    match state % 10 {
                        0 => 0,
                        v => (400 + v * 400 + state % 97) as u16,
                    }
                })
                .collect()
        })
        .collect();
    for (i, f) in frames.iter().enumerate() {
        phri_depth::write_depth_png(p.join(format!("{i:03}.png")), k.width, k.height, f).unwrap();
        std::fs::write(r.join(format!("{i:03}.raw")), raw(f)).unwrap();
    }
    let (mut a, mut b) = (
        Replay::open(&config(&p, false), &p).unwrap(),
        Replay::open(&config(&r, false), &r).unwrap(),
    );
    let (mut fa, mut fb) = (vec![0u16; k.pixel_count()], vec![0u16; k.pixel_count()]);
    for f in &frames {
        a.next_into(&mut fa).unwrap().unwrap();
        b.next_into(&mut fb).unwrap().unwrap();
        assert!(fa == *f && fb == *f);
    }
    // another depth unit scales both alike (TUM's 1/5000 m)
    let tum = |d: &PathBuf| CameraConfig {
        depth_scale_m: phri_depth::png::TUM_SCALE_M,
        ..config(d, false)
    };
    let (mut a, mut b) = (
        Replay::open(&tum(&p), &p).unwrap(),
        Replay::open(&tum(&r), &r).unwrap(),
    );
    a.next_into(&mut fa).unwrap().unwrap();
    b.next_into(&mut fb).unwrap().unwrap();
    assert_eq!(fa, fb);
    let i = frames[0].iter().position(|&v| v > 0).unwrap();
    assert_eq!(fa[i], (f64::from(frames[0][i]) * 0.2).round() as u16);
}

#[test]
fn a_bad_recording_is_refused_naming_the_file_before_any_frame_plays() {
    let k = Config::defaults().camera.intrinsics;
    let refused = |name: &str, bytes: &[u8]| -> String {
        let d = dir(&format!("bad-{}", name.replace('.', "_")));
        phri_depth::write_depth_png(
            d.join("a.png"),
            k.width,
            k.height,
            &vec![1000; k.pixel_count()],
        )
        .unwrap();
        std::fs::write(d.join(name), bytes).unwrap();
        let e = Replay::open(&config(&d, true), &d).unwrap_err();
        assert!(matches!(e, ReplayError::NotAFrame { .. }), "{e}");
        let text = e.to_string();
        assert!(
            text.contains(name) && text.starts_with("camera.replay_dir"),
            "{text}"
        );
        assert_eq!(text.lines().count(), 1, "{text}");
        text
    };
    // a photo, a truncated raw frame, a raw frame of another size, a PNG that is not one
    assert!(refused("photo.jpg", b"\xff\xd8\xff").contains("not a recorded frame"));
    let t = refused("cut.raw", &vec![0u8; k.pixel_count() * 2 - 1]);
    assert!(t.contains("614399 bytes"), "{t}");
    refused("big", &vec![0u8; 1280 * 720 * 2]);
    refused(
        "fake.png",
        b"not a png at all, but long enough to hold a header",
    );
    let small = phri_depth::encode_depth_png(320, 240, &vec![1000; 320 * 240]).unwrap();
    assert!(refused("small.png", &small).contains("320"));
}

#[test]
fn a_file_that_went_bad_since_is_dropped_at_its_turn() {
    let k = Config::defaults().camera.intrinsics;
    let d = dir("went-bad");
    let frame = vec![1500u16; k.pixel_count()];
    std::fs::write(d.join("a.raw"), raw(&frame)).unwrap();
    std::fs::write(d.join("b.raw"), raw(&frame)).unwrap();
    let mut replay = Replay::open(&config(&d, true), &d).unwrap();
    std::fs::write(d.join("b.raw"), &raw(&frame)[..1000]).unwrap();
    let mut out = vec![0u16; k.pixel_count()];
    replay.next_into(&mut out).unwrap().unwrap();
    let e = replay.next_into(&mut out).unwrap().unwrap_err();
    assert!(
        e.to_string().contains("b.raw") && e.to_string().contains("1000 bytes"),
        "{e}"
    );
    replay.next_into(&mut out).unwrap().unwrap();
}

#[test]
fn a_directory_without_frames_is_refused_naming_it() {
    let d = dir("empty");
    std::fs::write(d.join("x.txt"), "").unwrap();
    let e = Replay::open(&config(&d, true), &d).unwrap_err();
    assert!(matches!(e, ReplayError::Empty { .. }), "{e}");
    assert!(
        e.to_string().contains("camera.replay_dir")
            && e.to_string().contains(&d.display().to_string())
    );
    let missing = d.join("no-such-dir");
    let e = Replay::open(&config(&missing, true), &d).unwrap_err();
    assert!(matches!(e, ReplayError::Dir { .. }), "{e}");
}

#[test]
fn the_older_png_source_is_the_first_camera_s_replay() {
    let mut table = phri_config::defaults_table();
    phri_config::apply_set(&mut table, "perception.source=\"png\"").unwrap();
    phri_config::apply_set(&mut table, "perception.png_dir=\"/tmp/frames\"").unwrap();
    phri_config::apply_set(&mut table, "perception.png_rate_hz=12.5").unwrap();
    phri_config::apply_set(&mut table, "perception.png_loop=false").unwrap();
    let c = Config::from_table(&table, "test").unwrap();
    assert_eq!(c.perception.source, phri_config::DepthSource::Camera);
    for cam in [&c.camera, &c.cameras[0]] {
        assert_eq!(cam.source, CameraSource::Replay);
        assert_eq!(
            (cam.replay_dir.as_str(), cam.rate_hz, cam.replay_loop),
            ("/tmp/frames", 12.5, false)
        );
    }
    let camera = &c.services["camera"];
    assert_eq!(camera.binary, "phri-camera");
}

#[test]
fn a_late_tick_drops_the_ticks_it_overran_instead_of_running_them_back_to_back() {
    const MS: u64 = 1_000_000;
    // 30 Hz, on time: one period after the other, nothing dropped
    let mut t = phri_perception::Ticks::new(0, 33 * MS);
    assert_eq!(t.deadline_ns(), 33 * MS);
    assert_eq!(t.done(33 * MS, 36 * MS), 66 * MS);
    assert_eq!(t.done(66 * MS, 69 * MS), 99 * MS);
    assert_eq!(t.dropped(), 0);
    // one slow file (a tick that worked 200 ms): the next tick comes no sooner
    // than 200 ms after it ended, on the original phase; the overrun ticks are dropped
    let next = t.done(99 * MS, 299 * MS);
    assert_eq!(
        next,
        528 * MS,
        "first tick of the schedule at or after 499 ms"
    );
    assert_eq!(t.dropped(), 12);
    assert_eq!(t.done(528 * MS, 530 * MS), 561 * MS, "then on time again");
}

#[test]
fn at_the_highest_rate_the_replay_takes_at_most_half_the_cpu() {
    const MS: u64 = 1_000_000;
    // png_rate_hz = 1000 with files that take 3 ms each: before, every tick
    // was late and the loop ran files back to back (100 % of CPU 0)
    let mut t = phri_perception::Ticks::new(0, MS);
    let (mut busy, mut now, mut frames) = (0u64, 0u64, 0u64);
    while now < 1_000 * MS {
        now = now.max(t.deadline_ns()); // sleep until the deadline
        let woke = now;
        now += 3 * MS; // the work
        busy += 3 * MS;
        frames += 1;
        t.done(woke, now);
    }
    // over whole cycles: each tick's work and the rest it is owed
    let share = busy as f64 / t.deadline_ns() as f64;
    assert!(share <= 0.5 + 1e-9, "{share}");
    assert!(frames >= 150, "{frames} frames: the replay still runs");
    assert!(t.dropped() > 0);
}

#[test]
fn a_repeated_error_is_one_line_a_second_with_its_count() {
    const MS: u64 = 1_000_000;
    let mut r = phri_perception::RateLimited::new(phri_perception::RateLimited::SECOND_NS);
    // a bad file replayed at 30 Hz for 3 s: 90 errors
    let lines: Vec<(u64, u64)> = (0..90u64)
        .filter_map(|i| r.hit(i * 33 * MS).map(|n| (i, n)))
        .collect();
    // the first at once, then one a second, each counting the errors since the last line
    assert_eq!(lines, [(0, 1), (31, 31), (62, 31)]);
}

#[test]
fn a_fakenect_recording_replays_as_the_kinect_s_millimetres() {
    use phri_depth::kinect::{Disparity, RAW_NONE};
    let k = Config::defaults().camera.intrinsics;
    let d = dir("fakenect");
    let table = Disparity::new();
    let mm: Vec<u16> = (0..k.pixel_count())
        .map(|i| {
            if i % 7 == 0 {
                0
            } else {
                600 + (i % 3000) as u16
            }
        })
        .collect();
    let mut index = String::new();
    for (i, t) in [(0u32, 1.0f64), (1, 1.033)] {
        let name = format!("d-{t:.6}-{}.pgm", 1000 + i);
        let mut bytes = b"P5 640 480 65535\n".to_vec();
        for &v in &mm {
            bytes.extend_from_slice(&table.mm_to_raw(v).to_le_bytes());
        }
        std::fs::write(d.join(&name), bytes).unwrap();
        index.push_str(&format!("{name}\nr-{t:.6}-{}.ppm\n", 1000 + i));
    }
    std::fs::write(d.join("INDEX.txt"), index).unwrap();
    let mut replay = Replay::open(&config(&d, false), &d).unwrap();
    assert_eq!(replay.files().len(), 2, "the depth files only");
    assert!(replay
        .files()
        .iter()
        .all(|f| f.format == FrameFormat::FakenectPgm));
    let mut out = vec![0u16; k.pixel_count()];
    replay.next_into(&mut out).unwrap().unwrap();
    for (i, (&o, &v)) in out.iter().zip(&mm).enumerate() {
        let expected = table.raw_to_mm(table.mm_to_raw(v));
        assert_eq!(o, expected, "pixel {i}");
        if v == 0 {
            assert_eq!(o, 0);
        } else {
            assert!(
                o.abs_diff(v) <= table.step_mm(v) / 2 + 1,
                "pixel {i}: {v} → {o}"
            );
        }
    }
    // a disparity beyond 11 bits is no Kinect's: the frame is dropped, naming it
    let mut bad = std::fs::read(&replay.files()[1].path).unwrap();
    let at = 17 + 2 * 5;
    bad[at..at + 2].copy_from_slice(&(RAW_NONE + 1).to_le_bytes());
    std::fs::write(&replay.files()[1].path, bad).unwrap();
    let e = replay.next_into(&mut out).unwrap().unwrap_err();
    assert!(e.to_string().contains("pixel 5"), "{e}");
}
