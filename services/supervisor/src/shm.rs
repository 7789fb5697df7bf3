//! iceoryx2's node counter: one shared-memory object per prefix,
//! `/dev/shm/<prefix><hash>_node.<version>.global_mgmt`, that every node
//! creation opens and increments. iceoryx2 0.10 creates it readable and
//! writable by every local user: a user who pre-creates it, or writes into
//! it, stops every later node creation of the prefix (the cell never starts,
//! or no service can be restarted).
//!
//! So, before its first node, the supervisor refuses a segment of its prefix
//! that is not a regular file of this user or whose contents are not what
//! iceoryx2 writes ([`check_global_mgmt`]); once its first node has created
//! the segment it makes it owner-only ([`restrict_global_mgmt`]), which
//! iceoryx2 accepts for every later node of the same user. What remains is
//! the short window between the creation and the `chmod`, and other users'
//! read access to `/dev/shm` names: README, "What the cell trusts".

use std::io::Read;
use std::os::unix::fs::{MetadataExt, OpenOptionsExt, PermissionsExt};
use std::path::{Path, PathBuf};

/// Where POSIX shared-memory objects live.
pub const SHM_DIR: &str = "/dev/shm";

/// What follows the hash in the segment's name (`_node.0_10_0.global_mgmt`).
const NODE_PART: &str = "_node.";
const SUFFIX: &str = ".global_mgmt";

/// Size iceoryx2 0.10 gives the segment: its version (u64) and the counter (u32), padded [bytes].
const SEGMENT_LEN: u64 = 16;

/// A node-counter segment that cannot be trusted, naming it.
#[derive(Debug, thiserror::Error)]
pub enum ShmError {
    /// not a regular file of this user: another user could stop every node creation
    #[error("{}: iceoryx2's node counter of this prefix is {what}: refused (another user could stop every node creation; remove it, or use another --prefix)", path.display())]
    Foreign {
        /// the segment
        path: PathBuf,
        /// what it is instead (`not a regular file`, `owned by uid N`, ...)
        what: String,
    },
    /// its contents are not what iceoryx2 writes (size, version field)
    #[error("{}: iceoryx2's node counter of this prefix was altered ({what}): refused (remove it once no cell of this prefix runs)", path.display())]
    Altered {
        /// the segment
        path: PathBuf,
        /// what differs from what iceoryx2 writes
        what: String,
    },
    /// it could not be inspected or made owner-only
    #[error("{}: {source}", path.display())]
    Io {
        /// the segment
        path: PathBuf,
        /// the error of the operation on it
        source: std::io::Error,
    },
}

/// The iceoryx2 version a segment's name states (`0_10_0` → 0.10.0), as
/// iceoryx2 stores it in the segment: `major << 32 | minor << 16 | patch`.
fn version_of(name: &str) -> Option<u64> {
    let mid = name.strip_suffix(SUFFIX)?;
    let (_, ver) = mid.rsplit_once(NODE_PART)?;
    let mut parts = ver.split('_').map(|p| p.parse::<u16>().ok());
    let (major, minor, patch) = (parts.next()??, parts.next()??, parts.next()??);
    if parts.next().is_some() {
        return None;
    }
    Some((major as u64) << 32 | (minor as u64) << 16 | patch as u64)
}

/// `name` is the node-counter segment of `prefix`: the prefix, a hex hash,
/// `_node.<version>.global_mgmt` (and not a longer prefix's).
fn is_segment_of(name: &str, prefix: &str) -> bool {
    let Some(rest) = name.strip_prefix(prefix) else {
        return false;
    };
    let Some(hash_end) = rest.find(NODE_PART) else {
        return false;
    };
    let hash = &rest[..hash_end];
    !hash.is_empty() && hash.bytes().all(|b| b.is_ascii_hexdigit()) && version_of(rest).is_some()
}

