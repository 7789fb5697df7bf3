//! Read-only probes: subscribe to an existing channel (never create it,
//! never publish) with a draining queue, and measure what arrives.

use std::any::Any;
use std::collections::{HashMap, VecDeque};

use phri_ipc::*;
use phri_ipc_json::{frame_json, to_json};
use phri_runtime::now_ns;
use serde_json::{json, Value};

/// Why a channel could not be watched.
#[derive(Debug, thiserror::Error)]
pub enum ProbeError {
    #[error("unknown channel '{name}'; channels: {}", ALL.join(", "))]
    UnknownChannel { name: String },
    #[error(transparent)]
    Ipc(#[from] IpcError),
}

/// One received sample, as the statistics need it.
#[derive(Clone, Copy)]
struct Event {
    /// publish time when known, else receive time [ns, CLOCK_MONOTONIC]
    t_ns: u64,
    bytes: usize,
    drops: u64,
}

/// Rate, interval, age, bandwidth and drops over a window of samples.
#[derive(Default)]
pub struct Stats {
    events: VecDeque<Event>,
    last_seq: HashMap<u64, u64>,
    newest_pub_ns: Option<u64>,
    /// when the newest sample was received [ns, CLOCK_MONOTONIC]
    newest_recv_ns: Option<u64>,
    window_start_ns: u64,
    /// where the window ended, once observation stopped [ns, CLOCK_MONOTONIC]
    window_end_ns: Option<u64>,
    pub total_samples: u64,
    pub total_drops: u64,
}

impl Stats {
    fn new() -> Stats {
        Stats {
            window_start_ns: now_ns(),
            ..Default::default()
        }
    }

    /// Remember a sequence number without counting (samples already queued on connect).
    fn prime(&mut self, stream: u64, seq: u64, pub_ns: Option<u64>) {
        self.last_seq.insert(stream, seq);
        if pub_ns.is_some() {
            self.newest_pub_ns = pub_ns;
        }
        self.newest_recv_ns = Some(now_ns());
    }

    fn record(&mut self, stream: u64, seq: u64, pub_ns: Option<u64>, bytes: usize) {
        let now = now_ns();
        let drops = match self.last_seq.insert(stream, seq) {
            // a publisher that restarted starts over: not a drop
            Some(last) if seq > last => seq - last - 1,
            _ => 0,
        };
        if pub_ns.is_some() {
            self.newest_pub_ns = pub_ns;
        }
        self.newest_recv_ns = Some(now);
        self.total_samples += 1;
        self.total_drops += drops;
        self.events.push_back(Event {
            t_ns: pub_ns.unwrap_or(now),
            bytes,
            drops,
        });
    }

    /// Start a new window (for periodic reports).
    pub fn reset(&mut self) {
        self.events.clear();
        self.window_start_ns = now_ns();
        self.window_end_ns = None;
    }

    /// End the window now: figures computed later (after the channels'
    /// publisher and subscriber counts, which take time on a busy host)
    /// still cover only the observed span.
    pub fn close(&mut self) {
        self.window_end_ns = Some(now_ns());
    }

    /// Keep only the last `window_ns` (rolling window), by publish time
    /// where the message carries one: samples that waited in the queue
    /// while this process was not running (a loaded machine) and were
    /// published before the window belong to the window before.
    pub fn trim(&mut self, window_ns: u64) {
        let now = now_ns();
        let cut = now.saturating_sub(window_ns);
        self.events.retain(|e| e.t_ns >= cut);
        self.window_start_ns = self.window_start_ns.max(cut);
        self.window_end_ns = None;
    }

    /// Time since the newest sample was received \[ms\] (streams whose
    /// messages carry no publish time have no `age_ms`).
    pub fn recv_age_ms(&self) -> Option<f64> {
        self.newest_recv_ns
            .map(|r| now_ns().saturating_sub(r) as f64 * 1e-6)
    }

