//! phri-viz serves its owner only: another user's WebSocket client gets no
//! byte (run here as user nobody through `setpriv` when the tests run as
//! root), the owner's gets the cell; clients past `--max-clients` are
//! refused with a 503 naming the flag; a slow client does not grow the
//! server's memory past its `--client-buffer`; and when the cell stops the
//! scene stops with it: statuses say `stale` with a growing age, until a cell
//! runs again under the prefix.

mod common;

use std::collections::BTreeMap;
use std::process::Command;
use std::sync::atomic::Ordering;
use std::time::{Duration, Instant};

use common::*;
use phri_viz::server::{Limits, Server};
use serde_json::{json, Value};
use tungstenite::Message;

/// The probe's port: set, the ignored `probe` test is a client.
const PROBE_PORT: &str = "PHRI_VIZ_PROBE_PORT";
const NOBODY: u32 = 65534;

fn is_root() -> bool {
    // SAFETY: geteuid(2) cannot fail.
    unsafe { libc::geteuid() == 0 }
}

/// Not a test alone: the Foxglove client the tests run as another user (the
/// test binary again, under `setpriv`). Connects to the port in
/// `PHRI_VIZ_PROBE_PORT`, subscribes to everything advertised, reads 3 s and
/// prints one line `PROBE {json}`: its uid, served or why not, the bytes it
/// received (handshake included) and the messages per topic.
#[test]
#[ignore = "a client the other tests run as another user; does nothing alone"]
fn probe() {
    let Some(port) = std::env::var(PROBE_PORT)
        .ok()
        .and_then(|p| p.parse::<u16>().ok())
    else {
        return;
    };
    let (ws, bytes) = try_connect(port);
    let mut topics: BTreeMap<String, u64> = BTreeMap::new();
    let error = match ws {
        Err(e) => Some(e),
        Ok(mut ws) => {
            let channels = advertised(&mut ws, phri_viz::TOPICS.len());
            subscribe_all(&mut ws, &channels);
            let end = Instant::now() + Duration::from_secs(3);
            let mut error = None;
            while Instant::now() < end {
                match read(&mut ws) {
                    Ok(Some(Message::Binary(b))) => {
                        if let Some((sub, _, _)) = message_data(&b) {
                            let topic = channels.get(&sub).map_or("?", |c| c.0.as_str());
                            *topics.entry(topic.to_string()).or_default() += 1;
                        }
                    }
                    Ok(_) => {}
                    Err(e) => {
                        error = Some(format!("after the handshake: {e}"));
                        break;
                    }
                }
            }
            error.filter(|_| topics.is_empty())
        }
    };
    // SAFETY: geteuid(2) cannot fail.
    let uid = unsafe { libc::geteuid() };
    println!(
        "PROBE {}",
        json!({"uid": uid, "served": error.is_none(), "error": error,
               "bytes": bytes.load(Ordering::Relaxed), "topics": topics})
    );
}

/// Run the probe against `port`, as user `uid` (`setpriv`, as root) or as this user.
fn run_probe(port: u16, uid: Option<u32>) -> Value {
    let exe = std::env::current_exe().expect("the test binary");
    let mut cmd = match uid {
        Some(uid) => {
            let mut c = Command::new("setpriv");
            c.args([
                &format!("--reuid={uid}"),
                &format!("--regid={uid}"),
                "--clear-groups",
            ])
            .arg(&exe);
            c
        }
        None => Command::new(&exe),
    };
    let out = cmd
        .args(["probe", "--exact", "--ignored", "--nocapture"])
        .env(PROBE_PORT, port.to_string())
        .output()
        .expect("run the probe");
    let stdout = String::from_utf8_lossy(&out.stdout);
    let line = stdout
        .lines()
        .find_map(|l| l.strip_prefix("PROBE "))
        .unwrap_or_else(|| {
            panic!(
                "the probe printed no result: {stdout}{}",
                String::from_utf8_lossy(&out.stderr)
            )
        });
    let v: Value = serde_json::from_str(line).expect("the probe's JSON");
    eprintln!("probe (uid {uid:?}): {v}");
    v
}

/// One message data a client read: topic, payload.
fn topic_of(
    channels: &std::collections::HashMap<u64, (String, String)>,
    b: &[u8],
) -> Option<(String, Vec<u8>)> {
    let (sub, _, payload) = message_data(b)?;
    Some((channels.get(&sub)?.0.clone(), payload.to_vec()))
}

