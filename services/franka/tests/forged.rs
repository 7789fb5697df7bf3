//! `phri-franka` takes states only from its box. Against franka-sim on
//! 127.0.0.1, another local process sends FCI datagrams to the adapter's
//! state port (a garbage 100-byte datagram; full-size FR3 states 0.3 rad
//! ahead, with NaN positions, with a message id far ahead): every one is
//! dropped and counted on `robot/box`, the adapter keeps serving, and no
//! forged position reaches `robot/state`. A box that never answers, or
//! nothing listening, ends the adapter within its start-up deadline with
//! one line naming the address and a non-zero exit; so does a box that
//! dies while served; `--robot-ip ""` is refused.

mod common;

use std::io::Read;
use std::net::{TcpListener, UdpSocket};
use std::process::{Child, Command, Stdio};
use std::time::{Duration, Instant};

use phri_ipc::{Queue, TorqueCommand, Zeroed, ROBOT_BOX, ROBOT_COMMAND, ROBOT_STATE};

/// The adapter's start-up deadline as its `START_DEADLINE_S` says \[s\].
const START_DEADLINE_S: f64 = 5.0;

/// The adapter process, stopped (SIGTERM) when dropped.
struct Adapter(Child);

impl Drop for Adapter {
    fn drop(&mut self) {
        // SAFETY: kill(2) on our own child.
        unsafe { libc::kill(self.0.id() as i32, libc::SIGTERM) };
        let _ = self.0.wait();
    }
}

