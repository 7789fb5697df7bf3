//! `phri-record --prefix P --out FILE.mcap [--seconds S] [--frame-every N] [--frame-downsample K] [--compression zstd|lz4|none] [--config phri.toml] [--threshold NM]`
//!
//! Attaches read-only to every channel of `phri_ipc::ALL` of a running cell
//! (subscribers only, never creating a channel, normal scheduling, 5 ms between
//! polls) and writes an MCAP file: one channel per phri channel (topic = its
//! name), `json` messages with a `jsonschema` schema, log time = the message's
//! publish/stamp time [ns, CLOCK_MONOTONIC] (else the receive time). Depth frames:
//! every N-th received frame, header fields plus the image downsampled K× per axis,
//! and the same image as `foxglove.RawImage` (16UC1) on `<channel>/image` for
//! Foxglove's Image panel. Chunks are compressed with zstd. N (10), K (4) and
//! the compression come from `[record]` of `--config`; the flags override them.
//!
//! Beside them, the 3-D scene as `phri-viz` serves it, on the same topics and
//! in Foxglove's own schemas (protobuf; the status in JSON): `/viz/robot`,
//! `/viz/person`, `/viz/repulsion`, `/viz/collab` (`foxglove.SceneUpdate`,
//! 30 Hz), `/viz/tf` (`foxglove.FrameTransforms`), `/viz/joints`
//! (`foxglove.JointStates`, 250 Hz), `/viz/status` (`phri.viz.Status`), and
//! the recorded `perception/depth` frames as `/viz/depth/points`
//! (`foxglove.PointCloud`) and `/viz/depth/image` (`foxglove.RawImage`): a
//! recording opens in Foxglove with `deploy/foxglove/phri-layout.json` as the
//! live cell does. The robot model is the configuration's (`--config`, else
//! the built-in defaults).
//!
//! Stops after `--seconds` or on Ctrl-C and writes the summary and indexes; a
//! progress bar on a terminal, a line per second otherwise.

use std::collections::BTreeMap;
use std::error::Error;
use std::fs::File;
use std::io::BufWriter;
use std::path::PathBuf;
use std::process::ExitCode;
use std::time::{Duration, Instant};

use clap::Parser;
use phri_ipc::*;
use phri_record::config::{self, RecordConfig};
use phri_record::json::{log_ns, to_json};
use phri_record::progress::Progress;
use phri_record::{foxglove, ENCODING, METADATA_NAME};
use phri_runtime::cli::CompletionsCmd;
use phri_runtime::{now_ns, Shutdown};
use phri_viz::{Output, Pipeline, Rates};
use serde_json::{json, Value};

const BIN: &str = "phri-record";
const POLL: Duration = Duration::from_millis(5);
/// Rates of the 3-D scene in a recording: the scene as phri-viz serves it by default.
const SCENE_RATES: Rates = Rates {
    scene_hz: 30.0,
    joints_hz: 250.0,
    // both set from [record] frame_downsample
    depth_downsample: 4,
    cloud_downsample: 4,
};

/// The command line.
#[derive(Parser, Debug)]
#[command(
    version = phri_runtime::cli::VERSION,
    about = "Records a running cell to MCAP: every channel as JSON, depth frames downsampled, and the 3-D scene in Foxglove's schemas (read-only)",
    args_conflicts_with_subcommands = true,
    subcommand_negates_reqs = true
)]
struct Cli {
    /// iceoryx2 prefix of the cell [default: phri_]
    #[arg(long, value_name = "PREFIX", env = phri_runtime::PREFIX_ENV)]
    prefix: Option<String>,
    /// MCAP file to write
    #[arg(long, value_name = "FILE.mcap", required = true)]
    out: Option<PathBuf>,
    /// Stop after this long [s] (default: on Ctrl-C)
    #[arg(long, value_name = "S")]
    seconds: Option<f64>,
    /// Keep every N-th depth frame [default: [record] frame_every, 10]
    #[arg(long, value_name = "N")]
    frame_every: Option<u64>,
    /// Keep one depth pixel in K per axis [default: [record] frame_downsample, 4]
    #[arg(long, value_name = "K")]
    frame_downsample: Option<usize>,
    /// Chunk compression: zstd, lz4 or none [default: [record] compression, zstd]
    #[arg(long, value_name = "zstd|lz4|none")]
    compression: Option<String>,
    /// Cell configuration: [record], the robot model, the collision threshold and the cameras (a further camera's channels, `camera/1/depth`, …, are recorded too)
    #[arg(long, value_name = "FILE")]
    config: Option<PathBuf>,
    /// Collision norm threshold written into the metadata for phri-plot [Nm] [default: the configuration's]
    #[arg(long, value_name = "NM", allow_negative_numbers = true)]
    threshold: Option<f64>,
    #[command(subcommand)]
    completions: Option<CompletionsCmd>,
}

