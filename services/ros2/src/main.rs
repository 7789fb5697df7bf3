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
//! writers never wait; reliable ones give up at once when full). The loop is
//! [`phri_ros2::service`]; this only wires it.

use std::error::Error;
use std::process::ExitCode;

use phri_config::ros2::Ros2Discovery;
use phri_ipc::{
    Queue, COLLAB_STATE, CONTROL_STATUS, DYNAMICS_RESIDUAL, HRI_REQUEST, PERCEPTION_DEPTH,
    PERCEPTION_REPULSION, ROBOT_STATE, ROS2_REQUESTS,
};
use phri_ros2::participant::{domain_id, participant, LOG_FILTER};
use phri_ros2::service::{Ports, Service};
use phri_ros2::topics::Topics;
use phri_ros2::{report, Bridge};
use phri_runtime::ServiceContext;
use ros2_client::{NodeName, NodeOptions};

fn main() -> ExitCode {
    if std::env::var("RUST_LOG").map_or(true, |f| f.trim().is_empty()) {
        // before any thread starts (edition 2021: safe to call here)
        std::env::set_var("RUST_LOG", LOG_FILTER);
    }
    phri_runtime::service::run("phri-ros2", body)
}

fn body() -> Result<(), Box<dyn Error>> {
    let (ctx, phri_runtime::cli::NoExtra {}) = ServiceContext::from_cli(
        "phri-ros2",
        "ros2",
        "The cell as ROS 2 topics over DDS (/joint_states, /tf, /phri/*, /humans/bodies/tracked) and /phri/request into hri/request",
    )?;
    let bridge = Bridge::new(ctx.config(), ctx.robot_model()?)?;
    let domain = domain_id()?;
    let (reach, decided_by) = phri_ros2::participant::reach(ctx.config())?;
    let local = reach == Ros2Discovery::Localhost;
    if ctx.checking() {
        return Ok(());
    }
    phri_runtime::placement::keep_off_the_loop(ctx.config());
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
    let topics = Topics::new(&mut ros)?;
    // ROS 2's discovery (matched subscribers, ros_discovery_info) runs on a
    // thread of its own
    phri_ros2::participant::spin_discovery(&mut ros)?;

    ctx.start_deadman()?;
    let node = ctx.node()?;
    let ports = Ports {
        states: ROBOT_STATE.waking_subscriber(&node, Queue::Drain)?,
        control: CONTROL_STATUS.latest_reader(&node)?,
        collab: COLLAB_STATE.latest_reader(&node)?,
        residual: DYNAMICS_RESIDUAL.latest_reader(&node)?,
        results: PERCEPTION_REPULSION.subscriber(&node, Queue::Drain)?,
        frames: PERCEPTION_DEPTH.frame_subscriber(&node, Queue::Latest)?,
        skeletons: phri_ipc::cameras(ctx.config().cameras.len())
            .iter()
            .map(|c| c.skeleton.subscriber(&node, Queue::Drain))
            .collect::<Result<Vec<_>, _>>()?,
        requests: HRI_REQUEST.publisher(&node)?,
        audit: ROS2_REQUESTS.publisher(&node)?,
    };
    let mut beat = ctx.beat(&node)?;
    let (joints, cameras) = (bridge.joint_names().len(), ports.skeletons.len());
    let cfg = &ctx.config().ros2;
    tracing::info!(
        "{}",
        report::started(domain, local, decided_by, joints, cameras, cfg)
    );

    let mut service = Service::new(bridge, topics, ports);
    while !ctx.shutdown.requested() {
        service.step(&ros, &mut beat)?;
    }
    service.finish()?;
    Ok(())
}
