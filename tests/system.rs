//! System tests: the real processes of the cell, started by the real
//! supervisor, with processes really killed. Each run has its own iceoryx2
//! prefix; runs are serialised so that two cells never share the 2 cores.

use std::path::{Path, PathBuf};
use std::process::{Child, Command, Stdio};
use std::sync::Mutex;
use std::time::{Duration, Instant};

use serde_json::Value;

mod support;

static SERIAL: Mutex<()> = Mutex::new(());

/// The tests of the `coexistence` scenario meet its person 5 s into the
/// script: walking across 1 m in front of the base and 1.4 m to its side,
/// 5 s before the hand moves into the end effector's path (`[sim]
/// human_offset_s`). The walk from the script's start, 1.8 m to the side,
/// is 5 s of cell the tests do not need
const OFFSET: &str = "sim.human_offset_s=5";

fn repo() -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR"))
        .join("../..")
        .canonicalize()
        .unwrap()
}

fn bin(name: &str) -> PathBuf {
    let p = Path::new(env!("CARGO_BIN_EXE_phri-supervisor"))
        .parent()
        .unwrap()
        .join(name);
    assert!(
        p.is_file(),
        "{} not built (cargo test --workspace builds it)",
        p.display()
    );
    p
}

struct Cell {
    child: Child,
    prefix: String,
    run_dir: PathBuf,
    report: PathBuf,
}

impl Cell {
    fn start(test: &str, scenario: &str, duration: Option<f64>, sets: &[&str]) -> Cell {
        Cell::start_with("deploy/phri.toml", test, scenario, duration, sets)
    }

    /// As [`Cell::start`], with the configuration file `config` (relative to the repository).
    fn start_with(
        config: &str,
        test: &str,
        scenario: &str,
        duration: Option<f64>,
        sets: &[&str],
    ) -> Cell {
        support::loud_panics();
        for b in ["phri-sim", "phri-dynamics", "phri-control"] {
            bin(b);
        }
        // the supervisor creates its run directory itself, private (0700)
        let place = support::RunPlace::new('t', test);
        let mut cmd = place.command(env!("CARGO_BIN_EXE_phri-supervisor"), &repo());
        cmd.arg("--config")
            .arg(repo().join(config))
            .arg("--scenario")
            .arg(scenario);
        if let Some(d) = duration {
            cmd.arg("--duration").arg(d.to_string());
        }
        for s in sets {
            cmd.arg("--set").arg(s);
        }
        cmd.stdout(Stdio::null()).stderr(Stdio::inherit());
        Cell {
            child: cmd.spawn().unwrap(),
            prefix: place.prefix,
            run_dir: place.run_dir,
            report: place.report,
        }
    }

    fn pid_of(&self, service: &str) -> i32 {
        let deadline = Instant::now() + Duration::from_secs(10);
        loop {
            if let Ok(text) = std::fs::read_to_string(self.run_dir.join("state.json")) {
                if let Ok(v) = serde_json::from_str::<Value>(&text) {
                    if let Some(pid) = v["services"][service]["pid"].as_i64() {
                        return pid as i32;
                    }
                }
            }
            assert!(Instant::now() < deadline, "no pid for {service}");
            std::thread::sleep(Duration::from_millis(50));
        }
    }

    fn kill(&self, service: &str, sig: i32) -> i32 {
        let pid = self.pid_of(service);
        // SAFETY: kill(2) on a pid the supervisor reported as its child.
        assert_eq!(unsafe { libc::kill(pid, sig) }, 0, "kill {service} ({pid})");
        pid
    }

    /// Ends the run now (SIGINT to the supervisor: its ordered shutdown
    /// and report), for a test whose script is done before the duration
    /// it set as a cap; then [`Cell::finish`].
    fn end_now(self) -> Value {
        // SAFETY: a signal to our own child.
        unsafe { libc::kill(self.child.id() as i32, libc::SIGINT) };
        self.finish()
    }

    fn finish(mut self) -> Value {
        let status = self.child.wait().unwrap();
        assert!(status.success(), "supervisor failed: {status}");
        let v: Value =
            serde_json::from_str(&std::fs::read_to_string(&self.report).unwrap()).unwrap();
        assert_nothing_left(&self.prefix);
        eprintln!("{}", serde_json::to_string(&v["torque_loop"]).unwrap());
        v
    }
}

/// No process of the run and no shared-memory file of its prefix remain.
fn assert_nothing_left(prefix: &str) {
    let out = Command::new("pgrep")
        .arg("-f")
        .arg(format!("--prefix {prefix}"))
        .output()
        .unwrap();
    assert!(
        out.stdout.is_empty(),
        "processes left: {}",
        String::from_utf8_lossy(&out.stdout)
    );
    let files = phri_ipc::files_of(prefix);
    assert!(files.is_empty(), "left behind: {files:?}");
}

fn events<'a>(r: &'a Value, kind: &str, service: &str) -> Vec<&'a Value> {
    r["events"]
        .as_array()
        .unwrap()
        .iter()
        .filter(|e| e["kind"] == kind && (service.is_empty() || e["service"] == service))
        .collect()
}

/// Restarts of `service` other than the watchdog's: a loaded machine may
/// starve a service past its liveness deadline, and the supervisor rightly
/// kills and restarts it ("frozen"); what a test counts is its own kills.
fn restarts(r: &Value, service: &str) -> u64 {
    let all = r["services"][service]["restarts"].as_u64().unwrap_or(0);
    all.saturating_sub(events(r, "frozen", service).len() as u64)
}

/// How far the robot's loop fell behind the wall clock over the run (1: not
/// at all): the periods it should have run over those it ran. A bound on a
/// span that mixes the robot's clock with the wall's stretches by as much.
fn behind(r: &Value) -> f64 {
    let tl = &r["torque_loop"];
    let expected = tl["cycles_expected"].as_f64().unwrap_or(1.0);
    let ran = expected - tl["cycles_short"].as_f64().unwrap_or(0.0);
    (expected / ran.max(1.0)).max(1.0)
}

/// No contact at all and no false detection in the run's report.
/// The report's contacts: none unintended.
fn assert_no_unintended_contact(r: &Value) {
    let unintended: Vec<&Value> = r["contacts"]
        .as_array()
        .unwrap()
        .iter()
        .filter(|c| c["intended"] == false)
        .collect();
    assert!(unintended.is_empty(), "unintended contacts: {unintended:?}");
}

fn assert_untouched(r: &Value) {
    assert!(
        r["contacts"].as_array().unwrap().is_empty(),
        "{}",
        r["contacts"]
    );
    assert_eq!(r["false_detections"], 0, "{}", r["events"]);
}

fn wait(s: f64) {
    std::thread::sleep(Duration::from_secs_f64(s));
}

#[test]
fn free_motion_cycles_without_false_detections() {
    let _g = SERIAL.lock().unwrap_or_else(|e| e.into_inner());
    // 3 waypoints take 9-10 s of the robot's time: 14 s leave room for a
    // loaded machine's slipped ticks
    let r = Cell::start("free", "free-motion", Some(14.0), &[]).finish();
    let tl = &r["torque_loop"];
    let cycles = tl["cycles"].as_u64().unwrap();
    // a loaded 2-core machine makes the robot's loop slip ticks (overruns)
    assert!(cycles >= 11200, "{cycles} cycles in 14 s");
    // deadlines are the benchmark's business; here: the loop holds
    assert!(
        tl["missed_deadlines"].as_u64().unwrap() * 100 <= cycles,
        "missed {}",
        tl["missed_deadlines"]
    );
    assert_eq!(r["false_detections"], 0);
    assert_eq!(r["detections"], 0);
    assert!(
        r["task"]["waypoints_reached"].as_u64().unwrap() >= 3,
        "waypoints {}",
        r["task"]["waypoints_reached"]
    );
    for s in ["sim", "dynamics", "control"] {
        assert_eq!(r["services"][s]["alive_at_end"], true, "{s}");
        assert_eq!(restarts(&r, s), 0, "{s}");
    }
}

#[test]
fn collisions_are_detected_within_the_bound_and_the_reaction_ends_them() {
    let _g = SERIAL.lock().unwrap_or_else(|e| e.into_inner());
    // the detection and reaction layer alone: with avoidance on, the arm
    // evades these reaches in most phases of its cycle (phri-lockstep --sweep)
    let r = Cell::start("coll", "collision", None, &["control.avoidance=false"]).finish();
    let contacts = r["contacts"].as_array().unwrap();
    // contacts that reached twice the threshold and lasted past the bound
    // after it: the bound is the residual's step response, and a graze
    // over before it (7 ms at 76 N, seen once under load) is a pulse the
    // first-order residual only partly sees
    let lasted_past_bound = |c: &&Value| {
        let f = |k: &str| c[k].as_f64().unwrap_or(f64::NAN);
        let dur_ms = (f("t_end_s") - f("t_start_s")) * 1e3;
        dur_ms >= f("reached_twice_threshold_after_ms") + f("bound_ms")
    };
    let strong: Vec<&Value> = contacts
        .iter()
        .filter(|c| c["intended"] == false && !c["reached_twice_threshold_after_ms"].is_null())
        .filter(lasted_past_bound)
        .collect();
    assert!(
        !strong.is_empty(),
        "the scenario produced no contact reaching twice the threshold: {contacts:?}"
    );
    for c in &strong {
        let after = c["detected_after_twice_threshold_ms"]
            .as_f64()
            .unwrap_or(f64::INFINITY);
        // the bound is the residual's response to a step of 2θ held; a
        // contact that does not hold it (a stuttering simulation on a
        // loaded machine) is judged against the exact observer's own
        // crossing (the model fed with the true τ_ext) plus the bound's
        // 2 ms of pipeline and one period
        let model = c["model_crossed_threshold_after_ms"]
            .as_f64()
            .unwrap_or(f64::NAN)
            - c["reached_twice_threshold_after_ms"]
                .as_f64()
                .unwrap_or(f64::NAN);
        let bound = c["bound_ms"].as_f64().unwrap();
        let allowed = if model.is_finite() {
            bound.max(model + 3.0)
        } else {
            bound
        };
        assert!(
            after <= allowed,
            "detected {after} ms after 2θ, bound {bound} (the exact observer's crossing + 3 ms: {model:.3} + 3): {c}"
        );
        // the reaction ends the contact while the person still reaches (1.5 s)
        let dur = c["t_end_s"].as_f64().unwrap() - c["t_start_s"].as_f64().unwrap();
        assert!(dur < 1.0, "contact lasted {dur} s: {c}");
    }
    assert!(!events(&r, "reaction", "control").is_empty());
    assert_eq!(r["false_detections"], 0, "{}", r["events"]);
    // ISO/TS 15066: every contact judged against its region's limit; the
    // thrown hand's impacts against the hand's transient limit
    let iso = &r["iso_ts_15066"];
    assert_judged(&r);
    let hand: Vec<&Value> = iso["contacts"]
        .as_array()
        .unwrap()
        .iter()
        .filter(|c| c["region"] == "hand_and_fingers" && c["kind"] == "transient")
        .collect();
    assert!(!hand.is_empty(), "{iso}");
    for c in hand {
        assert_eq!(c["limit_n"], 280.0, "{c}");
    }
}

