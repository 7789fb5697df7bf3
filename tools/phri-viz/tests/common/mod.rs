//! What the live tests share: child processes killed when dropped, a cell
//! (the release supervisor), phri-viz on a free port, and a client speaking
//! Foxglove's WebSocket protocol (`foxglove.sdk.v1`: JSON `serverInfo` and
//! `advertise`, a JSON `subscribe`, binary message data `0x01 | u32
//! subscription | u64 log time | payload`).

#![allow(dead_code)] // each test file uses its part

use std::collections::HashMap;
use std::io::{BufRead, BufReader, Read, Write};
use std::net::TcpStream;
use std::path::{Path, PathBuf};
use std::process::{Child, Command, Stdio};
use std::sync::atomic::{AtomicU64, Ordering};
use std::sync::{mpsc, Arc};
use std::time::{Duration, Instant};

use serde_json::{json, Value};
use tungstenite::client::IntoClientRequest;
use tungstenite::{Message, WebSocket};

pub const VIZ: &str = env!("CARGO_BIN_EXE_phri-viz");

pub fn repo() -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR")).join("../..")
}

/// A child process killed (SIGTERM, then SIGKILL) when dropped.
pub struct Proc(pub Child);

impl Proc {
    /// SIGTERM, and wait for the exit (SIGKILL after 10 s).
    pub fn stop(&mut self) -> std::process::ExitStatus {
        // SAFETY: kill(2) on our own child's pid.
        unsafe { libc::kill(self.0.id() as i32, libc::SIGTERM) };
        let t0 = Instant::now();
        loop {
            if let Ok(Some(s)) = self.0.try_wait() {
                return s;
            }
            if t0.elapsed() > Duration::from_secs(10) {
                let _ = self.0.kill();
                return self.0.wait().expect("wait");
            }
            std::thread::sleep(Duration::from_millis(50));
        }
    }
}

impl Drop for Proc {
    fn drop(&mut self) {
        if self.0.try_wait().ok().flatten().is_none() {
            self.stop();
        }
    }
}

/// The release supervisor next to phri-viz (built by `cargo build --release --bins`).
pub fn supervisor() -> PathBuf {
    let s = Path::new(VIZ).with_file_name("phri-supervisor");
    assert!(
        s.exists(),
        "{} is not built: cargo build --release --bins first",
        s.display()
    );
    s
}

/// A cell of the coexistence scenario for `secs` under `prefix`, its run
/// directory under `run_dir` (the report at `run_dir/report.json`).
pub fn start_cell(prefix: &str, secs: u32, run_dir: &Path) -> Proc {
    let _ = std::fs::remove_dir_all(run_dir);
    Proc(
        Command::new(supervisor())
            .current_dir(repo())
            .args(["--config", "deploy/phri.toml", "--scenario", "coexistence"])
            .args([
                "--duration",
                &secs.to_string(),
                "--prefix",
                prefix,
                "--run-dir",
            ])
            .arg(run_dir)
            .arg("--report")
            .arg(run_dir.join("report.json"))
            .stdout(Stdio::null())
            .stderr(Stdio::inherit())
            .spawn()
            .expect("start the supervisor"),
    )
}

/// Start phri-viz on a free port with `extra` flags; returns it and the port
/// it serves on (read from its "serving ws://HOST:PORT" line; every stderr
/// line is echoed, and those containing a word of `watch` are sent to the
/// returned receiver).
pub fn start_viz_watching(
    prefix: &str,
    extra: &[&str],
    watch: &'static [&'static str],
) -> (Proc, u16, mpsc::Receiver<String>) {
    let mut child = Command::new(VIZ)
        .current_dir(repo())
        .args(["--prefix", prefix, "--addr", "127.0.0.1:0", "--rate", "30"])
        .args(extra)
        .stdout(Stdio::null())
        .stderr(Stdio::piped())
        .spawn()
        .expect("start phri-viz");
    let stderr = child.stderr.take().expect("stderr");
    let (tx, rx) = mpsc::channel();
    let (wtx, wrx) = mpsc::channel();
    std::thread::spawn(move || {
        for line in BufReader::new(stderr).lines().map_while(Result::ok) {
            eprintln!("[viz] {line}");
            if let Some(rest) = line.split("serving ws://").nth(1) {
                let port = rest
                    .split_whitespace()
                    .next()
                    .and_then(|a| a.rsplit(':').next())
                    .and_then(|p| p.parse::<u16>().ok());
                let _ = tx.send(port);
            }
            if watch.iter().any(|w| line.contains(w)) {
                let _ = wtx.send(line);
            }
        }
    });
    let port = rx
        .recv_timeout(Duration::from_secs(20))
        .expect("phri-viz announces its port")
        .expect("a port number");
    (Proc(child), port, wrx)
}

pub fn start_viz(prefix: &str, extra: &[&str]) -> (Proc, u16) {
    let (p, port, _) = start_viz_watching(prefix, extra, &[]);
    (p, port)
}

/// A stream that counts the bytes read from it.
pub struct Counted {
    pub inner: TcpStream,
    pub read: Arc<AtomicU64>,
}

