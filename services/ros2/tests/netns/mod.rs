//! Two hosts on one machine for phri-ros2's wire tests: network namespaces
//! made with `unshare --net` (as root), joined by a veth pair on a /24 of
//! their own, and the Cyclone DDS peer (`deploy/ros2/install`,
//! `deploy/ros2/peer.py`). Nothing leaves this machine.

use std::path::{Path, PathBuf};
use std::process::{Child, Command, Stdio};
use std::time::{Duration, Instant};

/// The peer's Python (Cyclone DDS installed by the project's script).
pub fn peer_python(repo: &Path) -> PathBuf {
    let out = Command::new(repo.join("deploy/ros2/install"))
        .stderr(Stdio::inherit())
        .output()
        .expect("deploy/ros2/install runs");
    assert!(out.status.success(), "deploy/ros2/install failed");
    let dir = String::from_utf8(out.stdout).expect("a path");
    PathBuf::from(dir.trim()).join("venv/bin/python")
}

/// A new network namespace, then the command: its loopback up; once the
/// test has moved the veth end `$PHRI_VETH` in, IPv6 off on it if
/// `$PHRI_NO_IPV6` is set (no router solicitations, neighbour discovery or
/// MLD reports of the kernel's own), that end up with address `$PHRI_ADDR`
/// and multicast routed through it; then, if `$PHRI_AFTER` is set, a wait
/// for that file (the cell's state, for the peer).
pub const NETNS_SETUP: &str = "ip link set lo up \
    && i=0 && while ! ip link show \"$PHRI_VETH\" >/dev/null 2>&1; do \
         i=$((i+1)); [ $i -le 400 ] || exit 97; sleep 0.05; done \
    && { [ -z \"$PHRI_NO_IPV6\" ] || [ ! -e /proc/sys/net/ipv6/conf/\"$PHRI_VETH\" ] \
         || echo 1 > /proc/sys/net/ipv6/conf/\"$PHRI_VETH\"/disable_ipv6; } \
    && ip addr add \"$PHRI_ADDR\" dev \"$PHRI_VETH\" && ip link set \"$PHRI_VETH\" up \
    && ip route add 224.0.0.0/4 dev \"$PHRI_VETH\" \
    && i=0 && while [ -n \"$PHRI_AFTER\" ] && [ ! -e \"$PHRI_AFTER\" ]; do \
         i=$((i+1)); [ $i -le 400 ] || exit 98; sleep 0.05; done \
    && exec \"$0\" \"$@\"";

/// Joins the network namespaces of processes `a` and `b` with a veth pair
/// named `name_a` (in a's) and `name_b` (in b's), once both have left this
/// process's namespace (unshare made theirs).
pub fn veth(a: &Child, name_a: &str, b: &Child, name_b: &str) {
    let ns = |pid: u32| std::fs::read_link(format!("/proc/{pid}/ns/net")).ok();
    let own = ns(std::process::id());
    let t0 = Instant::now();
    while ns(a.id()) == own || ns(b.id()) == own {
        assert!(
            t0.elapsed() < Duration::from_secs(10),
            "no network namespaces: this test needs root (unshare --net)"
        );
        std::thread::sleep(Duration::from_millis(10));
    }
    let status = Command::new("ip")
        .args(["link", "add", "name", name_a, "netns", &a.id().to_string()])
        .args([
            "type",
            "veth",
            "peer",
            "name",
            name_b,
            "netns",
            &b.id().to_string(),
        ])
        .status()
        .expect("ip runs");
    assert!(
        status.success(),
        "ip link add {name_a} … veth … {name_b}: {status}"
    );
}

/// Waits for the cell's `state.json` in `run_dir` (its services started).
pub fn wait_for_cell(supervisor: &mut Child, run_dir: &Path) {
    let t0 = Instant::now();
    while !run_dir.join("state.json").exists() {
        if let Some(s) = supervisor.try_wait().expect("the supervisor's status") {
            panic!(
                "the cell did not start in a network namespace of its own ({s}): \
                 this test needs root (unshare --net, ip link)"
            );
        }
        assert!(t0.elapsed() < Duration::from_secs(20), "no state.json");
        std::thread::sleep(Duration::from_millis(50));
    }
}

/// Waits at most `limit` for `child` to end.
pub fn wait_at_most(child: &mut Child, limit: Duration, what: &str) -> std::process::ExitStatus {
    let deadline = Instant::now() + limit;
    loop {
        if let Some(s) = child.try_wait().expect("a child's status") {
            return s;
        }
        assert!(Instant::now() < deadline, "{what} did not stop");
        std::thread::sleep(Duration::from_millis(100));
    }
}