/// The report's `iso_ts_15066` section lists every contact of `contacts`,
/// each with its region, the limit of its kind and the margin to it.
fn assert_judged(r: &Value) {
    let iso = &r["iso_ts_15066"];
    let judged = iso["contacts"].as_array().unwrap();
    let contacts = r["contacts"].as_array().unwrap();
    assert_eq!(judged.len(), contacts.len(), "{iso}");
    let mut over = 0;
    for (j, c) in judged.iter().zip(contacts) {
        assert_eq!(j["part"], c["part"], "{j}");
        assert_eq!(j["peak_force_n"], c["peak_force_n"], "{j}");
        assert!(j["region"].as_str().is_some_and(|s| s != "unknown"), "{j}");
        let (limit, peak) = (
            j["limit_n"].as_f64().unwrap(),
            j["peak_force_n"].as_f64().unwrap(),
        );
        assert!(
            (j["margin_n"].as_f64().unwrap() - (limit - peak)).abs() < 1e-9,
            "{j}"
        );
        let transient = j["t_end_s"].as_f64().unwrap() - j["t_start_s"].as_f64().unwrap() <= 0.5;
        assert_eq!(
            j["kind"],
            if transient {
                "transient"
            } else {
                "quasi_static"
            },
            "{j}"
        );
        over += usize::from(j["within_limit"] == false);
    }
    assert_eq!(iso["over_limit"], over, "{iso}");
}

#[test]
fn a_stalled_supervisor_loses_no_contact_and_counts_what_it_lost() {
    let _g = SERIAL.lock().unwrap_or_else(|e| e.into_inner());
    // issue 10, reproduction 5: a supervisor stopped for 0.8 s overflows the
    // 256-deep sim/truth queue; contact episodes come on sim/contacts
    let cell = Cell::start("stall", "collision", None, &["control.avoidance=false"]);
    let sup = cell.child.id() as i32;
    cell.pid_of("control");
    // stopped 0.8 s of every 1.2 s: every contact of the scenario (the person
    // reaches for 1.5 s) overlaps a stop
    let t0 = Instant::now();
    while t0.elapsed() < Duration::from_secs(17) {
        // SAFETY: kill(2) on our own child, the supervisor.
        if unsafe { libc::kill(sup, libc::SIGSTOP) } != 0 {
            break;
        }
        wait(0.8);
        // SAFETY: as above.
        unsafe { libc::kill(sup, libc::SIGCONT) };
        wait(0.4);
    }
    let r = cell.finish();
    let lost = &r["evaluation"];
    eprintln!("evaluation: {lost}");
    assert!(
        lost["truth_samples_lost"].as_u64().unwrap() > 0,
        "the stops did not overflow sim/truth: the test tests nothing"
    );
    assert_eq!(lost["contact_events_lost"], 0);
    let contacts = r["contacts"].as_array().unwrap();
    let strong: Vec<&Value> = contacts
        .iter()
        .filter(|c| c["intended"] == false && c["peak_force_n"].as_f64() > Some(50.0))
        .collect();
    assert!(!strong.is_empty(), "the contacts vanished: {contacts:?}");
    for c in contacts {
        assert!(c["t_end_s"].as_f64() >= c["t_start_s"].as_f64(), "{c}");
        assert!(!c["link"].is_null(), "{c}");
    }
}

#[test]
fn killing_dynamics_means_protective_stop_restart_and_resume() {
    let _g = SERIAL.lock().unwrap_or_else(|e| e.into_inner());
    // one residual service ([control] standby = false): today's stop
    let cell = Cell::start(
        "kdyn",
        "free-motion",
        Some(10.0),
        &["control.standby=false"],
    );
    wait(5.0);
    cell.kill("dynamics", libc::SIGKILL);
    let r = cell.finish();
    assert_eq!(restarts(&r, "dynamics"), 1);
    assert_eq!(r["services"]["dynamics"]["alive_at_end"], true);
    let stop = events(&r, "protective_stop", "control");
    assert!(!stop.is_empty(), "no protective stop: {}", r["events"]);
    let t_stop = stop[0]["t_s"].as_f64().unwrap();
    assert!(events(&r, "restart", "dynamics")
        .iter()
        .any(|e| e["t_s"].as_f64().unwrap() >= t_stop - 0.5));
    assert!(
        events(&r, "resume", "control")
            .iter()
            .any(|e| e["t_s"].as_f64().unwrap() > t_stop),
        "no resume: {}",
        r["events"]
    );
    assert_eq!(r["false_detections"], 0);
    // the torque loop itself never stopped: the controller kept answering
    // (the arm waits braked only at the start, before the controller's first
    // command; a brake engaged later is more than 20 answers missed)
    assert!(events(&r, "brake", "sim").is_empty(), "{}", r["events"]);
}

#[test]
fn killing_either_residual_service_causes_no_protective_stop() {
    let _g = SERIAL.lock().unwrap_or_else(|e| e.into_inner());
    let cell = Cell::start("kdyn2", "free-motion", Some(11.0), &[]);
    wait(4.0);
    cell.kill("dynamics", libc::SIGKILL);
    wait(4.0);
    cell.kill("dynamics_standby", libc::SIGKILL);
    let r = cell.finish();
    eprintln!("dynamics: {}", r["dynamics"]);
    for s in ["dynamics", "dynamics_standby"] {
        assert_eq!(restarts(&r, s), 1, "{s}");
        assert_eq!(r["services"][s]["alive_at_end"], true, "{s}");
    }
    // the controller acted on the other residual meanwhile
    assert_eq!(r["protective_stops"], 0, "{}", r["events"]);
    assert!(events(&r, "protective_stop", "control").is_empty());
    assert!(events(&r, "brake", "sim").is_empty(), "{}", r["events"]);
    assert_eq!(r["false_detections"], 0);
    // the two observers agree: the same states, the same model
    let d = &r["dynamics"];
    // (the standby's residual wakes every 10 ms while the first answers:
    // one of its states in ten)
    assert!(d["residuals_compared"].as_u64().unwrap() > 500, "{d}");
    let disagreement = d["max_residual_disagreement_nm"].as_f64().unwrap();
    assert!(disagreement < 1.0, "{d}");
}

#[test]
fn killing_the_controller_brakes_then_resumes_without_a_jump() {
    let _g = SERIAL.lock().unwrap_or_else(|e| e.into_inner());
    // one controller ([control] standby = false): today's brake and resume
    let cell = Cell::start(
        "kctl",
        "free-motion",
        Some(9.0),
        &[
            "supervisor.restart_backoff_min_ms=300",
            "control.standby=false",
        ],
    );
    wait(5.0);
    cell.kill("control", libc::SIGKILL);
    let r = cell.finish();
    assert_eq!(restarts(&r, "control"), 1);
    assert!(
        !events(&r, "brake", "sim").is_empty(),
        "no brake: {}",
        r["events"]
    );
    let resync = &r["resyncs"][0];
    assert!(
        resync["max_joint_speed_rad_s"].as_f64().unwrap() < 0.3,
        "jump after restart: {resync}"
    );
    assert!(
        resync["max_joint_travel_rad"].as_f64().unwrap() < 0.05,
        "jump after restart: {resync}"
    );
    let t_restart = resync["t_s"].as_f64().unwrap();
    assert!(events(&r, "sync", "control")
        .iter()
        .any(|e| e["t_s"].as_f64().unwrap() >= t_restart - 0.01));
    assert_eq!(r["false_detections"], 0);
}

/// The report's takeovers (`control.takeovers`).
fn takeovers(r: &Value) -> &Vec<Value> {
    r["control"]["takeovers"].as_array().unwrap()
}

