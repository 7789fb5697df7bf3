//! Range checks shared by the sections' `validate`, each naming the key.

use std::io::Read;
use std::path::Path;

use crate::error::Invalid;

/// A configuration or scenario file larger than this is refused \[bytes\]
/// (the deployed ones are under 40 KiB): one read never takes all memory.
pub const MAX_FILE_BYTES: u64 = 1 << 20;

/// The text of `path`, at most `MAX_FILE_BYTES` of UTF-8 (read so, even
/// from a file whose size the file system does not report), once the file
/// passed [`crate::trust`]'s rule: a regular file of this user or root that
/// no one else can write, in directories no one else can write.
pub(crate) fn read_text(path: &Path) -> Result<String, crate::trust::TrustError> {
    let io = |source| crate::trust::TrustError::Io {
        path: path.to_path_buf(),
        source,
    };
    let mut bytes = Vec::new();
    crate::trust::open_trusted(path)?
        .take(MAX_FILE_BYTES + 1)
        .read_to_end(&mut bytes)
        .map_err(io)?;
    if bytes.len() as u64 > MAX_FILE_BYTES {
        return Err(io(std::io::Error::new(
            std::io::ErrorKind::InvalidData,
            format!("larger than {MAX_FILE_BYTES} bytes: not a configuration"),
        )));
    }
    String::from_utf8(bytes).map_err(|_| {
        io(std::io::Error::new(
            std::io::ErrorKind::InvalidData,
            "not UTF-8 text",
        ))
    })
}

/// The text of a system file (`/etc/passwd`), at most `max` bytes; `None`
/// when it cannot be read.
pub(crate) fn read_small(path: &Path, max: u64) -> Option<String> {
    let mut bytes = Vec::new();
    std::fs::File::open(path)
        .ok()?
        .take(max)
        .read_to_end(&mut bytes)
        .ok()?;
    String::from_utf8(bytes).ok()
}

/// `section.key` for errors.
pub(crate) fn key(section: &str, name: &str) -> String {
    format!("{section}.{name}")
}

/// finite and > 0
pub(crate) fn positive(section: &str, name: &str, v: f64) -> Result<(), Invalid> {
    if v.is_finite() && v > 0.0 {
        Ok(())
    } else {
        Err(Invalid::new(
            key(section, name),
            format!("{v} is not a positive number"),
        ))
    }
}

/// finite and ≥ 0
pub(crate) fn non_negative(section: &str, name: &str, v: f64) -> Result<(), Invalid> {
    if v.is_finite() && v >= 0.0 {
        Ok(())
    } else {
        Err(Invalid::new(
            key(section, name),
            format!("{v} is not a finite non-negative number"),
        ))
    }
}

/// finite and in `[lo, hi]`
pub(crate) fn within(section: &str, name: &str, v: f64, lo: f64, hi: f64) -> Result<(), Invalid> {
    if v.is_finite() && v >= lo && v <= hi {
        Ok(())
    } else {
        Err(Invalid::new(
            key(section, name),
            format!("{v} is not in [{lo}, {hi}]"),
        ))
    }
}

/// every component finite
pub(crate) fn finite(section: &str, name: &str, v: &[f64]) -> Result<(), Invalid> {
    match v.iter().find(|x| !x.is_finite()) {
        Some(x) => Err(Invalid::new(
            key(section, name),
            format!("{x} is not a finite number"),
        )),
        None => Ok(()),
    }
}
