//! Replaying a directory of depth PNGs: name order, only `.png` files, the
//! configured camera in every header, looping or stopping at the end, and
//! unreadable files refused without a frame number.

use std::path::PathBuf;

use phri_config::{Config, DepthSource, IngestConfig};
use phri_ipc::FrameHeader;
use phri_perception::{PngReplay, SourceError};

fn dir(name: &str) -> PathBuf {
    let d = std::env::temp_dir().join(format!("phri-png-{}-{name}", std::process::id()));
    let _ = std::fs::remove_dir_all(&d);
    std::fs::create_dir_all(&d).unwrap();
    d
}

fn config(dir: &std::path::Path, looping: bool) -> IngestConfig {
    IngestConfig {
        source: DepthSource::Png,
        png_dir: dir.display().to_string(),
        png_loop: looping,
        ..Config::defaults().perception
    }
}

#[test]
fn a_directory_replays_in_name_order_as_frames_of_the_configured_camera() {
    let camera = Config::defaults().camera;
    let k = camera.intrinsics;
    let d = dir("order");
    // written out of order; a text file and a bad PNG among them
    for (name, mm) in [("b.png", 2000u16), ("a.png", 1000), ("c.PNG", 3000)] {
        let frame = vec![mm; k.pixel_count()];
        phri_depth::write_depth_png(d.join(name), k.width, k.height, &frame).unwrap();
    }
    std::fs::write(d.join("notes.txt"), "not a frame").unwrap();
    std::fs::write(d.join("b2.png"), "not a png").unwrap();
    let mut replay = PngReplay::open(&config(&d, true), &camera, &d.join("phri.toml")).unwrap();
    let names: Vec<String> = replay
        .files()
        .iter()
        .map(|p| p.file_name().unwrap().to_string_lossy().into_owned())
        .collect();
    assert_eq!(names, ["a.png", "b.png", "b2.png", "c.PNG"]);
    assert_eq!(
        replay.period_ns(),
        (1e9 / Config::defaults().perception.png_rate_hz) as u64
    );
    let mut h = FrameHeader::default();
    let mut seen = Vec::new();
    for i in 0..8u64 {
        match replay.next_frame(1_000 + i, 2_000 + i, &mut h).unwrap() {
            Ok(depths) => {
                assert_eq!(depths.len(), k.pixel_count());
                assert_eq!((h.width, h.height, h.fx), (k.width, k.height, k.fx));
                assert_eq!((h.capture_ns, h.capture_wall_ns), (1_000 + i, 2_000 + i));
                let (k2, _) = phri_perception::camera::header_camera(&h).unwrap();
                assert_eq!(k2, k);
                seen.push((h.seq, depths[0]));
            }
            Err(e) => {
                assert!(e.to_string().contains("b2.png"), "{e}");
                seen.push((0, 0));
            }
        }
    }
    // looping: a, b, (bad), c, a, b, (bad), c — frame numbers skip the bad file
    assert_eq!(
        seen,
        [
            (1, 1000),
            (2, 2000),
            (0, 0),
            (3, 3000),
            (4, 1000),
            (5, 2000),
            (0, 0),
            (6, 3000)
        ]
    );
    // without looping the replay ends
    let mut once = PngReplay::open(&config(&d, false), &camera, &d).unwrap();
    let frames = std::iter::from_fn(|| once.next_frame(0, 0, &mut h)).count();
    assert_eq!(frames, 4);
    assert!(once.next_frame(0, 0, &mut h).is_none());
}

#[test]
fn a_directory_without_frames_is_refused_naming_it() {
    let camera = Config::defaults().camera;
    let d = dir("empty");
    std::fs::write(d.join("x.txt"), "").unwrap();
    let e = PngReplay::open(&config(&d, true), &camera, &d).unwrap_err();
    assert!(matches!(e, SourceError::Empty { .. }), "{e}");
    assert!(
        e.to_string().contains("perception.png_dir")
            && e.to_string().contains(&d.display().to_string())
    );
    let missing = d.join("no-such-dir");
    let e = PngReplay::open(&config(&missing, true), &camera, &d).unwrap_err();
    assert!(matches!(e, SourceError::Dir { .. }), "{e}");
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
