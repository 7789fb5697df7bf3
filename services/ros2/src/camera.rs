//! `phri-camera-ros2`: any ROS 2 depth camera behind `camera/depth`. It
//! subscribes to a `sensor_msgs/Image` (`[camera] image_topic`, REP 118:
//! `16UC1`/`mono16` millimetres or `32FC1` metres) and its
//! `sensor_msgs/CameraInfo` (`[camera] info_topic`), both best effort, keep
//! last (what a camera driver's sensor-data or default QoS writer matches),
//! resamples each image to the channel's 640×480 keeping the nearest
//! reading of each output pixel's footprint ([`phri_depth::ros_image`]),
//! scales the intrinsics to match and publishes through
//! [`phri_perception::CameraOut`]: the capture time is the image's header
//! stamp (ROS time: CLOCK_REALTIME) mapped onto CLOCK_MONOTONIC; a frame
//! from the future or older than `[camera] max_age_s`, an image before a
//! valid CameraInfo, a malformed image or a refused encoding is dropped,
//! counted on `camera/status` and logged at most once a second.
//!
//! The DDS participant is phri-ros2's: ROS 2's domain from `ROS_DOMAIN_ID`,
//! this host only unless `[ros2] discovery = "subnet"` (ROS 2's
//! variables override it, [`crate::discovery`]), every socket checked to be
//! on 127.0.0.1 then.

use std::error::Error;
use std::time::Duration;

use phri_config::ros2::Ros2Discovery;
use phri_config::{CameraConfig, CameraSource};
use phri_depth::ros_image::{self, ImageView, Resampler};
use phri_depth::Intrinsics;
use phri_ipc::{CameraChannels, CameraStatus, IpcError};
use phri_perception::{CameraOut, CameraStamps, DropCause, RateLimited};
use phri_runtime::{now_ns, ServiceContext};
use ros2_client::{qos::History, MessageTypeName, Name, Node, QosProfile, Subscription};
use serde::{Deserialize, Serialize};

use crate::msgs::{Header, Image, RosType};
use crate::participant::{domain_id, participant, reach, realtime_ns};

mod dds;
use dds::Inputs;

/// Images as read: best effort (matches a reliable or a best-effort
/// writer), the newest two.
pub const IMAGE_QOS: QosProfile =
    QosProfile::subscription_default().history(History::KeepLast { depth: 2 });
/// Camera infos as read: best effort, the newest.
pub const INFO_QOS: QosProfile =
    QosProfile::subscription_default().history(History::KeepLast { depth: 1 });

/// The longest wait for an image [ms]: the heartbeat and the status go on
/// without images.
const WAIT: Duration = Duration::from_millis(50);

/// `sensor_msgs/RegionOfInterest`.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Serialize, Deserialize)]
pub struct RegionOfInterest {
    /// the region's leftmost column \[px\]
    pub x_offset: u32,
    /// the region's top row \[px\]
    pub y_offset: u32,
    /// the region's rows \[px\]
    pub height: u32,
    /// the region's columns \[px\]
    pub width: u32,
    /// whether a rectified region is to be computed from this raw one
    pub do_rectify: bool,
}

/// `sensor_msgs/CameraInfo`.
#[derive(Clone, Debug, Default, PartialEq, Serialize, Deserialize)]
pub struct CameraInfo {
    /// the camera's optical frame and the time
    pub header: Header,
    /// rows of the images it calibrates \[px\] (0 with `width` 0: the image's)
    pub height: u32,
    /// columns of the images it calibrates \[px\] (0 with `height` 0: the image's)
    pub width: u32,
    /// the distortion model of `d` (`plumb_bob`, ...); unused by phri
    pub distortion_model: String,
    /// the distortion coefficients; unused by phri
    pub d: Vec<f64>,
    /// row-major 3×3 intrinsics: fx, 0, cx; 0, fy, cy; 0, 0, 1
    pub k: [f64; 9],
    /// row-major 3×3 rectification rotation (stereo); unused by phri
    pub r: [f64; 9],
    /// row-major 3×4 projection of the rectified image; unused by phri
    pub p: [f64; 12],
    /// horizontal binning (0 or 1: none); unused by phri
    pub binning_x: u32,
    /// vertical binning (0 or 1: none); unused by phri
    pub binning_y: u32,
    /// the region of the full image captured (all 0: the full image); unused by phri
    pub roi: RegionOfInterest,
}

