//! Foxglove's WebSocket protocol for the user who runs phri-viz, and only a
//! few clients of theirs.
//!
//! The shared memory of a cell is its owner's alone; what phri-viz serves of
//! it must be too. The Foxglove SDK's server accepts every connection and
//! offers no hook before data flows (its listener learns of a client after
//! the handshake, without its address), so this server accepts the sockets
//! itself and speaks the protocol with the SDK's own message types
//! (`foxglove::ws_protocol`: `serverInfo`, `advertise`, `subscribe`,
//! `unsubscribe`, binary message data), over `tungstenite`:
//!
//! - a connection is admitted only when the kernel's socket table says its
//!   peer socket belongs to this user or to root ([`crate::peer`]); another
//!   user's is closed before a byte is sent or read;
//! - at most `max_clients` are served at once; one more is answered
//!   `503` (naming `--max-clients`) and closed;
//! - each client has its own outbox of at most `queue_bytes`: a client that
//!   reads slower than the cell publishes loses its oldest messages, never
//!   grows the server's memory (the socket's kernel buffers aside).
//!
//! One thread accepts, one thread per client reads its requests and writes its
//! outbox; [`Server::publish`] only copies a message into the outboxes of the
//! clients subscribed to its topic.

use std::collections::{HashMap, VecDeque};
use std::io::{self, Write};
use std::net::{SocketAddr, TcpListener, TcpStream};
use std::os::fd::AsRawFd;
use std::sync::atomic::{AtomicBool, AtomicU64, AtomicUsize, Ordering};
use std::sync::{Arc, Condvar, Mutex, MutexGuard};
use std::thread::JoinHandle;
use std::time::Duration;

use foxglove::ws_protocol::client::ClientMessage;
use foxglove::ws_protocol::schema::Schema;
use foxglove::ws_protocol::server::{Advertise, Channel, MessageData, ServerInfo};
use foxglove::ws_protocol::{BinaryMessage, JsonMessage};
use tungstenite::handshake::server::{ErrorResponse, Request, Response};
use tungstenite::protocol::WebSocketConfig;
use tungstenite::{Message, WebSocket};

use crate::peer;
use crate::topics::Topic;

/// The subprotocol spoken (the SDK's server also speaks `.v1.1`, with schema tables).
pub const SUBPROTOCOL: &str = "foxglove.sdk.v1";
/// Longest wait of a client's thread before it looks at its socket again.
const WAKE: Duration = Duration::from_millis(20);
/// Longest wait of the accepting thread before it looks at the stop flag.
const ACCEPT_WAKE: Duration = Duration::from_millis(100);
/// Time a client has to finish its WebSocket handshake.
const HANDSHAKE: Duration = Duration::from_secs(5);
/// Largest request a client may send (a subscription list is a few kB).
const MAX_REQUEST: usize = 1 << 20;

/// How many clients, and how much memory each may hold.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct Limits {
    /// clients served at once (more are refused)
    pub max_clients: usize,
    /// messages waiting for one client, at most \[bytes\] (the oldest go first)
    pub queue_bytes: usize,
}

impl Default for Limits {
    fn default() -> Limits {
        Limits {
            max_clients: 4,
            queue_bytes: 8 << 20,
        }
    }
}

/// What the server has done so far (counters since its start).
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub struct Counts {
    /// clients being served now
    pub clients: usize,
    /// connections refused: another user's (or a peer not found)
    pub refused_user: u64,
    /// connections refused: already `max_clients`
    pub refused_full: u64,
    /// messages a slow client lost
    pub dropped: u64,
}

/// The messages waiting for one client.
#[derive(Default)]
struct Outbox {
    msgs: VecDeque<Vec<u8>>,
    bytes: usize,
}

/// One admitted client, shared by its thread and the publisher.
struct Client {
    peer: SocketAddr,
    /// subscription id → channel index
    subs: Mutex<HashMap<u32, usize>>,
    outbox: Mutex<Outbox>,
    ready: Condvar,
    gone: AtomicBool,
}

struct Shared {
    limits: Limits,
    own_uid: u32,
    server_info: String,
    advertise: String,
    /// per channel (index into the topics), subscriptions over all clients
    subscribed: Vec<AtomicUsize>,
    topics: Vec<&'static str>,
    clients: Mutex<Vec<Arc<Client>>>,
    /// admitted and not yet gone (counted by the accepting thread)
    slots: AtomicUsize,
    stop: AtomicBool,
    refused_user: AtomicU64,
    refused_full: AtomicU64,
    dropped: AtomicU64,
    threads: Mutex<Vec<JoinHandle<()>>>,
}

