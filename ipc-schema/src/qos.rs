//! Quality of service of every channel, and the only functions that open them,
//! so that every process opens a service with the same settings.

use std::fmt::Debug;

use iceoryx2::prelude::*;
use iceoryx2::service::builder::publish_subscribe::PublishSubscribeOpenError;
use iceoryx2::service::port_factory::{event, publish_subscribe};

use crate::names::*;

/// Settings of one publish-subscribe service.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct Qos {
    /// publishers allowed at once (1 for every channel: one source of truth, one commander)
    pub max_publishers: usize,
    pub max_subscribers: usize,
    /// largest queue a subscriber may ask for (evaluation readers drain at ~100 Hz)
    pub subscriber_max_buffer: usize,
    /// samples a late subscriber receives on connecting
    pub history: usize,
}

/// The QoS table.
pub fn qos(name: &str) -> Qos {
    let one_publisher = Qos {
        max_publishers: 1,
        max_subscribers: 16,
        subscriber_max_buffer: 256,
        history: 1,
    };
    match name {
        // the robot and its commander: exactly one publisher each
        ROBOT_STATE | ROBOT_COMMAND | DYNAMICS_RESIDUAL | CONTROL_STATUS | SIM_TRUTH => {
            one_publisher
        }
        ROBOT_STATS | SUPERVISOR_HEALTH => Qos {
            subscriber_max_buffer: 8,
            ..one_publisher
        },
        // frames: a latest-value queue (the newest replaces an unread one)
        CAMERA_DEPTH | PERCEPTION_DEPTH => Qos {
            subscriber_max_buffer: 2,
            history: 0,
            ..one_publisher
        },
        // one publisher per repulsion worker; small queues keep each worker's
        // segment small (readers map it when a worker (re)starts)
        PERCEPTION_REPULSION => Qos {
            max_publishers: 16,
            max_subscribers: 8,
            subscriber_max_buffer: 32,
            history: 0,
        },
        // fault injection: one injector at a time; a restarted camera must not
        // replay an old fault, so no history
        FAULT_DEPTH => Qos {
            subscriber_max_buffer: 8,
            history: 0,
            ..one_publisher
        },
        _ => one_publisher,
    }
}

/// Queue length a subscriber asks for: 1 (latest value) for control, deep for evaluation.
pub const LATEST: usize = 1;
pub const DRAIN: usize = 256;

/// Error opening a channel, naming it.
#[derive(Debug)]
pub struct IpcError {
    pub channel: String,
    pub what: String,
}

impl std::fmt::Display for IpcError {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        write!(f, "channel '{}': {}", self.channel, self.what)
    }
}

impl std::error::Error for IpcError {}

pub fn ipc_err(channel: &str, e: impl Debug) -> IpcError {
    IpcError {
        channel: channel.to_string(),
        what: format!("{e:?}"),
    }
}

/// Create a node whose shared-memory resources carry `prefix` (one per run, so
/// that parallel runs never collide). Signals are left to the process (signal-hook).
pub fn node(name: &str, prefix: &str) -> Result<Node<ipc::Service>, IpcError> {
    let mut config = Config::default();
    config.global.prefix = FileName::new(prefix.as_bytes())
        .map_err(|e| ipc_err("<node>", format!("invalid prefix '{prefix}': {e:?}")))?;
    let node_name = NodeName::new(name).map_err(|e| ipc_err("<node>", e))?;
    NodeBuilder::new()
        .name(&node_name)
        .config(&config)
        .signal_handling_mode(SignalHandlingMode::Disabled)
        .create::<ipc::Service>()
        .map_err(|e| ipc_err("<node>", e))
}

