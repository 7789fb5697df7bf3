//! No request lost silently, a stop never: a flood of requests from one
//! publisher on `hri/request` neither pushes a `stop` out of the
//! controllers' queues nor hides it; requests a controller may have lost
//! (its queue stayed full past the publishers' wait) are counted in the
//! report (`collaboration.requests_dropped`, the run degraded) and the
//! controller in charge stops as if one had been a stop.
//!
//! Multi-process: each test runs a cell (`free-motion`, the hot standby)
//! under its own prefix and floods it from this process, which speaks as the
//! operator's command line (`cli`). Needs the release binaries
//! (`cargo build --release --bins`).

#[path = "../../../tests/support/mod.rs"]
mod support;
#[path = "../../../tests/support/workspace.rs"]
mod workspace;

use std::process::{Child, Stdio};
use std::time::{Duration, Instant};

use phri_ipc::{
    CollabState, ControlMode, ControlStatus, HriRequest, Queue, RequestKind, RequestSource, Zeroed,
    COLLAB_STATE, CONTROL_STATUS, HRI_REQUEST,
};
use serde_json::Value;
use support::RunPlace;
use workspace::{bin, repo};

/// One cell at a time: two would share this machine's two cores.
fn serial() -> std::sync::MutexGuard<'static, ()> {
    static LOCK: std::sync::Mutex<()> = std::sync::Mutex::new(());
    LOCK.lock().unwrap_or_else(|e| e.into_inner())
}

fn now_ns() -> u64 {
    let mut ts = libc::timespec {
        tv_sec: 0,
        tv_nsec: 0,
    };
    // SAFETY: ts is a valid timespec to write
    unsafe { libc::clock_gettime(libc::CLOCK_MONOTONIC, &mut ts) };
    ts.tv_sec as u64 * 1_000_000_000 + ts.tv_nsec as u64
}

/// Request `seq` of `kind`, made now.
fn request(kind: RequestKind, seq: u64) -> HriRequest {
    let mut r = HriRequest::zeroed();
    r.seq = seq;
    r.stamp_ns = now_ns();
    r.source = RequestSource::Cli as u32;
    r.kind = kind as u32;
    r.person = u32::MAX;
    r.confidence = 1.0;
    r
}

/// A cell of `duration_s` seconds, its stderr in the run's folder.
struct Cell {
    place: RunPlace,
    child: Child,
    stderr: std::path::PathBuf,
}

impl Cell {
    fn start(test: &str, duration_s: u32) -> Cell {
        let place = RunPlace::new('q', test);
        let scratch = std::env::temp_dir().join(format!("phri-test-{}err", place.prefix));
        std::fs::create_dir_all(&scratch).unwrap();
        let stderr = scratch.join("stderr.txt");
        let mut cmd = place.command(bin("phri-supervisor").to_str().unwrap(), &repo());
        cmd.args([
            "--scenario",
            "free-motion",
            "--duration",
            &duration_s.to_string(),
        ])
        .stdout(Stdio::null())
        .stderr(std::fs::File::create(&stderr).unwrap());
        Cell {
            child: cmd.spawn().unwrap(),
            place,
            stderr,
        }
    }

    fn stderr(&self) -> String {
        std::fs::read_to_string(&self.stderr).unwrap_or_default()
    }

    /// The pid of service `name` (the run's state file).
    fn pid(&self, name: &str) -> i32 {
        let deadline = Instant::now() + Duration::from_secs(20);
        loop {
            let v: Value = std::fs::read_to_string(self.place.run_dir.join("state.json"))
                .ok()
                .and_then(|t| serde_json::from_str(&t).ok())
                .unwrap_or(Value::Null);
            if let Some(p) = v["services"][name]["pid"].as_i64() {
                return p as i32;
            }
            assert!(Instant::now() < deadline, "no pid of {name}");
            std::thread::sleep(Duration::from_millis(50));
        }
    }