/// A poisoned lock is still the data: a panicking client thread must not
/// stop the others.
fn lock<T>(m: &Mutex<T>) -> MutexGuard<'_, T> {
    m.lock().unwrap_or_else(|p| p.into_inner())
}

/// The running server; stopped (its threads joined) by [`Server::stop`] or on drop.
pub struct Server {
    shared: Arc<Shared>,
    local: SocketAddr,
    accept: Option<JoinHandle<()>>,
}

/// Why the server did not start.
#[derive(Debug, thiserror::Error)]
pub enum ServeError {
    #[error("{0}")]
    Io(#[from] io::Error),
    #[error("topic {topic}: {reason}")]
    Schema { topic: String, reason: String },
}

impl Server {
    /// Listen on `addr` and serve `topics` (channel id = position + 1) to
    /// this process's user (and root).
    pub fn start(
        addr: SocketAddr,
        name: &str,
        topics: &[Topic],
        limits: Limits,
    ) -> Result<Server, ServeError> {
        Server::start_for(peer::own_uid(), addr, name, topics, limits)
    }

    /// As [`Server::start`], serving the user `owner` (and root): a root
    /// process serving another user's cell, or a test.
    pub fn start_for(
        owner: u32,
        addr: SocketAddr,
        name: &str,
        topics: &[Topic],
        limits: Limits,
    ) -> Result<Server, ServeError> {
        let mut channels = Vec::with_capacity(topics.len());
        for (i, t) in topics.iter().enumerate() {
            let schema = Schema::new(
                t.schema.name.as_str(),
                t.schema.encoding.as_str(),
                &t.schema.data[..],
            );
            let ch = Channel::builder(i as u64 + 1, t.name, t.encoding.as_str())
                .with_schema(schema)
                .build()
                .map_err(|e| ServeError::Schema {
                    topic: t.name.to_string(),
                    reason: e.to_string(),
                })?;
            channels.push(ch);
        }
        let session = std::time::SystemTime::now()
            .duration_since(std::time::UNIX_EPOCH)
            .map(|d| d.as_millis().to_string())
            .unwrap_or_default();
        let listener = TcpListener::bind(addr)?;
        listener.set_nonblocking(true)?;
        let local = listener.local_addr()?;
        let shared = Arc::new(Shared {
            limits,
            own_uid: owner,
            server_info: ServerInfo::new(name).with_session_id(session).to_string(),
            advertise: Advertise::new(channels).to_string(),
            subscribed: topics.iter().map(|_| AtomicUsize::new(0)).collect(),
            topics: topics.iter().map(|t| t.name).collect(),
            clients: Mutex::new(Vec::new()),
            slots: AtomicUsize::new(0),
            stop: AtomicBool::new(false),
            refused_user: AtomicU64::new(0),
            refused_full: AtomicU64::new(0),
            dropped: AtomicU64::new(0),
            threads: Mutex::new(Vec::new()),
        });
        let s = shared.clone();
        let accept = std::thread::Builder::new()
            .name("viz-accept".into())
            .spawn(move || accept_loop(&s, &listener))?;
        Ok(Server {
            shared,
            local,
            accept: Some(accept),
        })
    }

    /// The address actually bound (port 0 resolved).
    pub fn local_addr(&self) -> SocketAddr {
        self.local
    }

    /// Whether any client subscribed to `topic`.
    pub fn wanted(&self, topic: &str) -> bool {
        self.index(topic)
            .is_some_and(|i| self.shared.subscribed[i].load(Ordering::Relaxed) > 0)
    }

    fn index(&self, topic: &str) -> Option<usize> {
        self.shared.topics.iter().position(|t| *t == topic)
    }

