//! phri-ros2 by default (`[ros2] discovery = "localhost"`, ROS 2's
//! variables unset): nothing on the network. The real cell runs in a
//! network namespace of its own joined to another by a veth pair (as two
//! hosts of one subnet, `unshare --net` as root); there a Cyclone DDS peer
//! (`deploy/ros2/peer.py`) discovers by multicast and by unicast to the
//! cell's address, several times a second, subscribes to `/joint_states`
//! and asks for stops. The cell sends no UDP datagram on the veth (an
//! AF_PACKET socket in its namespace counts what crosses it, `sniff.py`),
//! joins no multicast group there, and the far peer receives nothing and
//! stops nothing. Every socket of the bridge is bound to 127.0.0.1. On the
//! same host the bridge still serves: a second Cyclone DDS peer in the
//! cell's namespace, on its loopback, reads `/phri/status` and asks to
//! begin 8 times at once, of which the bridge passes its burst (5) and
//! drops and counts the rest.

use std::io::{BufRead, BufReader, Read};
use std::process::{Command, Stdio};
use std::time::{Duration, Instant};

use serde_json::Value;

#[path = "../../../tests/support/workspace.rs"]
mod workspace;
use workspace::{bin, repo};
mod netns;
use netns::{peer_python, veth, wait_at_most, wait_for_cell, NETNS_SETUP};

/// Cyclone DDS on the far host: its veth only, the cell's address as a
/// unicast peer, participant announcements every 0.2 s.
const FAR_PEER: &str = "<CycloneDDS><Domain id=\"any\"><General><Interfaces>\
    <NetworkInterface name=\"peer0\"/></Interfaces></General><Discovery>\
    <ParticipantIndex>auto</ParticipantIndex><Peers><Peer address=\"10.231.1.1\"/></Peers>\
    <SPDPInterval>0.2s</SPDPInterval></Discovery></Domain></CycloneDDS>";

/// Cyclone DDS on the cell's host: its loopback only, unicast discovery,
/// participant announcements every 0.5 s.
const NEAR_PEER: &str = "<CycloneDDS><Domain id=\"any\"><General><Interfaces>\
    <NetworkInterface name=\"lo\"/></Interfaces><AllowMulticast>false</AllowMulticast>\
    </General><Discovery><ParticipantIndex>auto</ParticipantIndex>\
    <Peers><Peer address=\"127.0.0.1\"/></Peers><SPDPInterval>0.5s</SPDPInterval>\
    </Discovery></Domain></CycloneDDS>";

/// The local IPv4 addresses of the UDP sockets process `pid` holds, from
/// its network namespace's `/proc/net/udp` (hex, network order read as a
/// little-endian word: `0100007F` is 127.0.0.1).
fn udp_sockets(pid: i64) -> Vec<String> {
    let mut inodes = Vec::new();
    // a process not (yet, or no longer) there has none
    let Ok(fds) = std::fs::read_dir(format!("/proc/{pid}/fd")) else {
        return Vec::new();
    };
    for fd in fds.flatten() {
        let link = std::fs::read_link(fd.path()).unwrap_or_default();
        let link = link.to_string_lossy();
        if let Some(inode) = link
            .strip_prefix("socket:[")
            .and_then(|s| s.strip_suffix(']'))
        {
            inodes.push(inode.to_string());
        }
    }
    let table = std::fs::read_to_string(format!("/proc/{pid}/net/udp")).unwrap_or_default();
    table
        .lines()
        .skip(1)
        .filter_map(|line| {
            let f: Vec<&str> = line.split_whitespace().collect();
            (f.len() > 9 && inodes.iter().any(|i| i == f[9])).then(|| f[1].to_string())
        })
        .collect()
}

/// Interface `iface`'s (rx, tx) packets in process `pid`'s network namespace.
fn packets(pid: u32, iface: &str) -> (u64, u64) {
    let dev = std::fs::read_to_string(format!("/proc/{pid}/net/dev")).unwrap();
    let line = dev
        .lines()
        .find(|l| l.trim_start().starts_with(&format!("{iface}:")))
        .unwrap_or_else(|| panic!("no {iface} in {dev}"));
    let f: Vec<u64> = line
        .split_once(':')
        .unwrap()
        .1
        .split_whitespace()
        .map(|x| x.parse().unwrap())
        .collect();
    (f[1], f[9])
}