impl RosType for CameraInfo {
    const PACKAGE: &'static str = "sensor_msgs";
    const NAME: &'static str = "CameraInfo";
}

/// A ROS stamp `stamp_real_ns` [ns, CLOCK_REALTIME] on CLOCK_MONOTONIC,
/// from both clocks read now: `now_mono − (now_real − stamp)`.
pub fn capture_mono_ns(stamp_real_ns: u64, now_mono_ns: u64, now_real_ns: u64) -> u64 {
    let t = i128::from(now_mono_ns) - (i128::from(now_real_ns) - i128::from(stamp_real_ns));
    t.clamp(0, i128::from(u64::MAX)) as u64
}

/// A subscription of `topic` (`/a/b/c`, or `a/b/c` taken as absolute).
pub fn subscription<M: RosType + serde::de::DeserializeOwned + 'static>(
    node: &mut Node,
    topic: &str,
    qos: QosProfile,
) -> Result<Subscription<M>, String> {
    let t = topic.strip_prefix('/').unwrap_or(topic);
    let (ns, name) = match t.rsplit_once('/') {
        Some((ns, name)) => (format!("/{ns}"), name),
        None => ("/".to_string(), t),
    };
    let name = Name::new(&ns, name).map_err(|e| format!("ROS 2 topic {topic}: {e}"))?;
    let t = node
        .create_topic(&name, MessageTypeName::new(M::PACKAGE, M::NAME), &qos)
        .map_err(|e| format!("ROS 2 topic {topic}: {e:?}"))?;
    node.create_subscription::<M>(&t, Some(qos))
        .map_err(|e| format!("ROS 2 subscription of {topic}: {e:?}"))
}

/// The newest camera info's geometry, as received.
#[derive(Clone, Copy, Debug, PartialEq)]
struct Info {
    width: u32,
    height: u32,
    k: [f64; 9],
}

/// The ROS 2 side of the camera: the newest CameraInfo, the resampler, the
/// intrinsics of the last image size and the rate-limited logs. No I/O but
/// through the [`CameraOut`] it is given.
pub struct RosCamera {
    image_topic: String,
    info_topic: String,
    info: Option<Info>,
    /// the output intrinsics for (image width, height)
    scaled: Option<((u32, u32), Intrinsics)>,
    resampler: Resampler,
    malformed_log: RateLimited,
    no_info_log: RateLimited,
    info_log: RateLimited,
    /// images received
    pub images: u64,
    /// camera infos refused
    pub infos_refused: u64,
    /// this process's time per published image, from its take out of DDS
    /// (deserialisation) to its publication: total and largest \[ns\]
    pub work_ns: (u64, u64),
}

impl RosCamera {
    /// For `cfg`'s topics.
    pub fn new(cfg: &CameraConfig) -> RosCamera {
        RosCamera {
            image_topic: cfg.image_topic.clone(),
            info_topic: cfg.info_topic.clone(),
            info: None,
            scaled: None,
            resampler: Resampler::new(),
            malformed_log: RateLimited::new(RateLimited::SECOND_NS),
            no_info_log: RateLimited::new(RateLimited::SECOND_NS),
            info_log: RateLimited::new(RateLimited::SECOND_NS),
            images: 0,
            infos_refused: 0,
            work_ns: (0, 0),
        }
    }