    /// Queue one message of `topic` ([log time, ns], its encoded payload) for
    /// every client subscribed to it.
    pub fn publish(&self, topic: &str, log_ns: u64, payload: &[u8]) {
        let Some(i) = self.index(topic) else {
            return;
        };
        if self.shared.subscribed[i].load(Ordering::Relaxed) == 0 {
            return;
        }
        let clients = lock(&self.shared.clients).clone();
        for c in clients {
            let subs: Vec<u32> = lock(&c.subs)
                .iter()
                .filter(|(_, ch)| **ch == i)
                .map(|(id, _)| *id)
                .collect();
            for id in subs {
                let frame = MessageData::new(id, log_ns, payload).to_bytes();
                let dropped = c.push(frame, self.shared.limits.queue_bytes);
                self.shared.dropped.fetch_add(dropped, Ordering::Relaxed);
            }
        }
    }

    /// Counters since the start.
    pub fn counts(&self) -> Counts {
        let s = &self.shared;
        Counts {
            clients: lock(&s.clients).len(),
            refused_user: s.refused_user.load(Ordering::Relaxed),
            refused_full: s.refused_full.load(Ordering::Relaxed),
            dropped: s.dropped.load(Ordering::Relaxed),
        }
    }

    /// Close every connection and join the threads.
    pub fn stop(mut self) {
        self.shutdown();
    }

    fn shutdown(&mut self) {
        self.shared.stop.store(true, Ordering::SeqCst);
        for c in lock(&self.shared.clients).iter() {
            c.ready.notify_all();
        }
        if let Some(a) = self.accept.take() {
            let _ = a.join();
        }
        let threads = std::mem::take(&mut *lock(&self.shared.threads));
        for t in threads {
            let _ = t.join();
        }
    }
}

impl Drop for Server {
    fn drop(&mut self) {
        self.shutdown();
    }
}

impl Client {
    /// Queue `frame`, dropping the oldest past `budget` bytes; returns how many were dropped.
    fn push(&self, frame: Vec<u8>, budget: usize) -> u64 {
        if self.gone.load(Ordering::Relaxed) {
            return 0;
        }
        let mut o = lock(&self.outbox);
        let mut dropped = 0;
        if frame.len() > budget {
            return 1;
        }
        while o.bytes + frame.len() > budget {
            match o.msgs.pop_front() {
                Some(old) => {
                    o.bytes -= old.len();
                    dropped += 1;
                }
                None => break,
            }
        }
        o.bytes += frame.len();
        o.msgs.push_back(frame);
        drop(o);
        self.ready.notify_one();
        dropped
    }

