//! Only files that the user who runs the cell (or root) wrote are read:
//! the configuration, a scenario, the robot file, the URDF and what they
//! pull in (a scenario's voice recordings), as `ssh` treats its keys.
//!
//! The rule ([`check_file`]):
//! - the file is a regular file (not a FIFO, a device or a directory: a
//!   FIFO would hang the reader), owned by this user or root, and writable
//!   by neither its group nor others;
//! - every directory above it, up to `/`, of the path as given and of the
//!   path with its links resolved, is owned by this user or root and writable
//!   by neither group nor others, except a root-owned directory with the
//!   sticky bit (`/tmp`, `/dev/shm`): there only an entry's owner (or root)
//!   may rename or remove it, so another user cannot replace what the
//!   entry below it (checked in turn) is. A directory another user could
//!   write is refused even when the file itself is ours: its owner could
//!   swap the file for one of their own between the check and the read.
//!
//! A refusal is one line naming the file (and the directory at fault),
//! its owner and its mode ([`TrustError`]).

use std::fs::{File, Metadata, OpenOptions};
use std::os::unix::fs::{MetadataExt, OpenOptionsExt};
use std::path::{Component, Path, PathBuf};

/// Why a file is not read.
#[derive(Debug, thiserror::Error)]
pub enum TrustError {
    /// the file could not be opened, examined or read
    #[error("{}: cannot read: {source}", path.display())]
    Io {
        /// the file
        path: PathBuf,
        /// the system's error
        source: std::io::Error,
    },
    /// not a regular file (a FIFO, a device, a directory)
    #[error("{}: is a {kind}, not a regular file: refused", path.display())]
    NotRegular {
        /// the file
        path: PathBuf,
        /// what it is instead (`FIFO`, `directory`, …)
        kind: &'static str,
    },
    /// the file, or `dir` above it, is another user's or writable by others
    #[error("{}: {}owned by {}, mode {mode:04o}{}: refused (only files of this user, uid {me}, or root that no one else can write are read)",
        path.display(),
        dir.as_ref().map(|d| format!("directory {} above it is ", d.display())).unwrap_or_default(),
        user_name(*owner),
        if *writable { ", writable by other users" } else { "" })]
    Untrusted {
        /// the file
        path: PathBuf,
        /// the directory at fault (`None`: the file itself)
        dir: Option<PathBuf>,
        /// the owner's uid (of `dir` when given, else of the file)
        owner: u32,
        /// its permission bits
        mode: u32,
        /// group or others may write it
        writable: bool,
        /// this process's effective uid
        me: u32,
    },
}

/// This process's effective user id.
pub fn euid() -> u32 {
    // SAFETY: geteuid cannot fail and touches no memory
    unsafe { libc::geteuid() }
}

/// `uid N (name)` from `/etc/passwd`, or `uid N`.
fn user_name(uid: u32) -> String {
    let name = crate::check::read_small("/etc/passwd".as_ref(), 1 << 20).and_then(|text| {
        text.lines().find_map(|l| {
            let mut f = l.split(':');
            let name = f.next()?;
            let id = f.nth(1)?.parse::<u32>().ok()?;
            (id == uid).then(|| name.to_string())
        })
    });
    match name {
        Some(n) => format!("uid {uid} ({n})"),
        None => format!("uid {uid}"),
    }
}

fn kind_of(meta: &Metadata) -> &'static str {
    use std::os::unix::fs::FileTypeExt;
    let t = meta.file_type();
    if t.is_dir() {
        "directory"
    } else if t.is_fifo() {
        "FIFO"
    } else if t.is_socket() {
        "socket"
    } else if t.is_block_device() || t.is_char_device() {
        "device"
    } else {
        "special file"
    }
}

/// The owner and mode of `meta` are this user's or root's and writable by
/// no one else (`sticky_root_ok`: a root-owned sticky directory passes).
fn owner_mode(
    path: &Path,
    dir: Option<&Path>,
    meta: &Metadata,
    sticky_root_ok: bool,
) -> Result<(), TrustError> {
    let me = euid();
    let owner = meta.uid();
    let mode = meta.mode() & 0o7777;
    let writable = mode & 0o022 != 0;
    let sticky_root = sticky_root_ok && owner == 0 && mode & 0o1000 != 0;
    if (owner != me && owner != 0) || (writable && !sticky_root) {
        return Err(TrustError::Untrusted {
            path: path.to_path_buf(),
            dir: dir.map(Path::to_path_buf),
            owner,
            mode,
            writable,
            me,
        });
    }
    Ok(())
}

/// `path` made absolute (against the current directory) without resolving links.
fn absolute(path: &Path) -> PathBuf {
    if path.is_absolute() {
        return path.to_path_buf();
    }
    std::env::current_dir()
        .map(|d| d.join(path))
        .unwrap_or_else(|_| path.to_path_buf())
}

/// Every directory above `file` (`file` absolute), nearest first.
fn directories(file: &Path) -> Vec<PathBuf> {
    // lexical: `a/../b` names `b`'s parent as the kernel resolves it only
    // after `a`, which is checked as well
    let mut out: Vec<PathBuf> = Vec::new();
    let mut at = PathBuf::new();
    for c in file.components() {
        at.push(c);
        if matches!(c, Component::ParentDir) {
            out.push(at.clone());
        }
    }
    out.extend(file.ancestors().skip(1).map(Path::to_path_buf));
    out.sort();
    out.dedup();
    out.reverse();
    out
}