/// The node-counter segments of `prefix` in `dir` (normally one).
pub fn global_mgmt_segments(dir: &Path, prefix: &str) -> Vec<PathBuf> {
    let Ok(rd) = std::fs::read_dir(dir) else {
        return Vec::new();
    };
    let mut found: Vec<PathBuf> = rd
        .flatten()
        .filter(|e| is_segment_of(&e.file_name().to_string_lossy(), prefix))
        .map(|e| e.path())
        .collect();
    found.sort();
    found
}

/// Every node-counter segment of `prefix` in `dir` is a regular file (not a
/// link) of this user, of iceoryx2's size, holding the version its name
/// states. A segment that is writable by others is acceptable here (iceoryx2
/// creates it so); [`restrict_global_mgmt`] closes it.
pub fn check_global_mgmt(dir: &Path, prefix: &str) -> Result<(), ShmError> {
    for path in global_mgmt_segments(dir, prefix) {
        let foreign = |what: String| ShmError::Foreign {
            path: path.clone(),
            what,
        };
        let altered = |what: String| ShmError::Altered {
            path: path.clone(),
            what,
        };
        let meta = std::fs::symlink_metadata(&path).map_err(|source| ShmError::Io {
            path: path.clone(),
            source,
        })?;
        if !meta.file_type().is_file() {
            return Err(foreign("not a regular file".into()));
        }
        let me = phri_runtime::rundir::euid();
        if meta.uid() != me {
            return Err(foreign(format!(
                "owned by uid {}, not by this user (uid {me})",
                meta.uid()
            )));
        }
        if meta.len() != SEGMENT_LEN {
            return Err(altered(format!(
                "{} bytes, iceoryx2 writes {SEGMENT_LEN}",
                meta.len()
            )));
        }
        let name = path
            .file_name()
            .map(|n| n.to_string_lossy().into_owned())
            .unwrap_or_default();
        let expected = version_of(&name).unwrap_or(0);
        let mut head = [0u8; 8];
        let read = std::fs::OpenOptions::new()
            .read(true)
            .custom_flags(libc::O_NOFOLLOW | libc::O_NONBLOCK)
            .open(&path)
            .and_then(|mut f| f.read_exact(&mut head));
        match read {
            Ok(()) => {
                let version = u64::from_ne_bytes(head);
                // 0: a node is creating it right now (a takeover's cell)
                if version != expected && version != 0 {
                    return Err(altered(format!(
                        "version field {version:#x}, its name says {expected:#x}"
                    )));
                }
            }
            // iceoryx2 holds it write-only while it initialises it
            Err(e) if e.kind() == std::io::ErrorKind::PermissionDenied => {}
            Err(source) => {
                return Err(ShmError::Io {
                    path: path.clone(),
                    source,
                })
            }
        }
    }
    Ok(())
}

/// Make every node-counter segment of `prefix` in `dir` owner-only (0600),
/// after checking it ([`check_global_mgmt`]); returns how many were found.
pub fn restrict_global_mgmt(dir: &Path, prefix: &str) -> Result<usize, ShmError> {
    check_global_mgmt(dir, prefix)?;
    let found = global_mgmt_segments(dir, prefix);
    for path in &found {
        let io = |source| ShmError::Io {
            path: path.clone(),
            source,
        };
        // through a descriptor opened without following links: the object
        // checked is the object changed
        let f = std::fs::OpenOptions::new()
            .read(true)
            .custom_flags(libc::O_NOFOLLOW | libc::O_NONBLOCK)
            .open(path)
            .map_err(io)?;
        let meta = f.metadata().map_err(io)?;
        if meta.uid() != phri_runtime::rundir::euid() {
            return Err(ShmError::Foreign {
                path: path.clone(),
                what: format!("owned by uid {}", meta.uid()),
            });
        }
        if meta.permissions().mode() & 0o077 != 0 {
            f.set_permissions(std::fs::Permissions::from_mode(0o600))
                .map_err(io)?;
        }
    }
    Ok(found.len())
}

#[cfg(test)]
mod tests {
    use super::*;

    const NAME: &str = "p_9204dd183d1c4d8e1ff592a30766ffa6765aa8b5_node.0_10_0.global_mgmt";

