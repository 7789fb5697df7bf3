//! The recording loop: attach to the channels that exist (once a second),
//! drain them every 5 ms into the file, report progress, stop after the
//! requested time or on Ctrl-C, then close the file and say what it holds.

use std::time::{Duration, Instant};

use phri_ipc::IpcNode;
use phri_runtime::Shutdown;

use super::channels::{counts_line, Rec, Viz};
use super::writer::Recording;
use super::RecordError;
use crate::progress::Progress;

/// Time between two polls of the channels.
pub const POLL: Duration = Duration::from_millis(5);

/// Records `recs` (and the scene of `viz`) through `node` into `recording`,
/// written to `path`, until `shutdown` or after `seconds` \[s\]; the last line
/// on stderr says what was written.
pub fn record(
    mut recording: Recording,
    path: &str,
    mut recs: Vec<Box<dyn Rec>>,
    mut viz: Viz,
    node: &IpcNode,
    shutdown: &Shutdown,
    seconds: Option<f64>,
) -> Result<(), RecordError> {
    let bin = "phri-record";
    let t0 = Instant::now();
    let end = seconds.map(Duration::from_secs_f64);
    // a bar of whole seconds for a timed recording, a message counter otherwise
    let bar = match seconds {
        Some(s) => Progress::new(bin, Some(s.ceil() as u64), "s"),
        None => Progress::new(bin, None, "messages"),
    };
    let mut next_attach = Instant::now();
    let mut next_report = t0 + Duration::from_secs(1);
    while !shutdown.requested() && end.is_none_or(|e| t0.elapsed() < e) {
        if Instant::now() >= next_attach {
            for r in recs.iter_mut() {
                r.attach(node)?;
            }
            next_attach = Instant::now() + Duration::from_secs(1);
        }
        recording.poll(&mut recs, &mut viz)?;
        match seconds {
            Some(_) => bar.set_position(t0.elapsed().as_secs()),
            None => bar.set_position(recording.total),
        }
        if Instant::now() >= next_report {
            next_report += Duration::from_secs(1);
            if bar.shown() {
                bar.set_message(format!("{} messages", recording.total));
            } else {
                eprintln!(
                    "phri-record: {:.0} s  {}",
                    t0.elapsed().as_secs_f64(),
                    counts_line(&recs, &recording.counts)
                );
            }
        }
        std::thread::sleep(POLL);
    }
    bar.finish();
    let (total, counts) = (recording.total, recording.counts.clone());
    let (chunks, scene) = recording.finish()?;
    let size = std::fs::metadata(path).map(|m| m.len()).unwrap_or(0);
    eprintln!(
        "phri-record: wrote {path}: {total} messages in {:.1} s, {:.1} MB, {chunks} chunks; {}; scene {scene}",
        t0.elapsed().as_secs_f64(),
        size as f64 / 1e6,
        counts_line(&recs, &counts)
    );
    Ok(())
}
