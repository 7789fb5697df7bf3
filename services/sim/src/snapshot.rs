//! The arm's last joint positions on disk (`<run-dir>/sim-arm.state`,
//! bincode), so that a simulator restarted inside a running cell puts the arm
//! back where it was, at rest, as a real arm stands braked while its adapter
//! restarts, instead of at the scenario's initial configuration.
//!
//! The 1 kHz loop only stores into [`SharedArm`] (atomics: no allocation, no
//! lock); a helper thread copies it out and writes the file.

use std::path::{Path, PathBuf};
use std::sync::atomic::{fence, AtomicU64, Ordering};

use serde::{Deserialize, Serialize};

use crate::sim::MAX_JOINTS;

/// File name of the snapshot inside the run directory.
pub const FILE_NAME: &str = "sim-arm.state";
/// A snapshot older than this is not the arm's state any more \[ns\].
pub const MAX_AGE_NS: u64 = 2_000_000_000;
const VERSION: u32 = 1;

/// The arm at one instant.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct ArmSnapshot {
    pub version: u32,
    /// when the positions were true [ns, CLOCK_MONOTONIC]
    pub stamp_ns: u64,
    /// joint positions \[rad\]
    pub q: Vec<f64>,
}

#[derive(Debug, thiserror::Error)]
pub enum SnapshotError {
    #[error("{path}: {source}")]
    Io {
        path: PathBuf,
        source: std::io::Error,
    },
    #[error("{path}: not an arm snapshot: {reason}")]
    Decode { path: PathBuf, reason: String },
    #[error("{path}: {found} joints, the model has {expected}")]
    Joints {
        path: PathBuf,
        found: usize,
        expected: usize,
    },
}

/// Joint positions shared by the control loop (one writer) with the thread
/// that saves them: a sequence lock over atomics.
pub struct SharedArm {
    seq: AtomicU64,
    stamp_ns: AtomicU64,
    n: usize,
    q: [AtomicU64; MAX_JOINTS],
}

impl SharedArm {
    /// For an arm of `n` joints (at most [`MAX_JOINTS`]; more are ignored).
    pub fn new(n: usize) -> SharedArm {
        SharedArm {
            seq: AtomicU64::new(0),
            stamp_ns: AtomicU64::new(0),
            n: n.min(MAX_JOINTS),
            q: std::array::from_fn(|_| AtomicU64::new(0)),
        }
    }

    /// Store positions `q` \[rad\] true at `stamp_ns`. Single writer; allocates nothing.
    pub fn store(&self, q: &[f64], stamp_ns: u64) {
        let s = self.seq.load(Ordering::Relaxed);
        self.seq.store(s.wrapping_add(1), Ordering::Relaxed);
        fence(Ordering::Release);
        for (dst, x) in self.q.iter().zip(q).take(self.n) {
            dst.store(x.to_bits(), Ordering::Relaxed);
        }
        self.stamp_ns.store(stamp_ns, Ordering::Relaxed);
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
            fence(Ordering::Acquire);
            if self.seq.load(Ordering::Relaxed) == s1 {
                return Some(ArmSnapshot {
                    version: VERSION,
                    stamp_ns,
                    q,
                });
            }
        }
    }
}

/// Write `s` to `path` atomically (a temporary file, then rename).
pub fn save(path: &Path, s: &ArmSnapshot) -> Result<(), SnapshotError> {
    let io = |source| SnapshotError::Io {
        path: path.to_path_buf(),
        source,
    };
    let bytes = bincode::serde::encode_to_vec(s, bincode::config::standard()).map_err(|e| {
        SnapshotError::Decode {
            path: path.to_path_buf(),
            reason: e.to_string(),
        }
    })?;
    let tmp = path.with_extension("tmp");
    std::fs::write(&tmp, bytes).map_err(io)?;
    std::fs::rename(&tmp, path).map_err(io)
}

/// The snapshot at `path` if it exists, is for `n` joints, all finite, was
/// taken at or after `not_before_ns` (this cell's start: never a previous
/// run's) and at most [`MAX_AGE_NS`] before `now_ns`; `Ok(None)` when absent or
/// not of this moment.
pub fn load_fresh(
    path: &Path,
    n: usize,
    not_before_ns: u64,
    now_ns: u64,
) -> Result<Option<ArmSnapshot>, SnapshotError> {
    let bytes = match std::fs::read(path) {
        Ok(b) => b,
        Err(e) if e.kind() == std::io::ErrorKind::NotFound => return Ok(None),
        Err(source) => {
            return Err(SnapshotError::Io {
                path: path.to_path_buf(),
                source,
            })
        }
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
    if s.stamp_ns < not_before_ns || s.stamp_ns > now_ns || now_ns - s.stamp_ns > MAX_AGE_NS {
        return Ok(None);
    }
    Ok(Some(s))
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
    fn shared_arm_round_trips_through_the_file() {
        let arm = SharedArm::new(7);
        assert!(arm.load().is_none());
        let q = [0.1, -0.2, 0.3, -1.4, 0.5, 0.6, -0.7];
        arm.store(&q, 5_000_000_000);
        let s = arm.load().unwrap();
        assert_eq!(s.q, q);
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
        };
        save(&p, &good).unwrap();
        assert!(load_fresh(&p, 7, 0, 2).is_err());
    }

    #[test]
    fn a_reader_never_sees_a_torn_write() {
        let arm = std::sync::Arc::new(SharedArm::new(7));
        let writer = {
            let arm = std::sync::Arc::clone(&arm);
            std::thread::spawn(move || {
                for k in 1..=200_000u64 {
                    let x = k as f64;
                    arm.store(&[x; 7], k);
                }
            })
        };
        let mut seen = 0;
        while !writer.is_finished() || seen == 0 {
            if let Some(s) = arm.load() {
                assert!(s.q.iter().all(|x| *x == s.stamp_ns as f64), "{s:?}");
                seen += 1;
            }
        }
        writer.join().unwrap();
    }
}
