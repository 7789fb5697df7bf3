//! The run directory and the files in it are private to the user who runs
//! the cell: nothing another local user can write is ever read.
//!
//! - The supervisor creates its run directory itself with mode 0700
//!   ([`create_private_dir`]); an existing one is used only if it is a real
//!   directory (not a symbolic link) owned by this user and writable by no one
//!   else ([`check_private_dir`]).
//! - State files are written atomically and owner-only ([`write_private`]) and
//!   read only through [`read_trusted`]: no symbolic link, a regular file
//!   owned by this user, writable by no one else, no larger than a bound.
//! - A configuration file given to a service must be owned by this user or
//!   root and writable by no one else, in directories no one else can write
//!   (`phri_config::trust`, which services apply; [`check_trusted_file`]
//!   checks the file alone).
//!
//! The default run directory ([`default_run_dir`]) is under the user's
//! runtime directory (`$XDG_RUNTIME_DIR`, else `/run/user/<uid>`), or, where
//! there is none, under `<tmp>/phri-<uid>/` (created 0700 and checked like
//! the run directory itself).

use std::fs::{File, OpenOptions};
use std::io::{Read, Write};
use std::os::unix::fs::{DirBuilderExt, MetadataExt, OpenOptionsExt, PermissionsExt};
use std::path::{Path, PathBuf};

/// Why a path is not trusted, naming it.
#[derive(Debug, thiserror::Error)]
pub enum TrustError {
    /// the path could not be examined, created, read or written
    #[error("{}: {source}", path.display())]
    Io {
        /// the path
        path: PathBuf,
        /// the system's error
        source: std::io::Error,
    },
    /// the path is a symbolic link
    #[error("{}: is a symbolic link (refused: it could point anywhere)", .0.display())]
    Symlink(PathBuf),
    /// the path is not the kind of file expected
    #[error("{}: not a {expected}", path.display())]
    Kind {
        /// the path
        path: PathBuf,
        /// what it should be (`directory`, `regular file`)
        expected: &'static str,
    },
    /// the path is owned by another user
    #[error("{}: owned by uid {owner}, not by this user (uid {me}): refused", path.display())]
    Owner {
        /// the path
        path: PathBuf,
        /// its owner's uid
        owner: u32,
        /// this process's effective uid
        me: u32,
    },
    /// the path is writable by its group or by other users
    #[error("{}: writable by other users (mode {mode:o}): refused", path.display())]
    Writable {
        /// the path
        path: PathBuf,
        /// its permission bits
        mode: u32,
    },
    /// the state file is larger than the bound its reader gives
    #[error("{}: {size} bytes, more than the {max} a state file may have", path.display())]
    TooLarge {
        /// the path
        path: PathBuf,
        /// its size \[bytes\]
        size: u64,
        /// the bound \[bytes\]
        max: u64,
    },
}

fn io(path: &Path) -> impl FnOnce(std::io::Error) -> TrustError + '_ {
    move |source| TrustError::Io {
        path: path.to_path_buf(),
        source,
    }
}

/// This process's effective user id.
pub fn euid() -> u32 {
    // SAFETY: geteuid cannot fail
    unsafe { libc::geteuid() }
}

/// `meta` (of `path`, not followed) is owned by this user (or root, with
/// `root_ok`) and writable by no one else.
fn check_owner_mode(
    path: &Path,
    meta: &std::fs::Metadata,
    root_ok: bool,
) -> Result<(), TrustError> {
    let me = euid();
    if meta.uid() != me && !(root_ok && meta.uid() == 0) {
        return Err(TrustError::Owner {
            path: path.to_path_buf(),
            owner: meta.uid(),
            me,
        });
    }
    let mode = meta.permissions().mode() & 0o7777;
    if mode & 0o022 != 0 {
        return Err(TrustError::Writable {
            path: path.to_path_buf(),
            mode,
        });
    }
    Ok(())
}

/// `path` is a directory (not a symbolic link) owned by this user and
/// writable by no one else.
pub fn check_private_dir(path: &Path) -> Result<(), TrustError> {
    let meta = std::fs::symlink_metadata(path).map_err(io(path))?;
    if meta.file_type().is_symlink() {
        return Err(TrustError::Symlink(path.to_path_buf()));
    }
    if !meta.is_dir() {
        return Err(TrustError::Kind {
            path: path.to_path_buf(),
            expected: "directory",
        });
    }
    check_owner_mode(path, &meta, false)
}

