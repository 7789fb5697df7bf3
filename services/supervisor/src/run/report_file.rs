//! `--report FILE`, opened (created if need be) before anything starts, so
//! that an unwritable place is refused at once. A file this run created is
//! removed again unless the report was written into it.

use std::fs::File;
use std::io::{Seek, Write};
use std::path::{Path, PathBuf};

use crate::SupervisorError;

/// The report's file, open for the run.
pub struct ReportFile {
    path: PathBuf,
    file: File,
    created: bool,
    written: bool,
}

impl ReportFile {
    /// Open `path` for writing (`None`: no report asked for).
    pub fn open(path: Option<&str>) -> Result<Option<ReportFile>, SupervisorError> {
        let Some(path) = path else { return Ok(None) };
        let report_err = |source| SupervisorError::Report {
            path: path.into(),
            source,
        };
        let created = !Path::new(path).exists();
        let file = std::fs::OpenOptions::new()
            .write(true)
            .create(true)
            .truncate(false)
            .open(path)
            .map_err(report_err)?;
        Ok(Some(ReportFile {
            path: path.into(),
            file,
            created,
            written: false,
        }))
    }

    /// Where it is.
    pub fn path(&self) -> &Path {
        &self.path
    }

    /// Replace the file's content with `json` and a newline.
    pub fn write(&mut self, json: &str) -> Result<(), SupervisorError> {
        let report_err = |source| SupervisorError::Report {
            path: self.path.clone(),
            source,
        };
        self.file.set_len(0).map_err(report_err)?;
        self.file.rewind().map_err(report_err)?;
        self.file
            .write_all(json.as_bytes())
            .and_then(|_| self.file.write_all(b"\n"))
            .map_err(report_err)?;
        self.written = true;
        Ok(())
    }
}

impl Drop for ReportFile {
    fn drop(&mut self) {
        if self.created && !self.written {
            let _ = std::fs::remove_file(&self.path);
        }
    }
}