    /// The window's figures as JSON (`null` where unknown).
    pub fn summary(&self) -> Value {
        let now = self.window_end_ns.unwrap_or_else(now_ns);
        let span_s = (now.saturating_sub(self.window_start_ns) as f64 * 1e-9).max(1e-9);
        // the window's samples: published in it (received in it when the
        // message carries no publish time); a sample read late from the
        // queue but published before the window began is not counted
        let start = self.window_start_ns;
        let in_window = || self.events.iter().filter(move |e| e.t_ns >= start);
        let n = in_window().count();
        let (mut sum, mut max, mut k) = (0u64, 0u64, 0u64);
        let mut prev: Option<u64> = None;
        for e in in_window() {
            if let Some(p) = prev {
                let d = e.t_ns.saturating_sub(p);
                sum += d;
                max = max.max(d);
                k += 1;
            }
            prev = Some(e.t_ns);
        }
        let bytes: usize = in_window().map(|e| e.bytes).sum();
        let drops: u64 = in_window().map(|e| e.drops).sum();
        let ms = |ns: u64| (ns as f64 * 1e-6 * 1000.0).round() / 1000.0;
        json!({
            "rate_hz": (n as f64 / span_s * 100.0).round() / 100.0,
            "samples": n,
            "drops": drops,
            "mean_interval_ms": sum.checked_div(k).map_or(Value::Null, |m| json!(ms(m))),
            "max_interval_ms": if k > 0 { json!(ms(max)) } else { Value::Null },
            "age_ms": self.newest_pub_ns.map(|p| ms(now.saturating_sub(p))),
            "bandwidth_bps": (bytes as f64 / span_s).round(),
            "total_samples": self.total_samples,
            "total_drops": self.total_drops,
        })
    }
}

/// A channel being watched.
pub trait Probe {
    fn name(&self) -> &'static str;
    /// the channel existed when the probe opened
    fn present(&self) -> bool;
    /// (publishers, subscribers other than this monitor) now; (0, 0) when absent
    fn counts(&self, node: &IpcNode) -> Result<(usize, usize), IpcError>;
    /// drain the queue into the statistics; `each` sees every sample as JSON
    /// when given, and stops the draining by returning false (then so does this)
    fn poll(&mut self, each: Option<&mut dyn FnMut(Value) -> bool>) -> Result<bool, IpcError>;
    fn stats(&self) -> &Stats;
    fn stats_mut(&mut self) -> &mut Stats;
    fn as_any(&self) -> &dyn Any;
    /// the newest sample as `echo` shows it (`None`: none seen, or a frame
    /// channel not asked to [`Probe::keep_latest`])
    fn latest(&self) -> Option<Value>;
    /// keep the newest sample's JSON while polling (frames: a pass over the
    /// pixels each, so only while someone looks; messages always keep it)
    fn keep_latest(&mut self, on: bool);
}

/// The ports of a channel the probe subscribed to, this monitor's subscriber left out.
fn others(ports: Option<(usize, usize)>) -> (usize, usize) {
    ports.map_or((0, 0), |(p, s)| (p, s.saturating_sub(1)))
}

/// Typed probe of a fixed-size message channel.
pub struct MsgProbe<T: Message> {
    channel: Channel<T>,
    sub: Option<Subscriber<T>>,
    stats: Stats,
    pub last: Option<T>,
}

impl<T: Message> MsgProbe<T> {
    pub fn open(node: &IpcNode, channel: Channel<T>) -> Result<MsgProbe<T>, IpcError> {
        // only if it exists: a monitor never creates a channel
        let sub = channel.subscriber_if_exists(node, Queue::Drain)?;
        let mut p = MsgProbe {
            channel,
            sub,
            stats: Stats::new(),
            last: None,
        };
        // samples delivered on connecting (history) are not counted
        if let Some(s) = &p.sub {
            while let Some(m) = s.receive()? {
                p.stats.prime(m.stream(), m.seq(), m.published_ns());
                p.last = Some(m);
            }
        }
        p.stats.reset();
        Ok(p)
    }
}

impl<T: Message> Probe for MsgProbe<T> {
    fn name(&self) -> &'static str {
        self.channel.name
    }
    fn present(&self) -> bool {
        self.sub.is_some()
    }
    fn counts(&self, node: &IpcNode) -> Result<(usize, usize), IpcError> {
        if !self.present() {
            return Ok((0, 0));
        }
        Ok(others(self.channel.ports(node)?))
    }
    fn poll(&mut self, mut each: Option<&mut dyn FnMut(Value) -> bool>) -> Result<bool, IpcError> {
        let Some(sub) = &self.sub else {
            return Ok(true);
        };
        while let Some(m) = sub.receive()? {
            self.stats.record(
                m.stream(),
                m.seq(),
                m.published_ns(),
                std::mem::size_of::<T>(),
            );
            self.last = Some(m);
            if let Some(f) = each.as_mut() {
                if !f(to_json(&m)) {
                    return Ok(false);
                }
            }
        }
        Ok(true)
    }
    fn stats(&self) -> &Stats {
        &self.stats
    }
    fn stats_mut(&mut self) -> &mut Stats {
        &mut self.stats
    }
    fn as_any(&self) -> &dyn Any {
        self
    }
    fn latest(&self) -> Option<Value> {
        self.last.as_ref().map(to_json)
    }
    fn keep_latest(&mut self, _on: bool) {}
}

/// Probe of a depth-frame channel (`[u16]` with a [`FrameHeader`]).
pub struct FrameProbe {
    channel: FrameChannel,
    sub: Option<FrameSubscriber>,
    stats: Stats,
    /// the newest frame's summary, while [`Probe::keep_latest`] is on
    latest: Option<Value>,
    keep: bool,
}