/// A publish-subscribe builder with the channel's QoS applied: the one place
/// every process (service or tool) configures a channel.
fn with_qos<P: Debug + IceoryxSend + ?Sized, H: Debug + ZeroCopySend>(
    b: PubSubBuilder<P, H>,
    name: &str,
) -> PubSubBuilder<P, H> {
    let q = qos(name);
    b.max_publishers(q.max_publishers)
        .max_subscribers(q.max_subscribers)
        .subscriber_max_buffer_size(q.subscriber_max_buffer)
        .history_size(q.history)
        .enable_safe_overflow(true)
}

type PubSubBuilder<P, H> =
    iceoryx2::service::builder::publish_subscribe::Builder<P, H, ipc::Service>;

/// Message channel port factory.
pub type MsgFactory<T> = publish_subscribe::PortFactory<ipc::Service, T, ()>;
/// Frame channel port factory: `[u16]` depths with a [`crate::FrameHeader`].
pub type FrameFactory = publish_subscribe::PortFactory<ipc::Service, [u16], crate::FrameHeader>;

fn service_name(name: &str) -> Result<ServiceName, IpcError> {
    name.try_into().map_err(|e| ipc_err(name, e))
}

/// Open (or create) the publish-subscribe service `name` with its QoS.
pub fn open_pubsub<T: Debug + ZeroCopySend>(
    node: &Node<ipc::Service>,
    name: &str,
) -> Result<MsgFactory<T>, IpcError> {
    with_qos(
        node.service_builder(&service_name(name)?)
            .publish_subscribe::<T>(),
        name,
    )
    .open_or_create()
    .map_err(|e| ipc_err(name, e))
}

/// Open `name` only if it exists, for tools that watch a cell and must never
/// create a channel: `Ok(None)` when it does not exist (yet).
pub fn open_existing_pubsub<T: Debug + ZeroCopySend>(
    node: &Node<ipc::Service>,
    name: &str,
) -> Result<Option<MsgFactory<T>>, IpcError> {
    match with_qos(
        node.service_builder(&service_name(name)?)
            .publish_subscribe::<T>(),
        name,
    )
    .open()
    {
        Ok(f) => Ok(Some(f)),
        Err(PublishSubscribeOpenError::DoesNotExist) => Ok(None),
        Err(e) => Err(ipc_err(name, e)),
    }
}

/// [`open_existing_pubsub`] for the frame channels.
pub fn open_existing_frames(
    node: &Node<ipc::Service>,
    name: &str,
) -> Result<Option<FrameFactory>, IpcError> {
    match with_qos(
        node.service_builder(&service_name(name)?)
            .publish_subscribe::<[u16]>()
            .user_header::<crate::FrameHeader>(),
        name,
    )
    .open()
    {
        Ok(f) => Ok(Some(f)),
        Err(PublishSubscribeOpenError::DoesNotExist) => Ok(None),
        Err(e) => Err(ipc_err(name, e)),
    }
}

/// The deepest queue a reader that drains `name` may have ([`DRAIN`], capped by the channel's QoS).
pub fn drain_buffer(name: &str) -> usize {
    DRAIN.clamp(1, qos(name).subscriber_max_buffer)
}

/// Open (or create) the event service `name` (wakes readers of the channel of the same name).
pub fn open_event(
    node: &Node<ipc::Service>,
    name: &str,
) -> Result<event::PortFactory<ipc::Service>, IpcError> {
    let service_name: ServiceName = name.try_into().map_err(|e| ipc_err(name, e))?;
    node.service_builder(&service_name)
        .event()
        .max_notifiers(4)
        .max_listeners(16)
        .open_or_create()
        .map_err(|e| ipc_err(name, e))
}

/// Subscriber port type of this project's channels.
pub type Sub<T> = iceoryx2::port::subscriber::Subscriber<ipc::Service, T, ()>;
/// Publisher port type of this project's channels.
pub type Pub<T> = iceoryx2::port::publisher::Publisher<ipc::Service, T, ()>;
pub type Listener = iceoryx2::port::listener::Listener<ipc::Service>;
pub type Notifier = iceoryx2::port::notifier::Notifier<ipc::Service>;

