//! One recorder per channel of the cell ([`Rec`]): which MCAP topics it
//! writes, how it attaches (never creating a channel) and how it drains its
//! queue, passing the 3-D scene's inputs to [`Viz`].

use phri_ipc::*;
use phri_runtime::now_ns;
use phri_viz::{Output, Pipeline};
use serde_json::Value;

use super::frames::FrameRec;
use crate::config::RecordConfig;
use crate::json::{log_ns, to_json};

/// The 3-D scene of the recording: phri-viz's pipeline and what it made last.
pub struct Viz {
    /// `None`: no scene (the configuration's model did not load)
    pub pipeline: Option<Pipeline>,
    /// the scene messages made since they were last written
    pub out: Vec<Output>,
}

impl Viz {
    /// Offers message `m` to the scene.
    pub fn offer<T: std::any::Any>(&mut self, m: &T) {
        if let Some(p) = &mut self.pipeline {
            p.offer(m, &|_| true, &mut self.out);
        }
    }
}

/// `out(topic, log_ns, seq, json)`: `topic` indexes [`Rec::topics`].
pub type Out<'a> = dyn FnMut(usize, u64, u32, Value) + 'a;

/// One MCAP topic: name, schema name, JSON schema.
pub struct Topic {
    pub name: String,
    pub schema_name: String,
    pub schema: Vec<u8>,
}

impl Topic {
    /// a phri channel as it is: topic and schema named after the channel
    pub fn channel(name: &str) -> Topic {
        Topic {
            name: name.to_string(),
            schema_name: name.to_string(),
            schema: br#"{"type":"object"}"#.to_vec(),
        }
    }
}

/// One channel being recorded.
pub trait Rec {
    /// the channel's name
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

/// The recorder of a message channel: every message, as JSON.
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
        self.recs.push(Box::new(FrameRec::new(
            channel,
            self.rc.frame_every,
            self.rc.frame_downsample,
        )));
    }
}

/// A recorder per channel of a cell of `cameras` cameras: every channel of
/// [`ALL`], then each further camera's.
pub fn recorders(rc: &RecordConfig, cameras: usize) -> Vec<Box<dyn Rec>> {
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

/// `name=count` per channel, space-separated: `counts[i]` messages of `recs[i]`.
pub fn counts_line(recs: &[Box<dyn Rec>], counts: &[u64]) -> String {
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
    fn every_channel_is_recorded() {
        let rc = crate::config::defaults();
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

    #[test]
    fn counts_name_their_channels() {
        let recs = recorders(&crate::config::defaults(), 1);
        let counts: Vec<u64> = (0..recs.len() as u64).collect();
        let line = counts_line(&recs, &counts);
        assert!(
            line.starts_with(&format!("{}=0 {}=1", ALL[0], ALL[1])),
            "{line}"
        );
    }
}
