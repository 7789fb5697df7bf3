//! `phri-bench transport`: time to hand a payload from one process to another,
//! iceoryx2 zero-copy (loaned `[u8]` slice, only a reference crosses) against
//! a Unix stream socket (the bytes are copied into and out of the kernel).
//! Ping-pong with busy polling on both transports (non-blocking socket reads
//! spin like the iceoryx2 side): A sends the payload, B answers with 8 bytes;
//! the figure is half the median round trip, per payload size.

use std::io::{Read, Write};
use std::os::unix::net::{UnixListener, UnixStream};
use std::path::PathBuf;
use std::process::{Command, Stdio};
use std::time::Instant;

use iceoryx2::prelude::*;
use phri_ipc::{node, IpcError, IpcNode};
use serde_json::json;

const SIZES: [usize; 5] = [64, 4096, 65536, 262_144, 614_400];
const PING: &str = "bench/transport/ping";
const PONG: &str = "bench/transport/pong";

/// Why the transport benchmark failed.
#[derive(Debug, thiserror::Error)]
pub enum TransportError {
    #[error(transparent)]
    Node(#[from] IpcError),
    /// an iceoryx2 call on one of the benchmark's own services
    #[error("service '{service}': {detail}")]
    Service {
        service: &'static str,
        detail: String,
    },
    #[error("{}: {source}", path.display())]
    Socket {
        path: PathBuf,
        #[source]
        source: std::io::Error,
    },
    #[error("socket: {0}")]
    Io(#[source] std::io::Error),
    #[error("transport peer closed the socket")]
    PeerClosed,
    #[error("transport peer: {0}")]
    Spawn(#[source] std::io::Error),
    #[error("transport peer did not start")]
    PeerDidNotStart,
}

/// An iceoryx2 error of `service`.
fn service_err<E: std::fmt::Debug>(service: &'static str) -> impl FnOnce(E) -> TransportError {
    move |e| TransportError::Service {
        service,
        detail: format!("{e:?}"),
    }
}

type Factory<T> =
    iceoryx2::service::port_factory::publish_subscribe::PortFactory<ipc::Service, T, ()>;

fn services(node: &IpcNode) -> Result<(Factory<[u8]>, Factory<u64>), TransportError> {
    let ping = node
        .service_builder(&PING.try_into().map_err(service_err(PING))?)
        .publish_subscribe::<[u8]>()
        .open_or_create()
        .map_err(service_err(PING))?;
    let pong = node
        .service_builder(&PONG.try_into().map_err(service_err(PONG))?)
        .publish_subscribe::<u64>()
        .open_or_create()
        .map_err(service_err(PONG))?;
    Ok((ping, pong))
}

/// The answering side, in its own process.
pub fn peer(prefix: &str, socket: &str) -> Result<(), TransportError> {
    let node = node("bench-peer", prefix)?;
    let (ping, pong) = services(&node)?;
    let sub = ping
        .subscriber_builder()
        .create()
        .map_err(service_err(PING))?;
    let publ = pong
        .publisher_builder()
        .create()
        .map_err(service_err(PONG))?;
    // iceoryx2 phase: answer until the sentinel
    loop {
        match sub.receive().map_err(service_err(PING))? {
            Some(sample) => {
                let first = sample.payload().first().copied().unwrap_or(0);
                let last = sample.payload().last().copied().unwrap_or(0);
                publ.send_copy(first as u64 + last as u64)
                    .map_err(service_err(PONG))?;
                if sample.payload().len() == 1 {
                    break;
                }
            }
            None => std::hint::spin_loop(),
        }
    }
    // socket phase
    let mut stream = UnixStream::connect(socket).map_err(|source| TransportError::Socket {
        path: socket.into(),
        source,
    })?;
    stream.set_nonblocking(true).map_err(TransportError::Io)?;
    let mut buf = vec![0u8; *SIZES.iter().max().unwrap_or(&1)];
    let mut len = [0u8; 8];
    loop {
        read_spin(&mut stream, &mut len)?;
        let n = u64::from_le_bytes(len) as usize;
        if n == 0 || n > buf.len() {
            break;
        }
        read_spin(&mut stream, &mut buf[..n])?;
        write_spin(
            &mut stream,
            &(buf[0] as u64 + buf[n - 1] as u64).to_le_bytes(),
        )?;
    }
    Ok(())
}

/// Fill `buf` from a non-blocking stream, spinning like the iceoryx2 side does.
fn read_spin(stream: &mut UnixStream, buf: &mut [u8]) -> Result<(), TransportError> {
    let mut at = 0;
    while at < buf.len() {
        match stream.read(&mut buf[at..]) {
            Ok(0) => return Err(TransportError::PeerClosed),
            Ok(n) => at += n,
            Err(e) if e.kind() == std::io::ErrorKind::WouldBlock => std::hint::spin_loop(),
            Err(e) => return Err(TransportError::Io(e)),
        }
    }
    Ok(())
}

/// Write all of `buf` to a non-blocking stream, spinning when the kernel buffer is full.
fn write_spin(stream: &mut UnixStream, buf: &[u8]) -> Result<(), TransportError> {
    let mut at = 0;
    while at < buf.len() {
        match stream.write(&buf[at..]) {
            Ok(n) => at += n,
            Err(e) if e.kind() == std::io::ErrorKind::WouldBlock => std::hint::spin_loop(),
            Err(e) => return Err(TransportError::Io(e)),
        }
    }
    Ok(())
}

fn median(mut v: Vec<f64>) -> f64 {
    v.sort_by(f64::total_cmp);
    v[v.len() / 2]
}

/// The measuring side; spawns the peer.
pub fn run(iterations: usize) -> Result<serde_json::Value, TransportError> {
    let prefix = format!("benchtx{}_", std::process::id());
    let socket = std::env::temp_dir().join(format!("phri-bench-{}.sock", std::process::id()));
    let _ = std::fs::remove_file(&socket);
    let listener = UnixListener::bind(&socket).map_err(|source| TransportError::Socket {
        path: socket.clone(),
        source,
    })?;
    let node = node("bench-main", &prefix)?;
    let (ping, pong) = services(&node)?;
    let publ = ping
        .publisher_builder()
        .initial_max_slice_len(*SIZES.iter().max().unwrap_or(&1))
        .create()
        .map_err(service_err(PING))?;
    let sub = pong
        .subscriber_builder()
        .create()
        .map_err(service_err(PONG))?;
    let exe = std::env::current_exe().map_err(TransportError::Spawn)?;
    let mut child = Command::new(exe)
        .arg("transport-peer")
        .arg(&prefix)
        .arg(&socket)
        .stdout(Stdio::null())
        .spawn()
        .map_err(TransportError::Spawn)?;
    // wait until the peer's subscriber is connected
    let t0 = Instant::now();
    while ping.dynamic_config().number_of_subscribers() == 0 {
        if t0.elapsed().as_secs() > 10 {
            let _ = child.kill();
            return Err(TransportError::PeerDidNotStart);
        }
        std::thread::sleep(std::time::Duration::from_millis(5));
    }
    let mut iox = Vec::new();
    for &size in &SIZES {
        let mut rtts = Vec::with_capacity(iterations);
        for i in 0..iterations + 100 {
            let t = Instant::now();
            let mut sample = publ.loan_slice_uninit(size).map_err(service_err(PING))?;
            // the producer writes only what it produces; here a marker at both ends
            let payload = sample.payload_mut();
            payload[0].write(i as u8);
            payload[size - 1].write(1);
            // SAFETY: the rest of the frame is what a producer would render in place;
            // its content does not matter for the hand-off being timed
            let sample = unsafe { sample.assume_init() };
            sample.send().map_err(service_err(PING))?;
            loop {
                if sub.receive().map_err(service_err(PONG))?.is_some() {
                    break;
                }
                std::hint::spin_loop();
            }
            if i >= 100 {
                rtts.push(t.elapsed().as_nanos() as f64 / 2000.0);
            }
        }
        iox.push(median(rtts));
    }
    let sentinel = publ.loan_slice_uninit(1).map_err(service_err(PING))?;
    sentinel
        .write_from_fn(|_| 0)
        .send()
        .map_err(service_err(PING))?;
    let (mut stream, _) = listener.accept().map_err(|source| TransportError::Socket {
        path: socket.clone(),
        source,
    })?;
    stream.set_nonblocking(true).map_err(TransportError::Io)?;
    let frame = vec![7u8; *SIZES.iter().max().unwrap_or(&1)];
    let mut ack = [0u8; 8];
    let mut uds = Vec::new();
    for &size in &SIZES {
        let mut rtts = Vec::with_capacity(iterations);
        for i in 0..iterations + 100 {
            let t = Instant::now();
            write_spin(&mut stream, &(size as u64).to_le_bytes())?;
            write_spin(&mut stream, &frame[..size])?;
            read_spin(&mut stream, &mut ack)?;
            if i >= 100 {
                rtts.push(t.elapsed().as_nanos() as f64 / 2000.0);
            }
        }
        uds.push(median(rtts));
    }
    write_spin(&mut stream, &0u64.to_le_bytes())?;
    let _ = child.wait();
    let _ = std::fs::remove_file(&socket);
    drop((publ, sub, ping, pong));
    drop(node);
    let _ = phri_ipc::remove_leftovers(&prefix);
    let rows: Vec<serde_json::Value> = SIZES.iter().zip(iox.iter().zip(&uds)).map(|(s, (a, b))| json!({"bytes": s, "iceoryx2_us": (a * 100.0).round() / 100.0, "unix_socket_us": (b * 100.0).round() / 100.0})).collect();
    Ok(
        json!({"what": "one-way hand-off between two processes, half the median ping-pong round trip (busy polling)", "iterations": iterations, "sizes": rows, "frame_640x480_u16_bytes": 614_400}),
    )
}
