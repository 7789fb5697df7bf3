//! What the bridge says in its log when it starts and when it ends: where
//! DDS reaches and which topics it serves, then how many messages of each
//! topic it published and what became of `/phri/request`.

use phri_config::Ros2Config;

use crate::discovery::DecidedBy;
use crate::Counts;

/// How far DDS reaches, for a log line: this host only (`local`), or every
/// interface.
pub fn reach(local: bool) -> &'static str {
    if local {
        "this host only (every DDS socket on 127.0.0.1)"
    } else {
        "every interface (subnet)"
    }
}

/// The bridge's first line: ROS 2's `domain`, how far DDS reaches
/// ([`reach`]) and what decided it, the topics (`/joint_states` with its
/// `joints`, `/humans/bodies/tracked` from `cameras` cameras) and whether
/// `/phri/request` is taken (`ros2`'s `accept_requests`, its rate).
pub fn started(
    domain: u16,
    local: bool,
    decided_by: DecidedBy,
    joints: usize,
    cameras: usize,
    ros2: &Ros2Config,
) -> String {
    format!(
        "on ROS 2 domain {domain}, {} ({}): /joint_states ({} joints), /tf, /phri/status, /phri/contact_force, /phri/repulsion, /phri/depth, /phri/points, /humans/bodies/tracked ({} camera(s)); /phri/request {}",
        reach(local),
        decided_by.name(),
        joints,
        cameras,
        if ros2.accept_requests {
            format!(
                "taken into hri/request, stops first, {} per s and {} at once per peer",
                ros2.requests_per_s, ros2.requests_burst
            )
        } else {
            "refused (ros2.accept_requests = false)".to_string()
        }
    )
}

/// The messages published per topic since the start (`c`), and the
/// `unsent` ones DDS refused.
pub fn published(c: &Counts, unsent: u64) -> String {
    format!(
        "published /joint_states {}, /tf {} (bodies {}), /phri/status {}, /phri/contact_force {}, /phri/repulsion {}, /phri/depth {}, /phri/points {}, /humans/bodies/tracked {}; {unsent} not sent",
        c.joint_states, c.tf, c.bodies_tf, c.status, c.contact_force, c.repulsion, c.depth, c.points, c.humans
    )
}

/// What became of `/phri/request` since the start (`c`).
pub fn requests(c: &Counts) -> String {
    format!(
        "/phri/request: passed {} (stops {}), refused {}, dropped {} (over the rate limit), malformed {}",
        c.requests, c.requests_stops, c.requests_refused, c.requests_dropped, c.requests_malformed
    )
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn the_first_line_says_where_dds_reaches_and_what_is_taken() {
        let mut cfg = phri_config::Config::defaults().ros2;
        cfg.accept_requests = false;
        let line = started(3, true, DecidedBy::Config, 7, 2, &cfg);
        assert!(line.starts_with(
            "on ROS 2 domain 3, this host only (every DDS socket on 127.0.0.1) (ros2.discovery): /joint_states (7 joints), /tf,"
        ), "{line}");
        assert!(line.ends_with(
            "/humans/bodies/tracked (2 camera(s)); /phri/request refused (ros2.accept_requests = false)"
        ), "{line}");
        (cfg.accept_requests, cfg.requests_per_s, cfg.requests_burst) = (true, 2.5, 4);
        let line = started(0, false, DecidedBy::RangeVar, 7, 1, &cfg);
        assert!(
            line.contains("every interface (subnet) (ROS_AUTOMATIC_DISCOVERY_RANGE)"),
            "{line}"
        );
        assert!(line.ends_with(
            "/phri/request taken into hri/request, stops first, 2.5 per s and 4 at once per peer"
        ), "{line}");
    }

    #[test]
    fn the_last_lines_count_every_topic_and_every_request() {
        let c = Counts {
            joint_states: 1,
            tf: 2,
            bodies_tf: 3,
            status: 4,
            contact_force: 5,
            repulsion: 6,
            depth: 7,
            points: 8,
            humans: 9,
            requests: 10,
            requests_stops: 11,
            requests_refused: 12,
            requests_dropped: 13,
            requests_malformed: 14,
        };
        assert_eq!(
            published(&c, 15),
            "published /joint_states 1, /tf 2 (bodies 3), /phri/status 4, /phri/contact_force 5, /phri/repulsion 6, /phri/depth 7, /phri/points 8, /humans/bodies/tracked 9; 15 not sent"
        );
        assert_eq!(
            requests(&c),
            "/phri/request: passed 10 (stops 11), refused 12, dropped 13 (over the rate limit), malformed 14"
        );
    }
}
