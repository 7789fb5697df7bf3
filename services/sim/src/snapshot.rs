//! The arm's last joint positions on disk (`<run-dir>/sim-arm.state`,
//! bincode), so that a simulator restarted inside a running cell puts the arm
//! back where it was, at rest, as a real arm stands braked while its adapter
//! restarts, instead of at the scenario's initial configuration; and the
//! person's script time with them, so that the person goes on from where the
//! robot's clock had brought them (a loaded machine's robot runs behind the
//! wall clock, and the scenario with it).
//!
//! The 1 kHz loop only stores into [`SharedArm`] (atomics: no allocation, no
//! lock); a helper thread copies it out every [`SAVE_PERIOD`] and writes the
//! file ([`save`]). A restarted simulator picks the cell up with [`resume`].
//!
//! The file is private to the cell's user: written owner-only and atomically
//! ([`phri_runtime::rundir::write_private`]), read only if no one else can
//! have written it ([`phri_runtime::rundir::read_trusted`]).

use std::path::{Path, PathBuf};
use std::sync::atomic::{fence, AtomicU64, Ordering};
use std::time::Duration;

use serde::{Deserialize, Serialize};

use crate::error::SimError;
use crate::sim::MAX_JOINTS;
use crate::Simulator;

/// File name of the snapshot inside the run directory.
pub const FILE_NAME: &str = "sim-arm.state";
/// How often the arm's positions are saved for a restarted simulator.
pub const SAVE_PERIOD: Duration = Duration::from_millis(10);
/// A snapshot older than this is not the arm's state any more \[ns\].
pub const MAX_AGE_NS: u64 = 2_000_000_000;
/// The snapshot format's version: 2 added the person's script time.
pub const VERSION: u32 = 2;

/// The arm at one instant.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct ArmSnapshot {
    /// format version ([`VERSION`] when written by this build)
    pub version: u32,
    /// when the positions were true [ns, CLOCK_MONOTONIC]
    pub stamp_ns: u64,
    /// joint positions \[rad\]
    pub q: Vec<f64>,
    /// the person's script time at `stamp_ns` \[s\]
    pub scenario_s: f64,
}

/// Why a snapshot could not be saved or read.
#[derive(Debug, thiserror::Error)]
pub enum SnapshotError {
    /// not a file this user alone could have written (or too large)
    #[error(transparent)]
    Untrusted(#[from] phri_runtime::rundir::TrustError),
    /// not a snapshot of this version, or one with a non-finite value (also: it
    /// could not be encoded)
    #[error("{path}: not an arm snapshot: {reason}")]
    Decode {
        /// the snapshot file
        path: PathBuf,
        /// what is wrong with it
        reason: String,
    },
    /// a snapshot of an arm with another number of joints
    #[error("{path}: {found} joints, the model has {expected}")]
    Joints {
        /// the snapshot file
        path: PathBuf,
        /// joints in the snapshot
        found: usize,
        /// joints of the model
        expected: usize,
    },
}

/// Joint positions shared by the control loop (one writer) with the thread
/// that saves them: a sequence lock over atomics.
pub struct SharedArm {
    seq: AtomicU64,
    stamp_ns: AtomicU64,
    scenario_bits: AtomicU64,
    n: usize,
    q: [AtomicU64; MAX_JOINTS],
}

impl SharedArm {
    /// For an arm of `n` joints (at most [`MAX_JOINTS`]; more are ignored).
    pub fn new(n: usize) -> SharedArm {
        SharedArm {
            seq: AtomicU64::new(0),
            stamp_ns: AtomicU64::new(0),
            scenario_bits: AtomicU64::new(0),
            n: n.min(MAX_JOINTS),
            q: std::array::from_fn(|_| AtomicU64::new(0)),
        }
    }

    /// Store positions `q` \[rad\] true at `stamp_ns`, the person's script at
    /// `scenario_s` \[s\]. Single writer; allocates nothing.
    pub fn store(&self, q: &[f64], stamp_ns: u64, scenario_s: f64) {
        let s = self.seq.load(Ordering::Relaxed);
        self.seq.store(s.wrapping_add(1), Ordering::Relaxed);
        fence(Ordering::Release);
        for (dst, x) in self.q.iter().zip(q).take(self.n) {
            dst.store(x.to_bits(), Ordering::Relaxed);
        }
        self.stamp_ns.store(stamp_ns, Ordering::Relaxed);
        self.scenario_bits
            .store(scenario_s.to_bits(), Ordering::Relaxed);
        self.seq.store(s.wrapping_add(2), Ordering::Release);
    }

