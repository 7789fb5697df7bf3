//! The replay camera (`phri-camera`, `[camera] source = "replay"`) at the
//! highest rate the configuration allows (1000 Hz): a 128 MB file, or files
//! that take longer to decode than a period, never make it spin (reading
//! and decoding back to back would take CPU 0 from perception), and a bad
//! file is one line a second on stderr, not one per tick. The older keys
//! (`[perception] source = "png"`) still configure it.

use std::io::{BufRead, BufReader};
use std::path::{Path, PathBuf};
use std::process::{Child, Command, Stdio};
use std::time::{Duration, Instant};

use crate::workspace::repo;

fn dir(name: &str) -> PathBuf {
    let d = std::env::temp_dir().join(format!("phri-pngproc-{}-{name}", std::process::id()));
    let _ = std::fs::remove_dir_all(&d);
    std::fs::create_dir_all(&d).unwrap();
    d
}

/// `phri-camera` replaying `dir` at `rate_hz`, under its own prefix.
fn start(dir: &Path, rate_hz: f64, prefix: &str) -> Child {
    Command::new(env!("CARGO_BIN_EXE_phri-camera"))
        .current_dir(repo())
        .arg("--config")
        .arg(repo().join("deploy/phri.toml"))
        .args(["--prefix", prefix])
        .args(["--set", "camera.source=\"replay\""])
        .arg("--set")
        .arg(format!("camera.replay_dir=\"{}\"", dir.display()))
        .arg("--set")
        .arg(format!("camera.rate_hz={rate_hz}"))
        .stdout(Stdio::null())
        .stderr(Stdio::piped())
        .spawn()
        .unwrap()
}

/// CPU time the process has used [s] (user + system, from /proc).
fn cpu_s(pid: u32) -> f64 {
    let stat = std::fs::read_to_string(format!("/proc/{pid}/stat")).unwrap();
    // fields after the command name's closing parenthesis: state is field 3, utime 14, stime 15
    let rest = &stat[stat.rfind(')').unwrap() + 2..];
    let f: Vec<&str> = rest.split_whitespace().collect();
    let ticks: f64 = f[11].parse::<f64>().unwrap() + f[12].parse::<f64>().unwrap();
    let out = Command::new("getconf").arg("CLK_TCK").output().unwrap();
    let hz: f64 = String::from_utf8_lossy(&out.stdout)
        .trim()
        .parse()
        .unwrap_or(100.0);
    ticks / hz
}

/// Run for `seconds`, then stop it (SIGTERM) and clean its prefix; (the
/// share of one CPU it used over that time, its stderr lines).
fn measure(mut child: Child, seconds: f64, prefix: &str) -> (f64, Vec<String>) {
    let pid = child.id();
    let stderr = child.stderr.take().unwrap();
    let reader = std::thread::spawn(move || {
        BufReader::new(stderr)
            .lines()
            .map_while(Result::ok)
            .collect::<Vec<String>>()
    });
    // let it start (configuration, model, node)
    std::thread::sleep(Duration::from_millis(500));
    assert!(
        child.try_wait().unwrap().is_none(),
        "phri-camera exited early"
    );
    let (c0, t0) = (cpu_s(pid), Instant::now());
    std::thread::sleep(Duration::from_secs_f64(seconds));
    let share = (cpu_s(pid) - c0) / t0.elapsed().as_secs_f64();
    let _ = Command::new("kill")
        .args(["-TERM", &pid.to_string()])
        .status();
    let deadline = Instant::now() + Duration::from_secs(5);
    while child.try_wait().unwrap().is_none() {
        if Instant::now() > deadline {
            let _ = child.kill();
            let _ = child.wait();
            break;
        }
        std::thread::sleep(Duration::from_millis(20));
    }
    let lines = reader.join().unwrap();
    let _ = phri_ipc::remove_leftovers(prefix);
    (share, lines)
}