    /// A CameraInfo at `now_ns`: the newest valid one is used; a refused one
    /// (zero, negative or non-finite focal length, a centre outside the
    /// image) leaves no intrinsics until a valid one comes.
    pub fn info(&mut self, m: &CameraInfo, now_ns: u64) {
        // a driver that leaves the size 0: the image's, checked at each image
        let (w, h) = match (m.width, m.height) {
            (0, 0) => (ros_image::MAX_WIDTH, ros_image::MAX_HEIGHT),
            s => s,
        };
        match ros_image::camera_info_intrinsics(w, h, &m.k) {
            Ok(_) => {
                let info = Info {
                    width: m.width,
                    height: m.height,
                    k: m.k,
                };
                if self.info != Some(info) {
                    self.info = Some(info);
                    self.scaled = None;
                }
            }
            Err(e) => {
                self.info = None;
                self.scaled = None;
                self.infos_refused += 1;
                if let Some(n) = self.info_log.hit(now_ns) {
                    tracing::warn!(
                        "{}: camera info refused: {e} ({n} since the last line); frames dropped until a valid one",
                        self.info_topic
                    );
                }
            }
        }
    }

    /// The output intrinsics of an image of `width`×`height`, from the
    /// newest valid CameraInfo.
    fn intrinsics(&mut self, width: u32, height: u32) -> Result<Intrinsics, String> {
        if let Some((size, k)) = self.scaled {
            if size == (width, height) {
                return Ok(k);
            }
        }
        let Some(info) = self.info else {
            return Err(format!("no valid camera info on {} yet", self.info_topic));
        };
        if (info.width, info.height) != (0, 0) && (info.width, info.height) != (width, height) {
            return Err(format!(
                "camera info on {} is for {}×{}, the image is {width}×{height}",
                self.info_topic, info.width, info.height
            ));
        }
        let k = ros_image::camera_info_intrinsics(width, height, &info.k)
            .map_err(|e| format!("{} for a {width}×{height} image: {e}", self.info_topic))?;
        let k = ros_image::scale_intrinsics(&k);
        self.scaled = Some(((width, height), k));
        Ok(k)
    }

    /// An image received at `now_mono_ns` [ns, CLOCK_MONOTONIC] when
    /// CLOCK_REALTIME read `now_real_ns`: published on `out`, or dropped
    /// (counted, and logged at most once a second per cause).
    pub fn image(
        &mut self,
        out: &mut CameraOut,
        m: &Image,
        now_mono_ns: u64,
        now_real_ns: u64,
    ) -> Result<Option<DropCause>, IpcError> {
        self.images += 1;
        let view = ImageView {
            width: m.width,
            height: m.height,
            encoding: &m.encoding,
            is_bigendian: m.is_bigendian,
            step: m.step,
            data: &m.data,
        };
        if let Err(e) = ros_image::check(&view) {
            self.malformed(out, &e.to_string(), now_mono_ns);
            return Ok(Some(DropCause::Malformed));
        }
        let k = match self.intrinsics(m.width, m.height) {
            Ok(k) => k,
            Err(why) => {
                out.stamps().count(DropCause::NoInfo);
                if let Some(n) = self.no_info_log.hit(now_mono_ns) {
                    tracing::warn!(
                        "{}: image dropped: {why} ({n} since the last line)",
                        self.image_topic
                    );
                }
                return Ok(Some(DropCause::NoInfo));
            }
        };
        let capture = capture_mono_ns(m.header.stamp.to_ns(), now_mono_ns, now_real_ns);
        let resampler = &mut self.resampler;
        let mut fault = None;
        let r = out.publish(&k, capture, now_mono_ns, |px| {
            resampler.decode_into(&view, px).map_err(|e| {
                fault = Some(e);
                DropCause::Malformed
            })
        })?;
        if let Some(e) = fault {
            self.malformed_line(&e.to_string(), now_mono_ns);
        }
        Ok(r)
    }

    /// A sample DDS could not make an image of.
    pub fn undecodable(&mut self, out: &mut CameraOut, why: &str, now_ns: u64) {
        self.malformed(out, why, now_ns);
    }

