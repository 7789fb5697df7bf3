//! Removing the iceoryx2 resources of processes that died, beside the
//! supervision loop rather than in it: the files are on a disk (iceoryx2's
//! root path, `/tmp/iceoryx2`) that a build or a recording beside the cell
//! can keep busy, and removing them then waited 0.3-2.2 s on the file
//! system (measured: a `free-motion` cell, the camera killed every 8 s, `dd`
//! writing 3 GB files beside it). In the loop, that wait was a stall of the
//! supervisor: every heartbeat judged late, every death noticed late. A
//! restart waits for the removal instead ([`Cleaner::busy`],
//! `Event::Cleaning`): a process started meanwhile met the dead one's files
//! in its own start and stalled there itself.

use std::sync::atomic::{AtomicU64, Ordering};
use std::sync::mpsc::{sync_channel, SyncSender};
use std::sync::Arc;

use phri_runtime::now_ns;

/// A removal that took longer than this is said in the log \[ns\].
const SLOW_NS: u64 = 100_000_000;

/// The thread that removes dead processes' resources.
pub struct Cleaner {
    /// requests; `None` when the thread could not be started (then the
    /// removal runs in the caller, as before)
    tx: Option<SyncSender<()>>,
    /// requests made, and the last request a finished removal covered
    asked: Arc<AtomicU64>,
    done: Arc<AtomicU64>,
    /// the cell's iceoryx2 prefix
    prefix: String,
}

impl Cleaner {
    /// The thread for the cell of `prefix`.
    pub fn new(prefix: &str) -> Cleaner {
        // one request waits at most: a removal sweeps every dead node, so
        // the requests made while one runs are served by the next
        let (tx, rx) = sync_channel::<()>(1);
        let (asked, done) = (Arc::new(AtomicU64::new(0)), Arc::new(AtomicU64::new(0)));
        let (p, a, d) = (prefix.to_owned(), asked.clone(), done.clone());
        let started = std::thread::Builder::new()
            .name("iox2-cleaner".into())
            .spawn(move || {
                while rx.recv().is_ok() {
                    let covers = a.load(Ordering::Acquire);
                    let t0 = now_ns();
                    phri_ipc::live_nodes(&p);
                    d.store(covers, Ordering::Release);
                    let ns = now_ns().saturating_sub(t0);
                    if ns > SLOW_NS {
                        tracing::info!(
                            "removing the dead processes' iceoryx2 resources took {} ms (beside the supervision loop)",
                            ns / 1_000_000
                        );
                    }
                }
            });
        if let Err(e) = &started {
            tracing::warn!("no thread to remove dead processes' iceoryx2 resources ({e}): the supervision loop removes them");
        }
        Cleaner {
            tx: started.ok().map(|_| tx),
            asked,
            done,
            prefix: prefix.to_owned(),
        }
    }

    /// Have the resources of every dead process of the cell removed; returns
    /// at once unless there is no thread.
    pub fn request(&self) {
        match &self.tx {
            Some(tx) => {
                self.asked.fetch_add(1, Ordering::AcqRel);
                // full: a request is waiting already, and it covers this one
                let _ = tx.try_send(());
            }
            None => {
                phri_ipc::live_nodes(&self.prefix);
            }
        }
    }

    /// A removal asked for has not finished yet.
    pub fn busy(&self) -> bool {
        self.done.load(Ordering::Acquire) < self.asked.load(Ordering::Acquire)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn requests_return_at_once_and_are_all_served() {
        let prefix = format!("phri_cleaner_{}_", std::process::id());
        let c = Cleaner::new(&prefix);
        assert!(c.tx.is_some());
        for _ in 0..100 {
            c.request();
        }
        let t0 = now_ns();
        while c.busy() {
            assert!(now_ns() - t0 < 10_000_000_000, "not served in 10 s");
            std::thread::sleep(std::time::Duration::from_millis(1));
        }
        assert_eq!(c.done.load(Ordering::Acquire), 100);
    }
}
