//! The DDS participant every ROS 2 process of phri makes (the bridge
//! `phri-ros2`, the camera `phri-camera-ros2`): ROS 2's domain from
//! `ROS_DOMAIN_ID`, how far discovery reaches (`[ros2] discovery`, ROS 2's
//! variables over it: [`crate::discovery`]), and with `localhost` every
//! socket bound to 127.0.0.1, checked with the kernel's own table.

use phri_config::ros2::Ros2Discovery;
use phri_config::Config;
use ros2_client::dds::rustdds::DomainParticipantBuilder;
use ros2_client::Context;

use crate::discovery::{self, DecidedBy};

/// The log filter of phri's ROS 2 processes when `RUST_LOG` is unset: the
/// services' own, with RustDDS from `error` up (restricted to the loopback,
/// it warns at every send that its own builtin readers have no other
/// locators), and ros2-client's node silent (it logs an error each time a
/// publisher not yet matched is asked for its subscribers).
pub const LOG_FILTER: &str = "info,rustdds=error,ros2_client=warn,ros2_client::node=off";

/// ROS 2's domain from `ROS_DOMAIN_ID` (unset or empty: 0).
pub fn domain_id() -> Result<u16, String> {
    match std::env::var("ROS_DOMAIN_ID") {
        Err(_) => Ok(0),
        Ok(s) if s.trim().is_empty() => Ok(0),
        Ok(s) => s
            .trim()
            .parse::<u16>()
            .ok()
            .filter(|d| *d <= 232)
            .ok_or_else(|| format!("ROS_DOMAIN_ID: '{s}' is not a domain id (0-232)")),
    }
}

/// CLOCK_REALTIME \[ns\] (ROS time).
pub fn realtime_ns() -> u64 {
    std::time::SystemTime::now()
        .duration_since(std::time::UNIX_EPOCH)
        .map(|d| d.as_nanos() as u64)
        .unwrap_or(0)
}

/// The local addresses of this process's UDP sockets.
fn own_udp_sockets() -> Result<Vec<std::net::SocketAddrV4>, String> {
    let mut inodes = Vec::new();
    let fds = std::fs::read_dir("/proc/self/fd").map_err(|e| format!("/proc/self/fd: {e}"))?;
    for fd in fds.flatten() {
        if let Ok(link) = std::fs::read_link(fd.path()) {
            if let Some(inode) = link
                .to_string_lossy()
                .strip_prefix("socket:[")
                .and_then(|s| s.strip_suffix(']'))
                .and_then(|s| s.parse::<u64>().ok())
            {
                inodes.push(inode);
            }
        }
    }
    let table = std::fs::read_to_string("/proc/self/net/udp")
        .map_err(|e| format!("/proc/self/net/udp: {e}"))?;
    Ok(discovery::udp_local_addresses(&table, &inodes))
}

/// How far DDS reaches, and what decided it: phri-ros2's rule.
pub fn reach(config: &Config) -> Result<(Ros2Discovery, DecidedBy), String> {
    let env = |name: &str| std::env::var(name).ok();
    discovery::resolve(
        config.ros2.discovery,
        env(discovery::RANGE_VAR).as_deref(),
        env(discovery::LOCALHOST_ONLY_VAR).as_deref(),
    )
    .map_err(|e| e.to_string())
}

/// A DDS participant as phri-ros2 makes it: on domain `domain`, every
/// socket on 127.0.0.1 when `local` (checked with the kernel's table).
pub fn participant(domain: u16, local: bool) -> Result<Context, String> {
    let mut participant = DomainParticipantBuilder::new(domain);
    if local {
        participant = participant.with_only_networks([std::net::Ipv4Addr::LOCALHOST]);
    }
    let dds = participant
        .build()
        .map_err(|e| format!("DDS domain {domain}: {e:?}"))
        .and_then(|p| {
            Context::from_domain_participant(p).map_err(|e| format!("DDS domain {domain}: {e:?}"))
        })?;
    if local {
        let sockets = own_udp_sockets()?;
        if let Some(a) = sockets.iter().find(|a| !a.ip().is_loopback()) {
            return Err(format!(
                "ros2.discovery = localhost, but a DDS socket is bound to {a}: not started \
                 (RustDDS must be patches/rustdds)"
            ));
        }
        tracing::debug!("DDS sockets: {sockets:?}");
    }
    Ok(dds)
}

/// ROS 2's discovery of `node` (matched subscribers, `ros_discovery_info`)
/// on a thread of its own, under the normal scheduler.
pub fn spin_discovery(node: &mut ros2_client::Node) -> Result<(), String> {
    let spinner = node
        .spinner()
        .map_err(|e| format!("ROS 2 node's discovery: {e:?}"))?;
    std::thread::Builder::new()
        .name("ros2-discovery".into())
        .spawn(move || {
            if let Err(e) = futures::executor::block_on(spinner.spin()) {
                tracing::warn!("ROS 2 discovery stopped: {e:?}");
            }
        })
        .map_err(|e| format!("ROS 2 discovery thread: {e}"))?;
    Ok(())
}