    fn pop(&self) -> Option<Vec<u8>> {
        let mut o = lock(&self.outbox);
        let m = o.msgs.pop_front()?;
        o.bytes -= m.len();
        Some(m)
    }
}

/// Wait until `fd` is readable or (with `write`) writable, at most `timeout`.
fn wait_fd(fd: i32, write: bool, timeout: Duration) {
    let mut p = libc::pollfd {
        fd,
        events: libc::POLLIN | if write { libc::POLLOUT } else { 0 },
        revents: 0,
    };
    // SAFETY: one valid pollfd for the duration of the call.
    unsafe { libc::poll(&mut p, 1, timeout.as_millis() as i32) };
}

fn accept_loop(s: &Arc<Shared>, listener: &TcpListener) {
    let (mut warned_user, mut warned_full) = (false, false);
    while !s.stop.load(Ordering::SeqCst) {
        wait_fd(listener.as_raw_fd(), false, ACCEPT_WAKE);
        let (stream, peer) = match listener.accept() {
            Ok(x) => x,
            Err(e) if e.kind() == io::ErrorKind::WouldBlock => continue,
            Err(e) => {
                // e.g. out of file descriptors: retry later
                tracing::warn!("accept: {e}");
                std::thread::sleep(ACCEPT_WAKE);
                continue;
            }
        };
        let ours = match stream.local_addr() {
            Ok(a) => a,
            Err(e) => {
                tracing::warn!("{peer}: {e}");
                continue;
            }
        };
        let owner = peer::peer_uid(peer, ours);
        let refusal = match owner {
            Ok(Some(uid)) if peer::admitted(uid, s.own_uid) => None,
            Ok(Some(uid)) => Some(format!("its socket belongs to uid {uid}")),
            Ok(None) => Some("its socket is not in this machine's socket table".to_string()),
            Err(e) => Some(format!("cannot read the socket table: {e}")),
        };
        if let Some(why) = refusal {
            // closed unread: the peer gets a reset, not a byte
            s.refused_user.fetch_add(1, Ordering::Relaxed);
            let msg = format!(
                "refused {peer}: {why}; phri-viz serves uid {} (and root) only",
                s.own_uid
            );
            if warned_user {
                tracing::debug!("{msg}");
            } else {
                tracing::warn!("{msg}");
                warned_user = true;
            }
            drop(stream);
            continue;
        }
        if s.slots.load(Ordering::SeqCst) >= s.limits.max_clients {
            s.refused_full.fetch_add(1, Ordering::Relaxed);
            let msg = format!(
                "refused {peer}: {} clients already (--max-clients)",
                s.limits.max_clients
            );
            if warned_full {
                tracing::debug!("{msg}");
            } else {
                tracing::warn!("{msg}");
                warned_full = true;
            }
            refuse_full(stream, s.limits.max_clients);
            continue;
        }
        s.slots.fetch_add(1, Ordering::SeqCst);
        let sh = s.clone();
        let spawned = std::thread::Builder::new()
            .name("viz-client".into())
            .spawn(move || {
                serve(&sh, stream, peer);
                sh.slots.fetch_sub(1, Ordering::SeqCst);
            });
        match spawned {
            Ok(t) => {
                let mut threads = lock(&s.threads);
                threads.retain(|t| !t.is_finished());
                threads.push(t);
            }
            Err(e) => {
                s.slots.fetch_sub(1, Ordering::SeqCst);
                tracing::warn!("{peer}: cannot start its thread: {e}");
            }
        }
    }
}

/// Answer a client over the limit with a 503 naming the flag (waiting for
/// its request a moment at most).
fn refuse_full(mut stream: TcpStream, max: usize) {
    let body = format!("phri-viz serves {max} clients at most (--max-clients)\n");
    let reply = format!(
        "HTTP/1.1 503 Service Unavailable\r\nContent-Type: text/plain\r\nContent-Length: {}\r\nConnection: close\r\n\r\n{body}",
        body.len()
    );
    let _ = stream.set_nonblocking(false);
    let _ = stream.set_write_timeout(Some(Duration::from_millis(200)));
    let _ = stream.write_all(reply.as_bytes());
    let _ = stream.shutdown(std::net::Shutdown::Write);
    // take what the client sent, so that closing does not reset the reply away
    let _ = stream.set_read_timeout(Some(Duration::from_millis(100)));
    let mut sink = [0u8; 4096];
    let _ = std::io::Read::read(&mut stream, &mut sink);
}

/// The subprotocol check of the handshake: `foxglove.sdk.v1` or a 400.
#[allow(clippy::result_large_err)] // tungstenite's callback type
fn negotiate(req: &Request, mut res: Response) -> Result<Response, ErrorResponse> {
    let offered = req
        .headers()
        .get_all("sec-websocket-protocol")
        .iter()
        .filter_map(|h| h.to_str().ok())
        .flat_map(|h| h.split(','))
        .any(|p| p.trim() == SUBPROTOCOL);
    if !offered {
        let mut e = ErrorResponse::new(Some(format!(
            "phri-viz speaks the {SUBPROTOCOL} WebSocket subprotocol only\n"
        )));
        *e.status_mut() = tungstenite::http::StatusCode::BAD_REQUEST;
        return Err(e);
    }
    res.headers_mut().insert(
        "sec-websocket-protocol",
        tungstenite::http::HeaderValue::from_static(SUBPROTOCOL),
    );
    Ok(res)
}

fn is_would_block(e: &tungstenite::Error) -> bool {
    matches!(e, tungstenite::Error::Io(io) if io.kind() == io::ErrorKind::WouldBlock
        || io.kind() == io::ErrorKind::TimedOut)
}

/// One client, from its handshake to its last byte.
fn serve(s: &Arc<Shared>, stream: TcpStream, peer: SocketAddr) {
    let _ = stream.set_nodelay(true);
    if stream.set_nonblocking(false).is_err()
        || stream.set_read_timeout(Some(HANDSHAKE)).is_err()
        || stream.set_write_timeout(Some(HANDSHAKE)).is_err()
    {
        return;
    }
    let config = WebSocketConfig::default()
        .read_buffer_size(16 << 10)
        .write_buffer_size(0)
        .max_write_buffer_size(s.limits.queue_bytes + (1 << 20))
        .max_message_size(Some(MAX_REQUEST))
        .max_frame_size(Some(MAX_REQUEST));
    let mut ws = match tungstenite::accept_hdr_with_config(stream, negotiate, Some(config)) {
        Ok(ws) => ws,
        Err(e) => {
            tracing::info!("{peer}: no WebSocket handshake: {e}");
            return;
        }
    };
    for text in [&s.server_info, &s.advertise] {
        if let Err(e) = ws.send(Message::text(text.as_str())) {
            tracing::info!("{peer}: {e}");
            return;
        }
    }
    if ws.get_ref().set_nonblocking(true).is_err() {
        return;
    }
    let client = Arc::new(Client {
        peer,
        subs: Mutex::new(HashMap::new()),
        outbox: Mutex::new(Outbox::default()),
        ready: Condvar::new(),
        gone: AtomicBool::new(false),
    });
    lock(&s.clients).push(client.clone());
    tracing::info!("client {peer} connected");
    let why = run(s, &client, &mut ws);
    client.gone.store(true, Ordering::Relaxed);
    lock(&s.clients).retain(|c| !Arc::ptr_eq(c, &client));
    for (_, ch) in lock(&client.subs).drain() {
        s.subscribed[ch].fetch_sub(1, Ordering::Relaxed);
    }
    *lock(&client.outbox) = Outbox::default();
    tracing::info!("client {} left: {why}", client.peer);
}

/// Read requests and write the outbox until the client or the server stops;
/// returns why it ended.
fn run(s: &Shared, c: &Client, ws: &mut WebSocket<TcpStream>) -> String {
    let fd = ws.get_ref().as_raw_fd();
    loop {
        // bytes handed to tungstenite but not yet through the socket
        let mut pending = false;
        if s.stop.load(Ordering::SeqCst) {
            let _ = ws.close(None);
            let _ = ws.flush();
            return "the server stops".into();
        }
        // requests
        loop {
            match ws.read() {
                Ok(Message::Text(t)) => request(s, c, t.as_str()),
                Ok(_) => {}
                Err(e) if is_would_block(&e) => break,
                Err(tungstenite::Error::ConnectionClosed | tungstenite::Error::AlreadyClosed) => {
                    return "closed".into()
                }
                Err(e) => return e.to_string(),
            }
        }
        // replies tungstenite queued (pong, close), then the outbox, one
        // message at a time through the socket
        loop {
            match ws.flush() {
                Ok(()) => {}
                Err(e) if is_would_block(&e) => {
                    pending = true;
                    break;
                }
                Err(tungstenite::Error::ConnectionClosed | tungstenite::Error::AlreadyClosed) => {
                    return "closed".into()
                }
                Err(e) => return e.to_string(),
            }
            let Some(m) = c.pop() else {
                break;
            };
            match ws.write(Message::binary(m)) {
                Ok(()) => {}
                Err(e) if is_would_block(&e) => {
                    pending = true;
                    break;
                }
                Err(e) => return e.to_string(),
            }
        }
        if pending {
            // the socket is full: wait for room (or a request)
            wait_fd(fd, true, WAKE);
        } else {
            let o = lock(&c.outbox);
            if o.msgs.is_empty() {
                let _ = c.ready.wait_timeout(o, WAKE);
            }
        }
    }
}

/// One JSON request of a client: subscribe or unsubscribe (one subscription
/// per channel; anything else is ignored: no capability is advertised).
fn request(s: &Shared, c: &Client, text: &str) {
    let msg = match ClientMessage::parse_json(text) {
        Ok(m) => m,
        Err(e) => {
            tracing::debug!("{}: {e}", c.peer);
            return;
        }
    };
    let mut subs = lock(&c.subs);
    match msg {
        ClientMessage::Subscribe(m) => {
            for sub in m.subscriptions {
                let Some(ch) = usize::try_from(sub.channel_id)
                    .ok()
                    .and_then(|id| id.checked_sub(1))
                    .filter(|ch| *ch < s.subscribed.len())
                else {
                    continue;
                };
                if subs.contains_key(&sub.id) || subs.values().any(|x| *x == ch) {
                    continue;
                }
                subs.insert(sub.id, ch);
                s.subscribed[ch].fetch_add(1, Ordering::Relaxed);
            }
        }
        ClientMessage::Unsubscribe(m) => {
            for id in m.subscription_ids {
                if let Some(ch) = subs.remove(&id) {
                    s.subscribed[ch].fetch_sub(1, Ordering::Relaxed);
                }
            }
        }
        _ => {}
    }
}
