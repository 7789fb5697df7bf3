//! `phri-gesture`: recognises a hand wave on `perception/skeleton` and
//! publishes a `follow` request for the waving hand on `hri/request`.

use std::error::Error;
use std::process::ExitCode;
use std::time::Duration;

use phri_gesture::{follow_request, WaveDetector};
use phri_ipc::{Queue, HRI_REQUEST, PERCEPTION_SKELETON};
use phri_runtime::{now_ns, ServiceContext};

fn main() -> ExitCode {
    phri_runtime::service::run("phri-gesture", body)
}

fn body() -> Result<(), Box<dyn Error>> {
    let (ctx, phri_runtime::cli::NoExtra {}) = ServiceContext::from_cli(
        "phri-gesture",
        "gesture",
        "Gestures of the tracked person (wave, push) as collaboration requests on hri/request",
    )?;
    let cfg = ctx.config().gesture.clone();
    let mut detector = WaveDetector::new(&cfg)?;
    if ctx.checking() {
        return Ok(());
    }
    ctx.start_deadman()?;
    let node = ctx.node()?;
    let skeletons = PERCEPTION_SKELETON.waking_subscriber(&node, Queue::Drain)?;
    let requests = HRI_REQUEST.publisher(&node)?;
    ctx.go_realtime();
    let max_age_ns = (cfg.max_age_ms * 1e6) as u64;
    // numbers that grow across restarts (readers tell requests apart by
    // source and number): microseconds of CLOCK_MONOTONIC
    let mut seq = now_ns() / 1_000;
    while !ctx.shutdown.requested() {
        // a wait ended early (a signal, a failed wake-up) is one more poll
        let _ = skeletons.wait(Duration::from_millis(100));
        let mut waves = Vec::new();
        skeletons.drain(|sk| {
            // an old skeleton (a stalled tracker, a replay) is not a gesture now
            if now_ns().saturating_sub(sk.published_ns) <= max_age_ns {
                if let Some(w) = detector.step(sk) {
                    waves.push(w);
                }
            }
        })?;
        for w in waves {
            seq += 1;
            requests.publish(&follow_request(&w, seq, now_ns()))?;
            tracing::info!(
                "person {} waves the {}: follow requested",
                w.person,
                w.part.name()
            );
        }
    }
    Ok(())
}
