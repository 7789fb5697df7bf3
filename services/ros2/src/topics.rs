//! The bridge's side on ROS 2: a publisher per topic of the crate's table,
//! each with its QoS, the `/phri/request` subscription, which topics DDS has
//! matched readers for ([`Subscribed`]), and the messages DDS refused
//! ([`Unsent`]). Best-effort writers never wait; reliable ones give up at
//! once when their window is full: a slow or absent ROS 2 subscriber never
//! slows the bridge.

use ros2_client::{
    qos::{History, WhenFull},
    MessageTypeName, Name, Node, Publisher, QosProfile, Subscription,
};
use serde::Serialize;

use crate::msgs::{self, RosType};
use crate::{RequestSample, Subscribed};

/// Sensor data: best effort, the newest few.
pub const SENSOR: QosProfile =
    QosProfile::subscription_default().history(History::KeepLast { depth: 5 });
/// `/joint_states` at up to 1 kHz: best effort, a send queue of 0.2 s (a
/// shorter one loses states whenever DDS's sending thread waits a few ms)
pub const JOINTS: QosProfile =
    QosProfile::subscription_default().history(History::KeepLast { depth: 200 });
/// Images and clouds: best effort, only the newest.
pub const IMAGE: QosProfile =
    QosProfile::subscription_default().history(History::KeepLast { depth: 1 });
/// Status and requests: reliable, a writer whose window is full drops at
/// once instead of waiting.
pub const RELIABLE: QosProfile = QosProfile::publisher_default()
    .reliability_reliable(WhenFull::Fail)
    .history(History::KeepLast { depth: 10 });
/// `/phri/request` as read: reliable, the newest 64 samples between two
/// takes (one every 1-20 ms): a flood of one peer has to outrun that to
/// push another's stop out before the bridge sees it.
pub const REQUESTS: QosProfile = QosProfile::publisher_default()
    .reliability_reliable(WhenFull::Fail)
    .history(History::KeepLast { depth: 64 });

/// The bridge's topics on one ROS 2 node.
pub struct Topics {
    /// `/joint_states` (`sensor_msgs/JointState`, [`JOINTS`])
    pub joint_states: Publisher<msgs::JointState>,
    /// `/tf` (`tf2_msgs/TFMessage`, [`SENSOR`])
    pub tf: Publisher<msgs::TfMessage>,
    /// `/phri/status` (`diagnostic_msgs/DiagnosticArray`, [`RELIABLE`])
    pub status: Publisher<msgs::DiagnosticArray>,
    /// `/phri/contact_force` (`geometry_msgs/WrenchStamped`, [`SENSOR`])
    pub contact_force: Publisher<msgs::WrenchStamped>,
    /// `/phri/repulsion` (`visualization_msgs/MarkerArray`, [`SENSOR`])
    pub repulsion: Publisher<msgs::MarkerArray>,
    /// `/phri/depth` (`sensor_msgs/Image`, [`IMAGE`])
    pub depth: Publisher<msgs::Image>,
    /// `/phri/points` (`sensor_msgs/PointCloud2`, [`IMAGE`])
    pub points: Publisher<msgs::PointCloud2>,
    /// `/humans/bodies/tracked` (`hri_msgs/IdsList`, [`RELIABLE`])
    pub humans: Publisher<msgs::IdsList>,
    /// `/phri/request` as taken (`std_msgs/String`, [`REQUESTS`])
    pub requests: Subscription<msgs::StringMsg>,
}