/// The directories above `path`: of the path as given and of the path
/// with its links resolved.
fn check_directories(path: &Path) -> Result<(), TrustError> {
    let mut dirs = directories(&absolute(path));
    if let Ok(real) = std::fs::canonicalize(path) {
        dirs.extend(directories(&real));
    }
    for d in dirs {
        let meta = match std::fs::metadata(&d) {
            Ok(m) => m,
            // a component that is not there is the open's error to report
            Err(_) => continue,
        };
        owner_mode(path, Some(&d), &meta, true)?;
    }
    Ok(())
}

/// `path` may be read: a regular file of this user or root that no one
/// else can write, in directories no one else can write (see the module).
pub fn check_file(path: &Path) -> Result<(), TrustError> {
    open_trusted(path).map(drop)
}

/// `path` opened for reading once it passed [`check_file`]'s rule: opened
/// without blocking (a FIFO with no writer does not hang) and judged by the
/// open file's own status, so that what is read is what was checked.
pub fn open_trusted(path: &Path) -> Result<File, TrustError> {
    let io = |source| TrustError::Io {
        path: path.to_path_buf(),
        source,
    };
    check_directories(path)?;
    let file = OpenOptions::new()
        .read(true)
        .custom_flags(libc::O_NONBLOCK)
        .open(path)
        .map_err(io)?;
    let meta = file.metadata().map_err(io)?;
    if !meta.is_file() {
        return Err(TrustError::NotRegular {
            path: path.to_path_buf(),
            kind: kind_of(&meta),
        });
    }
    owner_mode(path, None, &meta, false)?;
    Ok(file)
}

#[cfg(test)]
mod tests {
    use super::*;
    use std::os::unix::fs::PermissionsExt;

    fn scratch(name: &str) -> PathBuf {
        let d =
            std::env::temp_dir().join(format!("phri-config-trust-{}-{name}", std::process::id()));
        let _ = std::fs::remove_dir_all(&d);
        std::fs::create_dir_all(&d).unwrap();
        std::fs::set_permissions(&d, std::fs::Permissions::from_mode(0o755)).unwrap();
        d
    }

    #[test]
    fn a_file_of_ours_in_our_directories_is_read() {
        let d = scratch("ok");
        let f = d.join("phri.toml");
        std::fs::write(&f, "").unwrap();
        std::fs::set_permissions(&f, std::fs::Permissions::from_mode(0o644)).unwrap();
        check_file(&f).unwrap();
        // the built-in deploy directory
        check_file(&Path::new(crate::DEFAULT_DEPLOY_DIR).join("phri.toml")).unwrap();
        let _ = std::fs::remove_dir_all(&d);
    }

    #[test]
    fn writable_files_and_directories_fifos_and_others_files_are_refused() {
        let d = scratch("bad");
        let f = d.join("robot.toml");
        std::fs::write(&f, "").unwrap();
        std::fs::set_permissions(&f, std::fs::Permissions::from_mode(0o666)).unwrap();
        let e = check_file(&f).unwrap_err().to_string();
        assert!(
            e.starts_with(&format!("{}: owned by uid {}", f.display(), euid()))
                && e.contains("mode 0666, writable by other users: refused"),
            "{e}"
        );
        assert_eq!(e.lines().count(), 1);
        std::fs::set_permissions(&f, std::fs::Permissions::from_mode(0o620)).unwrap();
        assert!(check_file(&f).is_err(), "group-writable");
        std::fs::set_permissions(&f, std::fs::Permissions::from_mode(0o644)).unwrap();
        // a directory above it that others can write (no sticky bit)
        std::fs::set_permissions(&d, std::fs::Permissions::from_mode(0o777)).unwrap();
        let e = check_file(&f).unwrap_err().to_string();
        assert!(
            e.contains(&format!("directory {} above it is owned", d.display()))
                && e.contains("mode 0777"),
            "{e}"
        );
        // sticky and writable by all passes only when root owns it (/tmp)
        std::fs::set_permissions(&d, std::fs::Permissions::from_mode(0o1777)).unwrap();
        if euid() != 0 {
            check_file(&f).unwrap_err();
        }
        std::fs::set_permissions(&d, std::fs::Permissions::from_mode(0o755)).unwrap();
        // a FIFO is refused at once, not waited on
        let fifo = d.join("fifo.toml");
        let c = std::ffi::CString::new(fifo.display().to_string()).unwrap();
        // SAFETY: a valid C string
        assert_eq!(unsafe { libc::mkfifo(c.as_ptr(), 0o600) }, 0);
        let e = check_file(&fifo).unwrap_err().to_string();
        assert!(e.contains("is a FIFO, not a regular file"), "{e}");
        // another user's file (root can make one)
        if euid() == 0 {
            std::os::unix::fs::chown(&f, Some(65534), Some(65534)).unwrap();
            let e = check_file(&f).unwrap_err().to_string();
            assert!(e.contains("owned by uid 65534"), "{e}");
        }
        let _ = std::fs::remove_dir_all(&d);
    }
}