    fn malformed(&mut self, out: &mut CameraOut, why: &str, now_ns: u64) {
        out.stamps().count(DropCause::Malformed);
        self.malformed_line(why, now_ns);
    }

    fn malformed_line(&mut self, why: &str, now_ns: u64) {
        if let Some(n) = self.malformed_log.hit(now_ns) {
            tracing::warn!(
                "{}: image dropped: {why} ({n} malformed since the last line)",
                self.image_topic
            );
        }
    }
}

/// The service: camera `index` configured by `cfg`, on `channels`, until
/// shutdown.
pub fn run(
    ctx: &ServiceContext,
    cfg: &CameraConfig,
    index: usize,
    channels: &CameraChannels,
) -> Result<(), Box<dyn Error>> {
    ros2_source(cfg, index)?;
    let domain = domain_id()?;
    let (reach, decided_by) = reach(ctx.config())?;
    let local = reach == Ros2Discovery::Localhost;
    let stamps = CameraStamps::new(index, cfg)?;
    if ctx.checking() {
        return Ok(());
    }
    phri_runtime::placement::keep_off_the_loop(ctx.config());
    let dds = participant(domain, local)?;
    let mut inputs = Inputs::open(&dds, index, cfg)?;

    ctx.start_deadman()?;
    let node = ctx.node()?;
    let mut out = CameraOut::new(&node, &channels.depth, stamps)?;
    let mut beat = ctx.beat(&node)?;
    // this loop at the camera's priority; DDS's own threads, started above,
    // stay under the normal scheduler
    ctx.go_realtime();
    let mut camera = RosCamera::new(cfg);
    tracing::info!(
        "camera {index} from ROS 2 domain {domain}, {} ({}): {} (sensor_msgs/Image 16UC1/mono16/32FC1) with {} (sensor_msgs/CameraInfo) on {}",
        crate::report::reach(local),
        decided_by.name(),
        cfg.image_topic,
        cfg.info_topic,
        channels.depth.name,
    );
    while !ctx.shutdown.requested() {
        inputs.wait();
        let now = now_ns();
        beat.beat(now);
        inputs.take_infos(&mut camera, &cfg.info_topic, now);
        // every image waiting: the newest is published, the ones it
        // replaced are counted as behind
        let taken_ns = now_ns();
        if let Some(m) = inputs.take_newest_image(&mut camera, &mut out, now) {
            if camera
                .image(&mut out, &m, now_ns(), realtime_ns())?
                .is_none()
            {
                let work = now_ns().saturating_sub(taken_ns);
                camera.work_ns = (camera.work_ns.0 + work, camera.work_ns.1.max(work));
            }
        }
        out.status_tick(now_ns(), false)?;
    }
    out.status_tick(now_ns(), true)?;
    let c = *out.stamps().counts();
    tracing::info!("{}", counts_line(&camera, &c));
    if let Some(line) = work_line(&camera, &c) {
        tracing::info!("{line}");
    }
    Ok(())
}

/// Camera `index`'s source must be ROS 2 (`cfg.source`): otherwise the
/// error names the binary that serves it.
fn ros2_source(cfg: &CameraConfig, index: usize) -> Result<(), String> {
    if cfg.source == CameraSource::Ros2 {
        return Ok(());
    }
    Err(format!(
        "camera {index}: source = \"{}\", not \"ros2\" (its binary is {})",
        cfg.source.name(),
        cfg.source.binary()
    ))
}

/// The last line's counts: images received, published and dropped (`c`,
/// per cause), camera infos refused.
fn counts_line(camera: &RosCamera, c: &CameraStatus) -> String {
    format!(
        "{} images: published {}, dropped old {}, future {}, malformed {}, no_info {}, behind {}; {} camera infos refused",
        camera.images,
        c.frames,
        c.dropped_old,
        c.dropped_future,
        c.dropped_malformed,
        c.dropped_no_info,
        c.dropped_behind,
        camera.infos_refused
    )
}