/// Create `path` with mode 0700 if it does not exist (its parent must), then
/// check it ([`check_private_dir`]).
pub fn create_private_dir(path: &Path) -> Result<(), TrustError> {
    match std::fs::DirBuilder::new().mode(0o700).create(path) {
        Ok(()) => {}
        Err(e) if e.kind() == std::io::ErrorKind::AlreadyExists => {}
        Err(e) => return Err(io(path)(e)),
    }
    check_private_dir(path)
}

/// The default run directory of the cell with `prefix`: under the user's
/// runtime directory when it is a private directory, else under
/// `<tmp>/phri-<uid>` (created 0700 here and checked).
pub fn default_run_dir(prefix: &str) -> Result<PathBuf, TrustError> {
    let me = euid();
    let runtime = std::env::var_os("XDG_RUNTIME_DIR")
        .map(PathBuf::from)
        .filter(|d| d.is_absolute())
        .or_else(|| Some(PathBuf::from(format!("/run/user/{me}"))))
        .filter(|d| check_private_dir(d).is_ok());
    let base = match runtime {
        Some(d) => d.join("phri"),
        None => std::env::temp_dir().join(format!("phri-{me}")),
    };
    create_private_dir(&base)?;
    Ok(base.join(format!("run-{prefix}")))
}

/// The contents of state file `path`, if it is a regular file (not a symbolic
/// link) owned by this user, writable by no one else and at most `max_len`
/// bytes; `Ok(None)` when it does not exist.
pub fn read_trusted(path: &Path, max_len: u64) -> Result<Option<Vec<u8>>, TrustError> {
    let file = match OpenOptions::new()
        .read(true)
        .custom_flags(libc::O_NOFOLLOW | libc::O_NONBLOCK)
        .open(path)
    {
        Ok(f) => f,
        Err(e) if e.kind() == std::io::ErrorKind::NotFound => return Ok(None),
        Err(e) if e.raw_os_error() == Some(libc::ELOOP) => {
            return Err(TrustError::Symlink(path.to_path_buf()))
        }
        Err(e) => return Err(io(path)(e)),
    };
    let meta = file.metadata().map_err(io(path))?;
    if !meta.is_file() {
        return Err(TrustError::Kind {
            path: path.to_path_buf(),
            expected: "regular file",
        });
    }
    check_owner_mode(path, &meta, false)?;
    if meta.len() > max_len {
        return Err(TrustError::TooLarge {
            path: path.to_path_buf(),
            size: meta.len(),
            max: max_len,
        });
    }
    let mut out = Vec::with_capacity(meta.len() as usize);
    file.take(max_len + 1)
        .read_to_end(&mut out)
        .map_err(io(path))?;
    if out.len() as u64 > max_len {
        return Err(TrustError::TooLarge {
            path: path.to_path_buf(),
            size: out.len() as u64,
            max: max_len,
        });
    }
    Ok(Some(out))
}

/// Replace `path` atomically with `bytes`, owner-only (0600): written to a
/// fresh temporary file beside it (never following a link), then renamed.
pub fn write_private(path: &Path, bytes: &[u8]) -> Result<(), TrustError> {
    write_private_open(path, bytes).map(drop)
}

/// [`write_private`], keeping the file open for writing: a writer that
/// later overwrites it in place (`pwrite`) writes the very file it made,
/// whatever the path names by then.
pub fn write_private_open(path: &Path, bytes: &[u8]) -> Result<File, TrustError> {
    let name = path
        .file_name()
        .map(|n| n.to_string_lossy().into_owned())
        .unwrap_or_default();
    let tmp = path.with_file_name(format!(".{name}.{}.tmp", std::process::id()));
    let _ = std::fs::remove_file(&tmp);
    let mut f: File = OpenOptions::new()
        .write(true)
        .create_new(true)
        .mode(0o600)
        .custom_flags(libc::O_NOFOLLOW)
        .open(&tmp)
        .map_err(io(&tmp))?;
    f.write_all(bytes).map_err(io(&tmp))?;
    std::fs::rename(&tmp, path).map_err(io(path))?;
    Ok(f)
}