#[test]
fn a_huge_file_costs_a_stat_per_tick_and_one_line_a_second() {
    let d = dir("huge");
    // a valid 640×480 16-bit header in front of 128 MB
    let k = phri_config::Config::defaults().camera.intrinsics;
    let good =
        phri_depth::encode_depth_png(k.width, k.height, &vec![1000; k.pixel_count()]).unwrap();
    let path = d.join("huge.png");
    std::fs::write(&path, &good[..64]).unwrap();
    std::fs::OpenOptions::new()
        .write(true)
        .open(&path)
        .unwrap()
        .set_len(128 << 20)
        .unwrap();
    let prefix = format!("pnghuge{}_", std::process::id());
    let (share, lines) = measure(start(&d, 1000.0, &prefix), 3.0, &prefix);
    let about: Vec<&String> = lines.iter().filter(|l| l.contains("huge.png")).collect();
    eprintln!(
        "128 MB file at 1000 Hz: {:.1} % of a CPU, {} lines in 3.5 s",
        share * 100.0,
        about.len()
    );
    // it read 128 MB per tick, back to back (100 % of CPU 0)
    assert!(share < 0.25, "{:.0} % of a CPU", share * 100.0);
    // 3.5 s of errors at 1000 Hz: one line a second, with the count
    assert!((2..=5).contains(&about.len()), "{lines:#?}");
    assert!(
        about
            .iter()
            .all(|l| l.contains("more than") && l.contains("unreadable files")),
        "{about:#?}"
    );
    let _ = std::fs::remove_dir_all(&d);
}

#[test]
fn files_slower_than_the_period_never_run_back_to_back() {
    let d = dir("slow");
    let k = phri_config::Config::defaults().camera.intrinsics;
    // smooth depths with a few bits of noise: each file takes milliseconds
    // to inflate and convert, more than the 1 ms period
    let mut state = 0x2545_f491_4f6c_dd1du64;
    for i in 0..3 {
        let frame: Vec<u16> = (0..k.pixel_count())
            .map(|p| {
                state ^= state << 13;
                state ^= state >> 7;
                state ^= state << 17;
                let (x, y) = (p % k.width as usize, p / k.width as usize);
                (1000 + (3 * x + 5 * y) % 2000) as u16 + (state % 16) as u16
            })
            .collect();
        phri_depth::write_depth_png(d.join(format!("f{i}.png")), k.width, k.height, &frame)
            .unwrap();
    }
    let t = Instant::now();
    for _ in 0..10 {
        phri_depth::read_depth_png(d.join("f0.png"), k.width, k.height, 0.001).unwrap();
    }
    let file_ms = t.elapsed().as_secs_f64() * 100.0;
    let prefix = format!("pngslow{}_", std::process::id());
    let (share, _) = measure(start(&d, 1000.0, &prefix), 3.0, &prefix);
    eprintln!(
        "640x480 files of {file_ms:.2} ms each at 1000 Hz: {:.1} % of a CPU",
        share * 100.0
    );
    // at most half the CPU (the rest a tick is owed after a late one), plus the loop's own
    assert!(share < 0.6, "{:.0} % of a CPU", share * 100.0);
    let _ = std::fs::remove_dir_all(&d);
}

#[test]
fn an_unbounded_rate_is_refused_naming_the_key() {
    let d = dir("rate");
    let prefix = format!("pngrate{}_", std::process::id());
    // the older keys, as a configuration of before the replay camera gives them
    let out = Command::new(env!("CARGO_BIN_EXE_phri-camera"))
        .current_dir(repo())
        .arg("--config")
        .arg(repo().join("deploy/phri.toml"))
        .args(["--prefix", &prefix])
        .args(["--set", "perception.source=\"png\""])
        .arg("--set")
        .arg(format!("perception.png_dir=\"{}\"", d.display()))
        .args(["--set", "perception.png_rate_hz=1e12"])
        .stdout(Stdio::null())
        .stderr(Stdio::piped())
        .spawn()
        .unwrap()
        .wait_with_output()
        .unwrap();
    let err = String::from_utf8_lossy(&out.stderr);
    assert_eq!(out.status.code(), Some(2), "{err}");
    assert!(err.contains("perception.png_rate_hz"), "{err}");
    assert_eq!(err.trim_end().lines().count(), 1, "{err}");
    let _ = std::fs::remove_dir_all(&d);
}
