//! How far the bridge's DDS reaches: `[ros2] discovery` (`localhost`, the
//! default, or `subnet`), unless ROS 2's own variables say otherwise:
//! `ROS_AUTOMATIC_DISCOVERY_RANGE` (Iron and later: `LOCALHOST`, `SUBNET`,
//! `OFF`, `SYSTEM_DEFAULT`) or, when that is unset, `ROS_LOCALHOST_ONLY=1`.
//! `OFF` (no discovery at all in ROS 2) is taken as `localhost`, the
//! nearest the bridge has; `SYSTEM_DEFAULT` leaves the choice to the
//! configuration.

use phri_config::ros2::Ros2Discovery;

/// ROS 2's discovery range variable.
pub const RANGE_VAR: &str = "ROS_AUTOMATIC_DISCOVERY_RANGE";
/// ROS 2's older localhost variable (Humble).
pub const LOCALHOST_ONLY_VAR: &str = "ROS_LOCALHOST_ONLY";

/// A discovery variable the bridge cannot honour: it does not start rather
/// than guess how far it may reach.
#[derive(Debug, Clone, PartialEq, Eq, thiserror::Error)]
pub enum DiscoveryError {
    /// [`RANGE_VAR`] holds none of ROS 2's values: the value, cut and escaped
    #[error("{RANGE_VAR}: '{0}' is not LOCALHOST, SUBNET, OFF or SYSTEM_DEFAULT")]
    Range(String),
}

/// What decided the discovery range.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum DecidedBy {
    /// `[ros2] discovery`
    Config,
    /// [`RANGE_VAR`]
    RangeVar,
    /// [`LOCALHOST_ONLY_VAR`]
    LocalhostOnlyVar,
}

impl DecidedBy {
    /// Its name in a log line: the configuration key or the variable.
    pub fn name(self) -> &'static str {
        match self {
            DecidedBy::Config => "ros2.discovery",
            DecidedBy::RangeVar => RANGE_VAR,
            DecidedBy::LocalhostOnlyVar => LOCALHOST_ONLY_VAR,
        }
    }
}

/// The discovery range from the configuration's `config` and the values of
/// [`RANGE_VAR`] (`range`) and [`LOCALHOST_ONLY_VAR`] (`localhost_only`),
/// `None` when unset; an empty value counts as unset.
pub fn resolve(
    config: Ros2Discovery,
    range: Option<&str>,
    localhost_only: Option<&str>,
) -> Result<(Ros2Discovery, DecidedBy), DiscoveryError> {
    if let Some(r) = range.map(str::trim).filter(|r| !r.is_empty()) {
        match r.to_ascii_uppercase().as_str() {
            "LOCALHOST" | "OFF" => return Ok((Ros2Discovery::Localhost, DecidedBy::RangeVar)),
            "SUBNET" => return Ok((Ros2Discovery::Subnet, DecidedBy::RangeVar)),
            "SYSTEM_DEFAULT" => return Ok((config, DecidedBy::Config)),
            _ => return Err(DiscoveryError::Range(crate::gate::shown(r))),
        }
    }
    if localhost_only.is_some_and(|v| v.trim() == "1") {
        return Ok((Ros2Discovery::Localhost, DecidedBy::LocalhostOnlyVar));
    }
    Ok((config, DecidedBy::Config))
}

/// The local addresses of the UDP sockets listed in `table` (the text of
/// `/proc/net/udp`) whose inode is among `inodes` (a process's sockets,
/// from `/proc/self/fd`). A line that does not parse is skipped.
pub fn udp_local_addresses(table: &str, inodes: &[u64]) -> Vec<std::net::SocketAddrV4> {
    table
        .lines()
        .skip(1)
        .filter_map(|line| {
            let f: Vec<&str> = line.split_whitespace().collect();
            let inode: u64 = f.get(9)?.parse().ok()?;
            if !inodes.contains(&inode) {
                return None;
            }
            // `0100007F:1CF2`: the address as the kernel's 32-bit word in
            // hex (this host's byte order), the port in hex
            let (ip, port) = f.get(1)?.split_once(':')?;
            let ip = u32::from_str_radix(ip, 16).ok()?;
            let port = u16::from_str_radix(port, 16).ok()?;
            Some(std::net::SocketAddrV4::new(
                std::net::Ipv4Addr::from(ip.to_ne_bytes()),
                port,
            ))
        })
        .collect()
}