fn main() -> ExitCode {
    let cli: Cli = phri_runtime::cli::parse(BIN);
    if let Some(CompletionsCmd::Completions { shell }) = cli.completions {
        phri_runtime::cli::completions::<Cli>(BIN, shell);
        return ExitCode::SUCCESS;
    }
    let prefix = phri_runtime::prefix_or_default(cli.prefix.as_deref().filter(|p| !p.is_empty()));
    let code = phri_runtime::service::run(BIN, || body(cli).map_err(|e| e.to_string()));
    // the last node out of the prefix (the cell stopped first) takes back
    // what iceoryx2 left in shared memory; nothing while any node lives
    let _ = phri_ipc::remove_leftovers(&prefix);
    code
}

/// The 3-D scene of the recording: phri-viz's pipeline and what it made last.
struct Viz {
    pipeline: Option<Pipeline>,
    out: Vec<Output>,
}

impl Viz {
    fn offer<T: std::any::Any>(&mut self, m: &T) {
        if let Some(p) = &mut self.pipeline {
            p.offer(m, &|_| true, &mut self.out);
        }
    }
}

/// `out(topic, log_ns, seq, json)`: `topic` indexes [`Rec::topics`].
type Out<'a> = dyn FnMut(usize, u64, u32, Value) + 'a;

/// One MCAP topic: name, schema name, JSON schema.
struct Topic {
    name: String,
    schema_name: String,
    schema: Vec<u8>,
}

impl Topic {
    /// a phri channel as it is: topic and schema named after the channel
    fn channel(name: &str) -> Topic {
        Topic {
            name: name.to_string(),
            schema_name: name.to_string(),
            schema: br#"{"type":"object"}"#.to_vec(),
        }
    }
}

/// One channel being recorded.
trait Rec {
    fn name(&self) -> &'static str;
    /// the MCAP topics this channel writes: the channel itself, plus views
    fn topics(&self) -> Vec<Topic> {
        vec![Topic::channel(self.name())]
    }
    /// subscribe if the channel exists now (a recorder never creates one); true when subscribed
    fn attach(&mut self, node: &IpcNode) -> Result<bool, IpcError>;
    /// drain the queue: `out(topic, log_ns, seq, json)` per recorded message;
    /// the scene's inputs go to `viz`
    fn poll(&mut self, out: &mut Out, viz: &mut Viz) -> Result<(), IpcError>;
}

struct MsgRec<T: Message> {
    channel: Channel<T>,
    sub: Option<Subscriber<T>>,
}

impl<T: Message> Rec for MsgRec<T> {
    fn name(&self) -> &'static str {
        self.channel.name
    }
    fn attach(&mut self, node: &IpcNode) -> Result<bool, IpcError> {
        if self.sub.is_none() {
            self.sub = self.channel.subscriber_if_exists(node, Queue::Drain)?;
        }
        Ok(self.sub.is_some())
    }
    fn poll(&mut self, out: &mut Out, viz: &mut Viz) -> Result<(), IpcError> {
        let Some(sub) = &self.sub else {
            return Ok(());
        };
        while let Some(m) = sub.receive()? {
            viz.offer(&m);
            let v = to_json(&m);
            out(0, log_ns(&m, &v, now_ns()), m.seq() as u32, v);
        }
        Ok(())
    }
}

struct FrameRec {
    channel: FrameChannel,
    sub: Option<FrameSubscriber>,
    every: u64,
    /// keep one pixel in `k` per axis
    k: usize,
    received: u64,
}

