//! `phri-bench transport`: time to hand a payload from one process to another,
//! iceoryx2 zero-copy (loaned `[u8]` slice, only a reference crosses) against
//! a Unix stream socket (the bytes are copied into and out of the kernel).
//! Ping-pong with busy polling on both transports (non-blocking socket reads
//! spin like the iceoryx2 side): A sends the payload, B answers with 8 bytes;
//! the figure is half the median round trip, per payload size.

use std::io::{Read, Write};
use std::os::unix::net::{UnixListener, UnixStream};
use std::process::{Command, Stdio};
use std::time::Instant;

use iceoryx2::prelude::*;
use phri_ipc::{ipc_err, node};
use serde_json::json;

const SIZES: [usize; 5] = [64, 4096, 65536, 262_144, 614_400];
const PING: &str = "bench/transport/ping";
const PONG: &str = "bench/transport/pong";

type Err = String;

type Factory<T> =
    iceoryx2::service::port_factory::publish_subscribe::PortFactory<ipc::Service, T, ()>;

fn services(node: &Node<ipc::Service>) -> Result<(Factory<[u8]>, Factory<u64>), Err> {
    let ping = node
        .service_builder(&PING.try_into().map_err(|e| ipc_err(PING, e).to_string())?)
        .publish_subscribe::<[u8]>()
        .open_or_create()
        .map_err(|e| ipc_err(PING, e).to_string())?;
    let pong = node
        .service_builder(&PONG.try_into().map_err(|e| ipc_err(PONG, e).to_string())?)
        .publish_subscribe::<u64>()
        .open_or_create()
        .map_err(|e| ipc_err(PONG, e).to_string())?;
    Ok((ping, pong))
}

/// The answering side, in its own process.
pub fn peer(prefix: &str, socket: &str) -> Result<(), Err> {
    let node = node("bench-peer", prefix).map_err(|e| e.to_string())?;
    let (ping, pong) = services(&node)?;
    let sub = ping
        .subscriber_builder()
        .create()
        .map_err(|e| ipc_err(PING, e).to_string())?;
    let publ = pong
        .publisher_builder()
        .create()
        .map_err(|e| ipc_err(PONG, e).to_string())?;
    // iceoryx2 phase: answer until the sentinel
    loop {
        match sub.receive().map_err(|e| ipc_err(PING, e).to_string())? {
            Some(sample) => {
                let first = sample.payload().first().copied().unwrap_or(0);
                let last = sample.payload().last().copied().unwrap_or(0);
                publ.send_copy(first as u64 + last as u64)
                    .map_err(|e| ipc_err(PONG, e).to_string())?;
                if sample.payload().len() == 1 {
                    break;
                }
            }
            None => std::hint::spin_loop(),
        }
    }
    // socket phase
    let mut stream = UnixStream::connect(socket).map_err(|e| format!("{socket}: {e}"))?;
    stream.set_nonblocking(true).map_err(|e| e.to_string())?;
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
fn read_spin(stream: &mut UnixStream, buf: &mut [u8]) -> Result<(), Err> {
    let mut at = 0;
    while at < buf.len() {
        match stream.read(&mut buf[at..]) {
            Ok(0) => return Err("transport peer closed the socket".into()),
            Ok(n) => at += n,
            Err(e) if e.kind() == std::io::ErrorKind::WouldBlock => std::hint::spin_loop(),
            Err(e) => return Err(e.to_string()),
        }
    }
    Ok(())
}

/// Write all of `buf` to a non-blocking stream, spinning when the kernel buffer is full.
fn write_spin(stream: &mut UnixStream, buf: &[u8]) -> Result<(), Err> {
    let mut at = 0;
    while at < buf.len() {
        match stream.write(&buf[at..]) {
            Ok(n) => at += n,
            Err(e) if e.kind() == std::io::ErrorKind::WouldBlock => std::hint::spin_loop(),
            Err(e) => return Err(e.to_string()),
        }
    }
    Ok(())
}

fn median(mut v: Vec<f64>) -> f64 {
    v.sort_by(f64::total_cmp);
    v[v.len() / 2]
}

/// The measuring side; spawns the peer.
pub fn run(iterations: usize) -> Result<serde_json::Value, Err> {
    let prefix = format!("benchtx{}_", std::process::id());
    let socket = std::env::temp_dir().join(format!("phri-bench-{}.sock", std::process::id()));
    let _ = std::fs::remove_file(&socket);
    let listener = UnixListener::bind(&socket).map_err(|e| format!("{}: {e}", socket.display()))?;
    let node = node("bench-main", &prefix).map_err(|e| e.to_string())?;
    let (ping, pong) = services(&node)?;
    let publ = ping
        .publisher_builder()
        .initial_max_slice_len(*SIZES.iter().max().unwrap_or(&1))
        .create()
        .map_err(|e| ipc_err(PING, e).to_string())?;
    let sub = pong
        .subscriber_builder()
        .create()
        .map_err(|e| ipc_err(PONG, e).to_string())?;
    let exe = std::env::current_exe().map_err(|e| e.to_string())?;
    let mut child = Command::new(exe)
        .arg("transport-peer")
        .arg(&prefix)
        .arg(&socket)
        .stdout(Stdio::null())
        .spawn()
        .map_err(|e| e.to_string())?;
    // wait until the peer's subscriber is connected
    let t0 = Instant::now();
    while ping.dynamic_config().number_of_subscribers() == 0 {
        if t0.elapsed().as_secs() > 10 {
            let _ = child.kill();
            return Err("transport peer did not start".into());
        }
        std::thread::sleep(std::time::Duration::from_millis(5));
    }
    let mut iox = Vec::new();
    for &size in &SIZES {
        let mut rtts = Vec::with_capacity(iterations);
        for i in 0..iterations + 100 {
            let t = Instant::now();
            let mut sample = publ
                .loan_slice_uninit(size)
                .map_err(|e| ipc_err(PING, e).to_string())?;
            // the producer writes only what it produces; here a marker at both ends
            let payload = sample.payload_mut();
            payload[0].write(i as u8);
            payload[size - 1].write(1);
            // SAFETY: the rest of the frame is what a producer would render in place;
            // its content does not matter for the hand-off being timed
            let sample = unsafe { sample.assume_init() };
            sample.send().map_err(|e| ipc_err(PING, e).to_string())?;
            loop {
                if sub
                    .receive()
                    .map_err(|e| ipc_err(PONG, e).to_string())?
                    .is_some()
                {
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
    let sentinel = publ
        .loan_slice_uninit(1)
        .map_err(|e| ipc_err(PING, e).to_string())?;
    sentinel
        .write_from_fn(|_| 0)
        .send()
        .map_err(|e| ipc_err(PING, e).to_string())?;
    let (mut stream, _) = listener.accept().map_err(|e| e.to_string())?;
    stream.set_nonblocking(true).map_err(|e| e.to_string())?;
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