#[cfg(test)]
mod tests {
    use super::*;
    use phri_config::ros2::Ros2Discovery::{Localhost, Subnet};

    #[test]
    fn the_configuration_decides_when_ros_says_nothing() {
        assert_eq!(
            resolve(Localhost, None, None),
            Ok((Localhost, DecidedBy::Config))
        );
        assert_eq!(resolve(Subnet, None, None), Ok((Subnet, DecidedBy::Config)));
        assert_eq!(
            resolve(Subnet, Some(" "), Some("")),
            Ok((Subnet, DecidedBy::Config))
        );
        assert_eq!(
            resolve(Subnet, None, Some("0")),
            Ok((Subnet, DecidedBy::Config))
        );
        assert_eq!(
            resolve(Subnet, Some("SYSTEM_DEFAULT"), None),
            Ok((Subnet, DecidedBy::Config))
        );
    }

    #[test]
    fn the_range_variable_overrides_the_configuration_both_ways() {
        assert_eq!(
            resolve(Subnet, Some("LOCALHOST"), None),
            Ok((Localhost, DecidedBy::RangeVar))
        );
        assert_eq!(
            resolve(Subnet, Some("off"), None),
            Ok((Localhost, DecidedBy::RangeVar))
        );
        assert_eq!(
            resolve(Localhost, Some(" subnet "), None),
            Ok((Subnet, DecidedBy::RangeVar))
        );
        // and ROS_LOCALHOST_ONLY, as in ROS 2 Iron and later
        assert_eq!(
            resolve(Localhost, Some("SUBNET"), Some("1")),
            Ok((Subnet, DecidedBy::RangeVar))
        );
    }

    #[test]
    fn localhost_only_keeps_a_subnet_configuration_on_this_host() {
        assert_eq!(
            resolve(Subnet, None, Some("1")),
            Ok((Localhost, DecidedBy::LocalhostOnlyVar))
        );
    }

    #[test]
    fn the_udp_table_gives_each_sockets_local_address() {
        let table = "   sl  local_address rem_address   st tx_queue rx_queue tr tm->when retrnsmt   uid  timeout inode ref pointer drops\n\
  100: 0100007F:1CF2 00000000:0000 07 00000000:00000000 00:00000000 00000000     0        0 4242 2 0000000000000000 0\n\
  101: 00000000:1CE8 00000000:0000 07 00000000:00000000 00:00000000 00000000     0        0 4343 2 0000000000000000 0\n\
  102: 0101E70A:0035 00000000:0000 07 00000000:00000000 00:00000000 00000000     0        0 99 2 0000000000000000 0\n\
  garbage\n";
        let ours = udp_local_addresses(table, &[4242, 4343]);
        let local = |a: [u8; 4], p| std::net::SocketAddrV4::new(a.into(), p);
        if cfg!(target_endian = "little") {
            assert_eq!(
                ours,
                vec![local([127, 0, 0, 1], 7410), local([0, 0, 0, 0], 7400)]
            );
        }
        assert!(udp_local_addresses(table, &[]).is_empty());
    }

    #[test]
    fn an_unknown_range_is_refused_not_guessed() {
        assert_eq!(
            resolve(Localhost, Some("EVERYWHERE"), None),
            Err(DiscoveryError::Range("EVERYWHERE".into()))
        );
        let e = resolve(Localhost, Some("a\nb"), None)
            .unwrap_err()
            .to_string();
        assert!(!e.contains('\n'), "{e}");
    }
}
