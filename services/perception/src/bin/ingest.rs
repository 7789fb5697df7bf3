//! `phri-perception`: depth ingestion. Takes frames from `camera/depth` (or a
//! directory of 16-bit PNG depth images replayed at their rate), validates
//! them, removes the robot's own pixels at the joint state nearest the
//! capture time, and publishes `perception/depth` (a loaned `[u16]` slice with
//! a header: sequence, capture time, intrinsics, camera pose, joint state used).

use std::path::PathBuf;
use std::process::ExitCode;
use std::time::Duration;

use phri_ipc::*;
use phri_perception::camera::fill_camera_header;
use phri_perception::ingest::{Ingest, StateHistory};
use phri_perception::{CameraConfig, IngestConfig};
use phri_runtime::{now_ns, sleep_until_ns, ServiceContext};

fn main() -> ExitCode {
    phri_runtime::service::run("phri-perception", body)
}

#[allow(clippy::large_enum_variant)] // one value per process, never moved in a loop
enum Source {
    Camera {
        frames: FrameSub,
        event: Listener,
    },
    Png {
        files: Vec<PathBuf>,
        next: usize,
        period_ns: u64,
        tick: u64,
        seq: u64,
    },
}

fn body() -> Result<(), String> {
    let ctx = ServiceContext::from_args("perception", &[])?;
    let cfg: IngestConfig = ctx.section("perception")?;
    let camera_cfg: CameraConfig = ctx.section("camera")?;
    let model = ctx.robot_model(MAX_DOF)?;
    let n = model.nv();
    let mut ingest = Ingest::new(
        model,
        cfg.self_filter,
        cfg.max_state_gap_ms,
        cfg.max_frame_age_ms,
    );
    let s = |x: IpcError| x.to_string();
    let node = node(&ctx.name, &ctx.prefix).map_err(s)?;
    let states = subscriber::<JointState>(&node, ROBOT_STATE, DRAIN).map_err(s)?;
    let pixels_max = camera_cfg.intrinsics.pixel_count().max(FRAME_PIXELS);
    let out = frame_publisher(&node, PERCEPTION_DEPTH, pixels_max)
        .map_err(|x| format!("{x} (is another ingestion running with this prefix?)"))?;
    let out_event = notifier(&node, PERCEPTION_DEPTH).map_err(s)?;
    let mut source = match cfg.source.as_str() {
        "camera" => Source::Camera {
            frames: frame_subscriber(&node, CAMERA_DEPTH).map_err(s)?,
            event: listener(&node, CAMERA_DEPTH).map_err(s)?,
        },
        "png" => {
            let dir = phri_runtime::service::resolve(&ctx.config_path, &cfg.png_dir);
            let mut files: Vec<PathBuf> = std::fs::read_dir(&dir)
                .map_err(|e| format!("[perception] png_dir {}: {e}", dir.display()))?
                .filter_map(|e| e.ok().map(|e| e.path()))
                .filter(|p| p.extension().is_some_and(|x| x.eq_ignore_ascii_case("png")))
                .collect();
            files.sort();
            if files.is_empty() {
                return Err(format!(
                    "[perception] png_dir {}: no .png file",
                    dir.display()
                ));
            }
            if !(cfg.png_rate_hz > 0.0) {
                return Err("[perception] png_rate_hz must be positive".into());
            }
            Source::Png {
                files,
                next: 0,
                period_ns: (1e9 / cfg.png_rate_hz) as u64,
                tick: now_ns(),
                seq: 0,
            }
        }
        other => {
            return Err(format!(
                "[perception] source: '{other}' is neither 'camera' nor 'png'"
            ))
        }
    };
    let camera_pose = camera_cfg.pose()?;
    ctx.go_realtime();
    let mut history = StateHistory::new(n, 2000);
    let mut robot_now = 0u64;
    let mut refused = 0u64;
    while !ctx.shutdown.requested() {
        // wait for the next frame
        match &mut source {
            Source::Camera { event, .. } => {
                let _ = event.timed_wait(|_| {}, Duration::from_millis(50));
            }
            Source::Png {
                tick, period_ns, ..
            } => {
                *tick += *period_ns;
                sleep_until_ns(*tick);
            }
        }
        while let Some(st) = states
            .receive()
            .map_err(|x| ipc_err(ROBOT_STATE, x).to_string())?
        {
            if st.dof as usize == n {
                history.push(st.stamp_ns, &st.q[..n]);
                robot_now = robot_now.max(st.stamp_ns);
            }
        }
        let mut handle = |header: &mut FrameHeader, input: &[u16]| -> Result<(), String> {
            let mut sample = out
                .loan_slice(input.len())
                .map_err(|x| ipc_err(PERCEPTION_DEPTH, x).to_string())?;
            match ingest.step(header, input, &history, robot_now, sample.payload_mut()) {
                Ok(_) => {
                    header.published_ns = now_ns();
                    *sample.user_header_mut() = *header;
                    sample
                        .send()
                        .map_err(|x| ipc_err(PERCEPTION_DEPTH, x).to_string())?;
                    let _ = out_event.notify();
                }
                Err(e) => {
                    refused += 1;
                    if refused.is_power_of_two() {
                        eprintln!("phri-perception: refused {e} ({refused} refused so far)");
                    }
                }
            }
            Ok(())
        };
        match &mut source {
            Source::Camera { frames, .. } => {
                while let Some(frame) = frames
                    .receive()
                    .map_err(|x| ipc_err(CAMERA_DEPTH, x).to_string())?
                {
                    let mut header = *frame.user_header();
                    handle(&mut header, frame.payload())?;
                }
            }
            Source::Png {
                files, next, seq, ..
            } => {
                if *next >= files.len() {
                    if !cfg.png_loop {
                        continue;
                    }
                    *next = 0;
                }
                let path = &files[*next];
                *next += 1;
                let k = camera_cfg.intrinsics;
                match phri_depth::read_depth_png(path, k.width, k.height, cfg.png_depth_scale) {
                    Ok(png_frame) => {
                        *seq += 1;
                        let mut header = FrameHeader::zeroed();
                        fill_camera_header(&mut header, *seq, &k, &camera_pose);
                        header.capture_ns = robot_now;
                        header.capture_wall_ns = now_ns();
                        handle(&mut header, &png_frame)?;
                    }
                    Err(e) => {
                        refused += 1;
                        eprintln!("phri-perception: refused {e}");
                    }
                }
            }
        }
    }
    Ok(())
}
