//! `phri-ros2`: the cell on ROS 2's wire. Reads `robot/state`,
//! `control/status`, `collab/state`, `dynamics/residual`,
//! `perception/repulsion` and `perception/depth` and publishes them as ROS
//! 2 topics over DDS ([`phri_ros2`]'s table); takes `/phri/request` into
//! `hri/request` when `[ros2] accept_requests` is set. ROS 2's domain:
//! `ROS_DOMAIN_ID` (default 0); this host only with
//! `ROS_AUTOMATIC_DISCOVERY_RANGE=LOCALHOST` or `ROS_LOCALHOST_ONLY=1`. Off the torque loop's CPUs, under the
//! normal scheduler: DDS's threads never compete with the 1 kHz loop, and a
//! slow or absent ROS 2 subscriber never slows a phri service (best-effort
//! writers never wait; reliable ones give up at once when full).

use std::error::Error;
use std::process::ExitCode;
use std::time::Duration;

use phri_ipc::{
    Queue, COLLAB_STATE, CONTROL_STATUS, DYNAMICS_RESIDUAL, HRI_REQUEST, PERCEPTION_DEPTH,
    PERCEPTION_REPULSION, ROBOT_STATE,
};
use phri_ros2::msgs::{self, RosType};
use phri_ros2::{Bridge, Clock, Subscribed};
use phri_runtime::{now_ns, ServiceContext};
use ros2_client::dds::rustdds::DomainParticipantBuilder;
use ros2_client::{
    qos::{History, WhenFull},
    Context, MessageTypeName, Name, Node, NodeName, NodeOptions, Publisher, QosProfile,
};
use serde::Serialize;

/// Sensor data: best effort, the newest few.
const SENSOR: QosProfile =
    QosProfile::subscription_default().history(History::KeepLast { depth: 5 });
/// `/joint_states` at up to 1 kHz: best effort, a send queue of 0.2 s (a
/// shorter one loses states whenever DDS's sending thread waits a few ms)
const JOINTS: QosProfile =
    QosProfile::subscription_default().history(History::KeepLast { depth: 200 });
/// Images and clouds: best effort, only the newest.
const IMAGE: QosProfile =
    QosProfile::subscription_default().history(History::KeepLast { depth: 1 });
/// Status and requests: reliable, a writer whose window is full drops at
/// once instead of waiting.
const RELIABLE: QosProfile = QosProfile::publisher_default()
    .reliability_reliable(WhenFull::Fail)
    .history(History::KeepLast { depth: 10 });

/// The log filter when `RUST_LOG` is unset: the services' own, with
/// RustDDS from `error` up (restricted to the loopback, it warns at every
/// send that its own builtin readers have no other locators), and
/// ros2-client's node silent (it logs an error each time a publisher not
/// yet matched is asked for its subscribers).
const LOG_FILTER: &str = "info,rustdds=error,ros2_client=warn,ros2_client::node=off";

/// How often the topics' matched subscribers are read from DDS discovery.
const SUBSCRIBED_EVERY: Duration = Duration::from_millis(100);
/// Without a `/joint_states` subscriber, `robot/state` is read in batches
/// this far apart instead of at every state (no 1 kHz wake-ups).
const BATCH: Duration = Duration::from_millis(10);

fn main() -> ExitCode {
    if std::env::var("RUST_LOG").map_or(true, |f| f.trim().is_empty()) {
        // before any thread starts (edition 2021: safe to call here)
        std::env::set_var("RUST_LOG", LOG_FILTER);
    }
    phri_runtime::service::run("phri-ros2", body)
}