/// The depth image downsampled by `k` per axis (the top-left pixel of each
/// block): `(width, height, mm)`; empty when the payload is short.
fn downsample(h: &FrameHeader, d: &[u16], k: usize) -> (usize, usize, Vec<u16>) {
    let (w, ht) = (h.width as usize, h.height as usize);
    let (dw, dh) = (w / k, ht / k);
    let mut data = Vec::with_capacity(dw * dh);
    if d.len() >= w * ht {
        for y in 0..dh {
            for x in 0..dw {
                data.push(d[y * k * w + x * k]);
            }
        }
    }
    (dw, dh, data)
}

/// Header fields (their JSON view, `q` cut to `dof`) plus the downsampled depth image.
fn frame_json(h: &FrameHeader, k: usize, dw: usize, dh: usize, data: &[u16]) -> Value {
    let Ok(Value::Object(mut m)) = serde_json::to_value(h) else {
        unreachable!("a frame header serializes as an object");
    };
    if let Some(Value::Array(q)) = m.get_mut("q") {
        q.truncate((h.dof as usize).min(MAX_DOF));
    }
    m.insert("downsample".into(), json!(k));
    m.insert("data_width".into(), json!(dw));
    m.insert("data_height".into(), json!(dh));
    m.insert("data".into(), json!(data));
    Value::Object(m)
}

impl Rec for FrameRec {
    fn name(&self) -> &'static str {
        self.channel.name
    }
    fn topics(&self) -> Vec<Topic> {
        vec![
            Topic::channel(self.channel.name),
            Topic {
                name: foxglove::image_topic(self.channel.name),
                schema_name: foxglove::RAW_IMAGE.to_string(),
                schema: foxglove::raw_image_schema(),
            },
        ]
    }
    fn attach(&mut self, node: &IpcNode) -> Result<bool, IpcError> {
        if self.sub.is_none() {
            self.sub = self
                .channel
                .frame_subscriber_if_exists(node, Queue::Drain)?;
        }
        Ok(self.sub.is_some())
    }
    fn poll(&mut self, out: &mut Out, viz: &mut Viz) -> Result<(), IpcError> {
        let Some(sub) = &self.sub else {
            return Ok(());
        };
        while let Some(f) = sub.receive()? {
            self.received += 1;
            if !(self.received - 1).is_multiple_of(self.every) {
                continue;
            }
            let h = *f.user_header();
            let (dw, dh, data) = downsample(&h, f.payload(), self.k);
            // the filtered depth is the scene's point cloud and image
            if self.channel.name == PERCEPTION_DEPTH.name {
                if let Some(p) = &mut viz.pipeline {
                    p.offer_frame(&h, f.payload());
                }
            }
            drop(f);
            let t = if h.published_ns > 0 {
                h.published_ns
            } else {
                now_ns()
            };
            if !data.is_empty() {
                let stamp = if h.capture_ns > 0 { h.capture_ns } else { t };
                out(
                    1,
                    t,
                    h.seq as u32,
                    foxglove::raw_image_16uc1(stamp, dw, dh, &data),
                );
            }
            out(0, t, h.seq as u32, frame_json(&h, self.k, dw, dh, &data));
        }
        Ok(())
    }
}

/// A recorder for every channel of the cell, in [`ALL`]'s order.
struct Recs<'a> {
    rc: &'a RecordConfig,
    recs: Vec<Box<dyn Rec>>,
}

impl ChannelVisitor for Recs<'_> {
    fn message<T: Message>(&mut self, channel: Channel<T>) {
        self.recs.push(Box::new(MsgRec { channel, sub: None }));
    }
    fn frames(&mut self, channel: FrameChannel) {
        self.recs.push(Box::new(FrameRec {
            channel,
            sub: None,
            every: self.rc.frame_every,
            k: self.rc.frame_downsample,
            received: 0,
        }));
    }
}

/// A recorder per channel of a cell of `cameras` cameras: every channel of
/// [`ALL`], then each further camera's.
fn recorders(rc: &RecordConfig, cameras: usize) -> Vec<Box<dyn Rec>> {
    let mut recs = Recs {
        rc,
        recs: Vec::new(),
    };
    visit_all(&mut recs);
    for i in 1..cameras {
        visit_camera(i, &mut recs);
    }
    recs.recs
}

fn mcap_err(e: mcap::McapError) -> String {
    format!("mcap: {e}")
}

