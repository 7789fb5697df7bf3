//! `phri-camera-ros2`: any ROS 2 depth camera (a `sensor_msgs/Image` of
//! 16UC1 or 32FC1 and its `sensor_msgs/CameraInfo`) behind `camera/depth`
//! (`--camera I`: `camera/I/depth`). The logic is [`phri_ros2::camera`];
//! this only wires it.

use std::error::Error;
use std::process::ExitCode;

use phri_perception::CameraFlag;
use phri_runtime::ServiceContext;

fn main() -> ExitCode {
    if std::env::var("RUST_LOG").map_or(true, |f| f.trim().is_empty()) {
        // before any thread starts (edition 2021: safe to call here)
        std::env::set_var("RUST_LOG", phri_ros2::participant::LOG_FILTER);
    }
    phri_runtime::service::run("phri-camera-ros2", body)
}

fn body() -> Result<(), Box<dyn Error>> {
    let (ctx, flag) = ServiceContext::from_cli::<CameraFlag>(
        "phri-camera-ros2",
        "camera",
        "A ROS 2 depth camera (sensor_msgs/Image 16UC1 or 32FC1 on [camera] image_topic, its \
         CameraInfo on info_topic) resampled to 640×480 on camera/depth",
    )?;
    let (cfg, channels) = flag.resolve(ctx.config())?;
    phri_ros2::camera::run(&ctx, cfg, flag.camera, channels)
}
