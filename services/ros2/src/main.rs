//! `phri-ros2`: the cell on ROS 2's wire. Reads `robot/state`,
//! `control/status`, `collab/state`, `dynamics/residual`,
//! `perception/repulsion`, `perception/depth` and every camera's
//! `perception/skeleton` and publishes them as ROS 2 topics over DDS
//! ([`phri_ros2`]'s table; the people as ROS4HRI does); takes `/phri/request` into
//! `hri/request` when `[ros2] accept_requests` is set, stops first and each
//! peer within its rate. ROS 2's domain: `ROS_DOMAIN_ID` (default 0). This
//! host only unless `[ros2] discovery = "subnet"`: every DDS socket bound to
//! 127.0.0.1 (ROS 2's `ROS_AUTOMATIC_DISCOVERY_RANGE` or
//! `ROS_LOCALHOST_ONLY=1` overrides the configuration, [`phri_ros2::discovery`]).
//! Off the torque loop's CPUs, under the
//! normal scheduler: DDS's threads never compete with the 1 kHz loop, and a
//! slow or absent ROS 2 subscriber never slows a phri service (best-effort
//! writers never wait; reliable ones give up at once when full).

use std::error::Error;
use std::process::ExitCode;
use std::time::Duration;

use phri_config::ros2::Ros2Discovery;
use phri_ipc::{
    Queue, COLLAB_STATE, CONTROL_STATUS, DYNAMICS_RESIDUAL, HRI_REQUEST, PERCEPTION_DEPTH,
    PERCEPTION_REPULSION, ROBOT_STATE, ROS2_REQUESTS,
};
use phri_ros2::gate::{shown, RefusalLog};
use phri_ros2::msgs::{self, RosType};
use phri_ros2::participant::{domain_id, participant, realtime_ns};
use phri_ros2::{Bridge, Clock, RefusalKind, RequestSample, Subscribed};
use phri_runtime::{now_ns, ServiceContext};
use ros2_client::{
    qos::{History, WhenFull},
    MessageTypeName, Name, Node, NodeName, NodeOptions, Publisher, QosProfile,
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
/// `/phri/request` as read: reliable, the newest 64 samples between two
/// takes (one every 1-20 ms): a flood of one peer has to outrun that to
/// push another's stop out before the bridge sees it.
const REQUESTS: QosProfile = QosProfile::publisher_default()
    .reliability_reliable(WhenFull::Fail)
    .history(History::KeepLast { depth: 64 });
/// `/phri/request` samples taken per loop at most (the rest wait for the next).
const MAX_REQUESTS_PER_LOOP: usize = 256;

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
/// How often `ros2/requests` tells the supervisor what became of `/phri/request`.
const REQUESTS_AUDIT_EVERY: Duration = Duration::from_millis(500);

fn main() -> ExitCode {
    if std::env::var("RUST_LOG").map_or(true, |f| f.trim().is_empty()) {
        // before any thread starts (edition 2021: safe to call here)
        std::env::set_var("RUST_LOG", LOG_FILTER);
    }
    phri_runtime::service::run("phri-ros2", body)
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

fn body() -> Result<(), Box<dyn Error>> {
    let (ctx, phri_runtime::cli::NoExtra {}) = ServiceContext::from_cli(
        "phri-ros2",
        "ros2",
        "The cell as ROS 2 topics over DDS (/joint_states, /tf, /phri/*, /humans/bodies/tracked) and /phri/request into hri/request",
    )?;
    let mut bridge = Bridge::new(ctx.config(), ctx.robot_model()?)?;
    let domain = domain_id()?;
    let (reach, decided_by) = phri_ros2::participant::reach(ctx.config())?;
    let local = reach == Ros2Discovery::Localhost;
    if ctx.checking() {
        return Ok(());
    }
    phri_viz::cpu::keep_off_the_loop(ctx.config());
    // DDS's own threads start here, under the normal scheduler, off the
    // loop's CPUs; with `localhost` RustDDS (patches/rustdds) binds every
    // socket to 127.0.0.1, which the kernel's table confirms
    let dds = participant(domain, local)?;
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
    let humans = publisher::<msgs::IdsList>(&mut ros, phri_ros2::humans::TRACKED_TOPIC, RELIABLE)?;
    let request_topic = ros
        .create_topic(
            &Name::new("/phri", "request").map_err(|e| format!("ROS 2 topic: {e}"))?,
            MessageTypeName::new(msgs::StringMsg::PACKAGE, msgs::StringMsg::NAME),
            &RELIABLE,
        )
        .map_err(|e| format!("ROS 2 topic /phri/request: {e:?}"))?;
    let requests_in = ros
        .create_subscription::<msgs::StringMsg>(&request_topic, Some(REQUESTS))
        .map_err(|e| format!("ROS 2 subscription of /phri/request: {e:?}"))?;

    // ROS 2's discovery (matched subscribers, ros_discovery_info) runs on a
    // thread of its own
    phri_ros2::participant::spin_discovery(&mut ros)?;

    ctx.start_deadman()?;
    let node = ctx.node()?;
    let states = ROBOT_STATE.waking_subscriber(&node, Queue::Drain)?;
    let control = CONTROL_STATUS.subscriber(&node, Queue::Latest)?;
    let collab = COLLAB_STATE.subscriber(&node, Queue::Latest)?;
    let residual = DYNAMICS_RESIDUAL.subscriber(&node, Queue::Latest)?;
    let results = PERCEPTION_REPULSION.subscriber(&node, Queue::Drain)?;
    let frames = PERCEPTION_DEPTH.frame_subscriber(&node, Queue::Latest)?;
    let skeletons = phri_ipc::cameras(ctx.config().cameras.len())
        .iter()
        .map(|c| c.skeleton.subscriber(&node, Queue::Drain))
        .collect::<Result<Vec<_>, _>>()?;
    let requests_out = HRI_REQUEST.publisher(&node)?;
    let requests_audit = ROS2_REQUESTS.publisher(&node)?;
    let mut audited_at = std::time::Instant::now();
    let mut beat = ctx.beat(&node)?;
    tracing::info!(
        "on ROS 2 domain {domain}, {} ({}): /joint_states ({} joints), /tf, /phri/status, /phri/contact_force, /phri/repulsion, /phri/depth, /phri/points, /humans/bodies/tracked ({} camera(s)); /phri/request {}",
        if local { "this host only (every DDS socket on 127.0.0.1)" } else { "every interface (subnet)" },
        decided_by.name(),
        bridge.joint_names().len(),
        skeletons.len(),
        if ctx.config().ros2.accept_requests {
            format!(
                "taken into hri/request, stops first, {} per s and {} at once per peer",
                ctx.config().ros2.requests_per_s,
                ctx.config().ros2.requests_burst
            )
        } else {
            "refused (ros2.accept_requests = false)".to_string()
        }
    );

    let (mut newest_control, mut newest_collab, mut newest_residual) = (None, None, None);
    let mut last_frame = 0u64;
    let mut failed = 0u64;
    let mut subscribed_at: Option<std::time::Instant> = None;
    let mut refusals = RefusalLog::default();
    let mut batch: Vec<RequestSample> = Vec::new();
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
                humans: humans.get_subscription_count(&ros) > 0,
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
        for (camera, skeleton) in skeletons.iter().enumerate() {
            skeleton.drain(|s| {
                let out = bridge.skeleton(camera, s, &clock);
                if let Some(m) = out.tracked {
                    send(&humans, m, &mut failed);
                }
                if let Some(t) = out.tf {
                    send(&tf, t, &mut failed);
                }
            })?;
        }
        // /phri/request: every sample waiting (up to a bound), stops first
        batch.clear();
        let now = now_ns();
        for _ in 0..MAX_REQUESTS_PER_LOOP {
            match requests_in.take() {
                Ok(Some((m, info))) => batch.push(RequestSample {
                    peer: info.publisher_gid().to_bytes16(),
                    text: m.data,
                }),
                Ok(None) => break,
                Err(e) => {
                    bridge.malformed_request();
                    let why = format!("malformed sample ({})", shown(&format!("{e:?}")));
                    if let Some(line) = refusals.note(RefusalKind::Malformed, "", &why, now) {
                        tracing::warn!("{line}");
                    }
                }
            }
        }
        for (i, result) in bridge.requests(&batch, now) {
            let text = &batch[i].text;
            match result {
                Ok(r) => {
                    requests_out.publish(&r)?;
                    tracing::info!("/phri/request '{}': on hri/request", shown(text.trim()));
                }
                Err(e) => {
                    if let Some(line) = refusals.note(e.kind(), text, &e.to_string(), now) {
                        tracing::warn!("{line}");
                    }
                }
            }
        }
        if let Some(line) = refusals.flush(now) {
            tracing::warn!("{line}");
        }
        if audited_at.elapsed() >= REQUESTS_AUDIT_EVERY {
            audited_at = std::time::Instant::now();
            requests_audit.publish(&bridge.requests_message(now, requests_out.undelivered()))?;
        }
    }
    requests_audit.publish(&bridge.requests_message(now_ns(), requests_out.undelivered()))?;
    let c = &bridge.counts;
    tracing::info!(
        "published /joint_states {}, /tf {} (bodies {}), /phri/status {}, /phri/contact_force {}, /phri/repulsion {}, /phri/depth {}, /phri/points {}, /humans/bodies/tracked {}; {failed} not sent",
        c.joint_states, c.tf, c.bodies_tf, c.status, c.contact_force, c.repulsion, c.depth, c.points, c.humans
    );
    tracing::info!(
        "/phri/request: passed {} (stops {}), refused {}, dropped {} (over the rate limit), malformed {}",
        c.requests, c.requests_stops, c.requests_refused, c.requests_dropped, c.requests_malformed
    );
    Ok(())
}
