//! The run's prefix is checked against the limits of the names iceoryx2
//! builds from it: a prefix that fits opens every kind of channel, one
//! character more is refused with an error naming it (it made services
//! panic deep inside iceoryx2 when a channel opened). And a waking
//! channel's wait with a zero timeout only consumes what is pending; one
//! with a timeout wakes on an announcement and ends at the timeout without.

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

#[test]
fn a_zero_wait_only_consumes_what_is_pending() {
    // iceoryx2's timed wait takes a zero timeout as none on its socket
    // events: a wait that blocks fails here instead of hanging the run
    let (done, watched) = std::sync::mpsc::channel::<()>();
    std::thread::spawn(move || {
        if watched.recv_timeout(Duration::from_secs(10)).is_err() {
            eprintln!("a zero wait blocked");
            std::process::abort();
        }
    });
    let prefix = prefix(20, 'w');
    let node = node("wake-test", &prefix).unwrap();
    let p = ROBOT_STATE.publisher(&node).unwrap();
    let s = ROBOT_STATE.waking_subscriber(&node, Queue::Drain).unwrap();
    let l = ROBOT_STATE.listener(&node).unwrap();
    let count = || {
        let mut n = 0;
        l.wait_each(Duration::ZERO, || n += 1).unwrap();
        n
    };
    // nothing pending: returns at once
    assert_eq!(count(), 0);
    for _ in 0..3 {
        p.publish(&<JointState as Zeroed>::zeroed()).unwrap();
    }
    // the announcements are consumed, then nothing is pending again
    assert!(count() >= 1);
    assert_eq!(count(), 0);
    s.wait(Duration::ZERO).unwrap();
    assert_eq!(s.drain(|_| {}).unwrap(), 3);
    done.send(()).unwrap();
    drop((l, p, s, node));
    let _ = remove_leftovers(&prefix);
}

#[test]
fn a_wait_wakes_on_an_announcement_and_ends_at_its_timeout_without_one() {
    let prefix = prefix(20, 'v');
    let node = node("wake-test", &prefix).unwrap();
    let p = ROBOT_STATE.publisher(&node).unwrap();
    let l = ROBOT_STATE.listener(&node).unwrap();
    let waited = |timeout_ms| {
        let (t0, mut n) = (std::time::Instant::now(), 0);
        l.wait_each(Duration::from_millis(timeout_ms), || n += 1)
            .unwrap();
        (t0.elapsed(), n)
    };
    // nothing announced: the wait lasts its timeout and consumes nothing
    let (took, n) = waited(30);
    assert!(took >= Duration::from_millis(25) && n == 0, "{took:?}, {n}");
    // announced before the wait: it returns with the announcement
    p.publish(&<JointState as Zeroed>::zeroed()).unwrap();
    let (took, n) = waited(10_000);
    assert!(n >= 1 && took < Duration::from_secs(5), "{took:?}, {n}");
    // announced by another thread while it waits: it wakes for it (a
    // stuck wait would last its 10 s; a machine this slow fails loudly)
    std::thread::scope(|s| {
        s.spawn(|| {
            // iceoryx2's ports stay in their thread: a node of its own,
            // and a notifier (the channel takes one publisher)
            let own = phri_ipc::node("wake-test-2", &prefix).unwrap();
            let n = ROBOT_STATE.notifier(&own).unwrap();
            std::thread::sleep(Duration::from_millis(50));
            n.notify();
        });
        let (took, n) = waited(10_000);
        assert!(n >= 1 && took < Duration::from_secs(5), "{took:?}, {n}");
    });
    // and nothing is pending after
    assert_eq!(waited(0).1, 0);
    drop((l, p, node));
    let _ = remove_leftovers(&prefix);
}

#[test]
fn a_behaviour_sent_by_its_head_arrives_whole_in_what_it_uses() {
    let prefix = prefix(20, 'h');
    let node = node("head-test", &prefix).unwrap();
    let p = CONTROL_BEHAVIOUR.publisher(&node).unwrap();
    let s = CONTROL_BEHAVIOUR.subscriber(&node, Queue::Drain).unwrap();
    let msg = |seq: u64, len: usize, fill: u8| {
        let mut m = <ControlBehaviour as Zeroed>::zeroed();
        (m.seq, m.state_seq, m.len) = (seq, 10 + seq, len as u32);
        m.bytes[..len].fill(fill);
        m
    };
    // a long one, then shorter ones (the samples' memory is reused)
    for m in [
        msg(1, 4000, 1),
        msg(2, 300, 2),
        msg(3, 0, 3),
        msg(4, 900, 4),
    ] {
        p.publish_head(&m, m.used_bytes()).unwrap();
        let mut got = 0;
        s.drain(|r| {
            assert_eq!((r.seq, r.state_seq, r.len), (m.seq, m.state_seq, m.len));
            assert_eq!(r.snapshot(), m.snapshot());
            got += 1;
        })
        .unwrap();
        assert_eq!(got, 1);
    }
    drop((p, s, node));
    let _ = remove_leftovers(&prefix);
}
