//! The camera's DDS side: its ROS 2 node, the image and camera-info
//! subscriptions, and the poll that waits on both; what is taken goes to
//! the [`RosCamera`].

use std::error::Error;

use phri_config::CameraConfig;
use phri_perception::{CameraOut, DropCause};
use ros2_client::dds::rustdds::mio1;
use ros2_client::{Context, Node, NodeName, NodeOptions, Subscription};

use super::{subscription, CameraInfo, RosCamera, IMAGE_QOS, INFO_QOS, WAIT};
use crate::msgs::Image;

/// Camera `index`'s subscriptions, registered with one poll.
pub(super) struct Inputs {
    poll: mio1::Poll,
    events: mio1::Events,
    infos: Subscription<CameraInfo>,
    images: Subscription<Image>,
    /// the node the subscriptions belong to (`/phri_camera_<index>`)
    _node: Node,
}

impl Inputs {
    /// The node `/phri_camera_<index>` on `dds` with `cfg`'s image and
    /// info subscriptions; ROS 2's discovery of it runs on a thread of its own.
    pub(super) fn open(
        dds: &Context,
        index: usize,
        cfg: &CameraConfig,
    ) -> Result<Inputs, Box<dyn Error>> {
        let mut node = dds
            .new_node(
                NodeName::new("/", &format!("phri_camera_{index}"))
                    .map_err(|e| format!("ROS 2 node name: {e}"))?,
                NodeOptions::new().enable_rosout(false),
            )
            .map_err(|e| format!("ROS 2 node: {e:?}"))?;
        let mut images = subscription::<Image>(&mut node, &cfg.image_topic, IMAGE_QOS)?;
        let mut infos = subscription::<CameraInfo>(&mut node, &cfg.info_topic, INFO_QOS)?;
        crate::participant::spin_discovery(&mut node)?;
        let poll = mio1::Poll::new()?;
        let events = mio1::Events::with_capacity(8);
        poll.registry()
            .register(&mut images, mio1::Token(0), mio1::Interest::READABLE)?;
        poll.registry()
            .register(&mut infos, mio1::Token(1), mio1::Interest::READABLE)?;
        Ok(Inputs {
            poll,
            events,
            infos,
            images,
            _node: node,
        })
    }

    /// Until an image or an info arrives, at most [`WAIT`].
    pub(super) fn wait(&mut self) {
        // a signal ends the wait early (EINTR): the loop's check follows
        let _ = self.poll.poll(&mut self.events, Some(WAIT));
    }

    /// Every camera info waiting, to `camera` at `now_ns` [ns, CLOCK_MONOTONIC];
    /// an undecodable one is counted as refused.
    pub(super) fn take_infos(&self, camera: &mut RosCamera, info_topic: &str, now_ns: u64) {
        loop {
            match self.infos.take() {
                Ok(Some((m, _))) => camera.info(&m, now_ns),
                Ok(None) => break,
                Err(e) => {
                    camera.infos_refused += 1;
                    tracing::debug!("{info_topic}: undecodable camera info: {e:?}");
                    break;
                }
            }
        }
    }

    /// The newest of the images waiting; the ones it replaced are counted
    /// on `out` as behind, an undecodable sample as malformed (at `now_ns`).
    pub(super) fn take_newest_image(
        &self,
        camera: &mut RosCamera,
        out: &mut CameraOut,
        now_ns: u64,
    ) -> Option<Image> {
        let mut newest: Option<Image> = None;
        loop {
            match self.images.take() {
                Ok(Some((m, _))) => {
                    if newest.replace(m).is_some() {
                        out.stamps().count(DropCause::Behind);
                    }
                }
                Ok(None) => break,
                Err(e) => {
                    let why = format!("not a sensor_msgs/Image ({e:?})");
                    camera.undecodable(out, crate::gate::shown(&why).as_str(), now_ns);
                    break;
                }
            }
        }
        newest
    }
}