fn body(cli: Cli) -> Result<(), Box<dyn Error>> {
    let prefix = phri_runtime::prefix_or_default(cli.prefix.as_deref().filter(|p| !p.is_empty()));
    // clap requires it unless a subcommand is given
    let out_path = cli
        .out
        .as_ref()
        .ok_or("--out is required")?
        .display()
        .to_string();
    let seconds = cli.seconds;
    if seconds.is_some_and(|s| !(s > 0.0 && s.is_finite())) {
        return Err("--seconds must be positive".into());
    }
    // [record] of --config, then the flags over it
    let config_path = cli.config.as_ref().map(|p| p.display().to_string());
    let (mut rc, mut threshold) = match &config_path {
        Some(p) => config::from_file(p).map_err(|e| format!("--config {p}: {e}"))?,
        None => (config::defaults(), None),
    };
    if let Some(v) = cli.frame_every {
        rc.frame_every = v;
    }
    if let Some(v) = cli.frame_downsample {
        rc.frame_downsample = v;
    }
    if let Some(v) = &cli.compression {
        rc.compression = v
            .parse()
            .map_err(|e: phri_config::Invalid| format!("--compression {}", e.reason))?;
    }
    // the keys' messages name them: record.frame_every → --frame-every
    rc.validate().map_err(|e| {
        let flag = e.key.trim_start_matches("record.").replace('_', "-");
        format!("--{flag}: {}", e.reason)
    })?;
    let compression = config::mcap_compression(rc.compression);
    let (every, k) = (rc.frame_every, rc.frame_downsample);
    if let Some(t) = cli.threshold {
        threshold = Some(t);
    }
    // the scene's robot model, thresholds and control points: the configuration's
    let loaded = match &config_path {
        Some(p) => phri_config::Loaded::load(std::path::Path::new(p), None, &[])
            .map_err(|e| format!("--config {p}: {e}"))?,
        None => phri_config::Loaded::defaults(),
    };
    let rates = Rates {
        depth_downsample: k,
        cloud_downsample: k,
        ..SCENE_RATES
    };
    let mut viz = Viz {
        pipeline: match Pipeline::from_config(&loaded, rates) {
            Ok(p) => Some(p),
            Err(e) => {
                // the channels are still worth recording
                eprintln!("{BIN}: warning: no 3-D scene in the recording: {e}");
                None
            }
        },
        out: Vec::new(),
    };
    if phri_ipc::live_nodes(&prefix) == 0 {
        return Err(
            format!("no cell running under prefix '{prefix}' (no live iceoryx2 node)").into(),
        );
    }
    let shutdown = Shutdown::install()?;
    let node = node(&format!("record{}", std::process::id()), &prefix)?;

    let file =
        File::create(&out_path).map_err(|e| format!("--out: cannot create '{out_path}': {e}"))?;
    let mut w = mcap::WriteOptions::new()
        .compression(compression)
        .profile(phri_record::PROFILE)
        .library(concat!("phri-record ", env!("CARGO_PKG_VERSION")))
        .create(BufWriter::new(file))
        .map_err(mcap_err)?;

    let mut recs = recorders(&rc, loaded.config.cameras.len());
    // ids[rec][topic]: MCAP channel ids
    let mut ids: Vec<Vec<u16>> = Vec::with_capacity(recs.len());
    for r in &recs {
        let mut rec_ids = Vec::new();
        for t in r.topics() {
            let schema = w
                .add_schema(&t.schema_name, "jsonschema", &t.schema)
                .map_err(mcap_err)?;
            let id = w
                .add_channel(schema, &t.name, ENCODING, &BTreeMap::new())
                .map_err(mcap_err)?;
            rec_ids.push(id);
        }
        ids.push(rec_ids);
    }
    // the scene's topics, in Foxglove's schemas: (topic, channel id, messages written)
    let mut scene_ids: Vec<(&'static str, u16, u32)> = Vec::new();
    if viz.pipeline.is_some() {
        for t in phri_viz::topics::all() {
            let schema = w
                .add_schema(&t.schema.name, &t.schema.encoding, &t.schema.data)
                .map_err(mcap_err)?;
            let id = w
                .add_channel(schema, t.name, &t.encoding, &BTreeMap::new())
                .map_err(mcap_err)?;
            scene_ids.push((t.name, id, 0));
        }
    }
    let mut meta = BTreeMap::new();
    meta.insert("prefix".to_string(), prefix.clone());
    meta.insert(
        "clock".into(),
        "log_time: publish/stamp time [ns, CLOCK_MONOTONIC], else receive time".into(),
    );
    meta.insert(
        "depth_frames".into(),
        format!(
            "camera/depth, perception/depth: every {every}-th received frame, header fields plus the depth image downsampled {k}x per axis (top-left pixel of each block; 640x480 -> {}x{}) in 'data' (u16 millimetres, row-major, 0 = no reading); the same image as foxglove.RawImage on <channel>/image", 640 / k, 480 / k
        ),
    );
    if viz.pipeline.is_some() {
        meta.insert(
            "scene".into(),
            format!(
                "the 3-D scene as phri-viz serves it, in Foxglove's schemas: {} (SceneUpdate at {} Hz, JointStates and phri.viz.Status at {} Hz, the recorded perception/depth frames as PointCloud and RawImage); robot model {}",
                phri_viz::TOPICS.join(", "),
                rates.scene_hz,
                rates.joints_hz,
                loaded.urdf().display()
            ),
        );
    }
    meta.insert("frame_every".into(), every.to_string());
    meta.insert("frame_downsample".into(), k.to_string());
    meta.insert("compression".into(), rc.compression.name().to_string());
    meta.insert("start_ns".into(), now_ns().to_string());
    if let Some(t) = threshold {
        meta.insert("collision_norm_threshold".into(), t.to_string());
    }
    w.write_metadata(&mcap::records::Metadata {
        name: METADATA_NAME.into(),
        metadata: meta,
    })
    .map_err(mcap_err)?;

    let t0 = Instant::now();
    let end = seconds.map(Duration::from_secs_f64);
    // a bar of whole seconds for a timed recording, a message counter otherwise
    let bar = match seconds {
        Some(s) => Progress::new(BIN, Some(s.ceil() as u64), "s"),
        None => Progress::new(BIN, None, "messages"),
    };
    // messages per channel (its own topic) and in all (image views and scene included)
    let mut counts = vec![0u64; recs.len()];
    let mut total = 0u64;
    let mut next_attach = Instant::now();
    let mut next_report = t0 + Duration::from_secs(1);
    let mut write_err: Option<String> = None;
    let mut buf: Vec<u8> = Vec::new();
    while !shutdown.requested() && end.is_none_or(|e| t0.elapsed() < e) {
        if Instant::now() >= next_attach {
            for r in recs.iter_mut() {
                r.attach(&node)?;
            }
            next_attach = Instant::now() + Duration::from_secs(1);
        }
        for (i, r) in recs.iter_mut().enumerate() {
            let rec_ids = &ids[i];
            let count = &mut counts[i];
            let total = &mut total;
            let w = &mut w;
            let we = &mut write_err;
            r.poll(
                &mut |topic, t, seq, v| {
                    let Some(&id) = rec_ids.get(topic) else {
                        return;
                    };
                    let data = serde_json::to_vec(&v).expect("JSON values serialize");
                    let hdr = mcap::records::MessageHeader {
                        channel_id: id,
                        sequence: seq,
                        log_time: t,
                        publish_time: t,
                    };
                    match w.write_to_known_channel(&hdr, &data) {
                        Ok(()) => {
                            *total += 1;
                            if topic == 0 {
                                *count += 1;
                            }
                        }
                        Err(e) if we.is_none() => *we = Some(mcap_err(e)),
                        Err(_) => {}
                    }
                },
                &mut viz,
            )?;
        }
        if let Some(p) = &mut viz.pipeline {
            p.tick(now_ns(), &|_| true, &mut viz.out);
        }
        for o in viz.out.drain(..) {
            let Some((_, id, seq)) = scene_ids.iter_mut().find(|(t, _, _)| *t == o.topic) else {
                continue;
            };
            buf.clear();
            if let Err(e) = o.message.encode(&mut buf) {
                write_err.get_or_insert(format!("{}: {e}", o.topic));
                continue;
            }
            *seq = seq.wrapping_add(1);
            let hdr = mcap::records::MessageHeader {
                channel_id: *id,
                sequence: *seq,
                log_time: o.log_ns,
                publish_time: o.log_ns,
            };
            match w.write_to_known_channel(&hdr, &buf) {
                Ok(()) => total += 1,
                Err(e) => {
                    write_err.get_or_insert(mcap_err(e));
                }
            }
        }
        if let Some(e) = write_err.take() {
            return Err(e.into());
        }
        match seconds {
            Some(_) => bar.set_position(t0.elapsed().as_secs()),
            None => bar.set_position(total),
        }
        if Instant::now() >= next_report {
            next_report += Duration::from_secs(1);
            if bar.shown() {
                bar.set_message(format!("{total} messages"));
            } else {
                eprintln!(
                    "phri-record: {:.0} s  {}",
                    t0.elapsed().as_secs_f64(),
                    progress(&recs, &counts)
                );
            }
        }
        std::thread::sleep(POLL);
    }
    bar.finish();
    let summary = w.finish().map_err(mcap_err)?;
    drop(w);
    let size = std::fs::metadata(&out_path).map(|m| m.len()).unwrap_or(0);
    let scene: u64 = scene_ids.iter().map(|(_, _, n)| u64::from(*n)).sum();
    eprintln!(
        "phri-record: wrote {out_path}: {total} messages in {:.1} s, {:.1} MB, {} chunks; {}; scene {scene}",
        t0.elapsed().as_secs_f64(),
        size as f64 / 1e6,
        summary.chunk_indexes.len(),
        progress(&recs, &counts)
    );
    Ok(())
}

fn progress(recs: &[Box<dyn Rec>], counts: &[u64]) -> String {
    recs.iter()
        .zip(counts)
        .map(|(r, c)| format!("{}={c}", r.name()))
        .collect::<Vec<_>>()
        .join(" ")
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn frame_messages_keep_their_fields() {
        let mut h = FrameHeader::zeroed();
        h.seq = 12;
        h.capture_ns = 100;
        h.capture_wall_ns = 200;
        h.published_ns = 300;
        h.width = 4;
        h.height = 2;
        h.fx = 525.0;
        h.fy = 525.0;
        h.cx = 319.5;
        h.cy = f64::NAN;
        h.depth_scale = 0.001;
        h.pose_r = [1.0, 0.0, 0.0, 0.0, 1.0, 0.0, 0.0, 0.0, 1.0];
        h.pose_t = [1.5, 0.0, 1.25];
        h.q[..3].copy_from_slice(&[0.5, -0.25, 1.0]);
        h.q_stamp_ns = 90;
        h.dof = 3;
        h.removed_pixels = 2;
        h.valid_pixels = 5;
        let d = [1000u16, 0, 1200, 0, 900, 0, 800, 0];
        let (dw, dh, data) = downsample(&h, &d, 2);
        assert_eq!((dw, dh, data.clone()), (2, 1, vec![1000, 1200]));
        // as the hand-written view had it, and the arrival → publication
        // time of issue 14 (a former padding field)
        let expected = json!({
            "seq": 12, "capture_ns": 100, "capture_wall_ns": 200, "published_ns": 300,
            "width": 4, "height": 2, "fx": 525.0, "fy": 525.0, "cx": 319.5, "cy": null,
            "depth_scale": 0.001, "pose_r": h.pose_r, "pose_t": h.pose_t,
            "q": [0.5, -0.25, 1.0], "q_stamp_ns": 90, "dof": 3, "removed_pixels": 2,
            "valid_pixels": 5, "ingest_ns": 0, "downsample": 2, "data_width": 2, "data_height": 1,
            "data": [1000, 1200],
        });
        assert_eq!(frame_json(&h, 2, dw, dh, &data), expected);
    }

    #[test]
    fn every_channel_is_recorded() {
        let rc = config::defaults();
        let recs = recorders(&rc, 1);
        let names: Vec<&str> = recs.iter().map(|r| r.name()).collect();
        assert_eq!(names, ALL);
        let topics: Vec<usize> = recs.iter().map(|r| r.topics().len()).collect();
        assert_eq!(
            topics.iter().sum::<usize>(),
            ALL.len() + 2,
            "frames add an image topic"
        );
        // two cameras: the second's five channels after them, its two
        // frame channels with their image topics
        let recs = recorders(&rc, 2);
        let names: Vec<&str> = recs.iter().map(|r| r.name()).collect();
        assert_eq!(names[..ALL.len()], *ALL);
        assert_eq!(names[ALL.len()..], FURTHER_CAMERAS[..5]);
        let topics: usize = recs.iter().map(|r| r.topics().len()).sum();
        assert_eq!(topics, ALL.len() + 2 + 5 + 2);
    }
}