impl FrameProbe {
    pub fn open(node: &IpcNode, channel: FrameChannel) -> Result<FrameProbe, IpcError> {
        let sub = channel.frame_subscriber_if_exists(node, Queue::Drain)?;
        let mut p = FrameProbe {
            channel,
            sub,
            stats: Stats::new(),
            latest: None,
            keep: false,
        };
        if let Some(s) = &p.sub {
            while let Some(f) = s.receive()? {
                let h = f.user_header();
                p.stats.prime(0, h.seq, Some(h.published_ns));
            }
        }
        p.stats.reset();
        Ok(p)
    }
}

impl Probe for FrameProbe {
    fn name(&self) -> &'static str {
        self.channel.name
    }
    fn present(&self) -> bool {
        self.sub.is_some()
    }
    fn counts(&self, node: &IpcNode) -> Result<(usize, usize), IpcError> {
        if !self.present() {
            return Ok((0, 0));
        }
        Ok(others(self.channel.ports(node)?))
    }
    fn poll(&mut self, mut each: Option<&mut dyn FnMut(Value) -> bool>) -> Result<bool, IpcError> {
        let Some(sub) = &self.sub else {
            return Ok(true);
        };
        while let Some(f) = sub.receive()? {
            let h = *f.user_header();
            let bytes = f.payload().len() * 2 + std::mem::size_of::<FrameHeader>();
            self.stats.record(0, h.seq, Some(h.published_ns), bytes);
            if self.keep {
                self.latest = Some(frame_json(&h, f.payload()));
            }
            if let Some(cb) = each.as_mut() {
                if !cb(frame_json(&h, f.payload())) {
                    return Ok(false);
                }
            }
        }
        Ok(true)
    }
    fn stats(&self) -> &Stats {
        &self.stats
    }
    fn stats_mut(&mut self) -> &mut Stats {
        &mut self.stats
    }
    fn as_any(&self) -> &dyn Any {
        self
    }
    fn latest(&self) -> Option<Value> {
        self.latest.clone()
    }
    fn keep_latest(&mut self, on: bool) {
        self.keep = on;
        if !on {
            self.latest = None;
        }
    }
}

/// Opens the probe of each channel visited (typed by the channel).
struct Opener<'a> {
    node: &'a IpcNode,
    probes: Result<Vec<Box<dyn Probe>>, IpcError>,
}

impl Opener<'_> {
    fn add<P: Probe + 'static>(&mut self, open: impl FnOnce(&IpcNode) -> Result<P, IpcError>) {
        if let Ok(probes) = &mut self.probes {
            match open(self.node) {
                Ok(p) => probes.push(Box::new(p)),
                Err(e) => self.probes = Err(e),
            }
        }
    }
}

impl ChannelVisitor for Opener<'_> {
    fn message<T: Message>(&mut self, channel: Channel<T>) {
        self.add(|node| MsgProbe::open(node, channel));
    }
    fn frames(&mut self, channel: FrameChannel) {
        self.add(|node| FrameProbe::open(node, channel));
    }
}

/// Open the probe of `channel`.
pub fn open(node: &IpcNode, channel: &str) -> Result<Box<dyn Probe>, ProbeError> {
    let mut o = Opener {
        node,
        probes: Ok(Vec::new()),
    };
    if !visit_named(channel, &mut o) {
        return Err(ProbeError::UnknownChannel {
            name: channel.to_string(),
        });
    }
    let mut probes = o.probes?;
    probes.pop().ok_or_else(|| ProbeError::UnknownChannel {
        name: channel.to_string(),
    })
}

/// Open the probes of every channel of the cell, in [`ALL`]'s order.
pub fn open_all(node: &IpcNode) -> Result<Vec<Box<dyn Probe>>, ProbeError> {
    let mut o = Opener {
        node,
        probes: Ok(Vec::new()),
    };
    visit_all(&mut o);
    Ok(o.probes?)
}

/// The newest value a typed probe has seen.
pub fn last<T: Message>(p: &dyn Probe) -> Option<T> {
    p.as_any()
        .downcast_ref::<MsgProbe<T>>()
        .and_then(|m| m.last)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_closed_window_keeps_its_span() {
        let mut s = Stats::new();
        for seq in 0..10 {
            s.record(0, seq, None, 8);
        }
        s.close();
        let before = s.summary();
        std::thread::sleep(std::time::Duration::from_millis(20));
        let after = s.summary();
        assert_eq!(before["rate_hz"], after["rate_hz"]);
        assert_eq!(before["bandwidth_bps"], after["bandwidth_bps"]);
        assert_eq!(after["samples"], 10);
        // a new window runs on the clock again
        s.reset();
        assert!(s.window_end_ns.is_none());
    }
}