/// A scratch directory with the FR3's configuration.
fn scratch(name: &str) -> std::path::PathBuf {
    let dir = std::env::temp_dir().join(format!("phri-franka-{name}-{}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    std::fs::write(dir.join("fr3.toml"), "[robot]\nname = \"fr3\"\n").unwrap();
    dir
}

fn adapter(dir: &std::path::Path, prefix: &str, robot_ip: &str, stderr: Stdio) -> Child {
    Command::new(env!("CARGO_BIN_EXE_phri-franka"))
        .arg("--config")
        .arg(dir.join("fr3.toml"))
        .arg("--prefix")
        .arg(prefix)
        .arg("--robot-ip")
        .arg(robot_ip)
        .stdout(Stdio::null())
        .stderr(stderr)
        .spawn()
        .expect("phri-franka starts")
}

/// The UDP ports process `pid` has bound (from /proc: its socket inodes
/// in /proc/net/udp).
fn udp_ports(pid: u32) -> Vec<u16> {
    let inodes: Vec<String> = std::fs::read_dir(format!("/proc/{pid}/fd"))
        .map(|d| {
            d.flatten()
                .filter_map(|e| std::fs::read_link(e.path()).ok())
                .filter_map(|l| {
                    let l = l.to_string_lossy().into_owned();
                    Some(l.strip_prefix("socket:[")?.strip_suffix(']')?.to_owned())
                })
                .collect()
        })
        .unwrap_or_default();
    let table = std::fs::read_to_string("/proc/net/udp").unwrap_or_default();
    table
        .lines()
        .skip(1)
        .filter_map(|line| {
            let f: Vec<&str> = line.split_whitespace().collect();
            let inode = f.get(9)?;
            if !inodes.iter().any(|i| i == inode) {
                return None;
            }
            let port = f.get(1)?.split(':').nth(1)?;
            u16::from_str_radix(port, 16).ok()
        })
        .collect()
}

/// A full-size FCI v10 state (1377 bytes) with `message_id` and joint
/// positions `q` (the rest zero), as the box would send it.
fn state_datagram(message_id: u64, q: [f32; 7]) -> Vec<u8> {
    use franka::wire::robot::v10::RobotState;
    let mut bytes = vec![0u8; std::mem::size_of::<RobotState>()];
    bytes[..8].copy_from_slice(&message_id.to_le_bytes());
    let at = std::mem::offset_of!(RobotState, q);
    for (k, x) in q.iter().enumerate() {
        bytes[at + 4 * k..at + 4 * k + 4].copy_from_slice(&x.to_le_bytes());
    }
    bytes
}

#[test]
fn forged_datagrams_from_another_process_are_dropped_counted_and_never_published() {
    let port = common::port(3);
    let _server = common::serve(port);
    let prefix = format!("tff{}_", std::process::id());
    let dir = scratch("forged");
    let mut proc_ = Adapter(adapter(
        &dir,
        &prefix,
        &format!("127.0.0.1:{port}"),
        Stdio::from(std::fs::File::create(dir.join("adapter.log")).unwrap()),
    ));
    let model =
        phri_model::Model::from_urdf_file(common::deploy().join("robots/fr3/fr3.urdf")).unwrap();
    let mut data = phri_model::Data::new(&model);
    let node = phri_ipc::node("franka-forged-test", &prefix).unwrap();
    let states = ROBOT_STATE.waking_subscriber(&node, Queue::Latest).unwrap();
    let boxes = ROBOT_BOX.subscriber(&node, Queue::Latest).unwrap();
    let commands = ROBOT_COMMAND.publisher(&node).unwrap();
    let forger = UdpSocket::bind("127.0.0.1:0").unwrap();
    let (kp, kd) = (200.0, 20.0);
    let mut q0: Option<[f64; 7]> = None;
    let mut last: Option<(u64, [f64; 7])> = None;
    // phases: hold 2 s, forge for 1.5 s while holding, hold 1.5 s
    let (hold, forge, after) = (2.0, 1.5, 1.5);
    let start = Instant::now();
    let deadline = start + Duration::from_secs(60);
    let mut started: Option<Instant> = None;
    let mut seq = 0u64;
    let (mut sent, mut ports) = (0u64, Vec::new());
    // the largest joint step between two published states, and |q − q0|, per phase
    let mut step = [0.0f64; 3];
    let mut drift = [0.0f64; 3];
    let mut published = [0u64; 3];
    let mut non_finite = 0u64;
    loop {
        assert!(Instant::now() < deadline, "no states from phri-franka");
        let t = started.map_or(0.0, |s| s.elapsed().as_secs_f64());
        if t > hold + forge + after {
            break;
        }
        let phase = match t {
            t if t < hold => 0,
            t if t < hold + forge => 1,
            _ => 2,
        };
        let _ = states.wait(Duration::from_millis(20));
        if let Some(s) = states.latest().unwrap() {
            let q: [f64; 7] = s.q[..7].try_into().unwrap();
            started.get_or_insert_with(Instant::now);
            if q.iter().any(|x| !x.is_finite()) {
                non_finite += 1;
                continue;
            }
            let q0 = *q0.get_or_insert(q);
            published[phase] += 1;
            if let Some((_, lq)) = last {
                for k in 0..7 {
                    step[phase] = step[phase].max((q[k] - lq[k]).abs());
                }
            }
            for k in 0..7 {
                drift[phase] = drift[phase].max((q[k] - q0[k]).abs());
            }
            let dq: Vec<f64> = match last {
                Some((ls, lq)) if s.stamp_ns > ls => {
                    let dt = (s.stamp_ns - ls) as f64 * 1e-9;
                    (0..7).map(|k| (q[k] - lq[k]) / dt).collect()
                }
                _ => vec![0.0; 7],
            };
            last = Some((s.stamp_ns, q));
            let g = phri_model::gravity(&model, &mut data, &q).unwrap();
            seq += 1;
            let mut c = TorqueCommand::zeroed();
            c.seq = seq;
            c.state_seq = s.seq;
            c.state_stamp_ns = s.stamp_ns;
            c.dof = 7;
            for k in 0..7 {
                c.tau[k] = g[k] + kp * (q0[k] - q[k]) - kd * dq[k];
            }
            commands.publish(&c).unwrap();
            if phase == 1 {
                if ports.is_empty() {
                    ports = udp_ports(proc_.0.id());
                    assert!(!ports.is_empty(), "phri-franka has no UDP socket");
                }
                // each kind, to every UDP port of the adapter (its FCI socket)
                let mut ahead = q.map(|x| x as f32);
                ahead[3] += 0.3;
                let nan = [f32::NAN; 7];
                let datagrams = [
                    vec![0xa5u8; 100],
                    state_datagram(s.seq, ahead),
                    state_datagram(s.seq + 1_000_000, ahead),
                    state_datagram(s.seq, nan),
                    state_datagram(u64::MAX / 2, q.map(|x| x as f32)),
                ];
                for d in &datagrams {
                    for p in &ports {
                        forger.send_to(d, ("127.0.0.1", *p)).unwrap();
                        sent += 1;
                    }
                }
            }
        }
    }
    // the adapter's figures, after its next robot/box (10 Hz)
    std::thread::sleep(Duration::from_millis(300));
    let mut status = None;
    while let Some(m) = boxes.receive().unwrap() {
        status = Some(m);
    }
    let alive = proc_.0.try_wait().unwrap().is_none();
    drop(proc_);
    let log = std::fs::read_to_string(dir.join("adapter.log")).unwrap_or_default();
    eprintln!(
        "published per phase (hold, forged, after) {published:?}, largest joint step {step:?} rad, \
         |q − q0| {drift:?} rad; {sent} forged datagrams to ports {ports:?}; robot/box: {:?}\nphri-franka said:\n{log}",
        status.map(|m| (
            m.refused_foreign,
            m.refused_malformed,
            m.refused_stale_id,
            m.refused_id_ahead,
            m.refused_non_finite,
            m.refused_too_fast,
            m.controlled,
            m.success_min
        ))
    );
    let _ = std::fs::remove_dir_all(&dir);
    assert!(alive, "phri-franka died under forged datagrams");
    assert!(sent >= 100, "only {sent} forged datagrams sent");
    let m = status.expect("robot/box from phri-franka");
    // every forged datagram came from another port than the box's: dropped
    // and counted, none parsed as a state
    assert!(
        m.refused_foreign >= sent,
        "{} of {sent} forged datagrams counted",
        m.refused_foreign
    );
    // served on through the forgery, the arm held, no step in what phri saw
    assert_eq!(non_finite, 0, "a non-finite state was published");
    assert!(published[1] >= 300 && published[2] >= 300, "{published:?}");
    for p in 0..3 {
        assert!(step[p] < 0.01, "joint step {} rad in phase {p}", step[p]);
        assert!(
            drift[p] < 0.01,
            "the arm moved {} rad in phase {p}",
            drift[p]
        );
    }
    // the box's success rate is the box's: from its own states only
    assert!(
        m.controlled > 0 && m.success_min > 0.0 && m.success_min <= 1.0,
        "{} controlled states, success rate min {}",
        m.controlled,
        m.success_min
    );
}

/// Runs `child` to its end (at most `limit`): its exit status, the time it
/// took and what it wrote on stderr.
fn finish(mut child: Child, limit: Duration) -> (std::process::ExitStatus, Duration, String) {
    let t0 = Instant::now();
    let status = loop {
        if let Some(s) = child.try_wait().unwrap() {
            break s;
        }
        if t0.elapsed() > limit {
            let _ = child.kill();
            let _ = child.wait();
            let mut err = String::new();
            if let Some(mut e) = child.stderr.take() {
                let _ = e.read_to_string(&mut err);
            }
            panic!("phri-franka still ran after {limit:?}; it said: {err}");
        }
        std::thread::sleep(Duration::from_millis(20));
    };
    let mut err = String::new();
    if let Some(mut e) = child.stderr.take() {
        let _ = e.read_to_string(&mut err);
    }
    (status, t0.elapsed(), err)
}

/// The lines of `err` that name `what`.
fn lines_naming<'a>(err: &'a str, what: &str) -> Vec<&'a str> {
    err.lines().filter(|l| l.contains(what)).collect()
}