/// Takeover `k` of run `r` was seamless: the two controllers answered the
/// states both answered alike (the standby steps as the one in charge
/// would), and the takeover changed the torque no more than 2 Nm or, when
/// more, no more than the controller in charge itself changes it from one
/// period to the next in the same run. (Its joint reference rides SNS's
/// acceleration bounds at phases of the path: a reference acceleration
/// switching by 10 rad/s² between periods is 10-15 Nm at the shoulder, in
/// 0.7 % of free motion's periods; a takeover in such a period, 1 in 100-200
/// in a SIGSTOP stress, measured 2.3-4.3 Nm. A standby stepping from a stale
/// reference or from its sync mode would be 50 Nm and more off.)
fn assert_seamless(r: &Value, k: &Value) {
    let c = &r["control"];
    assert!(c["both_answered"].as_u64().unwrap() > 0, "{c}");
    assert!(c["max_answer_diff_nm"].as_f64().unwrap() <= 0.01, "{c}");
    let own = c["max_period_step_nm"].as_f64().unwrap_or(0.0);
    let diff = k["command_diff_nm"].as_f64().unwrap();
    assert!(
        diff < 2.0 || diff <= own,
        "{k}: the controller's own steps {own} Nm"
    );
}

/// The restart of `service` (its first), the report's time \[s\].
fn restarted_at(r: &Value, service: &str) -> f64 {
    let e = events(r, "restart", service);
    assert!(!e.is_empty(), "{service} not restarted: {}", r["events"]);
    e[0]["t_s"].as_f64().unwrap()
}

/// The robot kept its brakes off from `from_s` on for `span_s` \[s\] and
/// applied a command of either controller in every period but at most
/// [`MISSED_BY_THE_MACHINE`] (the report's missed deadlines come at 10 Hz).
fn nothing_missed(r: &Value, from_s: f64, span_s: f64) {
    let within = |e: &&Value| {
        let t = e["t_s"].as_f64().unwrap();
        t >= from_s - 0.1 && t <= from_s + span_s
    };
    let brakes: Vec<&Value> = events(r, "brake", "sim")
        .into_iter()
        .filter(within)
        .collect();
    assert!(brakes.is_empty(), "brake at {from_s:.2} s: {brakes:?}");
    let misses: Vec<&Value> = events(r, "missed_deadlines", "sim")
        .into_iter()
        .filter(within)
        .collect();
    // "N commands missed since the last statistics"
    let missed: u64 = misses
        .iter()
        .map(|e| {
            let detail = e["detail"].as_str().unwrap_or("");
            detail
                .split_whitespace()
                .next()
                .and_then(|n| n.parse().ok())
                .unwrap_or(u64::MAX / 4)
        })
        .sum();
    assert!(
        missed <= MISSED_BY_THE_MACHINE,
        "{missed} commands missed from {from_s:.2} s: {misses:?}; inputs the controllers refused: {}",
        r["inputs"]
    );
}

/// Commands a loaded 2-vCPU virtual machine may make the robot miss in a
/// second or so by itself (both controllers starved in the same period),
/// takeover or not; a takeover that failed misses every period until the
/// supervisor restarts the controller (50 ms back-off at least), then brakes.
const MISSED_BY_THE_MACHINE: u64 = 2;

#[test]
fn killing_either_controller_costs_the_torque_loop_nothing() {
    let _g = SERIAL.lock().unwrap_or_else(|e| e.into_inner());
    let cell = Cell::start("kstandby", "free-motion", Some(11.0), &[]);
    wait(1.0);
    let charge = support::Charge::watch(&cell.prefix);
    // the controller in charge dies, twice: the other answers the same period
    wait(3.0);
    let first = charge.now();
    cell.kill(first, libc::SIGKILL);
    wait(4.0);
    let second = charge.now();
    cell.kill(second, libc::SIGKILL);
    // the watcher's node goes before the check that the run left nothing
    drop(charge);
    let r = cell.finish();
    eprintln!("killed {first}, then {second}; control: {}", r["control"]);
    assert_eq!(r["control"]["standby"], true);
    // a kill is noticed by the supervisor after its back-off (50 ms) at most
    let t = takeovers(&r);
    for killed in [first, second] {
        let to = match killed {
            "control" => "robot/command/standby",
            _ => "robot/command",
        };
        let back = restarted_at(&r, killed);
        // the takeover comes the period after the kill; the restart after
        // the supervisor saw the death (at once, or late on a loaded
        // machine) and its back-off; the kills are 4 s apart
        let took = t.iter().find(|k| {
            let at = k["t_s"].as_f64().unwrap();
            k["to"] == to && at > back - 1.5 && at <= back
        });
        let took = took.unwrap_or_else(|| panic!("no takeover for {killed}: {}", r["control"]));
        // one period's change of a computed torque, not a jump
        assert_seamless(&r, took);
        nothing_missed(
            &r,
            took["t_s"].as_f64().unwrap() - 0.1,
            back - took["t_s"].as_f64().unwrap() + 1.0,
        );
    }
    for k in t {
        assert_seamless(&r, k);
    }
    assert_eq!(restarts(&r, "control") + restarts(&r, "control_standby"), 2);
    for s in ["control", "control_standby"] {
        assert_eq!(r["services"][s]["alive_at_end"], true, "{s}");
    }
    assert!(events(&r, "brake", "sim").is_empty(), "{}", r["events"]);
    assert_eq!(r["protective_stops"], 0);
    assert_eq!(r["false_detections"], 0);
}

#[test]
fn a_controller_stopped_half_a_second_is_replaced_at_once_and_rejoins_as_the_standby() {
    let _g = SERIAL.lock().unwrap_or_else(|e| e.into_inner());
    let cell = Cell::start("stopctl", "free-motion", Some(10.5), &[]);
    wait(1.0);
    let charge = support::Charge::watch(&cell.prefix);
    wait(3.0);
    // the controller in charge stops (SIGSTOP) for 0.5 s, then the one in
    // charge 3 s later for 0.3 s: the other commands meanwhile; the first
    // woke as the standby, and commands again only once re-synced
    let mut stopped = Vec::new();
    for (hold, rest) in [(0.5, 3.0), (0.3, 1.0)] {
        let who = charge.now();
        let pid = cell.kill(who, libc::SIGSTOP);
        wait(0.2);
        let meanwhile = charge.now();
        wait(hold - 0.2);
        // SAFETY: kill(2) on the controller stopped above.
        assert_eq!(unsafe { libc::kill(pid, libc::SIGCONT) }, 0);
        assert_ne!(meanwhile, who, "the other controller took over");
        stopped.push(who);
        wait(rest);
    }
    drop(charge);
    let r = cell.finish();
    eprintln!("stopped {stopped:?}; control: {}", r["control"]);
    // (not listed: a takeover from the brakes, which is a start; the
    // robot brakes after more than 20 periods without an answer)
    assert!(
        takeovers(&r).len() >= 2,
        "{}; missed: {}; inputs the controllers refused: {}",
        r["control"],
        r["torque_loop"]["missed_deadlines"],
        r["inputs"]
    );
    for k in takeovers(&r) {
        assert_seamless(&r, k);
        nothing_missed(&r, k["t_s"].as_f64().unwrap() - 0.1, 0.8);
    }
    for s in ["control", "control_standby"] {
        assert_eq!(r["services"][s]["restarts"], 0, "{s}: not judged frozen");
    }
    assert!(events(&r, "brake", "sim").is_empty(), "{}", r["events"]);
    assert_eq!(r["protective_stops"], 0);
}

#[test]
fn both_controllers_killed_at_once_brake_and_resume_as_one_did_alone() {
    let _g = SERIAL.lock().unwrap_or_else(|e| e.into_inner());
    let cell = Cell::start(
        "kboth",
        "free-motion",
        Some(9.0),
        &["supervisor.restart_backoff_min_ms=300"],
    );
    wait(5.0);
    cell.kill("control", libc::SIGKILL);
    cell.kill("control_standby", libc::SIGKILL);
    let r = cell.finish();
    eprintln!("control: {}", r["control"]);
    assert!(
        !events(&r, "brake", "sim").is_empty(),
        "no brake: {}",
        r["events"]
    );
    for s in ["control", "control_standby"] {
        assert_eq!(restarts(&r, s), 1, "{s}");
    }
    let resync = &r["resyncs"][0];
    assert!(
        resync["max_joint_speed_rad_s"].as_f64().unwrap() < 0.3,
        "{resync}"
    );
    assert!(
        resync["max_joint_travel_rad"].as_f64().unwrap() < 0.05,
        "{resync}"
    );
    let t_restart = resync["t_s"].as_f64().unwrap();
    assert!(events(&r, "sync", "control")
        .iter()
        .any(|e| e["t_s"].as_f64().unwrap() >= t_restart - 0.01));
    // nobody took over while both were dead: a start from the brakes is none
    let braked = events(&r, "brake", "sim")[0]["t_s"].as_f64().unwrap();
    for k in takeovers(&r) {
        let at = k["t_s"].as_f64().unwrap();
        assert!(
            !(braked..t_restart + 0.2).contains(&at),
            "a takeover while braked: {}",
            r["control"]
        );
        // the two kills are two syscalls: the standby may answer a period
        // or two between them (a takeover just before the brake: 20 missing
        // commands, the event reported at 10 Hz), never longer
        assert!(
            at < braked - 0.5 || braked - at < 0.25,
            "the standby commanded between the kills: {}",
            r["control"]
        );
    }
    assert_eq!(r["false_detections"], 0);
}

#[test]
fn sigint_stops_everything_and_leaves_nothing_behind() {
    let _g = SERIAL.lock().unwrap_or_else(|e| e.into_inner());
    let cell = Cell::start("sigint", "free-motion", None, &[]);
    wait(3.0);
    let ctl = cell.pid_of("control");
    // a second commander is refused: the command channel has one publisher
    let out = Command::new(bin("phri-control"))
        .arg("--config")
        .arg(cell.run_dir.join("config.toml"))
        .arg("--prefix")
        .arg(&cell.prefix)
        .output()
        .unwrap();
    assert!(!out.status.success());
    let err = String::from_utf8_lossy(&out.stderr);
    assert!(
        err.contains("robot/command") && err.lines().count() == 1,
        "{err}"
    );
    let r = cell.end_now();
    assert_eq!(restarts(&r, "control"), 0);
    // SAFETY: probing a pid with signal 0.
    assert_ne!(unsafe { libc::kill(ctl, 0) }, 0, "controller still running");
}

