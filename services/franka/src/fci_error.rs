//! The FCI client's errors as what happened at the box's address: the
//! client speaks libfranka's texts, which advise enabling FCI in Desk for
//! any refused connection, also when the box (or franka-sim) just died.

/// What went wrong between the adapter and the control box at `address`.
#[derive(Debug, thiserror::Error)]
pub enum FciError {
    /// nothing accepts FCI connections at the address
    #[error("connection refused by the box at {address}: nothing accepts FCI connections there (the box is off or restarting, FCI is not enabled in Desk, or franka-sim is not running)")]
    Refused {
        /// the box's address as given
        address: String,
    },
    /// the box closed or reset the connection
    #[error("connection closed by the box at {address}")]
    Closed {
        /// the box's address as given
        address: String,
    },
    /// the box did not accept the connection in time
    #[error("the box at {address} did not accept the connection within the connect timeout")]
    ConnectTimeout {
        /// the box's address as given
        address: String,
    },
    /// the box accepted the connection but never answered the handshake
    #[error("the box at {address} accepted the connection but never answered the FCI handshake")]
    Silent {
        /// the box's address as given
        address: String,
    },
    /// no state datagram came within the receive timeout
    #[error("the box at {address} sent no state within the receive timeout")]
    NoStates {
        /// the box's address as given
        address: String,
    },
    /// the start-up (handshake, first state, robot model) took too long
    #[error("the box at {address} did not finish the start-up (handshake, first state, robot model) within {seconds:.1} s")]
    StartDeadline {
        /// the box's address as given
        address: String,
        /// the time allowed \[s\]
        seconds: f64,
    },
    /// no address given (`--robot-ip` empty)
    #[error("--robot-ip: empty; give the control box's address (`172.16.0.2`, or `127.0.0.1:1337` for franka-sim)")]
    EmptyAddress,
    /// any other error of the FCI client
    #[error("{address}: {what}: {source}")]
    Other {
        /// the box's address as given
        address: String,
        /// what the adapter was doing
        what: &'static str,
        /// the client's error
        source: Box<franka::FrankaError>,
    },
}

impl FciError {
    /// `e`, raised while doing `what` with the box at `address`, named by what happened.
    pub fn from_franka(address: &str, what: &'static str, e: franka::FrankaError) -> FciError {
        let address = address.to_owned();
        let text = match &e {
            franka::FrankaError::Network(t) => t.as_str(),
            _ => "",
        };
        if text.contains("Connection to FCI refused") || text.contains("Connection refused") {
            FciError::Refused { address }
        } else if text.contains("server closed connection")
            || text.contains("Connection reset")
            || text.contains("TCP connection got interrupted")
            || text.contains("Broken pipe")
        {
            FciError::Closed { address }
        } else if text.contains("Connection timeout") {
            FciError::ConnectTimeout { address }
        } else if text.contains("no response from the server") {
            FciError::Silent { address }
        } else if text.contains("UDP receive: Timeout") {
            FciError::NoStates { address }
        } else {
            FciError::Other {
                address,
                what,
                source: Box::new(e),
            }
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn net(t: &str) -> franka::FrankaError {
        franka::FrankaError::Network(t.to_owned())
    }

    #[test]
    fn a_refused_or_closed_connection_names_the_box_not_desk() {
        let a = "127.0.0.1:1337";
        let refused = FciError::from_franka(
            a,
            "connect",
            net("libfranka: Connection to FCI refused. Please install FCI feature or enable FCI mode in Desk."),
        );
        assert!(matches!(refused, FciError::Refused { .. }));
        assert!(refused
            .to_string()
            .starts_with("connection refused by the box at 127.0.0.1:1337"));
        let closed = FciError::from_franka(a, "read", net("libfranka: server closed connection"));
        assert_eq!(
            closed.to_string(),
            "connection closed by the box at 127.0.0.1:1337"
        );
        let silent = FciError::from_franka(
            a,
            "connect",
            net("libfranka: no response from the server within 1000 ms"),
        );
        assert!(matches!(silent, FciError::Silent { .. }));
        let other = FciError::from_franka(a, "GetRobotModel", net("libfranka: something else"));
        assert_eq!(
            other.to_string(),
            "127.0.0.1:1337: GetRobotModel: libfranka: something else"
        );
    }
}
