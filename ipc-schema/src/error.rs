//! Errors of the shared-memory layer, each naming the channel at fault.

use std::fmt::Debug;

/// Why a channel could not be opened, written or read.
#[derive(Debug, thiserror::Error)]
pub enum IpcError {
    /// the node (this process's handle on the run's shared memory) could not be created
    #[error("iceoryx2 node '{node}': {detail}")]
    Node {
        /// the node's name
        node: String,
        /// iceoryx2's error
        detail: String,
    },
    /// the run's prefix is not a valid file-name prefix
    #[error("prefix '{prefix}': {detail}")]
    Prefix {
        /// the prefix refused
        prefix: String,
        /// why: too long for the names iceoryx2 creates, or not a file-name prefix
        detail: String,
    },
    /// the channel's service could not be opened or created (e.g. another
    /// process created it with another type or QoS)
    #[error("channel '{channel}': {detail}")]
    Open {
        /// the channel's name
        channel: &'static str,
        /// iceoryx2's error
        detail: String,
    },
    /// the channel already has as many publishers as it accepts
    #[error("channel '{channel}': refused a publisher: it accepts {max} and has them (another process already publishes here?) ({detail})")]
    PublisherTaken {
        /// the channel's name
        channel: &'static str,
        /// publishers the channel accepts (its QoS)
        max: usize,
        /// iceoryx2's error
        detail: String,
    },
    /// a port (subscriber, listener, notifier) could not be created
    #[error("channel '{channel}': {detail}")]
    Port {
        /// the channel's name
        channel: &'static str,
        /// iceoryx2's error
        detail: String,
    },
    /// a sample could not be loaned, filled or sent
    #[error("channel '{channel}': send: {detail}")]
    Send {
        /// the channel's name
        channel: &'static str,
        /// iceoryx2's error, or the sizes that disagree
        detail: String,
    },
    /// a sample could not be received, or waiting for one failed
    #[error("channel '{channel}': receive: {detail}")]
    Receive {
        /// the channel's name
        channel: &'static str,
        /// iceoryx2's error, or the sizes that disagree
        detail: String,
    },
    /// a liveness service (`liveness/<service>`), its port or its WaitSet failed
    #[error("liveness of '{service}': {detail}")]
    Liveness {
        /// the service watched or beating (`waitset`, `tick`: the watcher's own)
        service: String,
        /// iceoryx2's error
        detail: String,
    },
    /// an event port was asked of a channel that does not wake its readers
    #[error("channel '{channel}' does not wake its readers (no event service)")]
    NoEvent {
        /// the channel's name
        channel: &'static str,
    },
    /// a channel name that is not one of the cell's
    #[error("channel '{0}': not a channel of the cell")]
    Unknown(String),
}

impl IpcError {
    pub(crate) fn open(channel: &'static str, e: impl Debug) -> IpcError {
        IpcError::Open {
            channel,
            detail: format!("{e:?}"),
        }
    }

    pub(crate) fn port(channel: &'static str, e: impl Debug) -> IpcError {
        IpcError::Port {
            channel,
            detail: format!("{e:?}"),
        }
    }

    pub(crate) fn publisher(
        channel: &'static str,
        max: usize,
        e: iceoryx2::port::publisher::PublisherCreateError,
    ) -> IpcError {
        let detail = format!("{e:?}");
        match e {
            iceoryx2::port::publisher::PublisherCreateError::ExceedsMaxSupportedPublishers => {
                IpcError::PublisherTaken {
                    channel,
                    max,
                    detail,
                }
            }
            _ => IpcError::Port { channel, detail },
        }
    }

    pub(crate) fn send(channel: &'static str, e: impl Debug) -> IpcError {
        IpcError::Send {
            channel,
            detail: format!("{e:?}"),
        }
    }

    pub(crate) fn receive(channel: &'static str, e: impl Debug) -> IpcError {
        IpcError::Receive {
            channel,
            detail: format!("{e:?}"),
        }
    }

    /// The channel at fault, if one.
    pub fn channel(&self) -> Option<&str> {
        match self {
            IpcError::Open { channel, .. }
            | IpcError::PublisherTaken { channel, .. }
            | IpcError::Port { channel, .. }
            | IpcError::Send { channel, .. }
            | IpcError::Receive { channel, .. }
            | IpcError::NoEvent { channel } => Some(channel),
            IpcError::Unknown(c) => Some(c),
            IpcError::Node { .. } | IpcError::Prefix { .. } | IpcError::Liveness { .. } => None,
        }
    }
}