#[test]
fn coexistence_avoids_the_person_without_deadline_misses() {
    let _g = SERIAL.lock().unwrap_or_else(|e| e.into_inner());
    // the person's script from 5 s (OFFSET): walking up, then the whole
    // visit, the hand held in the path until it steps back at 24 s (19 s)
    let r = Cell::start("coex", "coexistence", Some(19.0), &[OFFSET]).finish();
    assert_no_unintended_contact(&r);
    assert!(r["min_distance_m"].as_f64().unwrap() > 0.0);
    let p = &r["perception"];
    assert!(
        p["frames"].as_u64().unwrap() >= 19 * 25,
        "frames {}",
        p["frames"]
    );
    assert!(
        p["dropped_frames"].as_u64().unwrap() * 20 <= p["frames"].as_u64().unwrap(),
        "dropped {}",
        p["dropped_frames"]
    );
    let cycles = r["torque_loop"]["cycles"].as_u64().unwrap();
    assert!(r["torque_loop"]["missed_deadlines"].as_u64().unwrap() * 100 <= cycles);
    assert_eq!(r["false_detections"], 0);
    // the person blocks the path from t = 3 s: the task moved before, and waits, not collides
    assert!(r["task"]["waypoints_reached"].as_u64().unwrap() >= 1);
}

#[test]
fn a_person_walking_in_finds_the_arm_stopped_and_the_report_says_so() {
    let _g = SERIAL.lock().unwrap_or_else(|e| e.into_inner());
    // ISO/TS 15066 speed and separation monitoring: the person walks at
    // 1.6 m/s from 2 s and stands 7 cm in front of P2 from 3.45 s
    let r = Cell::start("walkin", "walk-in", Some(8.0), &["ssm.enabled=true"]).finish();
    assert_untouched(&r);
    let iso = &r["iso_ts_15066"];
    assert_eq!(iso["ssm_enabled"], true, "{iso}");
    // the monitor bounded the arm while the person came and stood there ...
    assert!(iso["ssm_limited_s"].as_f64().unwrap() > 1.0, "{iso}");
    // ... and never let it move on toward the person inside S_p
    assert_eq!(iso["ssm_violations"], 0, "{iso}");
    assert_eq!(iso["ssm_violation_times_s"].as_array().unwrap().len(), 0);
    assert_eq!(r["protective_stops"], 0);
    let cycles = r["torque_loop"]["cycles"].as_u64().unwrap();
    assert!(r["torque_loop"]["missed_deadlines"].as_u64().unwrap() * 100 <= cycles);
}

#[test]
fn killing_ingestion_and_a_worker_stops_safely_near_the_person_and_resumes() {
    let _g = SERIAL.lock().unwrap_or_else(|e| e.into_inner());
    let cell = Cell::start(
        "kperc",
        "coexistence",
        Some(15.0),
        &["supervisor.restart_backoff_min_ms=400", OFFSET],
    );
    // the person's hand is in the end effector's path from t = 5 s (the
    // robot's clock; the script's 10 s)
    let clock = support::RobotClock::watch(&cell.prefix);
    clock.wait_until(8.0);
    drop(clock);
    cell.kill("perception", libc::SIGKILL);
    cell.kill("repulsion1", libc::SIGKILL);
    let r = cell.finish();
    assert_eq!(restarts(&r, "perception"), 1);
    assert_eq!(restarts(&r, "repulsion1"), 1);
    assert_eq!(r["services"]["perception"]["alive_at_end"], true);
    let kill_t = events(&r, "exit", "perception")[0]["t_s"].as_f64().unwrap();
    // blind with the person near: a protective stop, then the task resumes.
    // The exit's time is when the supervisor reaped the process, the stop's
    // when the controller found perception stale 100 ms after the kill: a
    // loaded machine's supervisor may reap up to a second late
    let stop = events(&r, "protective_stop", "control");
    assert!(
        stop.iter()
            .any(|e| e["t_s"].as_f64().unwrap() >= kill_t - 1.0
                && e["detail"]
                    .as_str()
                    .unwrap_or("")
                    .contains("perception is stale")),
        "no protective stop on stale perception after the kill: {}",
        r["events"]
    );
    assert!(
        events(&r, "resume", "control")
            .iter()
            .any(|e| e["t_s"].as_f64().unwrap() > kill_t),
        "no resume: {}",
        r["events"]
    );
    // the torque loop did not notice: no brake, no contact, no false detection
    assert!(events(&r, "brake", "sim").is_empty());
    let cycles = r["torque_loop"]["cycles"].as_u64().unwrap();
    assert!(r["torque_loop"]["missed_deadlines"].as_u64().unwrap() * 100 <= cycles);
    assert_untouched(&r);
}

/// Two cameras, each its own camera and ingestion process: killing one
/// camera, then the other's ingestion, while the person is near costs no
/// protective stop (the other camera's distances are still lower bounds,
/// and the task goes on at their pace); each is restarted. Killing both
/// cameras at once is today's stale-perception stop.
#[test]
fn one_camera_killed_leaves_the_other_s_distances_and_both_killed_stop_safely() {
    let _g = SERIAL.lock().unwrap_or_else(|e| e.into_inner());
    // under the control-barrier filter: the paper's law halts the arm once
    // SNS scales its task to nothing, repulsion included, and the camera
    // left alone can put it in a shadow (distance 0-4 cm) where the
    // stepping-in hand is not told apart; the hand then walks into the
    // halted arm (the lock-step cell's `camera` outage at offset 1 s: 1.7
    // cm; here once, 128 N, 50 ms after camera-1's restart, on a fresh
    // clone's loaded machine). The filter's slack moves it away instead
    // (6.9-7.0 cm there; here 4.6-7.6 cm in 6 runs, 3 beside CPU hogs).
    // What this test is about, the cameras' processes dying and coming
    // back, is the same under either law
    let cell = Cell::start_with(
        "deploy/two-cameras.toml",
        "kcam2",
        "coexistence",
        Some(17.0),
        &[
            "supervisor.restart_backoff_min_ms=400",
            "avoidance.law=cbf",
            OFFSET,
        ],
    );
    // the person's hand is in the end effector's path from t = 5 s (the
    // robot's clock; the script's 10 s)
    let clock = support::RobotClock::watch(&cell.prefix);
    clock.wait_until(6.0);
    drop(clock);
    cell.kill("camera-1", libc::SIGKILL);
    wait(3.0);
    cell.kill("perception", libc::SIGKILL);
    wait(3.0);
    cell.kill("camera", libc::SIGKILL);
    cell.kill("camera-1", libc::SIGKILL);
    let r = cell.finish();
    assert_eq!(restarts(&r, "camera-1"), 2, "{}", r["services"]);
    assert_eq!(restarts(&r, "perception"), 1);
    assert_eq!(restarts(&r, "camera"), 1);
    for s in ["camera", "camera-1", "perception", "perception-1"] {
        assert_eq!(r["services"][s]["alive_at_end"], true, "{s}");
    }
    let exits = |s: &str| -> Vec<f64> {
        events(&r, "exit", s)
            .iter()
            .map(|e| e["t_s"].as_f64().unwrap())
            .collect()
    };
    // both killed: the first of their exits the supervisor reaped. It reaps
    // an exit up to a round after the kill, and the stale-perception stop
    // may come between the two (once here, 55 ms before the reaping)
    let both_t = exits("camera")[0].min(*exits("camera-1").last().unwrap());
    let one_t = exits("camera-1")[0];
    let ingest_t = exits("perception")[0];
    assert!(one_t < ingest_t && ingest_t < both_t, "{}", r["events"]);
    let stops: Vec<f64> = events(&r, "protective_stop", "control")
        .iter()
        .map(|e| e["t_s"].as_f64().unwrap())
        .collect();
    // one camera down at a time: no stop (the last of them 3 s before).
    // Before the first kill both cameras run: a stop there is start-up's
    // (once on a fresh clone, at 1.5 s: the first frames late with the
    // person near), not this test's
    assert!(
        stops.iter().all(|&t| t < one_t || t >= both_t - 0.3),
        "a protective stop with one camera left: {stops:?}, {}",
        r["events"]
    );
    // both down: the stale-perception stop, then the task resumes
    assert!(
        !stops.is_empty(),
        "no stop with both cameras down: {}",
        r["events"]
    );
    assert!(r["protective_stop_causes"]["stale_perception"].as_u64() >= Some(1));
    // each camera answered the fusion while the other was down: alone for
    // the other's 0.4 s back-off and start-up, it won every decision of
    // about 0.5 s of a 17 s run of two cameras' answers, over 1 % of them
    // (besides, each wins where its bound is the larger: the mirror 4.9-12
    // % under the barrier filter, more under the paper's law)
    let cams = r["perception"]["cameras"].as_array().unwrap();
    assert_eq!(cams.len(), 2);
    for c in cams {
        assert!(c["frames"].as_u64().unwrap() > 300, "{c}");
        assert!(c["fused_share"].as_f64().unwrap() > 0.01, "{c}");
    }
    assert!(events(&r, "brake", "sim").is_empty());
    // the kills cost the torque loop no deadline: none missed from the
    // first kill on (0.3 s before camera-1's first exit: the supervisor
    // reaps an exit up to a round after the kill, and the misses come in
    // the robot's 10 Hz statistics). Start-up, with every service opening
    // its channels at once, is not what this test is about, as for the
    // stops above; its misses stay within 1 % (once on a fresh clone: 14
    // in a row 0.2 s after the ROS 2 bridge came up, the robot on time and
    // both controllers silent)
    let late: Vec<&Value> = events(&r, "missed_deadlines", "sim")
        .into_iter()
        .filter(|e| e["t_s"].as_f64().unwrap() > one_t - 0.3)
        .collect();
    assert!(
        late.is_empty(),
        "missed from the first kill on: {late:?}; inputs the controllers refused: {}",
        r["inputs"]
    );
    let cycles = r["torque_loop"]["cycles"].as_u64().unwrap();
    assert!(r["torque_loop"]["missed_deadlines"].as_u64().unwrap() * 100 <= cycles);
    assert_untouched(&r);
}

