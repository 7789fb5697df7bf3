//! Quality of service of the channels, and the node every process opens them with.

use iceoryx2::prelude::*;

use crate::error::IpcError;

/// Settings of one publish-subscribe service.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct Qos {
    /// publishers allowed at once (1 for every channel but the workers' results:
    /// one source of truth, one commander)
    pub max_publishers: usize,
    /// subscribers allowed at once
    pub max_subscribers: usize,
    /// largest queue a subscriber may ask for (evaluation readers drain at ~100 Hz)
    pub subscriber_max_buffer: usize,
    /// samples a late subscriber receives on connecting
    pub history: usize,
    /// a full subscriber queue drops its oldest sample for the newest
    /// (iceoryx2's safe overflow); `false`: the publisher waits up to
    /// [`DELIVERY_WAIT`] for the reader to make room, then leaves that reader
    /// out of this sample and counts it (`Publisher::undelivered`)
    pub overflow: bool,
}

/// How long a publisher of a channel that does not overflow waits for a
/// full reader to make room before it leaves that reader out of a sample:
/// 100 control periods (a controller that has not read its queue for that
/// long has let the arm brake after 20, and its standby is in charge; the
/// supervisor reads every 10 ms), short enough that a reader stopped for
/// good (a tool suspended in a terminal) delays a flood's requests, not
/// blocks them.
pub const DELIVERY_WAIT: std::time::Duration = std::time::Duration::from_millis(100);

impl Qos {
    /// One publisher, deep enough for an evaluation reader draining at 100 Hz.
    pub const ONE_PUBLISHER: Qos = Qos {
        max_publishers: 1,
        max_subscribers: 16,
        subscriber_max_buffer: 256,
        history: 1,
        overflow: true,
    };
    /// What the controller in charge publishes: the hot standby holds the
    /// second publisher, idle until it takes over.
    pub const CONTROLLERS: Qos = Qos {
        max_publishers: 2,
        ..Qos::ONE_PUBLISHER
    };
    /// A controller's behaviour state for its standby: one publisher, one
    /// reader that takes every one, waking every `[control] standby_wake_ms`
    /// (25 ms at most), no history (a restarted standby waits for the next
    /// period's).
    pub const BEHAVIOUR: Qos = Qos {
        max_subscribers: 8,
        subscriber_max_buffer: 32,
        history: 0,
        ..Qos::ONE_PUBLISHER
    };
    /// One publisher at 10 Hz.
    pub const SLOW: Qos = Qos {
        // every service reads supervisor/health (up to the supervisor's
        // roster of 32, `phri_config::MAX_ROSTER`), and the tools beside them
        max_subscribers: 48,
        subscriber_max_buffer: 8,
        ..Qos::ONE_PUBLISHER
    };
    /// Frames: a latest-value queue (the newest replaces an unread one), no history.
    pub const FRAMES: Qos = Qos {
        subscriber_max_buffer: 2,
        history: 0,
        ..Qos::ONE_PUBLISHER
    };
    /// One publisher per repulsion worker; small queues keep each worker's
    /// segment small (readers map it when a worker (re)starts).
    pub const WORKERS: Qos = Qos {
        max_publishers: 16,
        // both controllers, the supervisor, the ROS 2 bridge, the recorder,
        // the viewer, the monitor and spares
        max_subscribers: 16,
        subscriber_max_buffer: 32,
        history: 0,
        overflow: true,
    };
    /// People's requests (`hri/request`): several publishers (gesture,
    /// voice, the ROS 2 bridge, the command line), 256 deep, and no request
    /// is ever pushed out by a newer one: a publisher that finds a reader's
    /// queue full waits for it ([`DELIVERY_WAIT`] at most), so a flood from
    /// one publisher is slowed to the pace of the controllers, which empty
    /// their queue every period, and a `stop` after it still arrives.
    pub const REQUESTS: Qos = Qos {
        max_publishers: 16,
        max_subscribers: 16,
        subscriber_max_buffer: 256,
        history: 0,
        overflow: false,
    };
    /// Rare evaluation events: one publisher, a deep queue (1024 events, minutes
    /// of contact episodes), so that a stalled reader loses none.
    pub const EVENTS: Qos = Qos {
        max_publishers: 1,
        max_subscribers: 8,
        subscriber_max_buffer: 1024,
        history: 0,
        overflow: true,
    };
    /// Audio chunks (50 Hz): one capture source, 4 s of queue per reader
    /// (a decode takes tens of ms; nothing is lost), no history (a restarted
    /// recogniser hears from now on).
    pub const AUDIO: Qos = Qos {
        max_publishers: 1,
        max_subscribers: 8,
        subscriber_max_buffer: 200,
        history: 0,
        overflow: true,
    };
    /// Fault injection: one injector at a time; a restarted camera must not
    /// replay an old fault, so no history.
    pub const INJECTION: Qos = Qos {
        subscriber_max_buffer: 8,
        history: 0,
        ..Qos::ONE_PUBLISHER
    };
}