/// This process's time per published image [ms], mean and largest: `None`
/// before one was published.
fn work_line(camera: &RosCamera, c: &CameraStatus) -> Option<String> {
    (c.frames > 0).then(|| {
        format!(
            "per published image, from its take out of DDS to camera/depth: mean {:.2} ms, max {:.2} ms",
            camera.work_ns.0 as f64 * 1e-6 / c.frames as f64,
            camera.work_ns.1 as f64 * 1e-6
        )
    })
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_ros_stamp_maps_onto_the_monotonic_clock() {
        let (mono, real) = (5_000_000_000u64, 1_764_000_000_000_000_000u64);
        assert_eq!(
            capture_mono_ns(real - 30_000_000, mono, real),
            mono - 30_000_000
        );
        assert_eq!(capture_mono_ns(real + 7, mono, real), mono + 7);
        // before the monotonic clock's start, or a zero stamp: as old as can be
        assert_eq!(capture_mono_ns(0, mono, real), 0);
    }

    #[test]
    fn a_camera_info_is_the_ros_layout() {
        // CDR: the fixed arrays without a length, in the .msg's order
        let m = CameraInfo {
            width: 640,
            height: 480,
            k: [580.0, 0.0, 320.0, 0.0, 580.0, 240.0, 0.0, 0.0, 1.0],
            ..CameraInfo::default()
        };
        let json = serde_json::to_value(&m).unwrap();
        let keys: Vec<&String> = json.as_object().unwrap().keys().collect();
        assert_eq!(keys.len(), 11);
        assert_eq!(json["k"].as_array().unwrap().len(), 9);
        assert_eq!(json["p"].as_array().unwrap().len(), 12);
    }

    #[test]
    fn only_a_ros2_camera_is_served() {
        let mut cfg = phri_config::Config::defaults().camera;
        cfg.source = CameraSource::Ros2;
        assert!(ros2_source(&cfg, 1).is_ok());
        cfg.source = CameraSource::Freenect;
        let e = ros2_source(&cfg, 1).unwrap_err();
        assert!(
            e.starts_with("camera 1: source = \"freenect\", not \"ros2\""),
            "{e}"
        );
    }

    #[test]
    fn the_last_lines_count_images_and_time_them() {
        use phri_ipc::Zeroed;
        let cfg = phri_config::Config::defaults().camera;
        let mut camera = RosCamera::new(&cfg);
        (camera.images, camera.infos_refused) = (9, 2);
        let mut c = CameraStatus::zeroed();
        assert_eq!(work_line(&camera, &c), None, "nothing published: no time");
        (c.frames, c.dropped_old, c.dropped_behind) = (4, 1, 3);
        camera.work_ns = (8_000_000, 3_500_000);
        assert_eq!(
            counts_line(&camera, &c),
            "9 images: published 4, dropped old 1, future 0, malformed 0, no_info 0, behind 3; 2 camera infos refused"
        );
        assert_eq!(
            work_line(&camera, &c).unwrap(),
            "per published image, from its take out of DDS to camera/depth: mean 2.00 ms, max 3.50 ms"
        );
    }

    #[test]
    fn a_refused_camera_info_leaves_no_intrinsics() {
        let cfg = phri_config::Config::defaults().camera;
        let mut c = RosCamera::new(&cfg);
        let mut m = CameraInfo {
            width: 1280,
            height: 720,
            k: [1160.0, 0.0, 640.5, 0.0, 870.0, 360.25, 0.0, 0.0, 1.0],
            ..CameraInfo::default()
        };
        c.info(&m, 1);
        let k = c.intrinsics(1280, 720).unwrap();
        assert!((k.fx - 580.0).abs() < 1e-9 && (k.cy - 240.0).abs() < 1e-9);
        assert!(c.intrinsics(640, 480).unwrap_err().contains("1280×720"));
        m.k[0] = 0.0;
        c.info(&m, 2);
        assert!(c.intrinsics(1280, 720).unwrap_err().contains("no valid"));
        assert_eq!(c.infos_refused, 1);
    }
}
