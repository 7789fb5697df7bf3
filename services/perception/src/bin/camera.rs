//! `phri-camera`: the simulated depth camera. At `[camera] rate_hz` it takes
//! the newest `sim/world`, renders it straight into a loaned `camera/depth`
//! sample (zero-copy: the frame is written once, in shared memory), waits the
//! sensor latency and publishes it.

use std::process::ExitCode;

use phri_ipc::*;
use phri_perception::camera::CameraSim;
use phri_perception::CameraConfig;
use phri_runtime::{now_ns, sleep_until_ns, ServiceContext};

fn main() -> ExitCode {
    phri_runtime::service::run("phri-camera", body)
}

fn body() -> Result<(), String> {
    let ctx = ServiceContext::from_args("camera", &[])?;
    let cfg: CameraConfig = ctx.section("camera")?;
    let rate_ok = cfg.rate_hz > 0.0 && cfg.rate_hz <= 1000.0;
    let latency_ok = cfg.latency_ms >= 0.0;
    if !rate_ok || !latency_ok {
        return Err(format!(
            "{}: [camera] rate_hz must be in (0, 1000], latency_ms ≥ 0",
            ctx.config_path.display()
        ));
    }
    let model = ctx.robot_model(MAX_DOF)?;
    let mut camera = CameraSim::new(model, &cfg)?;
    let pixels = camera.pixels();
    let s = |x: IpcError| x.to_string();
    let node = node(&ctx.name, &ctx.prefix).map_err(s)?;
    let worlds = subscriber::<WorldState>(&node, SIM_WORLD, LATEST).map_err(s)?;
    let frames = frame_publisher(&node, CAMERA_DEPTH, pixels)
        .map_err(|x| format!("{x} (is another camera running with this prefix?)"))?;
    let frame_event = notifier(&node, CAMERA_DEPTH).map_err(s)?;
    ctx.go_realtime();
    let period = (1e9 / cfg.rate_hz) as u64;
    let latency = (cfg.latency_ms * 1e6) as u64;
    let mut world: Option<WorldState> = None;
    let mut tick = now_ns();
    while !ctx.shutdown.requested() {
        tick += period;
        sleep_until_ns(tick);
        if now_ns() > tick + period {
            tick = now_ns(); // fell behind: skip frames rather than burst
        }
        if let Some(w) = latest(&worlds, SIM_WORLD).map_err(s)? {
            world = Some(w);
        }
        let Some(w) = world.as_ref() else { continue };
        let capture_wall = now_ns();
        let mut sample = frames
            .loan_slice(pixels)
            .map_err(|x| ipc_err(CAMERA_DEPTH, x).to_string())?;
        let mut header = FrameHeader::zeroed();
        camera.step(w, sample.payload_mut(), &mut header)?;
        header.capture_ns = w.stamp_ns;
        header.capture_wall_ns = capture_wall;
        sleep_until_ns(capture_wall + latency);
        header.published_ns = now_ns();
        *sample.user_header_mut() = header;
        sample
            .send()
            .map_err(|x| ipc_err(CAMERA_DEPTH, x).to_string())?;
        let _ = frame_event.notify();
    }
    Ok(())
}