    fn scratch(name: &str) -> PathBuf {
        let d = std::env::temp_dir().join(format!("phri-sup-shm-{}-{name}", std::process::id()));
        let _ = std::fs::remove_dir_all(&d);
        std::fs::create_dir_all(&d).unwrap();
        d
    }

    fn segment(version: u64) -> Vec<u8> {
        let mut b = version.to_ne_bytes().to_vec();
        b.extend([3, 0, 0, 0, 0, 0, 0, 0]);
        b
    }

    #[test]
    fn the_segment_is_recognised_by_prefix_hash_and_version() {
        assert_eq!(version_of(NAME), Some(10 << 16));
        assert!(is_segment_of(NAME, "p_"));
        // a longer prefix's segment, or another prefix's, is not ours
        assert!(!is_segment_of(NAME, "p"));
        assert!(!is_segment_of(NAME, "q_"));
        assert!(!is_segment_of(
            "p_x_9204dd183d1c4d8e1ff592a30766ffa6765aa8b5_node.0_10_0.global_mgmt",
            "p_"
        ));
        assert!(!is_segment_of("p_9204dd18_node.0_10.global_mgmt", "p_"));
        assert!(!is_segment_of("p_9204dd18_1234.data", "p_"));
    }

    #[test]
    fn an_altered_segment_is_refused_and_a_sound_one_made_owner_only() {
        let d = scratch("seg");
        let p = d.join(NAME);
        assert_eq!(restrict_global_mgmt(&d, "p_").unwrap(), 0);
        std::fs::write(&p, segment(10 << 16)).unwrap();
        std::fs::set_permissions(&p, std::fs::Permissions::from_mode(0o666)).unwrap();
        check_global_mgmt(&d, "p_").unwrap();
        assert_eq!(restrict_global_mgmt(&d, "p_").unwrap(), 1);
        let mode = std::fs::metadata(&p).unwrap().permissions().mode() & 0o777;
        assert_eq!(mode, 0o600);
        // another version in the version field
        std::fs::write(&p, segment(7 << 32)).unwrap();
        let e = check_global_mgmt(&d, "p_").unwrap_err().to_string();
        assert!(e.contains(NAME) && e.contains("altered"), "{e}");
        // another size
        std::fs::write(&p, [0u8; 4096]).unwrap();
        let e = check_global_mgmt(&d, "p_").unwrap_err().to_string();
        assert!(e.contains("4096 bytes"), "{e}");
        // a link (to anything) or a directory
        std::fs::remove_file(&p).unwrap();
        std::os::unix::fs::symlink("/etc/hostname", &p).unwrap();
        let e = check_global_mgmt(&d, "p_").unwrap_err().to_string();
        assert!(e.contains("not a regular file"), "{e}");
        std::fs::remove_file(&p).unwrap();
        std::fs::create_dir(&p).unwrap();
        assert!(matches!(
            check_global_mgmt(&d, "p_"),
            Err(ShmError::Foreign { .. })
        ));
        std::fs::remove_dir_all(&d).unwrap();
    }

    #[test]
    fn a_segment_of_another_user_is_refused() {
        let d = scratch("owner");
        let p = d.join(NAME);
        std::fs::write(&p, segment(10 << 16)).unwrap();
        let c = std::ffi::CString::new(p.to_string_lossy().as_bytes()).unwrap();
        if phri_runtime::rundir::euid() == 0 {
            // SAFETY: chown on a file this test created
            assert_eq!(unsafe { libc::chown(c.as_ptr(), 65534, 65534) }, 0);
            let e = check_global_mgmt(&d, "p_").unwrap_err().to_string();
            assert!(e.contains("owned by uid 65534"), "{e}");
            assert!(restrict_global_mgmt(&d, "p_").is_err());
        } else {
            // not root: a file cannot be given away; what another user could
            // write is closed instead
            std::fs::set_permissions(&p, std::fs::Permissions::from_mode(0o666)).unwrap();
            assert_eq!(restrict_global_mgmt(&d, "p_").unwrap(), 1);
        }
        std::fs::remove_dir_all(&d).unwrap();
    }
}