/// A file a service reads its settings from (a configuration file): a
/// regular file owned by this user or root and writable by no one else.
pub fn check_trusted_file(path: &Path) -> Result<(), TrustError> {
    let meta = std::fs::metadata(path).map_err(io(path))?;
    if !meta.is_file() {
        return Err(TrustError::Kind {
            path: path.to_path_buf(),
            expected: "regular file",
        });
    }
    check_owner_mode(path, &meta, true)
}

#[cfg(test)]
mod tests {
    use super::*;

    fn scratch(name: &str) -> PathBuf {
        let d = std::env::temp_dir().join(format!("phri-rundir-{}-{name}", std::process::id()));
        let _ = std::fs::remove_dir_all(&d);
        d
    }

    #[test]
    fn a_private_dir_is_created_0700_and_a_shared_one_refused() {
        let d = scratch("dir");
        create_private_dir(&d).unwrap();
        let mode = std::fs::metadata(&d).unwrap().permissions().mode() & 0o777;
        assert_eq!(mode, 0o700);
        // writable by others: refused, naming it
        std::fs::set_permissions(&d, std::fs::Permissions::from_mode(0o777)).unwrap();
        let e = create_private_dir(&d).unwrap_err().to_string();
        assert!(
            e.contains("writable by other users") && e.contains(&*d.to_string_lossy()),
            "{e}"
        );
        std::fs::set_permissions(&d, std::fs::Permissions::from_mode(0o700)).unwrap();
        // a symbolic link to a private directory is refused too
        let link = scratch("link");
        std::os::unix::fs::symlink(&d, &link).unwrap();
        assert!(matches!(
            check_private_dir(&link),
            Err(TrustError::Symlink(_))
        ));
        std::fs::remove_file(&link).unwrap();
        std::fs::remove_dir_all(&d).unwrap();
    }

    #[test]
    fn state_files_are_written_private_and_read_only_when_trusted() {
        let d = scratch("files");
        create_private_dir(&d).unwrap();
        let f = d.join("state");
        assert_eq!(read_trusted(&f, 16).unwrap(), None);
        write_private(&f, b"hello").unwrap();
        assert_eq!(
            std::fs::metadata(&f).unwrap().permissions().mode() & 0o777,
            0o600
        );
        assert_eq!(
            read_trusted(&f, 16).unwrap().as_deref(),
            Some(&b"hello"[..])
        );
        assert!(matches!(
            read_trusted(&f, 4),
            Err(TrustError::TooLarge { .. })
        ));
        std::fs::set_permissions(&f, std::fs::Permissions::from_mode(0o666)).unwrap();
        assert!(matches!(
            read_trusted(&f, 16),
            Err(TrustError::Writable { .. })
        ));
        let link = d.join("link");
        std::os::unix::fs::symlink(&f, &link).unwrap();
        assert!(matches!(
            read_trusted(&link, 16),
            Err(TrustError::Symlink(_))
        ));
        std::fs::remove_dir_all(&d).unwrap();
    }

    #[test]
    fn files_of_another_user_are_refused() {
        if euid() != 0 {
            // only root can give a file away; the mode checks above run for everyone
            let meta = std::fs::metadata("/").unwrap();
            assert_eq!(meta.uid(), 0);
            let e = check_private_dir(Path::new("/")).unwrap_err();
            assert!(matches!(e, TrustError::Owner { .. }), "{e}");
            return;
        }
        let d = scratch("other");
        create_private_dir(&d).unwrap();
        let f = d.join("state");
        write_private(&f, b"x").unwrap();
        // SAFETY: chown on a path we created
        let c = std::ffi::CString::new(f.to_string_lossy().as_bytes()).unwrap();
        assert_eq!(unsafe { libc::chown(c.as_ptr(), 65534, 65534) }, 0);
        assert!(matches!(
            read_trusted(&f, 16),
            Err(TrustError::Owner { owner: 65534, .. })
        ));
        let c = std::ffi::CString::new(d.to_string_lossy().as_bytes()).unwrap();
        assert_eq!(unsafe { libc::chown(c.as_ptr(), 65534, 65534) }, 0);
        assert!(matches!(
            check_private_dir(&d),
            Err(TrustError::Owner { .. })
        ));
        std::fs::remove_dir_all(&d).unwrap();
    }

    #[test]
    fn the_default_run_dir_is_private() {
        let d = default_run_dir("phri_test_").unwrap();
        check_private_dir(d.parent().unwrap()).unwrap();
        assert!(d.ends_with("run-phri_test_"));
    }
}
