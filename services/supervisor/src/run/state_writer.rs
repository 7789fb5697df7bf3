//! The state files (`state.json`, `supervisor.state`) written beside the
//! supervision loop rather than in it: creating and renaming a file waits on
//! the file system's journal, which a build or a recording writing to the
//! same disk can hold for a second (measured: 1 032 ms, a `free-motion` cell
//! with `dd` writing 3 GB files beside it, right after a kill). Each write
//! replaces the one before; the newest waiting is the one written.

use std::path::{Path, PathBuf};
use std::sync::mpsc::{channel, Receiver, Sender};
use std::thread::JoinHandle;

use crate::state::{StateJson, STATE_FILE};
use crate::SupervisorState;

/// What the writer is asked to do.
enum Job {
    /// both files' contents (serialised by the thread, not the loop)
    Write(StateJson, SupervisorState),
    /// remove both (the run is over)
    Remove,
}

/// The thread that writes the state files of one run directory.
pub struct StateWriter {
    /// jobs; `None` without a thread (then the caller writes, as before)
    tx: Option<Sender<Job>>,
    thread: Option<JoinHandle<()>>,
    run_dir: PathBuf,
}

impl StateWriter {
    /// The writer of the state files in `run_dir`.
    pub fn new(run_dir: &Path) -> StateWriter {
        let (tx, rx) = channel::<Job>();
        let dir = run_dir.to_path_buf();
        let started = std::thread::Builder::new()
            .name("state-writer".into())
            .spawn(move || serve(&dir, &rx));
        if let Err(e) = &started {
            tracing::warn!(
                "no thread to write the state files ({e}): the supervision loop writes them"
            );
        }
        let thread = started.ok();
        StateWriter {
            tx: thread.as_ref().map(|_| tx),
            thread,
            run_dir: run_dir.to_path_buf(),
        }
    }

    /// Have both files replaced by these; returns at once.
    pub fn write(&self, json: StateJson, state: SupervisorState) {
        let job = Job::Write(json, state);
        match &self.tx {
            Some(tx) => {
                if let Err(e) = tx.send(job) {
                    run(&self.run_dir, e.0);
                }
            }
            None => run(&self.run_dir, job),
        }
    }

    /// Remove both files once every write asked before is done; waits for it.
    pub fn remove(&mut self) {
        match self.tx.take() {
            Some(tx) => {
                let _ = tx.send(Job::Remove);
                drop(tx);
                if let Some(t) = self.thread.take() {
                    let _ = t.join();
                }
            }
            None => run(&self.run_dir, Job::Remove),
        }
    }
}

/// The thread's loop: the newest job waiting, one at a time, until the
/// writer is dropped.
fn serve(dir: &Path, rx: &Receiver<Job>) {
    while let Ok(mut job) = rx.recv() {
        // a removal is the last job; a newer write replaces an older one
        while let Ok(next) = rx.try_recv() {
            job = next;
        }
        run(dir, job);
    }
}

fn run(dir: &Path, job: Job) {
    match job {
        Job::Write(json, state) => {
            let written = json.write(dir).and_then(|_| state.write(dir));
            if let Err(e) = written {
                tracing::warn!("{e}");
            }
        }
        Job::Remove => {
            let _ = std::fs::remove_file(StateJson::path(dir));
            let _ = std::fs::remove_file(dir.join(STATE_FILE));
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::state::STATE_VERSION;

    /// The two files of a supervisor whose pid is `pid`.
    fn files(pid: u32) -> (StateJson, SupervisorState) {
        let prefix = "p_".to_string();
        let json = StateJson {
            prefix: prefix.clone(),
            services: Default::default(),
            supervisor_pid: pid,
        };
        let state = SupervisorState {
            version: STATE_VERSION,
            supervisor_pid: pid,
            prefix,
            cell_start_ns: 1,
            services: vec![],
        };
        (json, state)
    }

    #[test]
    fn the_newest_write_is_on_disk_and_the_removal_waits_for_the_writes() {
        let dir = std::env::temp_dir().join(format!("phri-state-writer-{}", std::process::id()));
        let _ = std::fs::remove_dir_all(&dir);
        std::fs::create_dir_all(&dir).unwrap();
        let mut w = StateWriter::new(&dir);
        for pid in 0..50 {
            let (json, state) = files(pid);
            w.write(json, state);
        }
        // removing waits for the writes before it, then removes both
        w.remove();
        assert!(!StateJson::path(&dir).exists());
        assert!(!dir.join(STATE_FILE).exists());
        let mut w = StateWriter::new(&dir);
        for pid in [1, 2] {
            let (json, state) = files(pid);
            w.write(json, state);
        }
        // dropping the sender ends the thread after its last job
        let t = w.thread.take().unwrap();
        w.tx = None;
        t.join().unwrap();
        let json = StateJson::read(&dir).unwrap().unwrap();
        let state = SupervisorState::read(&dir, "p_").unwrap().unwrap();
        assert_eq!((json.supervisor_pid, state.supervisor_pid), (2, 2));
        let _ = std::fs::remove_dir_all(&dir);
    }
}