impl Topics {
    /// Every topic of the table on `node`.
    pub fn new(node: &mut Node) -> Result<Topics, String> {
        let joint_states = publisher::<msgs::JointState>(node, "/joint_states", JOINTS)?;
        let tf = publisher::<msgs::TfMessage>(node, "/tf", SENSOR)?;
        let status = publisher::<msgs::DiagnosticArray>(node, "/phri/status", RELIABLE)?;
        let contact_force = publisher::<msgs::WrenchStamped>(node, "/phri/contact_force", SENSOR)?;
        let repulsion = publisher::<msgs::MarkerArray>(node, "/phri/repulsion", SENSOR)?;
        let depth = publisher::<msgs::Image>(node, "/phri/depth", IMAGE)?;
        let points = publisher::<msgs::PointCloud2>(node, "/phri/points", IMAGE)?;
        let humans = publisher::<msgs::IdsList>(node, crate::humans::TRACKED_TOPIC, RELIABLE)?;
        let request_topic = node
            .create_topic(
                &Name::new("/phri", "request").map_err(|e| format!("ROS 2 topic: {e}"))?,
                MessageTypeName::new(msgs::StringMsg::PACKAGE, msgs::StringMsg::NAME),
                &RELIABLE,
            )
            .map_err(|e| format!("ROS 2 topic /phri/request: {e:?}"))?;
        let requests = node
            .create_subscription::<msgs::StringMsg>(&request_topic, Some(REQUESTS))
            .map_err(|e| format!("ROS 2 subscription of /phri/request: {e:?}"))?;
        Ok(Topics {
            joint_states,
            tf,
            status,
            contact_force,
            repulsion,
            depth,
            points,
            humans,
            requests,
        })
    }

    /// Which topics have at least one matched reader now (DDS discovery, as
    /// `node`'s discovery thread keeps it).
    pub fn subscribed(&self, node: &Node) -> Subscribed {
        Subscribed {
            joint_states: self.joint_states.get_subscription_count(node) > 0,
            tf: self.tf.get_subscription_count(node) > 0,
            status: self.status.get_subscription_count(node) > 0,
            contact_force: self.contact_force.get_subscription_count(node) > 0,
            repulsion: self.repulsion.get_subscription_count(node) > 0,
            depth: self.depth.get_subscription_count(node) > 0,
            points: self.points.get_subscription_count(node) > 0,
            humans: self.humans.get_subscription_count(node) > 0,
        }
    }

    /// The next `/phri/request` sample waiting: `Ok(None)` when none,
    /// `Err` (DDS's error, as text) for one DDS could not make a
    /// `std_msgs/String` of.
    pub fn take_request(&self) -> Result<Option<RequestSample>, String> {
        match self.requests.take() {
            Ok(Some((m, info))) => Ok(Some(RequestSample {
                peer: info.publisher_gid().to_bytes16(),
                text: m.data,
            })),
            Ok(None) => Ok(None),
            Err(e) => Err(format!("{e:?}")),
        }
    }
}

/// A publisher of `topic` (`/ns/name`; `name` alone is in `/`).
fn publisher<M: RosType + Serialize>(
    node: &mut Node,
    topic: &str,
    qos: QosProfile,
) -> Result<Publisher<M>, String> {
    let (ns, name) = topic.rsplit_once('/').unwrap_or(("", topic));
    let ns = if ns.is_empty() { "/" } else { ns };
    let name = Name::new(ns, name).map_err(|e| format!("ROS 2 topic {topic}: {e}"))?;
    let t = node
        .create_topic(&name, MessageTypeName::new(M::PACKAGE, M::NAME), &qos)
        .map_err(|e| format!("ROS 2 topic {topic}: {e:?}"))?;
    node.create_publisher::<M>(&t, None)
        .map_err(|e| format!("ROS 2 publisher of {topic}: {e:?}"))
}

/// Messages DDS refused to send (a full reliable window, a closed
/// participant): counted, not fatal, since ROS 2 is a viewer of the cell;
/// a warning at the 1st, 2nd, 4th, 8th, ... refusal.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub struct Unsent {
    /// messages refused since the bridge started
    pub count: u64,
}

impl Unsent {
    /// Publish `m` on `p`, counting a refusal instead of failing.
    pub fn send<M: Serialize>(&mut self, p: &Publisher<M>, m: M) {
        if p.publish(m).is_err() && self.refused() {
            tracing::warn!(
                "{} ROS 2 message(s) not sent (DDS refused them)",
                self.count
            );
        }
    }

    /// Count one refusal: whether a warning is due (at powers of two).
    fn refused(&mut self) -> bool {
        self.count += 1;
        self.count.is_power_of_two()
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn refusals_are_warned_of_ever_more_rarely() {
        let mut u = Unsent::default();
        let warned: Vec<u64> = (1..=20u64).filter(|_| u.refused()).collect();
        assert_eq!(warned, [1, 2, 4, 8, 16]);
        assert_eq!(u.count, 20);
    }
}