    /// A consistent copy, or `None` before the first store.
    pub fn load(&self) -> Option<ArmSnapshot> {
        loop {
            let s1 = self.seq.load(Ordering::Acquire);
            if s1 == 0 {
                return None;
            }
            if s1 % 2 == 1 {
                std::hint::spin_loop();
                continue;
            }
            let q: Vec<f64> = self.q[..self.n]
                .iter()
                .map(|x| f64::from_bits(x.load(Ordering::Relaxed)))
                .collect();
            let stamp_ns = self.stamp_ns.load(Ordering::Relaxed);
            let scenario_s = f64::from_bits(self.scenario_bits.load(Ordering::Relaxed));
            fence(Ordering::Acquire);
            if self.seq.load(Ordering::Relaxed) == s1 {
                return Some(ArmSnapshot {
                    version: VERSION,
                    stamp_ns,
                    q,
                    scenario_s,
                });
            }
        }
    }
}

/// Largest snapshot file read [bytes] (a 64-joint arm needs about 530).
const MAX_FILE_LEN: u64 = 4096;

/// `s` as the file holds it.
fn encode(path: &Path, s: &ArmSnapshot) -> Result<Vec<u8>, SnapshotError> {
    bincode::serde::encode_to_vec(s, bincode::config::standard()).map_err(|e| {
        SnapshotError::Decode {
            path: path.to_path_buf(),
            reason: e.to_string(),
        }
    })
}

/// Write `s` to `path` atomically and owner-only (0600).
pub fn save(path: &Path, s: &ArmSnapshot) -> Result<(), SnapshotError> {
    phri_runtime::rundir::write_private(path, &encode(path, s)?)?;
    Ok(())
}

/// Saves one arm's snapshots to one file, every [`SAVE_PERIOD`]: the first
/// as [`save`] does (a fresh owner-only file, renamed into place), each
/// next one over it in place, one `pwrite`, while its encoding keeps the
/// file's length (an arm's snapshots do: its joint count fixes it, and the
/// clock's stamps past its first 4 s take the same bytes); anew as the
/// first otherwise, or after a failed write. Creating, writing and
/// renaming a file every 10 ms had cost the simulator's saver thread 1.9 %
/// of a core.
///
/// The next simulator reads the file only once this one has ended, and a
/// write of a few dozen bytes within one page is done whole or not at all
/// (a kill is acted on before the copy or after it): it never reads half of
/// one snapshot and half of another.
pub struct SnapshotWriter {
    path: PathBuf,
    /// the file made by the last atomic save, and its length [bytes]
    file: Option<(std::fs::File, usize)>,
}

impl SnapshotWriter {
    /// A writer of the snapshot file `path`; nothing written yet.
    pub fn new(path: PathBuf) -> SnapshotWriter {
        SnapshotWriter { path, file: None }
    }

    /// Save `s` (in place when it can, see [`SnapshotWriter`]).
    pub fn save(&mut self, s: &ArmSnapshot) -> Result<(), SnapshotError> {
        use std::os::unix::fs::FileExt;
        let bytes = encode(&self.path, s)?;
        if let Some((file, len)) = &self.file {
            if *len == bytes.len() && file.write_all_at(&bytes, 0).is_ok() {
                return Ok(());
            }
        }
        // (the file before is closed only once the new one is in place)
        let file = phri_runtime::rundir::write_private_open(&self.path, &bytes)?;
        self.file = Some((file, bytes.len()));
        Ok(())
    }