/// `phri-fault camera corrupt|delay`: bad and late frames are refused by
/// ingestion (which must survive them), the controller stops while the person
/// is near and it is blind, then resumes; the torque loop never notices.
#[test]
fn corrupt_and_late_depth_frames_stop_safely_and_cost_no_deadline() {
    let _g = SERIAL.lock().unwrap_or_else(|e| e.into_inner());
    // the last fault's stop at about 14.5 s resumes about 2 s later: 21 s
    // leave a loaded machine's late fault command its margin
    let cell = Cell::start("dfault", "coexistence", Some(21.0), &[OFFSET]);
    let fault = |args: &[&str]| {
        let out = Command::new(bin("phri-fault"))
            .arg("--run-dir")
            .arg(&cell.run_dir)
            .arg("camera")
            .args(args)
            .output()
            .unwrap();
        assert!(
            out.status.success(),
            "phri-fault {args:?}: {}",
            String::from_utf8_lossy(&out.stderr)
        );
    };
    // the person's hand is in the end effector's path from t = 6 s (the
    // robot's clock; the script's 11 s), each fault 3 s after the last on
    // that clock: a stop and its resume take about 2 s however far the
    // machine's load puts the robot behind the wall clock
    let clock = support::RobotClock::watch(&cell.prefix);
    clock.wait_until(7.5);
    fault(&["corrupt", "size", "--frames", "30"]);
    clock.wait_until(10.5);
    fault(&["corrupt", "stale", "--frames", "30"]);
    clock.wait_until(13.5);
    // late beyond the controller's 100 ms, yet frequent enough not to look frozen
    fault(&["delay", "150", "--for", "1.5"]);
    drop(clock);
    let r = cell.finish();
    // ingestion refused the frames and lived on
    for s in ["camera", "perception", "repulsion0"] {
        assert_eq!(restarts(&r, s), 0, "{s}: {}", r["events"]);
    }
    let stops: Vec<f64> = events(&r, "protective_stop", "control")
        .iter()
        .map(|e| e["t_s"].as_f64().unwrap())
        .collect();
    let resumes = events(&r, "resume", "control").len();
    assert!(
        stops.len() >= 3,
        "a stop per fault expected: {}",
        r["events"]
    );
    assert!(resumes >= 3, "a resume per fault expected: {}", r["events"]);
    assert!(events(&r, "brake", "sim").is_empty());
    assert_eq!(
        r["torque_loop"]["missed_deadlines"], 0,
        "{}",
        r["torque_loop"]
    );
    assert_untouched(&r);
}

/// A restarted simulator continues the scenario's clock: the world does not
/// rewind when the robot adapter crashes (the person is still at the robot).
#[test]
fn a_restarted_simulator_continues_the_scenario() {
    let _g = SERIAL.lock().unwrap_or_else(|e| e.into_inner());
    let cell = Cell::start("simkill", "coexistence", Some(11.0), &[OFFSET]);
    // the person's hand is in the end effector's path from t = 6 s (the
    // robot's clock; the script's 11 s)
    let clock = support::RobotClock::watch(&cell.prefix);
    clock.wait_until(7.5);
    drop(clock);
    cell.kill("sim", libc::SIGKILL);
    wait(1.5);
    let out = Command::new(bin("phri-monitor"))
        .args([
            "echo",
            "sim/truth",
            "--prefix",
            &cell.prefix,
            "--json",
            "--count",
            "1",
        ])
        .output()
        .unwrap();
    let text = String::from_utf8_lossy(&out.stdout);
    let line = text.lines().last().unwrap_or("");
    let v: Value = serde_json::from_str(line).unwrap_or(Value::Null);
    let d = v["min_distance"]
        .as_f64()
        .or_else(|| v["msg"]["min_distance"].as_f64())
        .unwrap_or_else(|| panic!("no min_distance in {text:?}"));
    // a script started over would put the person back where the run began:
    // 1 m in front of the base and 1.4 m to its side
    assert!(
        d < 0.5,
        "after the restart the person is {d} m away: the scenario rewound"
    );
    let r = cell.finish();
    assert_eq!(restarts(&r, "sim"), 1);
    assert!(
        r["contacts"].as_array().unwrap().is_empty(),
        "{}",
        r["contacts"]
    );
    // and the arm stood where it was (saved every 10 ms; the scenario's
    // initial configuration is far from where the arm is at 7.5 s)
    let restarts = r["sim_restarts"].as_array().expect("sim_restarts");
    assert_eq!(restarts.len(), 1, "{restarts:?}");
    let jump = restarts[0]["arm_jump_rad"].as_f64().unwrap();
    eprintln!("the restarted simulator's arm moved {jump:.4} rad");
    assert!(jump < 0.03, "the arm jumped {jump} rad at the restart");
}

fn alive(pid: i32) -> bool {
    // SAFETY: probing a pid with signal 0.
    let exists = unsafe { libc::kill(pid, 0) } == 0;
    exists
        && std::fs::read_to_string(format!("/proc/{pid}/stat")).is_ok_and(|s| !s.contains(") Z "))
}

#[test]
fn a_supervisor_that_dies_leaves_the_cell_running_and_a_new_one_takes_it_over() {
    let _g = SERIAL.lock().unwrap_or_else(|e| e.into_inner());
    let mut cell = Cell::start("takeover", "free-motion", None, &[]);
    wait(3.0);
    let pids: Vec<(&str, i32)> = ["sim", "dynamics", "control"]
        .iter()
        .map(|s| (*s, cell.pid_of(s)))
        .collect();
    // the supervisor dies without a word
    // SAFETY: signal to our own child.
    unsafe { libc::kill(cell.child.id() as i32, libc::SIGKILL) };
    cell.child.wait().unwrap();
    wait(1.0);
    for (s, pid) in &pids {
        assert!(alive(*pid), "{s} died with the supervisor");
    }
    // a new supervisor for the same cell adopts the services
    let report = cell.run_dir.join("report2.json");
    let out = Command::new(env!("CARGO_BIN_EXE_phri-supervisor"))
        .current_dir(repo())
        .arg("--config")
        .arg(repo().join("deploy/phri.toml"))
        .arg("--scenario")
        .arg("free-motion")
        .arg("--prefix")
        .arg(&cell.prefix)
        .arg("--run-dir")
        .arg(&cell.run_dir)
        .arg("--duration")
        .arg("4")
        .arg("--report")
        .arg(&report)
        .output()
        .unwrap();
    let err = String::from_utf8_lossy(&out.stderr);
    assert!(out.status.success(), "{err}");
    for (s, pid) in &pids {
        assert!(
            err.contains(&format!("adopted {s} (pid {pid})")),
            "{s} not adopted: {err}"
        );
        assert!(!alive(*pid), "{s} still running after the shutdown");
    }
    let r: Value = serde_json::from_str(&std::fs::read_to_string(&report).unwrap()).unwrap();
    assert!(!events(&r, "takeover", "supervisor").is_empty());
    for s in ["sim", "dynamics", "control"] {
        assert_eq!(restarts(&r, s), 0, "{s}");
        assert_eq!(r["services"][s]["alive_at_end"], true, "{s}");
    }
    assert!(r["torque_loop"]["cycles"].as_u64().unwrap() > 3000);
    assert_eq!(r["false_detections"], 0);
    assert_nothing_left(&cell.prefix);
}

/// CLOCK_MONOTONIC [ns], the cell's clock.
fn mono_ns() -> u64 {
    phri_runtime::now_ns()
}

/// The cell's start [ns, CLOCK_MONOTONIC], as the supervisor gave it to
/// `pid` (the report's times count from it).
fn cell_start_of(pid: i32) -> u64 {
    let env = std::fs::read(format!("/proc/{pid}/environ")).unwrap();
    env.split(|&b| b == 0)
        .filter_map(|kv| std::str::from_utf8(kv).ok())
        .find_map(|kv| kv.strip_prefix(&format!("{}=", phri_runtime::service::CELL_START_ENV)))
        .and_then(|v| v.parse().ok())
        .unwrap_or_else(|| panic!("no cell start in the environment of {pid}"))
}

