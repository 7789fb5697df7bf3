//! The recorder of a depth-frame channel: every N-th frame, downsampled,
//! as JSON with its header and as a `foxglove.RawImage` beside it.

use phri_ipc::*;
use phri_runtime::now_ns;
use serde_json::{json, Value};

use super::channels::{Out, Rec, Topic, Viz};
use crate::foxglove;

/// Records one depth-frame channel.
pub struct FrameRec {
    channel: FrameChannel,
    sub: Option<FrameSubscriber>,
    /// keep every `every`-th received frame
    every: u64,
    /// keep one pixel in `k` per axis
    k: usize,
    received: u64,
}

impl FrameRec {
    /// The recorder of `channel`, keeping every `every`-th frame, one pixel
    /// in `k` per axis; not yet attached.
    pub fn new(channel: FrameChannel, every: u64, k: usize) -> FrameRec {
        FrameRec {
            channel,
            sub: None,
            every,
            k,
            received: 0,
        }
    }
}

/// The depth image downsampled by `k` per axis (the top-left pixel of each
/// block): `(width, height, mm)`; empty when the payload is short.
pub fn downsample(h: &FrameHeader, d: &[u16], k: usize) -> (usize, usize, Vec<u16>) {
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
pub fn frame_json(h: &FrameHeader, k: usize, dw: usize, dh: usize, data: &[u16]) -> Value {
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
}