    /// Whether the next save of a snapshot as long as the last goes in place.
    pub fn in_place(&self) -> bool {
        self.file.is_some()
    }
}

/// The snapshot at `path` if it exists, is trusted (a regular file of this
/// user that no one else can write, at most 4 KiB), is for `n` joints, all finite, was
/// taken at or after `not_before_ns` (this cell's start: never a previous
/// run's) and at most [`MAX_AGE_NS`] before `now_ns`; `Ok(None)` when absent or
/// not of this moment.
pub fn load_fresh(
    path: &Path,
    n: usize,
    not_before_ns: u64,
    now_ns: u64,
) -> Result<Option<ArmSnapshot>, SnapshotError> {
    let Some(bytes) = phri_runtime::rundir::read_trusted(path, MAX_FILE_LEN)? else {
        return Ok(None);
    };
    let decode = |reason: String| SnapshotError::Decode {
        path: path.to_path_buf(),
        reason,
    };
    // a malformed length cannot make it allocate more than 4 KiB
    let config = bincode::config::standard().with_limit::<4096>();
    let (s, used): (ArmSnapshot, usize) =
        bincode::serde::decode_from_slice(&bytes, config).map_err(|e| decode(e.to_string()))?;
    if used != bytes.len() || s.version != VERSION {
        return Err(decode(format!(
            "version {} with {} trailing bytes",
            s.version,
            bytes.len() - used
        )));
    }
    if s.q.len() != n {
        return Err(SnapshotError::Joints {
            path: path.to_path_buf(),
            found: s.q.len(),
            expected: n,
        });
    }
    if s.q.iter().any(|x| !x.is_finite()) {
        return Err(decode("a joint position is not finite".into()));
    }
    if !s.scenario_s.is_finite() || s.scenario_s < 0.0 {
        return Err(decode(format!("scenario time {} s", s.scenario_s)));
    }
    if s.stamp_ns < not_before_ns || s.stamp_ns > now_ns || now_ns - s.stamp_ns > MAX_AGE_NS {
        return Ok(None);
    }
    Ok(Some(s))
}

/// How a simulator restarted inside a running cell picked the cell up ([`resume`]).
#[derive(Debug)]
pub struct Resumed {
    /// how long ago the cell started \[s\]
    pub behind_s: f64,
    /// where the person's script continues \[s\]: the predecessor's script
    /// time in its snapshot plus the time since, or `behind_s` without one
    pub scenario_s: f64,
    /// where the arm stands
    pub arm: ArmResume,
}

/// Where the arm of a restarted simulator stands.
#[derive(Debug)]
pub enum ArmResume {
    /// no run directory, or no snapshot of this cell's recent past: at its initial position
    Initial,
    /// at rest where the snapshot at `path` put it, taken `age_ns` \[ns\] ago
    Restored {
        /// the snapshot file
        path: PathBuf,
        /// age of the snapshot \[ns\]
        age_ns: u64,
    },
    /// the snapshot at `path` does not fit the arm (joint limits): at its initial position
    Refused {
        /// the snapshot file
        path: PathBuf,
        /// why the arm cannot stand there
        error: SimError,
    },
    /// the snapshot could not be read: at its initial position
    Unreadable(SnapshotError),
}

/// Restarted inside a running cell that started at `cell_start_ns` (it is
/// `now_ns`): the world went on without us, so the person continues where the
/// predecessor's script was (its snapshot's script time plus the time since;
/// without a snapshot, `[sim] human_offset_s` plus the time since the cell
/// started), and the arm stands,
/// at rest, where the predecessor last saved it in `snapshot` (if given,
/// fresh and fitting).
pub fn resume(
    sim: &mut Simulator,
    cell_start_ns: u64,
    now_ns: u64,
    snapshot: Option<&Path>,
) -> Resumed {
    let behind_s = now_ns.saturating_sub(cell_start_ns) as f64 * 1e-9;
    // the configured offset of the person's script, then the time since
    let mut scenario_s = sim.config().human_offset_s + behind_s;
    let arm = match snapshot {
        None => ArmResume::Initial,
        Some(path) => match load_fresh(path, sim.model().nv(), cell_start_ns, now_ns) {
            Ok(Some(s)) => {
                let age_ns = now_ns.saturating_sub(s.stamp_ns);
                scenario_s = s.scenario_s + age_ns as f64 * 1e-9;
                match sim.reset_state(&s.q) {
                    Ok(()) => ArmResume::Restored {
                        path: path.to_path_buf(),
                        age_ns,
                    },
                    Err(error) => ArmResume::Refused {
                        path: path.to_path_buf(),
                        error,
                    },
                }
            }
            Ok(None) => ArmResume::Initial,
            Err(e) => ArmResume::Unreadable(e),
        },
    };
    sim.set_human_time_offset(scenario_s);
    Resumed {
        behind_s,
        scenario_s,
        arm,
    }
}

impl Resumed {
    /// What to tell the operator, one line each (none when nothing notable happened).
    pub fn log_lines(&self) -> Vec<String> {
        let mut lines = Vec::new();
        if self.behind_s > 1.0 {
            lines.push(format!(
                "the cell started {:.1} s ago: the scenario continues from {:.1} s",
                self.behind_s, self.scenario_s
            ));
        }
        match &self.arm {
            ArmResume::Initial => {}
            ArmResume::Restored { path, age_ns } => lines.push(format!(
                "the arm continues from its state of {:.0} ms ago ({})",
                *age_ns as f64 * 1e-6,
                path.display()
            )),
            ArmResume::Refused { path, error } => lines.push(format!(
                "{}: {error}; the arm starts at its initial position",
                path.display()
            )),
            ArmResume::Unreadable(e) => {
                lines.push(format!("{e}; the arm starts at its initial position"))
            }
        }
        lines
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn tmp(name: &str) -> PathBuf {
        let d = std::env::temp_dir().join(format!("phri-sim-snap-{}-{name}", std::process::id()));
        std::fs::create_dir_all(&d).unwrap();
        d.join(FILE_NAME)
    }

    #[test]
    fn the_writer_saves_in_place_what_a_restarted_simulator_reads() {
        let p = tmp("writer");
        let _ = std::fs::remove_file(&p);
        let mut w = SnapshotWriter::new(p.clone());
        assert!(!w.in_place());
        let snap = |stamp_ns: u64, q0: f64, n: usize| ArmSnapshot {
            version: VERSION,
            stamp_ns,
            q: (0..n).map(|i| q0 + i as f64 * 0.1).collect(),
            scenario_s: stamp_ns as f64 * 1e-9,
        };
        let inode = || std::os::unix::fs::MetadataExt::ino(&std::fs::metadata(&p).unwrap());
        // the first atomically, owner-only
        let a = snap(5_000_000_000, 0.1, 7);
        w.save(&a).unwrap();
        assert!(w.in_place());
        let mode =
            std::os::unix::fs::PermissionsExt::mode(&std::fs::metadata(&p).unwrap().permissions());
        assert_eq!(mode & 0o777, 0o600);
        let first = inode();
        assert_eq!(load_fresh(&p, 7, 0, 5_100_000_000).unwrap(), Some(a));
        // the next ones in the same file, each read back whole
        for k in 1..=3u64 {
            let b = snap(5_000_000_000 + k * 10_000_000, -0.3 * k as f64, 7);
            w.save(&b).unwrap();
            assert_eq!(inode(), first, "written in place");
            assert_eq!(load_fresh(&p, 7, 0, 5_100_000_000).unwrap(), Some(b));
        }
        // another length (here: another joint count) is saved anew, whole
        let c = snap(5_050_000_000, 0.2, 6);
        w.save(&c).unwrap();
        assert_ne!(inode(), first);
        assert_eq!(load_fresh(&p, 6, 0, 5_100_000_000).unwrap(), Some(c));
        std::fs::remove_file(&p).unwrap();
    }

    #[test]
    fn shared_arm_round_trips_through_the_file() {
        let arm = SharedArm::new(7);
        assert!(arm.load().is_none());
        let q = [0.1, -0.2, 0.3, -1.4, 0.5, 0.6, -0.7];
        arm.store(&q, 5_000_000_000, 12.5);
        let s = arm.load().unwrap();
        assert_eq!((s.q.as_slice(), s.scenario_s), (&q[..], 12.5));
        let p = tmp("rt");
        save(&p, &s).unwrap();
        assert_eq!(load_fresh(&p, 7, 0, 5_500_000_000).unwrap(), Some(s));
        // too old, or from the future: not the arm's state
        assert_eq!(
            load_fresh(&p, 7, 0, 5_000_000_000 + MAX_AGE_NS + 1).unwrap(),
            None
        );
        assert_eq!(load_fresh(&p, 7, 0, 4_000_000_000).unwrap(), None);
        // a previous run's, in the same run directory
        assert_eq!(
            load_fresh(&p, 7, 5_100_000_000, 5_500_000_000).unwrap(),
            None
        );
        // another robot
        assert!(matches!(
            load_fresh(&p, 6, 0, 5_500_000_000),
            Err(SnapshotError::Joints {
                found: 7,
                expected: 6,
                ..
            })
        ));
        // absent
        std::fs::remove_file(&p).unwrap();
        assert_eq!(load_fresh(&p, 7, 0, 5_500_000_000).unwrap(), None);
    }

    #[test]
    fn a_malformed_file_is_an_error_naming_it() {
        let p = tmp("bad");
        // the last claims 2^56 joint positions
        let huge = [1u8, 0, 0xfd, 0, 0, 0, 0, 0, 0, 0, 1];
        for bytes in [&b"garbage"[..], &[][..], &[1, 2][..], &huge[..]] {
            std::fs::write(&p, bytes).unwrap();
            let e = load_fresh(&p, 7, 0, 1).unwrap_err().to_string();
            assert!(e.contains(FILE_NAME), "{e}");
        }
        let good = ArmSnapshot {
            version: VERSION,
            stamp_ns: 1,
            q: vec![f64::NAN; 7],
            scenario_s: 0.0,
        };
        save(&p, &good).unwrap();
        assert!(load_fresh(&p, 7, 0, 2).is_err());
        // nor a script time that is none
        for t in [f64::NAN, f64::INFINITY, -1.0] {
            let bad = ArmSnapshot {
                q: vec![0.1; 7],
                scenario_s: t,
                ..good.clone()
            };
            save(&p, &bad).unwrap();
            assert!(load_fresh(&p, 7, 0, 2).is_err(), "{t}");
        }
    }

    #[test]
    fn a_snapshot_is_written_private_and_one_others_could_write_is_refused() {
        use std::os::unix::fs::PermissionsExt;
        let p = tmp("trust");
        let s = ArmSnapshot {
            version: VERSION,
            stamp_ns: 1,
            q: vec![0.1; 7],
            scenario_s: 3.0,
        };
        save(&p, &s).unwrap();
        let mode = std::fs::metadata(&p).unwrap().permissions().mode() & 0o777;
        assert_eq!(mode, 0o600);
        assert_eq!(load_fresh(&p, 7, 0, 2).unwrap(), Some(s));
        // another user could have replaced the arm's state: not read
        std::fs::set_permissions(&p, std::fs::Permissions::from_mode(0o666)).unwrap();
        let e = load_fresh(&p, 7, 0, 2).unwrap_err().to_string();
        assert!(
            e.contains(FILE_NAME) && e.contains("writable by other users"),
            "{e}"
        );
        // a symbolic link is not followed
        std::fs::set_permissions(&p, std::fs::Permissions::from_mode(0o600)).unwrap();
        let link = p.with_file_name("link.state");
        let _ = std::fs::remove_file(&link);
        std::os::unix::fs::symlink(&p, &link).unwrap();
        assert!(matches!(
            load_fresh(&link, 7, 0, 2),
            Err(SnapshotError::Untrusted(_))
        ));
        // nor a file larger than any snapshot
        std::fs::write(&p, vec![0u8; MAX_FILE_LEN as usize + 1]).unwrap();
        assert!(matches!(
            load_fresh(&p, 7, 0, 2),
            Err(SnapshotError::Untrusted(_))
        ));
    }

    #[test]
    fn a_reader_never_sees_a_torn_write() {
        let arm = std::sync::Arc::new(SharedArm::new(7));
        let writer = {
            let arm = std::sync::Arc::clone(&arm);
            std::thread::spawn(move || {
                for k in 1..=200_000u64 {
                    let x = k as f64;
                    arm.store(&[x; 7], k, x);
                }
            })
        };
        let mut seen = 0;
        while !writer.is_finished() || seen == 0 {
            if let Some(s) = arm.load() {
                assert!(
                    s.q.iter().all(|x| *x == s.stamp_ns as f64)
                        && s.scenario_s == s.stamp_ns as f64,
                    "{s:?}"
                );
                seen += 1;
            }
        }
        writer.join().unwrap();
    }
}
