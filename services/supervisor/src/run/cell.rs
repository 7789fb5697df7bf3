//! The cell's processes: started (or taken over from a supervisor that
//! died), signalled, reaped, stopped in order; and the state files that
//! tell a supervisor taking over what runs.

use std::time::Duration;

use phri_runtime::now_ns;

use super::state_writer::StateWriter;
use crate::process::{process_matches, Launch, Proc};
use crate::supervision::Event;
use crate::{Roster, SupervisorError, SupervisorState};

/// The running cell's processes (by roster index), and how they are started.
pub struct Cell {
    /// per service: its process while it runs
    pub procs: Vec<Option<Proc>>,
    /// how this run starts its services
    pub launch: Launch,
    /// writes the state files beside the loop
    writer: StateWriter,
}

impl Cell {
    /// No process yet, for `services` services.
    pub fn new(launch: Launch, services: usize) -> Cell {
        Cell {
            procs: (0..services).map(|_| None).collect(),
            writer: StateWriter::new(&launch.run_dir),
            launch,
        }
    }

    /// Start service `i`.
    fn spawn(&self, roster: &Roster, i: usize) -> Result<std::process::Child, SupervisorError> {
        let (name, spec) = (&roster.get(i).name, &roster.get(i).spec);
        let mut cmd = self.launch.command(name, spec);
        if roster.get(i).started_before() {
            cmd.env(phri_runtime::service::RESTARTED_ENV, "1");
        }
        cmd.spawn().map_err(|source| SupervisorError::Spawn {
            service: name.clone(),
            binary: spec.binary.clone(),
            source,
        })
    }

    /// Start service `i`: what came of it.
    pub fn start(&mut self, roster: &Roster, i: usize) -> Event {
        match self.spawn(roster, i) {
            Ok(child) => {
                let pid = child.id();
                self.procs[i] = Some(Proc::Child(child));
                Event::Started { index: i, pid }
            }
            Err(e) => Event::SpawnFailed {
                index: i,
                error: e.to_string(),
            },
        }
    }

    /// Take over service `i`'s process from the supervisor that died
    /// (`previous`, its state) when it still runs, else start it.
    pub fn launch(
        &mut self,
        roster: &Roster,
        i: usize,
        previous: Option<&SupervisorState>,
    ) -> Event {
        let name = &roster.get(i).name;
        let adopt = previous
            .and_then(|p| p.service(name))
            .filter(|s| process_matches(s.pid, &self.launch.needles(name)));
        let Some(prev) = adopt else {
            return self.start(roster, i);
        };
        self.procs[i] = Some(Proc::Adopted {
            pid: prev.pid,
            prefix: self.launch.run_needle(),
        });
        Event::Adopted {
            index: i,
            pid: prev.pid,
            restarts: prev.restarts,
        }
    }

    /// SIGKILL service `i`'s process, if it runs.
    pub fn kill(&self, i: usize) {
        if let Some(p) = &self.procs[i] {
            p.signal(libc::SIGKILL);
        }
    }

    /// Service `i`'s process has ended: how (it is gone from the cell).
    pub fn reap(&mut self, i: usize) -> Option<String> {
        let detail = self.procs[i].as_mut().and_then(Proc::try_exited)?;
        self.procs[i] = None;
        Some(detail)
    }

    /// `state.json` and `supervisor.state`, each replaced atomically,
    /// owner-only, beside the loop ([`StateWriter`]).
    pub fn write_state(&self, roster: &Roster) {
        let me = std::process::id();
        let prefix = &self.launch.prefix;
        let json = roster.state_json(prefix, me);
        let state = roster.state(prefix, me, self.launch.cell_start_ns);
        self.writer.write(json, state);
    }

    /// Remove the state files, once the writes asked before are done.
    pub fn remove_state(&mut self) {
        self.writer.remove();
    }

    /// The first service of the start that has ended, and how.
    pub fn first_exit(&mut self) -> Option<(usize, String)> {
        self.procs
            .iter_mut()
            .enumerate()
            .find_map(|(i, p)| Some((i, p.as_mut()?.try_exited()?)))
    }

    /// Ordered shutdown in start order: the robot first (it brakes the arm as
    /// it exits), then what depends on it; SIGTERM, then SIGKILL after the
    /// grace period.
    pub fn stop(&mut self, roster: &Roster) {
        let grace_ns = roster.config().shutdown_grace_ms * 1_000_000;
        for (i, slot) in self.procs.iter_mut().enumerate() {
            let Some(mut child) = slot.take() else {
                continue;
            };
            let name = &roster.get(i).name;
            child.signal(libc::SIGTERM);
            let deadline = now_ns() + grace_ns;
            let mut killed = false;
            while child.try_exited().is_none() {
                if now_ns() > deadline + 2_000_000_000 {
                    tracing::warn!(
                        "{name} (pid {}) does not end even after SIGKILL",
                        child.pid()
                    );
                    break;
                }
                if now_ns() > deadline && !killed {
                    tracing::warn!("{name} ignored SIGTERM, killing it");
                    child.signal(libc::SIGKILL);
                    killed = true;
                }
                std::thread::sleep(Duration::from_millis(5));
            }
        }
    }
}