#[test]
fn a_box_that_never_answers_or_is_not_there_ends_the_adapter_with_one_line() {
    let dir = scratch("silent");
    let prefix = format!("tfs{}_", std::process::id());
    let limit = Duration::from_secs_f64(START_DEADLINE_S + 5.0);
    // a listener that accepts and says nothing
    let silent = TcpListener::bind("127.0.0.1:0").unwrap();
    let address = silent.local_addr().unwrap().to_string();
    let holder = std::thread::spawn(move || {
        let held: Vec<_> = silent.incoming().take(2).flatten().collect();
        std::thread::sleep(Duration::from_secs(20));
        drop(held);
    });
    let (status, took, err) = finish(adapter(&dir, &prefix, &address, Stdio::piped()), limit);
    eprintln!("silent box: {status} after {took:?}: {err}");
    assert!(!status.success(), "exit {status}");
    assert!(
        took.as_secs_f64() <= START_DEADLINE_S + 2.0,
        "ended after {took:?}"
    );
    let named = lines_naming(&err, &address);
    assert_eq!(named.len(), 1, "{err}");
    assert!(named[0].contains("never answered"), "{}", named[0]);
    drop(holder);

    // nothing listening: refused by the box's address, not "enable FCI in Desk"
    let gone = TcpListener::bind("127.0.0.1:0").unwrap();
    let address = gone.local_addr().unwrap().to_string();
    drop(gone);
    let (status, took, err) = finish(adapter(&dir, &prefix, &address, Stdio::piped()), limit);
    eprintln!("nothing listening: {status} after {took:?}: {err}");
    assert!(!status.success());
    let named = lines_naming(&err, &address);
    assert_eq!(named.len(), 1, "{err}");
    assert!(
        named[0].contains(&format!("connection refused by the box at {address}")),
        "{}",
        named[0]
    );

    // an empty address
    let (status, _, err) = finish(adapter(&dir, &prefix, "", Stdio::piped()), limit);
    eprintln!("--robot-ip \"\": {status}: {err}");
    assert!(!status.success());
    assert_eq!(lines_naming(&err, "--robot-ip").len(), 1, "{err}");
    let _ = std::fs::remove_dir_all(&dir);
}