#[test]
fn another_users_client_gets_nothing_the_owners_gets_the_cell_and_a_stopped_cell_is_stale() {
    let pid = std::process::id();
    let prefix = format!("vzown{pid}_");
    let run_dir = std::env::temp_dir().join(format!("phri-viz-owner-{pid}"));
    let mut cell = start_cell(&prefix, 30, &run_dir);
    std::thread::sleep(Duration::from_secs(3));
    let (mut viz, port, said) = start_viz_watching(
        &prefix,
        &["--stale-after", "500", "--client-buffer", "2"],
        &["stale", "live", "refused"],
    );
    let viz_pid = viz.0.id();

    // the owner's viewer, read all along
    let mut ws = connect(port);
    let channels = advertised(&mut ws, phri_viz::TOPICS.len());
    assert_eq!(channels.len(), phri_viz::TOPICS.len(), "{channels:?}");
    subscribe_all(&mut ws, &channels);
    // and a slow one of the owner's: subscribed to everything, never read
    let mut slow = connect(port);
    let slow_channels = advertised(&mut slow, phri_viz::TOPICS.len());
    subscribe_all(&mut slow, &slow_channels);

    let mut live: BTreeMap<String, u64> = BTreeMap::new();
    let read_for = |ws: &mut Ws, d: Duration, live: &mut BTreeMap<String, u64>| {
        let end = Instant::now() + d;
        while Instant::now() < end {
            if let Some(Message::Binary(b)) = read(ws).expect("the owner's viewer") {
                if let Some((t, _)) = topic_of(&channels, &b) {
                    *live.entry(t).or_default() += 1;
                }
            }
        }
    };
    read_for(&mut ws, Duration::from_secs(1), &mut live);
    let rss_before = rss_bytes(viz_pid);

    // another user's client, then the owner's, while the viewer reads
    let probes = std::thread::spawn(move || {
        let other = is_root().then(|| run_probe(port, Some(NOBODY)));
        let own = run_probe(port, None);
        (other, own)
    });
    while !probes.is_finished() {
        read_for(&mut ws, Duration::from_millis(200), &mut live);
    }
    let (other, own) = probes.join().expect("the probes");
    match other {
        Some(other) => {
            assert_eq!(other["uid"], 65534, "{other}");
            assert_eq!(other["served"], false, "{other}");
            assert_eq!(other["bytes"], 0, "another user received bytes: {other}");
            assert_eq!(other["topics"], json!({}), "{other}");
            let line = said
                .recv_timeout(Duration::from_secs(5))
                .expect("phri-viz says it refused a client");
            assert!(line.contains("uid 65534"), "{line}");
        }
        None => eprintln!(
            "not root: the other user's client is not run (the uid check is unit-tested in phri_viz::peer)"
        ),
    }
    assert_eq!(own["served"], true, "{own}");
    for topic in [
        "/viz/robot",
        "/viz/person",
        "/viz/joints",
        "/viz/depth/points",
    ] {
        assert!(
            own["topics"][topic].as_u64() > Some(0),
            "the owner's client gets {topic}: {own}"
        );
    }
    for topic in ["/viz/robot", "/viz/person", "/viz/status"] {
        assert!(
            live.get(topic) > Some(&0),
            "the viewer got {topic}: {live:?}"
        );
    }

    // the slow client cost at most its buffer (and the allocator's slack)
    let rss_after = rss_bytes(viz_pid);
    eprintln!(
        "phri-viz resident: {:.1} MiB with a slow client subscribed, {:.1} MiB before",
        rss_after as f64 / 1048576.0,
        rss_before as f64 / 1048576.0
    );
    assert!(
        rss_after < rss_before + (24 << 20),
        "a slow client grew phri-viz from {rss_before} to {rss_after} B"
    );

    // the cell stops: the scene goes stale
    cell.stop();
    let mut tail: Vec<(String, Value)> = Vec::new();
    let deadline = Instant::now() + Duration::from_secs(30);
    let stale_run = |tail: &[(String, Value)]| {
        tail.iter()
            .rev()
            .take_while(|(t, s)| t == "/viz/status" && s["stale"] == true)
            .count()
    };
    while stale_run(&tail) < 4 {
        assert!(
            Instant::now() < deadline,
            "no run of stale statuses after the cell stopped: {:?}",
            tail.iter().rev().take(10).collect::<Vec<_>>()
        );
        if let Some(Message::Binary(b)) = read(&mut ws).expect("the owner's viewer") {
            if let Some((t, payload)) = topic_of(&channels, &b) {
                let status = if t == "/viz/status" {
                    serde_json::from_slice(&payload).expect("a JSON status")
                } else {
                    Value::Null
                };
                tail.push((t, status));
            }
        }
    }
    let n = tail.len();
    let ages: Vec<f64> = tail[n - 4..]
        .iter()
        .map(|(_, s)| s["input_age"].as_f64().expect("the state's age"))
        .collect();
    assert!(ages[0] > 0.5, "stale only past --stale-after: {ages:?}");
    assert!(
        ages.windows(2).all(|w| w[1] > w[0]),
        "the age grows: {ages:?}"
    );
    assert_eq!(
        tail[n - 1].1["mode"],
        "none",
        "nothing of the stopped controller: {}",
        tail[n - 1].1
    );
    let line = said
        .recv_timeout(Duration::from_secs(5))
        .expect("phri-viz says the scene is stale");
    assert!(line.contains("stale"), "{line}");

    // a cell again under the prefix: the scene is live again
    let mut cell = start_cell(&prefix, 10, &run_dir);
    let deadline = Instant::now() + Duration::from_secs(40);
    let (mut robot, mut fresh) = (false, false);
    while !(robot && fresh) {
        assert!(
            Instant::now() < deadline,
            "the scene did not come back with the cell (robot {robot}, fresh status {fresh})"
        );
        if let Some(Message::Binary(b)) = read(&mut ws).expect("the owner's viewer") {
            match topic_of(&channels, &b) {
                Some((t, _)) if t == "/viz/robot" => robot = true,
                Some((t, p)) if t == "/viz/status" => {
                    let s: Value = serde_json::from_slice(&p).expect("a JSON status");
                    fresh |= s["stale"] == false && s["input_age"] == 0.0;
                }
                _ => {}
            }
        }
    }
    let line = said
        .recv_timeout(Duration::from_secs(5))
        .expect("phri-viz says the scene is live");
    assert!(line.contains("live"), "{line}");

    drop(slow);
    let _ = ws.close(None);
    assert!(viz.stop().success(), "phri-viz stops cleanly");
    cell.stop();
    let _ = std::fs::remove_dir_all(&run_dir);
}

