//! Read-only probes: open an existing channel (never create it, never
//! publish), subscribe with a draining queue, and measure what arrives.

use std::any::Any;
use std::collections::{HashMap, VecDeque};

use iceoryx2::prelude::*;
use iceoryx2::service::port_factory::publish_subscribe::PortFactory;
use iceoryx2::service::port_factory::PortFactory as _;
use phri_ipc::*;
use phri_runtime::now_ns;
use serde_json::{json, Value};

use crate::json::{frame_json, Msg};

/// One received sample, as the statistics need it.
#[derive(Clone, Copy)]
struct Event {
    recv_ns: u64,
    /// publish time when known, else receive time
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
    window_start_ns: u64,
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
        self.total_samples += 1;
        self.total_drops += drops;
        self.events.push_back(Event {
            recv_ns: now,
            t_ns: pub_ns.unwrap_or(now),
            bytes,
            drops,
        });
    }

    /// Start a new window (for periodic reports).
    pub fn reset(&mut self) {
        self.events.clear();
        self.window_start_ns = now_ns();
    }

    /// Keep only the last `window_ns` (rolling window).
    pub fn trim(&mut self, window_ns: u64) {
        let now = now_ns();
        let cut = now.saturating_sub(window_ns);
        while self.events.front().is_some_and(|e| e.recv_ns < cut) {
            self.events.pop_front();
        }
        self.window_start_ns = self.window_start_ns.max(cut);
    }

    /// The window's figures as JSON (`null` where unknown).
    pub fn summary(&self) -> Value {
        let now = now_ns();
        let span_s = (now.saturating_sub(self.window_start_ns) as f64 * 1e-9).max(1e-9);
        let n = self.events.len();
        let (mut sum, mut max, mut k) = (0u64, 0u64, 0u64);
        let mut prev: Option<u64> = None;
        for e in &self.events {
            if let Some(p) = prev {
                let d = e.t_ns.saturating_sub(p);
                sum += d;
                max = max.max(d);
                k += 1;
            }
            prev = Some(e.t_ns);
        }
        let bytes: usize = self.events.iter().map(|e| e.bytes).sum();
        let drops: u64 = self.events.iter().map(|e| e.drops).sum();
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
    fn name(&self) -> &str;
    /// the channel's service exists
    fn present(&self) -> bool;
    /// (publishers, subscribers other than this monitor)
    fn counts(&self) -> (usize, usize);
    /// drain the queue into the statistics; `each` sees every sample as JSON when given
    fn poll(&mut self, each: Option<&mut dyn FnMut(Value) -> bool>) -> Result<bool, String>;
    fn stats(&self) -> &Stats;
    fn stats_mut(&mut self) -> &mut Stats;
    fn as_any(&self) -> &dyn Any;
}

fn err(name: &str, e: impl std::fmt::Debug) -> String {
    ipc_err(name, e).to_string()
}

/// Typed probe of a fixed-size message channel.
pub struct MsgProbe<T: Msg> {
    name: String,
    factory: Option<PortFactory<ipc::Service, T, ()>>,
    sub: Option<Sub<T>>,
    stats: Stats,
    pub last: Option<T>,
}

impl<T: Msg> MsgProbe<T> {
    pub fn open(node: &Node<ipc::Service>, name: &str) -> Result<MsgProbe<T>, String> {
        // open only: a monitor never creates a channel
        let factory = open_existing_pubsub::<T>(node, name).map_err(|e| e.to_string())?;
        let sub = match &factory {
            Some(f) => Some(
                f.subscriber_builder()
                    .buffer_size(drain_buffer(name))
                    .create()
                    .map_err(|e| err(name, e))?,
            ),
            None => None,
        };
        let mut p = MsgProbe {
            name: name.to_string(),
            factory,
            sub,
            stats: Stats::new(),
            last: None,
        };
        // samples delivered on connecting (history) are not counted
        if let Some(s) = &p.sub {
            while let Some(m) = s.receive().map_err(|e| err(name, e))? {
                p.stats.prime(m.stream(), m.seq(), m.published_ns());
                p.last = Some(*m);
            }
        }
        p.stats.reset();
        Ok(p)
    }
}