#[test]
fn a_box_that_dies_while_served_is_named_as_such() {
    let port = common::port(4);
    let server = common::serve(port);
    let dir = scratch("died");
    let prefix = format!("tfd{}_", std::process::id());
    let address = format!("127.0.0.1:{port}");
    let child = adapter(&dir, &prefix, &address, Stdio::piped());
    let node = phri_ipc::node("franka-died-test", &prefix).unwrap();
    let states = ROBOT_STATE.waking_subscriber(&node, Queue::Latest).unwrap();
    let deadline = Instant::now() + Duration::from_secs(30);
    while states.latest().unwrap().is_none() {
        assert!(Instant::now() < deadline, "no states from phri-franka");
        let _ = states.wait(Duration::from_millis(50));
    }
    drop(server);
    let (status, took, err) = finish(child, Duration::from_secs(10));
    eprintln!("franka-sim killed: {status} after {took:?}: {err}");
    assert!(!status.success());
    let named = lines_naming(&err, &address);
    assert!(!named.is_empty(), "{err}");
    let last = named[named.len() - 1];
    assert!(
        last.contains(&format!("by the box at {address}"))
            || last.contains(&format!("the box at {address}")),
        "{last}"
    );
    assert!(!err.contains("Desk"), "{err}");
    drop((states, node));
    let _ = phri_ipc::remove_leftovers(&prefix);
    let _ = std::fs::remove_dir_all(&dir);
}