    /// Wait for the run's end; its report.
    fn finish(mut self) -> Value {
        let deadline = Instant::now() + Duration::from_secs(90);
        loop {
            if self.child.try_wait().unwrap().is_some() {
                break;
            }
            assert!(
                Instant::now() < deadline,
                "the supervisor did not end: {}",
                self.stderr()
            );
            std::thread::sleep(Duration::from_millis(50));
        }
        let text = std::fs::read_to_string(&self.place.report)
            .unwrap_or_else(|e| panic!("no report ({e}): {}", self.stderr()));
        serde_json::from_str(&text).unwrap()
    }
}

impl Drop for Cell {
    fn drop(&mut self) {
        if self.child.try_wait().ok().flatten().is_none() {
            // SAFETY: a signal to our own child
            unsafe { libc::kill(self.child.id() as i32, libc::SIGINT) };
            let _ = self.child.wait();
        }
    }
}

/// The controller in charge runs its task (control/status).
fn wait_for_the_task(status: &phri_ipc::Subscriber<ControlStatus>, cell: &Cell) {
    let deadline = Instant::now() + Duration::from_secs(40);
    loop {
        if let Some(s) = status.latest().unwrap() {
            if s.mode == ControlMode::Task as u32 {
                return;
            }
        }
        assert!(
            Instant::now() < deadline,
            "the task never ran: {}",
            cell.stderr()
        );
        std::thread::sleep(Duration::from_millis(20));
    }
}

/// 200 requests, a `stop`, 200 more, from one publisher as fast as it can:
/// the stop is answered (accepted, as the period's answer on `collab/state`)
/// and stops the arm; nothing is dropped anywhere, nobody was left out.
#[test]
fn a_stop_between_two_floods_of_requests_is_acted_on_and_nothing_is_dropped() {
    let _g = serial();
    let cell = Cell::start("flood", 14);
    let node = phri_ipc::node("flooder", &cell.place.prefix).unwrap();
    let status = loop {
        if let Some(s) = CONTROL_STATUS
            .subscriber_if_exists(&node, Queue::Latest)
            .unwrap()
        {
            break s;
        }
        std::thread::sleep(Duration::from_millis(100));
    };
    wait_for_the_task(&status, &cell);
    let collab = COLLAB_STATE.subscriber(&node, Queue::Drain).unwrap();
    // every status: a stop request's protective stop may last one period
    let statuses = CONTROL_STATUS.subscriber(&node, Queue::Drain).unwrap();
    let publisher = HRI_REQUEST.publisher(&node).unwrap();
    // let the readers connect: iceoryx2 connects them at the first send
    publisher.update_connections();
    std::thread::sleep(Duration::from_millis(200));
    let t0 = Instant::now();
    for seq in 1..=200 {
        publisher.publish(&request(RequestKind::End, seq)).unwrap();
    }
    publisher.publish(&request(RequestKind::Stop, 201)).unwrap();
    for seq in 202..=401 {
        publisher.publish(&request(RequestKind::End, seq)).unwrap();
    }
    let took = t0.elapsed();
    // the stop answered, and the arm stopped
    let deadline = Instant::now() + Duration::from_secs(3);
    let (mut answered, mut stopped) = (None::<CollabState>, false);
    while Instant::now() < deadline && !(answered.is_some() && stopped) {
        collab
            .drain(|s| {
                if s.request_kind == RequestKind::Stop as u32 && s.request_seq == 201 {
                    answered.get_or_insert(*s);
                }
            })
            .unwrap();
        statuses
            .drain(|s| stopped |= s.mode == ControlMode::ProtectiveStop as u32)
            .unwrap();
        std::thread::sleep(Duration::from_millis(1));
    }
    let answered = answered.expect("the stop was never answered");
    assert_eq!(answered.request_accepted, 1);
    assert_eq!(answered.request_source, RequestSource::Cli as u32);
    assert!(stopped, "no protective stop after the stop request");
    // a reader left out of a request only after not reading for
    // DELIVERY_WAIT (the controllers read every period, the supervisor every
    // 10 ms: on a loaded machine without real-time scheduling one may stall)
    let left_out = publisher.undelivered();
    println!("401 requests published in {took:?}, {left_out} deliveries left out");
    // the supervisor reads them before this publisher goes
    std::thread::sleep(Duration::from_millis(500));
    drop(publisher);
    let r = cell.finish();
    let c = &r["collaboration"];
    if left_out == 0 {
        // nobody left out: no controller can have lost one
        assert_eq!(c["requests_dropped"], 0, "{c}");
    }
    assert!(
        r["protective_stop_causes"]["request"].as_u64().unwrap_or(0) >= 1,
        "{}",
        r["protective_stop_causes"]
    );
    let listed = c["requests"].as_array().unwrap();
    assert!(
        listed
            .iter()
            .any(|q| q["seq"] == 201 && q["kind"] == "stop" && q["accepted"] == true),
        "{c}"
    );
    let summary = r["summary"].as_str().unwrap_or("");
    assert!(!summary.contains("dropped"), "{summary}");
}