impl<T: Msg> Probe for MsgProbe<T> {
    fn name(&self) -> &str {
        &self.name
    }
    fn present(&self) -> bool {
        self.factory.is_some()
    }
    fn counts(&self) -> (usize, usize) {
        match &self.factory {
            Some(f) => {
                let c = f.dynamic_config();
                (
                    c.number_of_publishers(),
                    c.number_of_subscribers().saturating_sub(1),
                )
            }
            None => (0, 0),
        }
    }
    fn poll(&mut self, mut each: Option<&mut dyn FnMut(Value) -> bool>) -> Result<bool, String> {
        let Some(sub) = &self.sub else {
            return Ok(true);
        };
        while let Some(m) = sub.receive().map_err(|e| err(&self.name, e))? {
            let m = *m;
            self.stats.record(
                m.stream(),
                m.seq(),
                m.published_ns(),
                std::mem::size_of::<T>(),
            );
            self.last = Some(m);
            if let Some(f) = each.as_mut() {
                if !f(m.to_json()) {
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
}

/// Probe of a depth-frame channel (`[u16]` with a [`FrameHeader`]).
pub struct FrameProbe {
    name: String,
    factory: Option<PortFactory<ipc::Service, [u16], FrameHeader>>,
    sub: Option<FrameSub>,
    stats: Stats,
}

impl FrameProbe {
    pub fn open(node: &Node<ipc::Service>, name: &str) -> Result<FrameProbe, String> {
        let factory = open_existing_frames(node, name).map_err(|e| e.to_string())?;
        let sub = match &factory {
            Some(f) => Some(
                f.subscriber_builder()
                    .buffer_size(drain_buffer(name))
                    .create()
                    .map_err(|e| err(name, e))?,
            ),
            None => None,
        };
        let mut p = FrameProbe {
            name: name.to_string(),
            factory,
            sub,
            stats: Stats::new(),
        };
        if let Some(s) = &p.sub {
            while let Some(f) = s.receive().map_err(|e| err(name, e))? {
                let h = f.user_header();
                p.stats.prime(0, h.seq, Some(h.published_ns));
            }
        }
        p.stats.reset();
        Ok(p)
    }
}

impl Probe for FrameProbe {
    fn name(&self) -> &str {
        &self.name
    }
    fn present(&self) -> bool {
        self.factory.is_some()
    }
    fn counts(&self) -> (usize, usize) {
        match &self.factory {
            Some(f) => {
                let c = f.dynamic_config();
                (
                    c.number_of_publishers(),
                    c.number_of_subscribers().saturating_sub(1),
                )
            }
            None => (0, 0),
        }
    }
    fn poll(&mut self, mut each: Option<&mut dyn FnMut(Value) -> bool>) -> Result<bool, String> {
        let Some(sub) = &self.sub else {
            return Ok(true);
        };
        while let Some(f) = sub.receive().map_err(|e| err(&self.name, e))? {
            let h = *f.user_header();
            let bytes = f.payload().len() * 2 + std::mem::size_of::<FrameHeader>();
            self.stats.record(0, h.seq, Some(h.published_ns), bytes);
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
}

/// Open the probe of `channel` (its message type from the channel name).
pub fn open(node: &Node<ipc::Service>, channel: &str) -> Result<Box<dyn Probe>, String> {
    Ok(match channel {
        ROBOT_STATE => Box::new(MsgProbe::<JointState>::open(node, channel)?),
        ROBOT_COMMAND => Box::new(MsgProbe::<TorqueCommand>::open(node, channel)?),
        ROBOT_STATS => Box::new(MsgProbe::<RobotStats>::open(node, channel)?),
        SIM_TRUTH => Box::new(MsgProbe::<Truth>::open(node, channel)?),
        DYNAMICS_RESIDUAL => Box::new(MsgProbe::<Residual>::open(node, channel)?),
        CONTROL_STATUS => Box::new(MsgProbe::<ControlStatus>::open(node, channel)?),
        SUPERVISOR_HEALTH => Box::new(MsgProbe::<Health>::open(node, channel)?),
        SIM_WORLD => Box::new(MsgProbe::<WorldState>::open(node, channel)?),
        PERCEPTION_REPULSION => Box::new(MsgProbe::<RepulsionResult>::open(node, channel)?),
        FAULT_DEPTH => Box::new(MsgProbe::<DepthFault>::open(node, channel)?),
        CAMERA_DEPTH | PERCEPTION_DEPTH => Box::new(FrameProbe::open(node, channel)?),
        other => return Err(unknown_channel(other)),
    })
}

pub fn unknown_channel(name: &str) -> String {
    format!("unknown channel '{name}'; channels: {}", ALL.join(", "))
}

/// The newest value a typed probe has seen.
pub fn last<T: Msg>(p: &dyn Probe) -> Option<T> {
    p.as_any()
        .downcast_ref::<MsgProbe<T>>()
        .and_then(|m| m.last)
}