#[test]
fn clients_past_the_limit_are_refused_and_a_cell_never_seen_is_stale() {
    let prefix = format!("vzlim{}_", std::process::id());
    let (mut viz, port) = start_viz(&prefix, &["--max-clients", "2"]);
    let mut a = connect(port);
    let mut b = connect(port);
    let (c, _) = try_connect(port);
    let err = c.err().expect("a third client is refused");
    assert!(
        err.contains("503") && err.contains("--max-clients"),
        "{err}"
    );

    // a place frees when a client leaves
    let _ = a.close(None);
    for _ in 0..50 {
        if read(&mut a).is_err() {
            break;
        }
    }
    drop(a);
    let deadline = Instant::now() + Duration::from_secs(10);
    let mut d = loop {
        match try_connect(port).0 {
            Ok(ws) => break ws,
            Err(e) => {
                assert!(Instant::now() < deadline, "no place freed: {e}");
                std::thread::sleep(Duration::from_millis(100));
            }
        }
    };

    // no cell: the status says stale, with no state's age
    let channels = advertised(&mut d, phri_viz::TOPICS.len());
    subscribe_all(&mut d, &channels);
    let deadline = Instant::now() + Duration::from_secs(10);
    let status = loop {
        assert!(Instant::now() < deadline, "no stale status");
        if let Some(Message::Binary(m)) = read(&mut d).expect("reading") {
            let (t, p) = topic_of(&channels, &m).expect("a subscribed channel");
            assert_eq!(t, "/viz/status", "nothing but the status without a cell");
            break serde_json::from_slice::<Value>(&p).expect("JSON");
        }
    };
    assert_eq!(status["stale"], true, "{status}");
    assert_eq!(status["input_age"], Value::Null, "{status}");
    assert_eq!(status["mode"], "none", "{status}");
    // the other client is still served
    b.send(Message::text(
        json!({"op": "unsubscribe", "subscriptionIds": [1]}).to_string(),
    ))
    .expect("the second client is still connected");
    assert!(viz.stop().success());
}

#[test]
fn a_non_root_owner_is_served_and_another_non_root_user_is_not() {
    if !is_root() {
        eprintln!("not root: no other uid to run a client as (the uid check is unit-tested in phri_viz::peer)");
        return;
    }
    // the server of a cell owned by uid 4242, in this process
    const OWNER: u32 = 4242;
    let server = Server::start_for(
        OWNER,
        "127.0.0.1:0".parse().expect("an address"),
        "phri-viz",
        &phri_viz::topics::all(),
        Limits::default(),
    )
    .expect("the server starts");
    let port = server.local_addr().port();
    let probes =
        std::thread::spawn(move || (run_probe(port, Some(NOBODY)), run_probe(port, Some(OWNER))));
    let mut t = 0;
    while !probes.is_finished() {
        server.publish(phri_viz::topics::STATUS, t, br#"{"stale":true}"#);
        t += 1;
        std::thread::sleep(Duration::from_millis(10));
    }
    let (other, own) = probes.join().expect("the probes");
    assert_eq!(
        (other["uid"].as_u64(), other["bytes"].as_u64()),
        (Some(65534), Some(0)),
        "{other}"
    );
    assert_eq!(other["served"], false, "{other}");
    assert_eq!(own["served"], true, "{own}");
    assert!(own["topics"]["/viz/status"].as_u64() > Some(0), "{own}");
    let counts = server.counts();
    assert_eq!(counts.refused_user, 1, "{counts:?}");
    server.stop();
}