/// Liveness by iceoryx2's deadlines: each watched service beats on
/// `liveness/<name>` (every quarter of its deadline), the supervisor waits
/// on all of them in one WaitSet. Stopped (SIGSTOP: silent, not dead), a
/// service is noticed once its deadline has passed and within one beat of
/// it; killed (SIGKILL), before that (its parent reaps it). Each is then
/// restarted.
#[test]
fn every_service_silent_past_its_deadline_or_killed_is_noticed_within_one_beat() {
    let _g = SERIAL.lock().unwrap_or_else(|e| e.into_inner());
    // the watched services of deploy/phri.toml and their deadlines
    // (heartbeat_timeout_ms, else the supervisor's)
    let loaded =
        phri_config::Loaded::load(&repo().join("deploy/phri.toml"), Some("free-motion"), &[])
            .unwrap();
    let c = &loaded.config;
    let watched: Vec<(&str, u64)> = [
        "sim",
        "dynamics",
        "dynamics_standby",
        "camera",
        "perception",
        "control",
        "control_standby",
        "mic",
    ]
    .into_iter()
    .map(|name| {
        let spec = &c.services[name];
        assert!(spec.heartbeat.is_some(), "{name} is not watched");
        let ms = spec
            .heartbeat_timeout_ms
            .unwrap_or(c.supervisor.heartbeat_timeout_ms);
        (name, ms)
    })
    .collect();
    let cell = Cell::start("liveness", "free-motion", Some(40.0), &[]);
    wait(3.0); // past the start-up grace (2 s)
    let t0 = cell_start_of(cell.pid_of("sim"));
    let restarted = |service: &str, old: i32| {
        let until = Instant::now() + Duration::from_secs(5);
        while cell.pid_of(service) == old {
            assert!(Instant::now() < until, "{service} not restarted");
            wait(0.02);
        }
        // its dependants judge it afresh once it is heard again
        wait(0.8);
    };
    let mut faults = Vec::new();
    for (service, deadline_ms) in watched {
        let signal = |sig: i32| {
            let pid = cell.pid_of(service);
            let at = mono_ns();
            // SAFETY: kill(2) on a pid the supervisor reported as its child
            assert_eq!(unsafe { libc::kill(pid, sig) }, 0, "kill {service} ({pid})");
            (pid, at)
        };
        let (pid, stopped_ns) = signal(libc::SIGSTOP);
        restarted(service, pid);
        let (pid, killed_ns) = signal(libc::SIGKILL);
        restarted(service, pid);
        faults.push((service, deadline_ms, stopped_ns, killed_ns));
    }
    // the duration is a cap for a loaded machine: the script is done
    let r = cell.end_now();
    let at_ns = |e: &Value| t0 + (e["t_s"].as_f64().unwrap() * 1e9) as u64;
    // the supervisor's own stalls (it did not run) within [from, to] [ns]:
    // what it noticed then, it noticed that much late (under the whole
    // suite's load, once 3.2 s right after a kill)
    let stalls: Vec<(u64, u64)> = events(&r, "stall", "supervisor")
        .iter()
        .map(|e| {
            let ms: u64 = e["detail"]
                .as_str()
                .unwrap()
                .trim_end_matches(" ms")
                .parse()
                .unwrap();
            (at_ns(e), ms * 1_000_000)
        })
        .collect();
    let stalled_within = |from: u64, to: u64| -> u64 {
        stalls
            .iter()
            .filter(|&&(end, ns)| end + 1 > from && end.saturating_sub(ns) <= to)
            .map(|&(_, ns)| ns)
            .sum()
    };
    // a service beats from its own loop once its last beat is a quarter of
    // its deadline old: a loop slower than 1 kHz (the camera's and
    // perception's, one pass per frame) beats up to one pass later, so its
    // last beat before the stop may be a beat and a frame old
    let frame_ns = (1e9 / c.camera.rate_hz) as u64;
    for (service, deadline_ms, stopped_ns, killed_ns) in faults {
        let (deadline, beat) = (deadline_ms * 1_000_000, deadline_ms * 1_000_000 / 4);
        let frozen = events(&r, "frozen", service);
        let noticed = frozen
            .iter()
            .map(|e| at_ns(e))
            .find(|&t| t > stopped_ns && t < killed_ns)
            .unwrap_or_else(|| panic!("{service}: stop not noticed: {}", r["events"]));
        let silent = noticed - stopped_ns;
        eprintln!(
            "{service}: stopped, noticed after {:.1} ms (deadline {deadline_ms} ms)",
            silent as f64 * 1e-6
        );
        let late = stalled_within(stopped_ns, noticed);
        assert!(
            silent + beat + frame_ns >= deadline && silent <= deadline + beat + late,
            "{service}: noticed {silent} ns after it stopped, deadline {deadline} ns"
        );
        let exit = events(&r, "exit", service)
            .into_iter()
            .map(at_ns)
            .find(|&t| t > killed_ns)
            .unwrap_or_else(|| panic!("{service}: kill not noticed: {}", r["events"]));
        eprintln!(
            "{service}: killed, noticed after {:.1} ms",
            (exit - killed_ns) as f64 * 1e-6
        );
        // reaped by its parent at the next round, well before its deadline
        assert!(
            exit - killed_ns <= deadline + beat + stalled_within(killed_ns, exit),
            "{service}: death noticed {} ns late",
            exit - killed_ns
        );
    }
    assert_no_unintended_contact(&r);
}

#[test]
fn a_frozen_process_is_detected_by_its_heartbeat_killed_and_restarted() {
    let _g = SERIAL.lock().unwrap_or_else(|e| e.into_inner());
    // one residual service: its silence is a protective stop
    let cell = Cell::start(
        "frozen",
        "free-motion",
        Some(8.0),
        &["control.standby=false"],
    );
    wait(4.0);
    // SIGSTOP: the process does not exit, it only stops answering
    let pid = cell.kill("dynamics", libc::SIGSTOP);
    let r = cell.finish();
    let frozen = events(&r, "frozen", "dynamics");
    assert!(!frozen.is_empty(), "not detected: {}", r["events"]);
    assert_eq!(r["services"]["dynamics"]["restarts"], 1);
    assert_eq!(r["services"]["dynamics"]["alive_at_end"], true);
    assert!(!alive(pid), "the frozen process was left behind");
    // meanwhile the controller held a protective stop (stale residual) and resumed
    let t_frozen = frozen[0]["t_s"].as_f64().unwrap();
    assert!(events(&r, "protective_stop", "control")
        .iter()
        .any(|e| e["t_s"].as_f64().unwrap() <= t_frozen + 0.1));
    assert!(events(&r, "resume", "control")
        .iter()
        .any(|e| e["t_s"].as_f64().unwrap() > t_frozen));
    assert_eq!(r["false_detections"], 0);
}

#[test]
fn collaboration_with_real_processes_reaches_the_hand_and_touches_nothing_else() {
    let _g = SERIAL.lock().unwrap_or_else(|e| e.into_inner());
    // deploy/scenarios/collaboration.toml through the real services: the
    // camera's skeleton, phri-gesture's request, ingestion's mask and hand,
    // the controller's phases. 2 s past the scenario's 22: a cell whose
    // simulator starts late (3.5 s once here) still resumes within the run
    let r = Cell::start("collab", "collaboration", Some(24.0), &[]).finish();
    assert_no_unintended_contact(&r);
    let contacts = r["contacts"].as_array().unwrap();
    let hand: Vec<&Value> = contacts
        .iter()
        .filter(|c| c["part"] == "hand_right" && c["link"] == "lwr_link_7")
        .collect();
    assert!(
        !hand.is_empty(),
        "the robot never reached the hand: {contacts:?}"
    );
    for c in &hand {
        assert!(c["peak_force_n"].as_f64().unwrap() <= 70.0, "{c}");
    }
    // no collision reaction: the intended contacts are no collisions
    assert!(
        events(&r, "reaction", "control").is_empty(),
        "{}",
        r["events"]
    );
    let cycles = r["torque_loop"]["cycles"].as_u64().unwrap();
    assert!(r["torque_loop"]["missed_deadlines"].as_u64().unwrap() * 100 <= cycles);
    // the report's collaboration section
    let c = &r["collaboration"];
    eprintln!("collaboration: {c}");
    let req = &c["requests"][0];
    assert!(
        req["source"] == "gesture" && req["part"] == "right_hand" && req["accepted"] == true,
        "{c}"
    );
    // the wave's onset and the approach are on the robot's clock; the
    // camera and the recogniser keep the wall's, which a robot loop behind
    // (a loaded machine) makes the wave slower on: the bound by as much
    let w2s = c["wave_to_start_ms"].as_f64().expect("wave_to_start_ms");
    let behind = behind(&r);
    assert!(
        w2s <= 2000.0 * behind,
        "approach {w2s} ms after the wave began (the robot's loop {behind:.2} × behind the wall)"
    );
    let phases: Vec<&str> = c["phases"]
        .as_array()
        .unwrap()
        .iter()
        .filter_map(|p| p["phase"].as_str())
        .collect();
    for p in ["approach", "contact", "follow", "idle"] {
        assert!(phases.contains(&p), "{phases:?}");
    }
    assert_eq!(c["ended_by"], "wrist_push", "{c}");
    assert!(c["contacts_intended"].as_u64().unwrap() >= 2, "{c}");
    // F̂ against the simulator's true force of the hand (a regression guard
    // above the measured 7 % p50; BENCHMARKS.md has the figure)
    assert!(c["force_error"]["samples"].as_u64().unwrap() > 500, "{c}");
    assert!(c["force_error"]["p50"].as_f64().unwrap() <= 0.15, "{c}");
    assert!(c["peak_intended_force_n"].as_f64().unwrap() <= 70.0, "{c}");
    // ISO/TS 15066: the intended touches within the hand's quasi-static limit
    assert_judged(&r);
    for j in r["iso_ts_15066"]["contacts"].as_array().unwrap() {
        if j["intended"] == true && j["region"] == "hand_and_fingers" {
            assert!(j["peak_force_n"].as_f64().unwrap() <= 140.0, "{j}");
            assert_eq!(j["within_limit"], true, "{j}");
        }
    }
    // the wrist push (15.5-16.5 s of the scenario, the left hand's touch)
    // ended it, and the task resumed once the residual had been quiet for
    // `resume_quiet_s` (1 s). Times from the simulator's truth, not the
    // scenario's clock: the cell's start-up shifts the scenario in the report
    let pushed = contacts
        .iter()
        .filter(|x| x["part"] == "hand_left")
        .filter_map(|x| x["t_start_s"].as_f64())
        .reduce(f64::min)
        .unwrap_or_else(|| panic!("the left hand never touched the robot: {contacts:?}"));
    let ended = c["phases"]
        .as_array()
        .unwrap()
        .iter()
        .filter(|p| p["phase"] == "idle" && p["reason"] == "wrist_push")
        .filter_map(|p| p["t_s"].as_f64())
        .next_back()
        .expect("ended by the wrist push");
    assert!(
        (pushed..pushed + 2.0).contains(&ended),
        "the push began at {pushed} s, the collaboration ended at {ended} s: {c}"
    );
    let resumed: Vec<f64> = events(&r, "resume", "control")
        .iter()
        .filter_map(|e| e["t_s"].as_f64())
        .collect();
    eprintln!(
        "the push began at {pushed:.2} s, ended the collaboration at {ended:.2} s, \
         the task resumed at {resumed:?} s"
    );
    assert!(
        resumed
            .iter()
            .any(|t| (ended + 1.0..ended + 3.5).contains(t)),
        "ended at {ended} s, resumed at {resumed:?}; events but detections: {:?}",
        r["events"]
            .as_array()
            .unwrap()
            .iter()
            .filter(|e| e["kind"] != "detection")
            .collect::<Vec<_>>()
    );
}

