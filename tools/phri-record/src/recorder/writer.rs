//! The MCAP file of a recording: one channel per recorder topic, the 3-D
//! scene's topics in Foxglove's schemas, the metadata, and the messages.

use std::collections::BTreeMap;
use std::fs::File;
use std::io::BufWriter;

use phri_runtime::now_ns;
use serde_json::Value;

use super::channels::{Rec, Viz};
use super::settings::Settings;
use super::RecordError;
use crate::{config, ENCODING, METADATA_NAME};

/// An MCAP file being written, and how many messages it holds.
pub struct Recording {
    w: mcap::Writer<BufWriter<File>>,
    /// `ids[rec][topic]`: MCAP channel ids of each recorder's topics
    ids: Vec<Vec<u16>>,
    /// the scene's topics: (topic, channel id, messages written)
    scene_ids: Vec<(&'static str, u16, u32)>,
    /// one encoded scene message
    buf: Vec<u8>,
    /// the first write that failed since the last poll
    write_err: Option<RecordError>,
    /// messages per recorder (its own topic)
    pub counts: Vec<u64>,
    /// messages in all (image views and scene included)
    pub total: u64,
}

impl Recording {
    /// Creates `path` with a channel per topic of `recs`, the scene's
    /// topics when `scene`, compressed as `settings` say.
    pub fn create(
        path: &str,
        settings: &Settings,
        recs: &[Box<dyn Rec>],
        scene: bool,
    ) -> Result<Recording, RecordError> {
        let file = File::create(path).map_err(|source| RecordError::Create {
            path: path.to_string(),
            source,
        })?;
        let mut w = mcap::WriteOptions::new()
            .compression(config::mcap_compression(settings.rc.compression))
            .profile(crate::PROFILE)
            .library(concat!("phri-record ", env!("CARGO_PKG_VERSION")))
            .create(BufWriter::new(file))?;
        let mut ids: Vec<Vec<u16>> = Vec::with_capacity(recs.len());
        for r in recs {
            let mut rec_ids = Vec::new();
            for t in r.topics() {
                let schema = w.add_schema(&t.schema_name, "jsonschema", &t.schema)?;
                rec_ids.push(w.add_channel(schema, &t.name, ENCODING, &BTreeMap::new())?);
            }
            ids.push(rec_ids);
        }
        let mut scene_ids = Vec::new();
        if scene {
            for t in phri_viz::topics::all() {
                let s = &t.schema;
                let schema = w.add_schema(&s.name, &s.encoding, &s.data)?;
                let id = w.add_channel(schema, t.name, &t.encoding, &BTreeMap::new())?;
                scene_ids.push((t.name, id, 0));
            }
        }
        Ok(Recording {
            w,
            ids,
            scene_ids,
            buf: Vec::new(),
            write_err: None,
            counts: vec![0; recs.len()],
            total: 0,
        })
    }

    /// Writes the metadata record.
    pub fn write_metadata(
        &mut self,
        metadata: BTreeMap<String, String>,
    ) -> Result<(), RecordError> {
        self.w.write_metadata(&mcap::records::Metadata {
            name: METADATA_NAME.into(),
            metadata,
        })?;
        Ok(())
    }

    /// Drains every recorder (`recs`, as created) into the file, then the
    /// scene's new messages; the first write that failed, if any.
    pub fn poll(&mut self, recs: &mut [Box<dyn Rec>], viz: &mut Viz) -> Result<(), RecordError> {
        for (i, r) in recs.iter_mut().enumerate() {
            let (rec_ids, count) = (&self.ids[i], &mut self.counts[i]);
            let (w, total, we) = (&mut self.w, &mut self.total, &mut self.write_err);
            r.poll(
                &mut |topic, t, seq, v: Value| {
                    let Some(&id) = rec_ids.get(topic) else {
                        return;
                    };
                    let data = serde_json::to_vec(&v).expect("JSON values serialize");
                    match write(w, id, seq, t, &data) {
                        Ok(()) => {
                            *total += 1;
                            if topic == 0 {
                                *count += 1;
                            }
                        }
                        Err(e) if we.is_none() => *we = Some(e),
                        Err(_) => {}
                    }
                },
                viz,
            )?;
        }
        if let Some(p) = &mut viz.pipeline {
            p.tick(now_ns(), &|_| true, &mut viz.out);
        }
        for o in viz.out.drain(..) {
            self.write_scene(o);
        }
        match self.write_err.take() {
            Some(e) => Err(e),
            None => Ok(()),
        }
    }

