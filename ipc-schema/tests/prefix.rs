//! The run's prefix is checked against the limits of the names iceoryx2
//! builds from it: a prefix that fits opens every kind of channel, one
//! character more is refused with an error naming it (it made services
//! panic deep inside iceoryx2 when a channel opened).

use std::time::Duration;

use iceoryx2::prelude::Config;
use phri_ipc::*;

/// A prefix of exactly `len` characters, unique to this process.
fn prefix(len: usize, tag: char) -> String {
    let head = format!("pfx{}{tag}", std::process::id());
    format!("{head}{}_", "x".repeat(len - head.len() - 1))
}

/// Open a node and every kind of resource on it: a waking channel (event
/// socket), a connection, a frame channel; one message through each.
fn open_all(prefix: &str) -> Result<(), IpcError> {
    let node = node("prefix-test", prefix)?;
    let result = open_channels(&node);
    drop(node);
    let _ = remove_leftovers(prefix);
    result
}

fn open_channels(node: &IpcNode) -> Result<(), IpcError> {
    let p = ROBOT_STATE.publisher(node)?;
    let s = ROBOT_STATE.waking_subscriber(node, Queue::Latest)?;
    p.publish(&<JointState as Zeroed>::zeroed())?;
    let _ = s.wait(Duration::from_millis(10));
    assert!(s.receive()?.is_some());
    let fp = CAMERA_DEPTH.frame_publisher(node, FRAME_PIXELS)?;
    let fs = CAMERA_DEPTH.frame_subscriber(node, Queue::Latest)?;
    let sample = fp.loan(100)?;
    fp.send(sample)?;
    assert!(fs.receive()?.is_some());
    Ok(())
}

#[test]
fn the_longest_prefix_works_and_one_more_character_is_refused_by_name() {
    let max = max_prefix_len(&Config::default());
    // /tmp/iceoryx2/ + prefix + a 39-digit id + ".event" fits a Unix socket path
    assert_eq!(max, 48);
    let longest = prefix(max, 'a');
    check_prefix(&longest).unwrap();
    open_all(&longest).unwrap_or_else(|e| panic!("{longest}: {e}"));
    for len in [max + 1, 131, 300] {
        let p = prefix(len, 'b');
        assert!(matches!(check_prefix(&p), Err(IpcError::Prefix { .. })));
        match open_all(&p) {
            Err(e @ IpcError::Prefix { .. }) => {
                let text = e.to_string();
                assert!(text.contains(&p), "{text}");
                assert!(text.contains(&format!("at most {max}")), "{text}");
            }
            other => panic!("{len} characters: {other:?}"),
        }
    }
}

#[test]
fn characters_iceoryx2_refuses_are_refused_by_name() {
    for p in ["a/b_", "", "tab\there_"] {
        match node("prefix-test", p) {
            Err(e @ IpcError::Prefix { .. }) => {
                assert!(e.to_string().contains("not a file-name prefix"), "{e}")
            }
            other => panic!("{p:?}: {:?}", other.map(|_| ())),
        }
    }
}
