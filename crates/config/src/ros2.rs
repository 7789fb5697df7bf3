//! `[ros2]`: phri-ros2, the bridge that publishes the cell's channels as
//! ROS 2 topics over DDS and takes requests from ROS 2.

use serde::{Deserialize, Serialize};

use crate::error::Invalid;

const S: &str = "ros2";

/// `[ros2] discovery`: how far the bridge's DDS looks for peers and answers.
/// ROS 2's own variables, when set, override it (`ROS_AUTOMATIC_DISCOVERY_RANGE`,
/// `ROS_LOCALHOST_ONLY=1`: phri-ros2 resolves them).
#[derive(Clone, Copy, Debug, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum Ros2Discovery {
    /// every socket of the bridge bound to 127.0.0.1: it neither sends nor
    /// answers on any other interface; ROS 2 peers on this host only
    Localhost,
    /// every interface: DDS's multicast discovery (239.255.0.1) and its
    /// traffic on the machine's networks, for ROS 2 peers on other hosts
    Subnet,
}

impl Ros2Discovery {
    /// The name in `[ros2] discovery`.
    pub fn name(self) -> &'static str {
        match self {
            Ros2Discovery::Localhost => "localhost",
            Ros2Discovery::Subnet => "subnet",
        }
    }
}

/// `[ros2]` (defaults and their reasons: `deploy/phri.toml`).
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct Ros2Config {
    /// `localhost` (the default: nothing on the network) or `subnet` (peers on
    /// other hosts)
    pub discovery: Ros2Discovery,
    /// `/joint_states`: every N-th robot state (1: every state, 1 kHz)
    pub joint_states_every: u32,
    /// `/tf`: every N-th robot state
    pub tf_every: u32,
    /// `/phri/status` \[Hz\]
    pub status_hz: f64,
    /// `/phri/contact_force` \[Hz\]
    pub contact_force_hz: f64,
    /// `/phri/repulsion` \[Hz\]
    pub repulsion_hz: f64,
    /// `/phri/depth`: every N-th filtered depth frame
    pub depth_every: u32,
    /// `/phri/points`: every N-th filtered depth frame
    pub points_every: u32,
    /// `/phri/points`: one pixel in N per axis
    pub points_stride: u32,
    /// take `/phri/request` into `hri/request`; false: refused (and counted)
    pub accept_requests: bool,
    /// `/phri/request`: each peer's (DDS writer's) sustained rate [requests/s];
    /// `stop` is never limited
    pub requests_per_s: f64,
    /// `/phri/request`: each peer's burst above that rate \[requests\]
    pub requests_burst: u32,
}

impl Ros2Config {
    /// Every "every N" and stride at least 1, rates in (0, 1000\] Hz,
    /// a request rate in (0, 1000\] per second and a burst of at least 1.
    pub fn validate(&self) -> Result<(), Invalid> {
        for (name, v) in [
            ("joint_states_every", self.joint_states_every),
            ("tf_every", self.tf_every),
            ("depth_every", self.depth_every),
            ("points_every", self.points_every),
            ("points_stride", self.points_stride),
        ] {
            if v == 0 {
                return Err(Invalid::new(format!("{S}.{name}"), "must be at least 1"));
            }
        }
        for (name, v) in [
            ("status_hz", self.status_hz),
            ("contact_force_hz", self.contact_force_hz),
            ("repulsion_hz", self.repulsion_hz),
        ] {
            if !(v > 0.0 && v <= 1000.0) {
                return Err(Invalid::new(
                    format!("{S}.{name}"),
                    format!("{v} is not in (0, 1000] Hz"),
                ));
            }
        }
        if !(self.requests_per_s > 0.0 && self.requests_per_s <= 1000.0) {
            return Err(Invalid::new(
                format!("{S}.requests_per_s"),
                format!("{} is not in (0, 1000] requests/s", self.requests_per_s),
            ));
        }
        if self.requests_burst == 0 {
            return Err(Invalid::new(
                format!("{S}.requests_burst"),
                "must be at least 1",
            ));
        }
        Ok(())
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn the_default_stays_on_this_host_and_a_rate_limit_must_let_some_through() {
        let d = crate::Config::defaults().ros2;
        assert_eq!(d.discovery, Ros2Discovery::Localhost);
        assert!(d.validate().is_ok());
        for bad in [0.0, -1.0, f64::NAN, 1e6] {
            let c = Ros2Config {
                requests_per_s: bad,
                ..d.clone()
            };
            assert!(c.validate().is_err(), "requests_per_s {bad}");
        }
        let c = Ros2Config {
            requests_burst: 0,
            ..d.clone()
        };
        assert!(c.validate().is_err());
    }
}