#[test]
fn killing_ingestion_during_an_approach_ends_the_collaboration_safely() {
    let _g = SERIAL.lock().unwrap_or_else(|e| e.into_inner());
    // the robot approaches the waving hand from ~4.5 s; ingestion dies at ~6.5 s:
    // the robot must not keep approaching a hand it no longer sees
    let cell = Cell::start("collabkill", "collaboration", Some(11.0), &[]);
    cell.pid_of("perception");
    let clock = support::RobotClock::watch(&cell.prefix);
    clock.wait_until(6.5);
    drop(clock);
    cell.kill("perception", libc::SIGKILL);
    let r = cell.finish();
    let c = &r["collaboration"];
    eprintln!("collaboration: {c}");
    let phases = c["phases"].as_array().unwrap();
    let approach = phases
        .iter()
        .find(|p| p["phase"] == "approach")
        .expect("the approach had begun");
    let end = phases
        .iter()
        .find(|p| p["phase"] == "idle")
        .expect("the collaboration ended");
    assert_eq!(end["reason"], "stale", "{c}");
    assert!(end["t_s"].as_f64() > approach["t_s"].as_f64());
    assert!(
        !events(&r, "protective_stop", "control").is_empty(),
        "{}",
        r["events"]
    );
    assert_eq!(restarts(&r, "perception"), 1);
    assert_no_unintended_contact(&r);
}

#[test]
fn a_controller_frozen_in_contact_ends_the_collaboration_and_holds_while_the_hand_is_there() {
    let _g = SERIAL.lock().unwrap_or_else(|e| e.into_inner());
    // the robot touches the held-out right hand from ~8-11 s; the controller
    // is stopped in contact until the supervisor finds it frozen (liveness
    // deadline 200 ms), kills and restarts it. The hand then moves on (11-12 s)
    // to where the robot would have followed it: 9.5 cm from the stopped
    // arm's surface (measured with the tracker's bias and noise off), where
    // it rests until it is lowered at 15-15.5 s; the left one pushes the
    // wrist (15.5-16.5 s) and the person steps back from 16.5 s. A hand is
    // "at the robot" within 20 cm here, not the default 10: the tracker's
    // drifting bias (σ 3 cm per axis) would otherwise decide whether a hand
    // 9.5 cm away is near. The run lasts until the hold is surely released
    // (the hands away for release_s after 18 s), also on a loaded machine.
    // One controller: the standby would go on with the collaboration
    let cell = Cell::start(
        "ctlcontact",
        "collaboration",
        Some(24.0),
        &["control.standby=false", "collaboration.restart_clear_m=0.2"],
    );
    cell.pid_of("control");
    // contact from about 8 s of the robot's clock, which a loaded machine
    // puts behind the wall clock
    let deadline = Instant::now() + Duration::from_secs(30);
    while collab_phase(&cell).as_deref() != Some("contact") {
        assert!(Instant::now() < deadline, "no contact within 30 s");
        wait(0.1);
    }
    wait(0.5);
    let pid = cell.kill("control", libc::SIGSTOP);
    let deadline = Instant::now() + Duration::from_secs(3);
    while alive(pid) && Instant::now() < deadline {
        wait(0.05);
    }
    // SAFETY: kill(2) on the stopped controller (gone once killed).
    unsafe { libc::kill(pid, libc::SIGCONT) };
    let r = cell.finish();
    let c = &r["collaboration"];
    eprintln!("collaboration: {c}");
    eprintln!("events: {}", r["events"]);
    assert_eq!(r["services"]["control"]["restarts"], 1, "{}", r["events"]);
    let restart_t = events(&r, "restart", "control")[0]["t_s"].as_f64().unwrap();
    let end = c["phases"]
        .as_array()
        .unwrap()
        .iter()
        .find(|p| p["phase"] == "idle" && p["reason"] == "controller_restart")
        .unwrap_or_else(|| panic!("not ended by the restart: {c}"));
    assert!(end["t_s"].as_f64().unwrap() >= restart_t - 0.01);
    assert_eq!(c["ended_by"], "controller_restart");
    // the restarted controller held: a protective stop for the hand at the
    // robot, and no task before the hand was lowered (15 s)
    assert_eq!(r["protective_stop_causes"]["controller_restart"], 1);
    let resumed: Vec<f64> = events(&r, "resume", "control")
        .iter()
        .chain(events(&r, "sync", "control").iter())
        .filter_map(|e| e["t_s"].as_f64())
        .filter(|t| *t > restart_t)
        .collect();
    assert!(
        resumed.iter().all(|t| *t >= 15.0),
        "task motion at {resumed:?} s with the hand at the robot"
    );
    assert!(
        !resumed.is_empty(),
        "the task never resumed: {}",
        r["events"]
    );
    assert_no_unintended_contact(&r);
}

/// The collaboration phase of the cell as `phri-hri watch --once` prints it
/// ("approach", "contact", …), None while the controller is not up.
fn collab_phase(cell: &Cell) -> Option<String> {
    let out = Command::new(bin("phri-hri"))
        .args(["--prefix", &cell.prefix, "watch", "--once"])
        .output()
        .ok()?;
    let text = String::from_utf8_lossy(&out.stdout);
    let rest = text.lines().last()?.strip_prefix("phase ")?;
    Some(rest.split_whitespace().next()?.to_string())
}

#[test]
fn killing_gesture_mid_collaboration_is_fail_safe() {
    let _g = SERIAL.lock().unwrap_or_else(|e| e.into_inner());
    // the person waves 3-6 s, the robot approaches the hand from ~4.5 s;
    // phri-gesture dies 1.5 s into the approach (~6 s, the wave's end). The
    // collaboration runs on the tracked hand, not on the recogniser: the
    // supervisor restarts it, nothing unsafe happens, and the restarted
    // recogniser (which sees at most the wave's tail) asks nothing again
    let cell = Cell::start("gestkill", "collaboration", Some(13.0), &[]);
    cell.pid_of("gesture");
    // (the robot's clock, which a loaded machine puts behind the wall clock)
    let deadline = Instant::now() + Duration::from_secs(30);
    loop {
        if collab_phase(&cell).as_deref() == Some("approach") {
            break;
        }
        assert!(Instant::now() < deadline, "no approach within 30 s");
        wait(0.1);
    }
    wait(1.5);
    cell.kill("gesture", libc::SIGKILL);
    let r = cell.finish();
    let c = &r["collaboration"];
    eprintln!("collaboration: {c}");
    eprintln!("gesture: {}", r["services"]["gesture"]);
    assert_eq!(restarts(&r, "gesture"), 1, "{}", r["events"]);
    assert_eq!(r["services"]["gesture"]["alive_at_end"], true);
    let kill_t = events(&r, "exit", "gesture")
        .first()
        .unwrap_or_else(|| panic!("no exit of gesture: {}", r["events"]))["t_s"]
        .as_f64()
        .unwrap();
    let phases = c["phases"].as_array().unwrap();
    let approach_t = phases
        .iter()
        .find(|p| p["phase"] == "approach")
        .expect("the approach had begun")["t_s"]
        .as_f64()
        .unwrap();
    assert!(
        kill_t > approach_t,
        "killed at {kill_t} s, before the approach ({approach_t} s): the test tests nothing"
    );
    // nothing unsafe: no unintended contact, no collision reaction, no brake
    assert_no_unintended_contact(&r);
    let contacts = r["contacts"].as_array().unwrap();
    assert!(
        events(&r, "reaction", "control").is_empty(),
        "{}",
        r["events"]
    );
    assert!(events(&r, "brake", "sim").is_empty(), "{}", r["events"]);
    // the robot still reaches the hand, or the collaboration ends cleanly
    let reached = contacts.iter().any(|c| {
        c["part"] == "hand_right"
            && c["link"] == "lwr_link_7"
            && c["intended"] == true
            && c["t_start_s"].as_f64() > Some(approach_t)
    });
    // orderly ends (a collision or a force limit would have shown above)
    let clean = [
        "wrist_push",
        "end_request",
        "stop_request",
        "hand_lost",
        "stale",
    ];
    let ended = phases.iter().find(|p| {
        p["phase"] == "idle"
            && p["t_s"].as_f64() > Some(approach_t)
            && clean.iter().any(|r| p["reason"] == *r)
    });
    assert!(
        reached || ended.is_some(),
        "neither reached the hand nor ended: {contacts:?}, {c}"
    );
    eprintln!(
        "killed {:.2} s after the approach began; hand reached: {reached}; ended: {}",
        kill_t - approach_t,
        ended.map_or("no".to_string(), |p| p.to_string())
    );
    for h in contacts.iter().filter(|c| c["part"] == "hand_right") {
        assert!(h["peak_force_n"].as_f64().unwrap() <= 70.0, "{h}");
    }
    // one request, the wave's, accepted before the kill; none accepted after
    let gesture: Vec<&Value> = c["requests"]
        .as_array()
        .unwrap()
        .iter()
        .filter(|q| q["source"] == "gesture")
        .collect();
    let accepted: Vec<&&Value> = gesture.iter().filter(|q| q["accepted"] == true).collect();
    assert_eq!(accepted.len(), 1, "gesture requests: {gesture:?}");
    assert!(
        accepted[0]["t_s"].as_f64() < Some(kill_t) && accepted[0]["part"] == "right_hand",
        "{gesture:?}"
    );
    let cycles = r["torque_loop"]["cycles"].as_u64().unwrap();
    assert!(r["torque_loop"]["missed_deadlines"].as_u64().unwrap() * 100 <= cycles);
}