/// Subscribe to `name` with a queue of `buffer` samples ([`LATEST`] or
/// [`DRAIN`]; at most the channel's `subscriber_max_buffer`).
pub fn subscriber<T: Debug + ZeroCopySend>(
    node: &Node<ipc::Service>,
    name: &str,
    buffer: usize,
) -> Result<Sub<T>, IpcError> {
    let buffer = buffer.clamp(1, qos(name).subscriber_max_buffer);

    open_pubsub::<T>(node, name)?
        .subscriber_builder()
        .buffer_size(buffer)
        .create()
        .map_err(|e| ipc_err(name, e))
}

/// Publish on `name` (refused when the channel already has its publisher).
pub fn publisher<T: Debug + ZeroCopySend>(
    node: &Node<ipc::Service>,
    name: &str,
) -> Result<Pub<T>, IpcError> {
    open_pubsub::<T>(node, name)?
        .publisher_builder()
        .create()
        .map_err(|e| ipc_err(name, e))
}

/// Wake on new samples of `name`.
pub fn listener(node: &Node<ipc::Service>, name: &str) -> Result<Listener, IpcError> {
    open_event(node, name)?
        .listener_builder()
        .create()
        .map_err(|e| ipc_err(name, e))
}

/// Announce new samples of `name`.
pub fn notifier(node: &Node<ipc::Service>, name: &str) -> Result<Notifier, IpcError> {
    open_event(node, name)?
        .notifier_builder()
        .create()
        .map_err(|e| ipc_err(name, e))
}

/// Copy `value` into a loaned sample and send it.
pub fn publish<T: Debug + ZeroCopySend + Copy>(
    publisher: &Pub<T>,
    name: &str,
    value: &T,
) -> Result<(), IpcError> {
    let sample = publisher.loan_uninit().map_err(|e| ipc_err(name, e))?;
    sample
        .write_payload(*value)
        .send()
        .map(|_| ())
        .map_err(|e| ipc_err(name, e))
}

/// The newest sample of `name` (older queued ones are consumed), or `None`.
pub fn latest<T: Debug + ZeroCopySend + Copy>(
    subscriber: &Sub<T>,
    name: &str,
) -> Result<Option<T>, IpcError> {
    let mut out = None;
    while let Some(s) = subscriber.receive().map_err(|e| ipc_err(name, e))? {
        out = Some(*s);
    }
    Ok(out)
}

/// Size of one 640×480 frame's payload, for frame channels.
pub const FRAME_PIXELS: usize = 640 * 480;

/// Frame publisher port type: `[u16]` depths with a [`crate::FrameHeader`].
pub type FramePub = iceoryx2::port::publisher::Publisher<ipc::Service, [u16], crate::FrameHeader>;
/// Frame subscriber port type.
pub type FrameSub = iceoryx2::port::subscriber::Subscriber<ipc::Service, [u16], crate::FrameHeader>;

fn open_frames(node: &Node<ipc::Service>, name: &str) -> Result<FrameFactory, IpcError> {
    with_qos(
        node.service_builder(&service_name(name)?)
            .publish_subscribe::<[u16]>()
            .user_header::<crate::FrameHeader>(),
        name,
    )
    .open_or_create()
    .map_err(|e| ipc_err(name, e))
}

/// Publish frames of up to `max_pixels` on `name`.
pub fn frame_publisher(
    node: &Node<ipc::Service>,
    name: &str,
    max_pixels: usize,
) -> Result<FramePub, IpcError> {
    open_frames(node, name)?
        .publisher_builder()
        .initial_max_slice_len(max_pixels)
        .create()
        .map_err(|e| ipc_err(name, e))
}

/// Subscribe to frames on `name` (latest-value queue).
pub fn frame_subscriber(node: &Node<ipc::Service>, name: &str) -> Result<FrameSub, IpcError> {
    open_frames(node, name)?
        .subscriber_builder()
        .buffer_size(1)
        .create()
        .map_err(|e| ipc_err(name, e))
}