/// Both controllers stopped (SIGSTOP, 0.4 s: short of their 1 s liveness
/// deadline) while 257 requests arrive: their queues (256) fill, the
/// publisher waits for each 100 ms and leaves it out of the last (counted
/// on the publisher); back, each finds its queue full after 100 ms unread:
/// requests may have been lost, counted in the report (the run degraded),
/// and the controller in charge stops as if one had been a stop.
#[test]
fn requests_a_stalled_controller_may_have_lost_are_counted_and_stop_the_arm() {
    let _g = serial();
    let cell = Cell::start("lost", 14);
    let node = phri_ipc::node("flooder", &cell.place.prefix).unwrap();
    let status = loop {
        if let Some(s) = CONTROL_STATUS
            .subscriber_if_exists(&node, Queue::Latest)
            .unwrap()
        {
            break s;
        }
        std::thread::sleep(Duration::from_millis(100));
    };
    wait_for_the_task(&status, &cell);
    let publisher = HRI_REQUEST.publisher(&node).unwrap();
    publisher.update_connections();
    std::thread::sleep(Duration::from_millis(200));
    let controllers = [cell.pid("control"), cell.pid("control_standby")];
    let stopped_at = Instant::now();
    for &p in &controllers {
        // SAFETY: a signal to a process of this test's cell
        unsafe { libc::kill(p, libc::SIGSTOP) };
    }
    for seq in 1..=257 {
        publisher.publish(&request(RequestKind::End, seq)).unwrap();
    }
    let left_out = publisher.undelivered();
    std::thread::sleep(Duration::from_millis(400).saturating_sub(stopped_at.elapsed()));
    for &p in &controllers {
        // SAFETY: as above
        unsafe { libc::kill(p, libc::SIGCONT) };
    }
    // the request past the queue, left out of both stopped controllers
    assert!(left_out >= 2, "{left_out} left out");
    std::thread::sleep(Duration::from_millis(500));
    drop(publisher);
    let r = cell.finish();
    let dropped = r["collaboration"]["requests_dropped"].as_u64().unwrap_or(0);
    assert!(dropped >= 1, "{}", r["collaboration"]);
    assert_eq!(r["clean"], false);
    let summary = r["summary"].as_str().unwrap_or("");
    assert!(summary.contains("dropped"), "{summary}");
    assert!(
        r["degraded"]
            .as_array()
            .unwrap()
            .iter()
            .any(|l| l.as_str().unwrap_or("").starts_with("hri/request: ")),
        "{}",
        r["degraded"]
    );
    // the controller in charge stopped as if one had been a stop
    assert!(
        r["protective_stops"].as_u64().unwrap_or(0) >= 1,
        "{}",
        r["protective_stop_causes"]
    );
}