impl Read for Counted {
    fn read(&mut self, buf: &mut [u8]) -> std::io::Result<usize> {
        let n = self.inner.read(buf)?;
        self.read.fetch_add(n as u64, Ordering::Relaxed);
        Ok(n)
    }
}

impl Write for Counted {
    fn write(&mut self, buf: &[u8]) -> std::io::Result<usize> {
        self.inner.write(buf)
    }
    fn flush(&mut self) -> std::io::Result<()> {
        self.inner.flush()
    }
}

pub type Ws = WebSocket<Counted>;

/// Connect offering `foxglove.sdk.v1`; the handshake's error as text when refused.
/// The bytes read (handshake included) are counted in the returned counter.
pub fn try_connect(port: u16) -> (Result<Ws, String>, Arc<AtomicU64>) {
    let read = Arc::new(AtomicU64::new(0));
    let stream = match TcpStream::connect(("127.0.0.1", port)) {
        Ok(s) => s,
        Err(e) => return (Err(format!("connect: {e}")), read),
    };
    let _ = stream.set_read_timeout(Some(Duration::from_secs(5)));
    let mut req = match format!("ws://127.0.0.1:{port}").into_client_request() {
        Ok(r) => r,
        Err(e) => return (Err(e.to_string()), read),
    };
    req.headers_mut().insert(
        "Sec-WebSocket-Protocol",
        tungstenite::http::HeaderValue::from_static("foxglove.sdk.v1"),
    );
    let counted = Counted {
        inner: stream,
        read: read.clone(),
    };
    let ws = match tungstenite::client::client(req, counted) {
        Ok((ws, resp)) => {
            let proto = resp
                .headers()
                .get("sec-websocket-protocol")
                .and_then(|v| v.to_str().ok());
            if proto != Some("foxglove.sdk.v1") {
                return (Err(format!("subprotocol {proto:?}")), read);
            }
            let _ = ws
                .get_ref()
                .inner
                .set_read_timeout(Some(Duration::from_millis(200)));
            Ok(ws)
        }
        Err(tungstenite::HandshakeError::Failure(tungstenite::Error::Http(r))) => {
            let body = r
                .body()
                .as_ref()
                .map(|b| String::from_utf8_lossy(b).into_owned())
                .unwrap_or_default();
            Err(format!("HTTP {}: {}", r.status(), body.trim()))
        }
        Err(e) => Err(e.to_string()),
    };
    (ws, read)
}

pub fn connect(port: u16) -> Ws {
    try_connect(port).0.expect("connect to phri-viz")
}

/// One read: Ok(None) when nothing came within the read timeout.
pub fn read(ws: &mut Ws) -> Result<Option<Message>, tungstenite::Error> {
    match ws.read() {
        Ok(m) => Ok(Some(m)),
        Err(tungstenite::Error::Io(e))
            if e.kind() == std::io::ErrorKind::WouldBlock
                || e.kind() == std::io::ErrorKind::TimedOut =>
        {
            Ok(None)
        }
        Err(e) => Err(e),
    }
}

/// Read until `n` channels are advertised (at most 10 s): channel id → (topic, schema name).
pub fn advertised(ws: &mut Ws, n: usize) -> HashMap<u64, (String, String)> {
    let mut channels = HashMap::new();
    let t0 = Instant::now();
    while channels.len() < n && t0.elapsed() < Duration::from_secs(10) {
        if let Some(Message::Text(t)) = read(ws).expect("reading the advertisements") {
            let v: Value = serde_json::from_str(t.as_str()).expect("JSON");
            if v["op"] == "advertise" {
                for c in v["channels"].as_array().expect("channels") {
                    channels.insert(
                        c["id"].as_u64().expect("id"),
                        (
                            c["topic"].as_str().unwrap_or("").to_string(),
                            c["schemaName"].as_str().unwrap_or("").to_string(),
                        ),
                    );
                }
            }
        }
    }
    channels
}

/// Subscribe to every channel: subscription id = channel id.
pub fn subscribe_all(ws: &mut Ws, channels: &HashMap<u64, (String, String)>) {
    let subs: Vec<Value> = channels
        .keys()
        .map(|id| json!({"id": id, "channelId": id}))
        .collect();
    ws.send(Message::text(
        json!({"op": "subscribe", "subscriptions": subs}).to_string(),
    ))
    .expect("subscribe");
}

/// A message data frame: (subscription, log time, payload).
pub fn message_data(b: &[u8]) -> Option<(u64, u64, &[u8])> {
    if b.len() < 13 || b[0] != 0x01 {
        return None;
    }
    let sub = u32::from_le_bytes(b[1..5].try_into().ok()?) as u64;
    let t = u64::from_le_bytes(b[5..13].try_into().ok()?);
    Some((sub, t, &b[13..]))
}

/// Resident memory of a process [bytes] (VmRSS).
pub fn rss_bytes(pid: u32) -> u64 {
    let s = std::fs::read_to_string(format!("/proc/{pid}/status")).unwrap_or_default();
    s.lines()
        .find_map(|l| l.strip_prefix("VmRSS:"))
        .and_then(|v| v.split_whitespace().next())
        .and_then(|kb| kb.parse::<u64>().ok())
        .map_or(0, |kb| kb * 1024)
}