/// ROS 2's domain from `ROS_DOMAIN_ID` (unset or empty: 0).
fn domain_id() -> Result<u16, String> {
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

fn publisher<M: RosType + Serialize>(
    node: &mut Node,
    topic: &str,
    qos: QosProfile,
) -> Result<Publisher<M>, Box<dyn Error>> {
    let (ns, name) = topic.rsplit_once('/').unwrap_or(("", topic));
    let ns = if ns.is_empty() { "/" } else { ns };
    let name = Name::new(ns, name).map_err(|e| format!("ROS 2 topic {topic}: {e}"))?;
    let t = node
        .create_topic(&name, MessageTypeName::new(M::PACKAGE, M::NAME), &qos)
        .map_err(|e| format!("ROS 2 topic {topic}: {e:?}"))?;
    Ok(node
        .create_publisher::<M>(&t, None)
        .map_err(|e| format!("ROS 2 publisher of {topic}: {e:?}"))?)
}

/// Publish, counting what DDS refused (a full reliable window, a closed
/// participant) instead of failing: ROS 2 is a viewer of the cell.
fn send<M: Serialize>(p: &Publisher<M>, m: M, failed: &mut u64) {
    if p.publish(m).is_err() {
        *failed += 1;
        if failed.is_power_of_two() {
            tracing::warn!("{failed} ROS 2 message(s) not sent (DDS refused them)");
        }
    }
}

/// How far DDS looks for peers, as ROS 2 says it: `ROS_AUTOMATIC_DISCOVERY_RANGE`
/// (`LOCALHOST`, `SUBNET`, the default, or `OFF`; Iron and later) or, before
/// it, `ROS_LOCALHOST_ONLY=1`. `true`: this host's loopback only.
fn localhost_only() -> Result<bool, String> {
    if let Ok(r) = std::env::var("ROS_AUTOMATIC_DISCOVERY_RANGE") {
        return match r.trim().to_ascii_uppercase().as_str() {
            "" | "SUBNET" | "SYSTEM_DEFAULT" => Ok(false),
            "LOCALHOST" | "OFF" => Ok(true),
            _ => Err(format!(
                "ROS_AUTOMATIC_DISCOVERY_RANGE: '{r}' is not LOCALHOST, SUBNET or OFF"
            )),
        };
    }
    Ok(std::env::var("ROS_LOCALHOST_ONLY").is_ok_and(|v| v.trim() == "1"))
}

/// CLOCK_REALTIME [ns].
fn realtime_ns() -> u64 {
    std::time::SystemTime::now()
        .duration_since(std::time::UNIX_EPOCH)
        .map(|d| d.as_nanos() as u64)
        .unwrap_or(0)
}

fn body() -> Result<(), Box<dyn Error>> {
    let (ctx, phri_runtime::cli::NoExtra {}) = ServiceContext::from_cli(
        "phri-ros2",
        "ros2",
        "The cell as ROS 2 topics over DDS (/joint_states, /tf, /phri/*) and /phri/request into hri/request",
    )?;
    let mut bridge = Bridge::new(ctx.config(), ctx.robot_model()?)?;
    let domain = domain_id()?;
    let local = localhost_only()?;
    if ctx.checking() {
        return Ok(());
    }
    phri_viz::cpu::keep_off_the_loop(ctx.config());
    // DDS's own threads start here, under the normal scheduler, off the loop's CPUs
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
    let mut ros = dds
        .new_node(
            NodeName::new("/", "phri").map_err(|e| format!("ROS 2 node name: {e}"))?,
            NodeOptions::new().enable_rosout(false),
        )
        .map_err(|e| format!("ROS 2 node: {e:?}"))?;
    let joint_states = publisher::<msgs::JointState>(&mut ros, "/joint_states", JOINTS)?;
    let tf = publisher::<msgs::TfMessage>(&mut ros, "/tf", SENSOR)?;
    let status = publisher::<msgs::DiagnosticArray>(&mut ros, "/phri/status", RELIABLE)?;
    let force = publisher::<msgs::WrenchStamped>(&mut ros, "/phri/contact_force", SENSOR)?;
    let repulsion = publisher::<msgs::MarkerArray>(&mut ros, "/phri/repulsion", SENSOR)?;
    let depth = publisher::<msgs::Image>(&mut ros, "/phri/depth", IMAGE)?;
    let points = publisher::<msgs::PointCloud2>(&mut ros, "/phri/points", IMAGE)?;
    let request_topic = ros
        .create_topic(
            &Name::new("/phri", "request").map_err(|e| format!("ROS 2 topic: {e}"))?,
            MessageTypeName::new(msgs::StringMsg::PACKAGE, msgs::StringMsg::NAME),
            &RELIABLE,
        )
        .map_err(|e| format!("ROS 2 topic /phri/request: {e:?}"))?;
    let requests_in = ros
        .create_subscription::<msgs::StringMsg>(&request_topic, None)
        .map_err(|e| format!("ROS 2 subscription of /phri/request: {e:?}"))?;

    // ROS 2's discovery (matched subscribers, ros_discovery_info) runs on a
    // thread of its own
    let spinner = ros
        .spinner()
        .map_err(|e| format!("ROS 2 node's discovery: {e:?}"))?;
    std::thread::Builder::new()
        .name("ros2-discovery".into())
        .spawn(move || {
            if let Err(e) = futures::executor::block_on(spinner.spin()) {
                tracing::warn!("ROS 2 discovery stopped: {e:?}");
            }
        })?;

    ctx.start_deadman()?;
    let node = ctx.node()?;
    let states = ROBOT_STATE.waking_subscriber(&node, Queue::Drain)?;
    let control = CONTROL_STATUS.subscriber(&node, Queue::Latest)?;
    let collab = COLLAB_STATE.subscriber(&node, Queue::Latest)?;
    let residual = DYNAMICS_RESIDUAL.subscriber(&node, Queue::Latest)?;
    let results = PERCEPTION_REPULSION.subscriber(&node, Queue::Drain)?;
    let frames = PERCEPTION_DEPTH.frame_subscriber(&node, Queue::Latest)?;
    let requests_out = HRI_REQUEST.publisher(&node)?;
    let mut beat = ctx.beat(&node)?;
    tracing::info!(
        "on ROS 2 domain {domain}{}: /joint_states ({} joints), /tf, /phri/status, /phri/contact_force, /phri/repulsion, /phri/depth, /phri/points; /phri/request {}",
        if local { " (this host only)" } else { "" },
        bridge.joint_names().len(),
        if ctx.config().ros2.accept_requests { "taken into hri/request" } else { "refused (ros2.accept_requests = false)" }
    );

    let (mut newest_control, mut newest_collab, mut newest_residual) = (None, None, None);
    let mut last_frame = 0u64;
    let mut failed = 0u64;
    let mut subscribed_at: Option<std::time::Instant> = None;
    while !ctx.shutdown.requested() {
        if subscribed_at.is_none_or(|t| t.elapsed() >= SUBSCRIBED_EVERY) {
            subscribed_at = Some(std::time::Instant::now());
            let was = bridge.subscribed;
            bridge.subscribed = Subscribed {
                joint_states: joint_states.get_subscription_count(&ros) > 0,
                tf: tf.get_subscription_count(&ros) > 0,
                status: status.get_subscription_count(&ros) > 0,
                contact_force: force.get_subscription_count(&ros) > 0,
                repulsion: repulsion.get_subscription_count(&ros) > 0,
                depth: depth.get_subscription_count(&ros) > 0,
                points: points.get_subscription_count(&ros) > 0,
            };
            if bridge.subscribed != was {
                tracing::info!("subscribed on ROS 2: {:?}", bridge.subscribed);
            }
        }
        if bridge.subscribed.every_state() {
            // every robot state wakes us; without states, a poll every 20 ms
            let _ = states.wait(Duration::from_millis(20));
        } else {
            std::thread::sleep(BATCH);
            // consume the wake-ups that came meanwhile
            let _ = states.wait(Duration::ZERO);
        }
        let now = now_ns();
        beat.beat(now);
        let clock = Clock::new(now, realtime_ns());
        states.drain(|s| {
            let out = bridge.state(s, &clock);
            if let Some(js) = out.joint_state {
                send(&joint_states, js.clone(), &mut failed);
            }
            if let Some(t) = out.tf {
                send(&tf, t, &mut failed);
            }
        })?;
        newest_control = control.latest()?.or(newest_control);
        newest_collab = collab.latest()?.or(newest_collab);
        newest_residual = residual.latest()?.or(newest_residual);
        if let Some(m) = bridge.status(
            now,
            &clock,
            newest_control.as_ref(),
            newest_collab.as_ref(),
            newest_residual.as_ref(),
        ) {
            send(&status, m, &mut failed);
        }
        if let Some(m) = bridge.contact_force(now, &clock, newest_collab.as_ref()) {
            send(&force, m, &mut failed);
        }
        results.drain(|r| bridge.result(r))?;
        if let Some(m) = bridge.repulsion(now, &clock) {
            send(&repulsion, m, &mut failed);
        }
        if let Some(f) = frames.latest()? {
            let h = f.user_header();
            if h.seq != last_frame {
                last_frame = h.seq;
                let out = bridge.frame(h, f.payload(), &clock);
                if let Some(img) = out.image {
                    send(&depth, img.clone(), &mut failed);
                }
                if let Some(pc) = out.points {
                    send(&points, pc.clone(), &mut failed);
                }
                if let Some(t) = out.camera_tf {
                    send(&tf, t, &mut failed);
                }
            }
        }
        while let Ok(Some((m, _info))) = requests_in.take() {
            match bridge.request(&m.data, now_ns()) {
                Ok(r) => {
                    requests_out.publish(&r)?;
                    tracing::info!("/phri/request '{}': on hri/request", m.data.trim());
                }
                Err(e) => tracing::warn!("/phri/request '{}' refused: {e}", m.data.trim()),
            }
        }
    }
    let c = &bridge.counts;
    tracing::info!(
        "published /joint_states {}, /tf {}, /phri/status {}, /phri/contact_force {}, /phri/repulsion {}, /phri/depth {}, /phri/points {}; requests {} passed, {} refused; {failed} not sent",
        c.joint_states, c.tf, c.status, c.contact_force, c.repulsion, c.depth, c.points, c.requests, c.requests_refused
    );
    Ok(())
}