/// The voice requests of a report's collaboration section.
fn voice_requests(c: &Value) -> Vec<&Value> {
    c["requests"]
        .as_array()
        .unwrap()
        .iter()
        .filter(|q| q["source"] == "voice")
        .collect()
}

#[test]
fn voice_collaboration_is_started_and_ended_by_voice_and_refuses_the_rest() {
    let _g = SERIAL.lock().unwrap_or_else(|e| e.into_inner());
    // deploy/scenarios/voice-collaboration.toml through the real services:
    // phri-mic plays the person's recorded speech into audio/mic on the
    // simulator's clock, phri-voice decodes it (pocketsphinx) and gates it
    // on the camera's skeleton, the controller answers
    let r = Cell::start("voice", "voice-collaboration", None, &[]).finish();
    assert_no_unintended_contact(&r);
    // 0 in the measured runs (BENCHMARKS.md); a loaded test machine may miss a few
    let cycles = r["torque_loop"]["cycles"].as_u64().unwrap();
    assert!(
        r["torque_loop"]["missed_deadlines"].as_u64().unwrap() * 100 <= cycles,
        "{}",
        r["torque_loop"]
    );
    let c = &r["collaboration"];
    eprintln!("collaboration: {c}");
    let voice = voice_requests(c);
    let find = |kind: &str, part: &str| {
        voice
            .iter()
            .find(|q| q["kind"] == kind && q["part"] == part)
            .unwrap_or_else(|| panic!("no voice {kind} {part}: {c}"))
    };
    // said out of the camera's view (0.5 s): refused by the gate
    let untracked = find("follow", "right_hand");
    assert_eq!(untracked["accepted"], false, "{c}");
    assert_eq!(untracked["reason"], "hand_not_tracked", "{c}");
    // the words as decoded: the recogniser may drop the article (a loaded
    // machine cuts the audio into other chunks), never the command's words
    let text = untracked["text"].as_str().unwrap_or_default();
    assert!(
        text.starts_with("follow") && text.ends_with("right hand"),
        "{c}"
    );
    // "hand me the wrench" (5 s): not a command
    let not_command = find("none", "none");
    assert_eq!(not_command["accepted"], false);
    assert!(
        ["no_match", "low_score"].contains(&not_command["reason"].as_str().unwrap()),
        "{c}"
    );
    // "follow the left hand" (7.5 s) and "end collaboration" (14.5 s): accepted,
    // with the words, the score and the latency
    let follow = find("follow", "left_hand");
    let end = find("end", "none");
    // the events too: a refusal as not tracked after a stale perception
    // (a protective stop) is not the same as a hand the camera lost
    assert_eq!(follow["accepted"], true, "{c} events: {}", r["events"]);
    assert_ended_by_the_request_or_the_force_limit(c, end);
    // the utterance's end is on the robot's clock (the microphone plays on
    // the simulator's), its request on the wall's: the bound stretches as far
    // as the robot fell behind
    let behind = behind(&r);
    for q in [follow, end] {
        assert!(q["score"].as_f64().is_some(), "{q}");
        let ms = q["utterance_end_to_request_ms"].as_f64().expect("latency");
        assert!(
            ms > 0.0 && ms <= 1000.0 * behind,
            "{q} (the robot's loop {behind:.2} × behind the wall)"
        );
    }
    assert_eq!(follow["text"], "follow the left hand");
    assert_eq!(end["text"], "end collaboration");
    // the collaboration: started by voice, reached the left hand, ended by voice
    let phases = c["phases"].as_array().unwrap();
    let t = |p: &str, reason: &str| {
        phases
            .iter()
            .find(|x| x["phase"] == p && x["reason"] == reason)
            .unwrap_or_else(|| panic!("no {p} ({reason}): {c}"))["t_s"]
            .as_f64()
            .unwrap()
    };
    let approach = t("approach", "accepted");
    let contact = t("contact", "contact_made");
    let ended = match c["ended_by"] == "request" {
        true => t("idle", "end_request"),
        false => t("idle", "force_limit"),
    };
    assert!(approach < contact && contact < ended, "{c}");
    let hand: Vec<&Value> = r["contacts"]
        .as_array()
        .unwrap()
        .iter()
        // the end effector's link, or the wrist it sits on: the position
        // task leaves the orientation free, and this hand, still coming in
        // when the approach starts, meets the wider wrist first (the
        // lock-step cell: every touch on link 6; BENCHMARKS.md)
        .filter(|x| {
            x["part"] == "hand_left" && (x["link"] == "lwr_link_7" || x["link"] == "lwr_link_6")
        })
        .collect();
    assert!(!hand.is_empty(), "the robot never reached the left hand");
    assert!(
        hand.iter()
            .all(|h| h["t_start_s"].as_f64().unwrap() > approach),
        "the hand was touched before the request: {hand:?}"
    );
    // the collaboration's force limit (0.5 × 140 N) where F̂ is estimated,
    // on link 7; on the wrist F̂ sees the force late (known, BENCHMARKS.md):
    // there ISO/TS 15066's quasi-static hand limit itself
    for h in &hand {
        let limit = if h["link"] == "lwr_link_7" {
            70.0
        } else {
            140.0
        };
        assert!(h["peak_force_n"].as_f64().unwrap() <= limit, "{h}");
    }
    // the task resumes after "end collaboration"
    assert!(
        events(&r, "resume", "control")
            .iter()
            .any(|e| e["t_s"].as_f64().unwrap() > ended),
        "{}",
        r["events"]
    );
    // every utterance is listed with its verdict
    assert_eq!(c["utterances"].as_array().unwrap().len(), 4, "{c}");
}

#[test]
fn killing_the_voice_recogniser_mid_collaboration_costs_the_torque_loop_nothing() {
    let _g = SERIAL.lock().unwrap_or_else(|e| e.into_inner());
    // phri-voice dies at ~12 s, in contact with the left hand; the supervisor
    // restarts it, the torque loop misses nothing, the collaboration goes on
    // on the tracked hand, and the restarted recogniser hears "end
    // collaboration" at 14.5 s
    let cell = Cell::start("voicekill", "voice-collaboration", None, &[]);
    cell.pid_of("voice");
    let clock = support::RobotClock::watch(&cell.prefix);
    clock.wait_until(12.0);
    drop(clock);
    cell.kill("voice", libc::SIGKILL);
    let r = cell.finish();
    let c = &r["collaboration"];
    eprintln!("collaboration: {c}");
    assert_eq!(restarts(&r, "voice"), 1, "{}", r["events"]);
    // 0 in the measured runs (BENCHMARKS.md); a loaded test machine may miss a few
    let cycles = r["torque_loop"]["cycles"].as_u64().unwrap();
    assert!(
        r["torque_loop"]["missed_deadlines"].as_u64().unwrap() * 100 <= cycles,
        "{}",
        r["torque_loop"]
    );
    assert_no_unintended_contact(&r);
    assert!(events(&r, "brake", "sim").is_empty(), "{}", r["events"]);
    let kill_t = events(&r, "exit", "voice")
        .first()
        .unwrap_or_else(|| panic!("no exit of voice: {}", r["events"]))["t_s"]
        .as_f64()
        .unwrap();
    let end = voice_requests(c)
        .into_iter()
        .find(|q| q["kind"] == "end")
        .unwrap_or_else(|| panic!("'end collaboration' not heard after the restart: {c}"));
    assert!(end["t_s"].as_f64().unwrap() > kill_t, "{c}");
    assert_ended_by_the_request_or_the_force_limit(c, end);
}

/// The collaboration ended by the "end collaboration" request, or, before
/// it, by the force limit: the wrist, which F̂ at the robot part sees late,
/// can take the hand's load in `voice-collaboration` (a known limit,
/// BENCHMARKS.md; about 1 multi-process run in 4). Then the request is heard
/// and refused because nothing collaborates any more.
fn assert_ended_by_the_request_or_the_force_limit(c: &Value, end: &Value) {
    match c["ended_by"].as_str() {
        Some("request") => assert_eq!(end["accepted"], true, "{c}"),
        Some("force_limit") => {
            assert_eq!(end["accepted"], false, "{c}");
            assert_eq!(end["reason"], "not_collaborating", "{c}");
        }
        _ => panic!("ended by neither the request nor the force limit: {c}"),
    }
}
