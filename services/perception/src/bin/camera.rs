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
    let fault_sub = subscriber::<DepthFault>(&node, FAULT_DEPTH, DRAIN).map_err(s)?;
    let mut faults = FaultState::default();
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
        while let Some(f) = fault_sub
            .receive()
            .map_err(|x| ipc_err(FAULT_DEPTH, x).to_string())?
        {
            faults.accept(&f, now_ns());
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
        let extra = faults.apply(sample.payload_mut(), &mut header, capture_wall);
        sleep_until_ns(capture_wall + latency + extra);
        header.published_ns = now_ns();
        *sample.user_header_mut() = header;
        sample
            .send()
            .map_err(|x| ipc_err(CAMERA_DEPTH, x).to_string())?;
        let _ = frame_event.notify();
    }
    Ok(())
}

/// Faults `phri-fault` asked for (channel `fault/depth`): corruptions of the
/// next frames and a publish delay until a deadline.
#[derive(Default)]
struct FaultState {
    kind: u32,
    frames_left: u32,
    delay_ns: u64,
    delay_until_ns: u64,
    rng: u64,
}

impl FaultState {
    fn accept(&mut self, f: &DepthFault, now: u64) {
        let kind = depth_fault::name(f.kind);
        if f.kind == depth_fault::DELAY {
            let ok = f.delay_ms.is_finite()
                && f.delay_ms >= 0.0
                && f.duration_s.is_finite()
                && f.duration_s >= 0.0;
            if !ok {
                eprintln!(
                    "phri-camera: {FAULT_DEPTH}: fault {}: delay {} ms for {} s refused",
                    f.seq, f.delay_ms, f.duration_s
                );
                return;
            }
            self.delay_ns = (f.delay_ms.min(10_000.0) * 1e6) as u64;
            self.delay_until_ns = now + (f.duration_s.min(3600.0) * 1e9) as u64;
            eprintln!(
                "phri-camera: {FAULT_DEPTH}: fault {}: frames {} ms late for {} s",
                f.seq, f.delay_ms, f.duration_s
            );
        } else if kind != "unknown" {
            self.kind = f.kind;
            self.frames_left = f.frames;
            self.rng = f.seq.wrapping_mul(0x9E37_79B9_7F4A_7C15) | 1;
            eprintln!(
                "phri-camera: {FAULT_DEPTH}: fault {}: {kind} on the next {} frames",
                f.seq, f.frames
            );
        } else {
            eprintln!(
                "phri-camera: {FAULT_DEPTH}: fault {}: unknown kind {} ignored",
                f.seq, f.kind
            );
        }
    }

    /// Corrupt this frame if asked; returns the extra publish delay [ns].
    fn apply(&mut self, depth: &mut [u16], header: &mut FrameHeader, now: u64) -> u64 {
        if self.frames_left > 0 {
            self.frames_left -= 1;
            match self.kind {
                depth_fault::NOISE => {
                    for d in depth.iter_mut() {
                        // xorshift64
                        self.rng ^= self.rng << 13;
                        self.rng ^= self.rng >> 7;
                        self.rng ^= self.rng << 17;
                        if self.rng.is_multiple_of(50) {
                            *d = 500 + ((self.rng >> 20) % 3500) as u16;
                        }
                    }
                }
                depth_fault::ZEROS => depth.fill(0),
                depth_fault::SIZE => header.width = header.width.saturating_sub(1),
                depth_fault::STALE => {
                    header.capture_ns = header.capture_ns.saturating_sub(1_000_000_000)
                }
                _ => {}
            }
        }
        if now < self.delay_until_ns {
            self.delay_ns
        } else {
            0
        }
    }
}
