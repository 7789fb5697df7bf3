//! `phri-gesture`: recognises a hand wave on `perception/skeleton` and
//! publishes a `follow` request for the waving hand on `hri/request`. With
//! several cameras it reads every camera's tracker (`perception/I/skeleton`)
//! and recognises on their merged views ([`phri_ipc::merge_newest`]), one
//! per new view of the first camera whose tracker is alive.

use std::error::Error;
use std::process::ExitCode;
use std::time::Duration;

use phri_gesture::{follow_request, WaveDetector};
use phri_ipc::{merge_newest, Queue, Skeleton, Zeroed, HRI_REQUEST, MAX_CAMERAS};
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
    let channels = phri_ipc::cameras(ctx.config().cameras.len());
    let cameras = channels.len();
    let skeletons = channels
        .iter()
        .map(|c| c.skeleton.waking_subscriber(&node, Queue::Drain))
        .collect::<Result<Vec<_>, _>>()?;
    let requests = HRI_REQUEST.publisher(&node)?;
    let mut beat = ctx.beat(&node)?;
    ctx.go_realtime();
    let max_age_ns = (cfg.max_age_ms * 1e6) as u64;
    // numbers that grow across restarts (readers tell requests apart by
    // source and number): microseconds of CLOCK_MONOTONIC
    let mut seq = now_ns() / 1_000;
    let mut newest: Vec<Option<Skeleton>> = vec![None; cameras];
    let mut merged = Skeleton::zeroed();
    let mut last_capture_ns = 0;
    while !ctx.shutdown.requested() {
        // the first camera wakes us; without it, every frame period or so
        // a wait ended early (a signal, a failed wake-up) is one more poll
        let _ = skeletons[0].wait(Duration::from_millis(40));
        beat.beat(now_ns());
        let mut waves = Vec::new();
        let mut one = |sk: &Skeleton, detector: &mut WaveDetector| {
            // an old skeleton (a stalled tracker, a replay) is not a gesture now
            if now_ns().saturating_sub(sk.published_ns) <= max_age_ns {
                if let Some(w) = detector.step(sk) {
                    waves.push(w);
                }
            }
        };
        if cameras == 1 {
            skeletons[0].drain(|sk| one(sk, &mut detector))?;
        } else {
            // every camera's newest view; the first live camera's new view
            // (merged with the others') is the next step
            for (slot, sub) in newest.iter_mut().zip(&skeletons) {
                sub.drain(|sk| *slot = Some(*sk))?;
            }
            let mono = now_ns();
            let live = |s: &Option<Skeleton>| {
                s.filter(|s| mono.saturating_sub(s.published_ns) <= max_age_ns)
            };
            let lead = newest.iter().find_map(live);
            if let Some(lead) = lead.filter(|l| l.capture_ns > last_capture_ns) {
                let mut views = [None; MAX_CAMERAS];
                for (v, s) in views.iter_mut().zip(&newest) {
                    *v = s
                        .as_ref()
                        .filter(|s| mono.saturating_sub(s.published_ns) <= max_age_ns);
                }
                if merge_newest(&views, max_age_ns, &mut merged) {
                    last_capture_ns = lead.capture_ns;
                    one(&merged, &mut detector);
                }
            }
        }
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