/// Digits of the longest id iceoryx2 writes into a resource name (a `u128` in decimal).
const ID_DIGITS: usize = 39;
/// What iceoryx2 puts between the prefix and a shared-memory resource's name:
/// the type's SHA-1 in hex and `_`.
const TYPE_HASH: usize = 41;
/// The longest resource name: a connection's, two ids joined by `_`.
const CONNECTION_NAME: usize = 2 * ID_DIGITS + 1;
/// Longest path of a Unix datagram socket (`sun_path` holds 108 bytes, its NUL included).
const SOCKET_PATH_MAX: usize = 107;

/// The longest prefix whose resources iceoryx2 can create under `config`
/// \[characters\]. Two of its limits bind: a listener's Unix socket
/// `<root><prefix><id>.event` must fit `sun_path` (with the default root
/// `/tmp/iceoryx2/`: 48 characters), and every shared-memory path
/// `<root><prefix><type hash>_<name><suffix>` iceoryx2's path capacity (255).
/// A longer prefix passes iceoryx2's own check but panics deep inside it when
/// a channel opens.
pub fn max_prefix_len(config: &Config) -> usize {
    let g = &config.global;
    let root = g.root_path().len();
    let event = g.service.event_connection_suffix.len();
    let suffix = [
        g.service.data_segment_suffix.len(),
        g.service.static_config_storage_suffix.len(),
        g.service.dynamic_config_storage_suffix.len(),
        g.service.connection_suffix.len(),
        g.service.event_connection_suffix.len(),
        g.service.blackboard_mgmt_suffix.len(),
        g.service.blackboard_data_suffix.len(),
        g.node.monitor_suffix.len(),
        g.node.static_config_suffix.len(),
        g.node.service_tag_suffix.len(),
        g.node.port_tag_suffix.len(),
    ]
    .into_iter()
    .max()
    .unwrap_or(0);
    let socket = SOCKET_PATH_MAX.saturating_sub(root + ID_DIGITS + event);
    let shm = Path::max_len().saturating_sub(root + TYPE_HASH + CONNECTION_NAME + suffix);
    socket.min(shm)
}

/// `prefix` as iceoryx2's file-name prefix, if it is one iceoryx2 can use
/// under `config`: characters it allows in file names (no `/`, no control
/// characters, not empty), at most [`max_prefix_len`] of them. Otherwise an
/// [`IpcError::Prefix`] naming it.
fn prefix_name(prefix: &str, config: &Config) -> Result<FileName, IpcError> {
    let refused = |detail: String| IpcError::Prefix {
        prefix: prefix.to_string(),
        detail,
    };
    let max = max_prefix_len(config);
    if prefix.len() > max {
        return Err(refused(format!(
            "{} characters, at most {max} fit the names iceoryx2 creates under {}",
            prefix.len(),
            config.global.root_path()
        )));
    }
    FileName::new(prefix.as_bytes()).map_err(|e| {
        refused(format!(
            "not a file-name prefix ({e:?}: no '/', no control characters, not empty)"
        ))
    })
}

/// Check a run's prefix as [`node`] will, without creating anything: for a
/// program that wants to refuse a bad `--prefix` before it writes or starts
/// anything.
pub fn check_prefix(prefix: &str) -> Result<(), IpcError> {
    prefix_name(prefix, &Config::default()).map(|_| ())
}

/// The iceoryx2 configuration of the cell of `prefix`: iceoryx2's defaults
/// with that prefix (what `config/iceoryx2.toml` holds for the default
/// prefix, so that `iox2` and the Python binding see the cell).
pub fn node_config(prefix: &str) -> Result<Config, IpcError> {
    let mut config = Config::default();
    config.global.prefix = prefix_name(prefix, &config)?;
    Ok(config)
}

/// Create a node whose shared-memory resources carry `prefix` (one per run, so
/// that parallel runs never collide). Signals are left to the process (signal-hook).
/// A prefix iceoryx2 cannot use ([`check_prefix`]) is an [`IpcError::Prefix`].
pub fn node(name: &str, prefix: &str) -> Result<Node<ipc::Service>, IpcError> {
    let config = node_config(prefix)?;
    let node_err = |e: &dyn std::fmt::Debug| IpcError::Node {
        node: name.to_string(),
        detail: format!("{e:?}"),
    };
    let node_name = NodeName::new(name).map_err(|e| node_err(&e))?;
    NodeBuilder::new()
        .name(&node_name)
        .config(&config)
        .signal_handling_mode(SignalHandlingMode::Disabled)
        .create::<ipc::Service>()
        .map_err(|e| node_err(&e))
}

/// Size of one 640×480 frame's payload, for frame channels.
pub const FRAME_PIXELS: usize = 640 * 480;