#[test]
fn by_default_the_bridge_sends_and_answers_nothing_on_the_network_and_serves_its_host() {
    let python = peer_python(&repo());
    let prefix = format!("ros2l{}_", std::process::id());
    let run_dir = std::env::temp_dir().join(format!("phri-test-{prefix}"));
    let _ = std::fs::remove_dir_all(&run_dir);
    std::fs::create_dir_all(&run_dir).unwrap();
    let report = run_dir.join("report.json");
    let stop_sniffing = run_dir.join("sniffed");
    // at most: the test stops the cell (SIGINT) once the peers are done
    let duration_s = 40.0;
    // the cell: the configuration's default, ROS 2's variables unset
    let mut supervisor = Command::new("unshare")
        .current_dir(repo())
        .env("PHRI_VETH", "phri0")
        .env("PHRI_ADDR", "10.231.1.1/24")
        .env("PHRI_NO_IPV6", "1")
        .env_remove("PHRI_AFTER")
        .env_remove("ROS_AUTOMATIC_DISCOVERY_RANGE")
        .env_remove("ROS_LOCALHOST_ONLY")
        .args(["--net", "--", "sh", "-c", NETNS_SETUP])
        .arg(bin("phri-supervisor"))
        .arg("--config")
        .arg(repo().join("deploy/phri.toml"))
        .args(["--scenario", "coexistence", "--prefix", &prefix])
        .arg("--run-dir")
        .arg(&run_dir)
        .arg("--report")
        .arg(&report)
        .args(["--duration", &duration_s.to_string()])
        .args(["--set", "services.ros2.enabled=true"])
        .args(["--set", "ros2.accept_requests=true"])
        .stderr(Stdio::piped())
        .spawn()
        .expect("unshare starts");
    // the cell's log, shown as it comes and kept
    let cell_stderr = supervisor.stderr.take().unwrap();
    let cell_log = std::thread::spawn(move || {
        let mut kept = String::new();
        for line in BufReader::new(cell_stderr).lines().map_while(Result::ok) {
            eprintln!("{line}");
            kept.push_str(&line);
            kept.push('\n');
        }
        kept
    });
    // the far host: discovers, subscribes, asks to stop
    let far = Command::new("unshare")
        .env("PHRI_VETH", "peer0")
        .env("PHRI_ADDR", "10.231.1.2/24")
        .env("PHRI_AFTER", run_dir.join("state.json"))
        .env_remove("PHRI_NO_IPV6")
        .env("CYCLONEDDS_URI", FAR_PEER)
        .args(["--net", "--", "sh", "-c", NETNS_SETUP])
        .arg(&python)
        .arg(repo().join("deploy/ros2/peer.py"))
        .args(["--duration", "4", "--topics", "joint_states,status"])
        .args(["--request", "1:stop", "--request", "3:stop"])
        .stdout(Stdio::piped())
        .spawn()
        .expect("the far peer starts");
    veth(&supervisor, "phri0", &far, "peer0");
    // the far namespace (and with it the veth pair) outlives the far peer
    let mut far_holder = Command::new("nsenter")
        .arg(format!("--net=/proc/{}/ns/net", far.id()))
        .args(["sleep", "120"])
        .spawn()
        .expect("nsenter holds the far namespace");
    // what crosses the cell's veth, from its creation on
    let netns = format!("--net=/proc/{}/ns/net", supervisor.id());
    let mut sniffer = Command::new("nsenter")
        .arg(&netns)
        .arg(&python)
        .arg(repo().join("services/ros2/tests/sniff.py"))
        .args(["phri0", &stop_sniffing.to_string_lossy(), "60"])
        .stdout(Stdio::piped())
        .stderr(Stdio::piped())
        .spawn()
        .expect("nsenter runs the sniffer");
    let mut line = [0u8; 9];
    sniffer
        .stderr
        .as_mut()
        .unwrap()
        .read_exact(&mut line)
        .expect("the sniffer starts");
    wait_for_cell(&mut supervisor, &run_dir);
    let t0 = Instant::now();
    // the bridge's sockets, once it runs: every one on 127.0.0.1
    let sockets = loop {
        let state: Value =
            serde_json::from_str(&std::fs::read_to_string(run_dir.join("state.json")).unwrap())
                .unwrap_or_default();
        let sockets = state["services"]["ros2"]["pid"]
            .as_i64()
            .map(udp_sockets)
            .unwrap_or_default();
        if sockets.len() >= 3 || t0.elapsed() > Duration::from_secs(10) {
            break sockets;
        }
        std::thread::sleep(Duration::from_millis(100));
    };
    assert!(sockets.len() >= 3, "the bridge's UDP sockets: {sockets:?}");
    assert!(
        sockets.iter().all(|a| a.starts_with("0100007F:")),
        "the bridge's UDP sockets bound elsewhere than 127.0.0.1: {sockets:?}"
    );

    // this host: a peer on the cell's loopback reads /phri/status and asks
    // to begin 8 times at once
    let near = Command::new("nsenter")
        .arg(&netns)
        .arg(&python)
        .arg(repo().join("deploy/ros2/peer.py"))
        .env("CYCLONEDDS_URI", NEAR_PEER)
        .args(["--duration", "4", "--topics", "status"])
        .args((0..8).flat_map(|_| ["--request", "2.5:begin"]))
        .stdout(Stdio::piped())
        .spawn()
        .expect("the near peer starts");

    let near = near.wait_with_output().unwrap();
    assert!(near.status.success(), "the near peer failed");
    let far_out = far.wait_with_output().unwrap();
    assert!(far_out.status.success(), "the far peer failed");
    // the veth's counters, in the cell's namespace (the sniffer's)
    let (rx, tx) = packets(sniffer.id(), "phri0");
    std::fs::write(&stop_sniffing, b"").unwrap();
    let sniffed = sniffer.wait_with_output().unwrap();
    assert!(
        sniffed.status.success(),
        "sniff.py: {}",
        String::from_utf8_lossy(&sniffed.stderr)
    );
    eprintln!(
        "after {:.1} s: phri0 rx {rx} tx {tx} packets; sniffed {}",
        t0.elapsed().as_secs_f64(),
        String::from_utf8_lossy(&sniffed.stdout).trim()
    );
    let _ = far_holder.kill();
    let _ = far_holder.wait();
    // SAFETY: kill(2) of our own child, the supervisor (unshare and sh exec'd it)
    unsafe { libc::kill(supervisor.id() as i32, libc::SIGINT) };
    let status = wait_at_most(&mut supervisor, Duration::from_secs(60), "the supervisor");
    let log = cell_log.join().unwrap();
    assert!(status.success(), "the supervisor failed: {status}\n{log}");

    // nothing sent on the network: no UDP datagram, no multicast join (the
    // kernel's own ICMP port unreachables to the far peer's unicast are
    // the kernel's, not the bridge's: no socket listens there)
    let s: Value = serde_json::from_slice(&sniffed.stdout).expect("sniff.py prints JSON");
    let count = |dir: &str, kind: &str| s[dir][kind].as_u64().unwrap_or(0);
    assert_eq!(count("out", "udp"), 0, "UDP sent on the veth: {s}");
    assert_eq!(
        count("out", "igmp"),
        0,
        "a multicast group joined on the veth: {s}"
    );
    assert_eq!(count("out", "ipv6"), 0, "{s}");
    // ... while the far peer's discovery reached the cell, multicast and unicast
    assert!(count("in", "udp") >= 10, "the far peer's discovery: {s}");
    assert!(rx > 0, "phri0 rx {rx}");
    let far: Value = serde_json::from_slice(&far_out.stdout).expect("peer.py prints JSON");
    eprintln!("far peer {far}");
    assert_eq!(far["joint_states"]["count"], 0, "{far}");
    assert_eq!(far["status"]["count"], 0, "{far}");

    // this host is served: /phri/status, and the burst of requests
    let near: Value = serde_json::from_slice(&near.stdout).expect("peer.py prints JSON");
    eprintln!("near peer {near}");
    assert!(
        near["status"]["count"].as_u64().unwrap_or(0) >= 5,
        "/phri/status on the loopback: {near}"
    );
    let r: Value = serde_json::from_str(&std::fs::read_to_string(&report).unwrap()).unwrap();
    let requests = r["collaboration"]["requests"].as_array().unwrap();
    let from_ros = |kind: &str| {
        requests
            .iter()
            .filter(|q| q["source"] == "ros2" && q["kind"] == kind)
            .count()
    };
    assert_eq!(
        from_ros("stop"),
        0,
        "the far peer stopped the cell: {requests:?}"
    );
    let begins = from_ros("begin");
    assert!(begins >= 1, "no begin from the near peer: {requests:?}");
    // the bridge's totals: of 8 at once, its burst (5) passed, the rest
    // dropped and counted
    let summary = log
        .lines()
        .rfind(|l| l.contains("phri-ros2") && l.contains("/phri/request: passed"))
        .unwrap_or_else(|| panic!("no summary of the bridge's requests in\n{log}"));
    eprintln!("{summary} (the report lists {begins} begins from ros2)");
    let after = |word: &str| -> u64 {
        summary
            .split_once(word)
            .and_then(|(_, rest)| rest.split_whitespace().next())
            .and_then(|n| n.trim_end_matches([')', ',']).parse().ok())
            .unwrap_or_else(|| panic!("no '{word}N' in {summary}"))
    };
    let (passed, dropped) = (after("passed "), after("dropped "));
    assert_eq!(passed + dropped, 8, "{summary}");
    assert!((5..=6).contains(&passed), "{summary}");
    assert_eq!(after("(stops "), 0, "{summary}");
    // ... and the report has them (ros2/requests), the run degraded by them
    let c = &r["collaboration"];
    assert_eq!(c["requests_dropped_ros2"], dropped, "{c}");
    assert!(c["requests_dropped"].as_u64() >= Some(dropped), "{c}");
    assert_eq!(r["clean"], false, "{}", r["summary"]);
    assert!(
        r["summary"].as_str().unwrap_or("").contains("dropped"),
        "{}",
        r["summary"]
    );
    let _ = std::fs::remove_dir_all(&run_dir);
}