    /// Writes one scene message (of a topic made at creation, else dropped).
    fn write_scene(&mut self, o: phri_viz::Output) {
        let Some((_, id, seq)) = self.scene_ids.iter_mut().find(|(t, _, _)| *t == o.topic) else {
            return;
        };
        self.buf.clear();
        if let Err(e) = o.message.encode(&mut self.buf) {
            self.write_err.get_or_insert(RecordError::Scene {
                topic: o.topic.to_string(),
                message: e.to_string(),
            });
            return;
        }
        *seq = seq.wrapping_add(1);
        match write(&mut self.w, *id, *seq, o.log_ns, &self.buf) {
            Ok(()) => self.total += 1,
            Err(e) => {
                self.write_err.get_or_insert(e);
            }
        }
    }

    /// Writes the summary and indexes: the number of chunks, and of scene messages.
    pub fn finish(mut self) -> Result<(usize, u64), RecordError> {
        let summary = self.w.finish()?;
        let scene = self.scene_ids.iter().map(|(_, _, n)| u64::from(*n)).sum();
        Ok((summary.chunk_indexes.len(), scene))
    }
}

/// One message on channel `id`, logged and published at `t` [ns].
fn write(
    w: &mut mcap::Writer<BufWriter<File>>,
    id: u16,
    sequence: u32,
    t: u64,
    data: &[u8],
) -> Result<(), RecordError> {
    let hdr = mcap::records::MessageHeader {
        channel_id: id,
        sequence,
        log_time: t,
        publish_time: t,
    };
    Ok(w.write_to_known_channel(&hdr, data)?)
}

/// The metadata of a recording of the cell at `prefix`: its clock, how
/// frames are kept, the scene (when `scene`), the compression, the start
/// and the collision threshold when known.
pub fn metadata(prefix: &str, settings: &Settings, scene: bool) -> BTreeMap<String, String> {
    let (every, k) = (settings.rc.frame_every, settings.rc.frame_downsample);
    let mut meta = BTreeMap::new();
    meta.insert("prefix".to_string(), prefix.to_string());
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
    if scene {
        let rates = settings.rates();
        meta.insert(
            "scene".into(),
            format!(
                "the 3-D scene as phri-viz serves it, in Foxglove's schemas: {} (SceneUpdate at {} Hz, JointStates and phri.viz.Status at {} Hz, the recorded perception/depth frames as PointCloud and RawImage); robot model {}",
                phri_viz::TOPICS.join(", "),
                rates.scene_hz,
                rates.joints_hz,
                settings.loaded.urdf().display()
            ),
        );
    }
    meta.insert("frame_every".into(), every.to_string());
    meta.insert("frame_downsample".into(), k.to_string());
    meta.insert(
        "compression".into(),
        settings.rc.compression.name().to_string(),
    );
    meta.insert("start_ns".into(), now_ns().to_string());
    if let Some(t) = settings.threshold {
        meta.insert("collision_norm_threshold".into(), t.to_string());
    }
    meta
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::recorder::Flags;

    #[test]
    fn metadata_says_how_frames_are_kept() {
        let settings = Settings::resolve(&Flags {
            frame_every: Some(5),
            frame_downsample: Some(2),
            threshold: Some(12.0),
            ..Flags::default()
        })
        .unwrap();
        let meta = metadata("p_", &settings, false);
        assert_eq!(meta["prefix"], "p_");
        assert_eq!(meta["frame_every"], "5");
        assert!(meta["depth_frames"].contains("640x480 -> 320x240"));
        assert_eq!(meta["collision_norm_threshold"], "12");
        assert!(!meta.contains_key("scene"));
    }
}
