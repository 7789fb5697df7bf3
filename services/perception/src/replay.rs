//! A replay camera (`[camera] source = "replay"`): a directory of recorded
//! depth frames played in name order at `[camera] rate_hz`, looping or once
//! (`replay_loop`), as frames of the configured camera (its intrinsics give
//! the frame size, its pose the frame's pose).
//!
//! A directory holds, in any mix:
//! - 16-bit grayscale PNGs (`*.png`, any case);
//! - headerless little-endian 16-bit raw frames (`*.raw`, `*.bin`, or no
//!   extension), exactly `width × height × 2` bytes;
//! - a fakenect recording: `INDEX.txt` names the files, of which the depth
//!   ones (`d-…`) are `P5 640 480 65535` PGMs of 11-bit disparity, turned
//!   into millimetres by the Kinect's conversion
//!   ([`phri_depth::kinect::Disparity`], as `phri-freenect` does).
//!
//! A sample `s` means `s · depth_scale_m` metres (PNG and raw); 0 is no
//! reading. Notes beside the frames (`*.md`, `*.txt`) and hidden files are
//! skipped; any other file is refused when the directory is opened, naming
//! it, and so is a frame whose size is wrong: a recording is checked whole
//! before its first frame plays. A file that cannot be read at its turn
//! (removed, changed since) is dropped and counted, never half-published.

use std::io::Read;
use std::path::{Path, PathBuf};

use phri_config::{CameraConfig, Invalid};
use phri_depth::{DepthPngError, Intrinsics};

/// Why a recording cannot be replayed.
#[derive(Debug, thiserror::Error)]
pub enum ReplayError {
    /// an invalid `[camera]` section
    #[error(transparent)]
    Config(#[from] Invalid),
    /// the directory could not be read
    #[error("camera.replay_dir {}: {source}", dir.display())]
    Dir {
        /// the directory (`camera.replay_dir`, resolved)
        dir: PathBuf,
        /// the system's error
        source: std::io::Error,
    },
    /// the directory holds no recorded frame
    #[error("camera.replay_dir {}: no recorded frame (16-bit PNG, raw or a fakenect INDEX.txt)", dir.display())]
    Empty {
        /// the directory (`camera.replay_dir`, resolved)
        dir: PathBuf,
    },
    /// a file that is no recorded frame of this camera
    #[error("camera.replay_dir: {}: {reason}", path.display())]
    NotAFrame {
        /// the file
        path: PathBuf,
        /// why it is refused
        reason: String,
    },
}

/// Why one frame could not be read at its turn.
#[derive(Debug, thiserror::Error)]
pub enum FrameReadError {
    /// a PNG that is not a depth frame of this camera, or could not be read
    #[error(transparent)]
    Png(#[from] DepthPngError),
    /// the file could not be read
    #[error("{}: {source}", path.display())]
    Io {
        /// the file
        path: PathBuf,
        /// the system's error
        source: std::io::Error,
    },
    /// the file is no frame of this camera (size, header, values)
    #[error("{}: {reason}", path.display())]
    Invalid {
        /// the file
        path: PathBuf,
        /// what is wrong with it
        reason: String,
    },
}

/// How a recorded frame is stored.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum FrameFormat {
    /// 16-bit grayscale PNG
    Png,
    /// headerless little-endian 16-bit
    Raw,
    /// fakenect's PGM of 11-bit disparity
    FakenectPgm,
}

/// The PGM header of a fakenect depth file at 640×480.
const FAKENECT_HEADER: &[u8] = b"P5 640 480 65535\n";

/// One recorded frame.
#[derive(Clone, Debug, PartialEq)]
pub struct FrameFile {
    /// the file
    pub path: PathBuf,
    /// how it is stored
    pub format: FrameFormat,
}

/// A recording being replayed.
#[derive(Debug)]
pub struct Replay {
    files: Vec<FrameFile>,
    next: usize,
    looping: bool,
    depth_scale_m: f64,
    period_ns: u64,
    intrinsics: Intrinsics,
    /// the raw bytes of the file being read (reused)
    bytes: Vec<u8>,
    /// the Kinect's disparity → millimetres (fakenect recordings)
    kinect: phri_depth::kinect::Disparity,
}

impl Replay {
    /// The recording of camera `cfg` (`replay_dir` resolved against
    /// `config_file`), every file checked.
    pub fn open(cfg: &CameraConfig, config_file: &Path) -> Result<Replay, ReplayError> {
        cfg.validate()?;
        let dir = phri_config::resolve(config_file, &cfg.replay_dir);
        let files = list(&dir, &cfg.intrinsics)?;
        Ok(Replay {
            files,
            next: 0,
            looping: cfg.replay_loop,
            depth_scale_m: cfg.depth_scale_m,
            period_ns: (1e9 / cfg.rate_hz) as u64,
            intrinsics: cfg.intrinsics,
            bytes: Vec::new(),
            kinect: phri_depth::kinect::Disparity::new(),
        })
    }

    /// Replay period \[ns\].
    pub fn period_ns(&self) -> u64 {
        self.period_ns
    }

    /// The frames in playing order.
    pub fn files(&self) -> &[FrameFile] {
        &self.files
    }

    /// The camera's intrinsics (the frames' size).
    pub fn intrinsics(&self) -> &Intrinsics {
        &self.intrinsics
    }

    /// Whether the recording is over (played once, not looping).
    pub fn done(&self) -> bool {
        !self.looping && self.next >= self.files.len()
    }

    /// Read the next frame into `out` (`width × height` depths \[mm\]); `None`
    /// once the recording is done. On an error `out` may hold part of a
    /// frame: the caller drops it.
    pub fn next_into(&mut self, out: &mut [u16]) -> Option<Result<(), FrameReadError>> {
        if self.next >= self.files.len() {
            if !self.looping {
                return None;
            }
            self.next = 0;
        }
        self.next += 1;
        let f = self.files[self.next - 1].clone();
        Some(self.read(&f, out))
    }

    fn read(&mut self, f: &FrameFile, out: &mut [u16]) -> Result<(), FrameReadError> {
        let k = self.intrinsics;
        let invalid = |reason: String| FrameReadError::Invalid {
            path: f.path.clone(),
            reason,
        };
        if out.len() != k.pixel_count() {
            return Err(invalid(format!(
                "a frame of {} pixels, the camera's is {}",
                out.len(),
                k.pixel_count()
            )));
        }
        match f.format {
            FrameFormat::Png => {
                let d = phri_depth::read_depth_png(&f.path, k.width, k.height, self.depth_scale_m)?;
                out.copy_from_slice(&d);
            }
            FrameFormat::Raw => {
                let n = k.pixel_count() * 2;
                read_exact_file(&f.path, n, &mut self.bytes)?;
                let scale_mm = self.depth_scale_m * 1000.0;
                for (o, b) in out.iter_mut().zip(self.bytes.chunks_exact(2)) {
                    *o = scaled_mm(u16::from_le_bytes([b[0], b[1]]), scale_mm);
                }
            }
            FrameFormat::FakenectPgm => {
                let n = FAKENECT_HEADER.len() + k.pixel_count() * 2;
                read_exact_file(&f.path, n, &mut self.bytes)?;
                if !self.bytes.starts_with(FAKENECT_HEADER) {
                    return Err(invalid(
                        "not a fakenect depth file (P5 640 480 65535)".into(),
                    ));
                }
                let data = &self.bytes[FAKENECT_HEADER.len()..];
                for (i, (o, b)) in out.iter_mut().zip(data.chunks_exact(2)).enumerate() {
                    let raw = u16::from_le_bytes([b[0], b[1]]);
                    if raw > phri_depth::kinect::RAW_NONE {
                        return Err(invalid(format!(
                            "pixel {i}: {raw} is not an 11-bit disparity"
                        )));
                    }
                    *o = self.kinect.raw_to_mm(raw);
                }
            }
        }
        Ok(())
    }
}

/// `v · scale_mm` millimetres, rounded; 0 and what 16 bits cannot hold stay
/// no reading.
fn scaled_mm(v: u16, scale_mm: f64) -> u16 {
    let mm = (f64::from(v) * scale_mm).round();
    if v == 0 || !(1.0..=65535.0).contains(&mm) {
        0
    } else {
        mm as u16
    }
}

/// Read exactly `n` bytes of `path` into `buf`: a file of another size is
/// refused before it is read whole.
fn read_exact_file(path: &Path, n: usize, buf: &mut Vec<u8>) -> Result<(), FrameReadError> {
    let io = |source| FrameReadError::Io {
        path: path.to_path_buf(),
        source,
    };
    let file = std::fs::File::open(path).map_err(io)?;
    let len = file.metadata().map_err(io)?.len();
    if len != n as u64 {
        return Err(FrameReadError::Invalid {
            path: path.to_path_buf(),
            reason: format!("{len} bytes, a frame of this camera is {n}"),
        });
    }
    buf.clear();
    buf.reserve(n);
    file.take(n as u64).read_to_end(buf).map_err(io)?;
    if buf.len() != n {
        return Err(FrameReadError::Invalid {
            path: path.to_path_buf(),
            reason: format!("truncated: {} of {n} bytes", buf.len()),
        });
    }
    Ok(())
}

/// The frames of `dir` in playing order, each checked against the camera's
/// size `k`: a fakenect recording when `INDEX.txt` is there, otherwise its
/// PNG and raw files in name order.
pub fn list(dir: &Path, k: &Intrinsics) -> Result<Vec<FrameFile>, ReplayError> {
    let dir_err = |source| ReplayError::Dir {
        dir: dir.to_path_buf(),
        source,
    };
    let index = dir.join("INDEX.txt");
    let files = if index.is_file() {
        fakenect_files(dir, &index, k)?
    } else {
        let mut paths: Vec<PathBuf> = std::fs::read_dir(dir)
            .map_err(dir_err)?
            .map(|e| e.map(|e| e.path()))
            .collect::<Result<_, _>>()
            .map_err(dir_err)?;
        paths.sort();
        let mut files = Vec::with_capacity(paths.len());
        for path in paths {
            if let Some(f) = classify(&path, k)? {
                files.push(f);
            }
        }
        files
    };
    if files.is_empty() {
        return Err(ReplayError::Empty {
            dir: dir.to_path_buf(),
        });
    }
    Ok(files)
}

/// What `path` is: a frame (checked), a note or hidden file (`None`), or
/// refused.
fn classify(path: &Path, k: &Intrinsics) -> Result<Option<FrameFile>, ReplayError> {
    let name = path.file_name().and_then(|n| n.to_str()).unwrap_or("");
    let not = |reason: String| ReplayError::NotAFrame {
        path: path.to_path_buf(),
        reason,
    };
    if name.starts_with('.') {
        return Ok(None);
    }
    let ext = path
        .extension()
        .and_then(|e| e.to_str())
        .map(str::to_ascii_lowercase);
    let format = match ext.as_deref() {
        Some("md" | "txt") => return Ok(None),
        Some("png") => FrameFormat::Png,
        None | Some("raw" | "bin") => FrameFormat::Raw,
        Some(other) => {
            return Err(not(format!(
                "not a recorded frame (.{other}): a replay directory holds 16-bit PNG, raw (.raw, .bin or no extension) or a fakenect recording"
            )))
        }
    };
    let meta = std::fs::metadata(path).map_err(|e| not(e.to_string()))?;
    if !meta.is_file() {
        return Err(not("not a regular file".into()));
    }
    match format {
        FrameFormat::Raw => {
            let n = k.pixel_count() as u64 * 2;
            if meta.len() != n {
                return Err(not(format!(
                    "{} bytes: a raw frame of {}×{} is {n} (16-bit little-endian)",
                    meta.len(),
                    k.width,
                    k.height
                )));
            }
        }
        _ => {
            let mut head = [0u8; phri_depth::png::HEADER_BYTES];
            let read = std::fs::File::open(path)
                .and_then(|mut f| f.read_exact(&mut head))
                .map_err(|e| not(format!("unreadable PNG header: {e}")));
            read?;
            phri_depth::png::check_header(path, &head, k.width, k.height)
                .map_err(|e| not(e.to_string()))?;
        }
    }
    Ok(Some(FrameFile {
        path: path.to_path_buf(),
        format,
    }))
}

/// The depth files a fakenect `INDEX.txt` lists, in its order.
fn fakenect_files(dir: &Path, index: &Path, k: &Intrinsics) -> Result<Vec<FrameFile>, ReplayError> {
    let not = |path: &Path, reason: String| ReplayError::NotAFrame {
        path: path.to_path_buf(),
        reason,
    };
    if (k.width, k.height) != (640, 480) {
        return Err(not(
            index,
            format!(
                "a fakenect recording is 640×480, the camera's intrinsics say {}×{}",
                k.width, k.height
            ),
        ));
    }
    let meta = std::fs::metadata(index).map_err(|e| not(index, e.to_string()))?;
    if meta.len() > 16 << 20 {
        return Err(not(index, "larger than 16 MiB: not an index".into()));
    }
    let text = std::fs::read_to_string(index).map_err(|e| not(index, e.to_string()))?;
    let n = (FAKENECT_HEADER.len() + k.pixel_count() * 2) as u64;
    let mut files = Vec::new();
    for line in text.lines().map(str::trim).filter(|l| l.starts_with("d-")) {
        if line.contains('/') || line.contains("..") {
            return Err(not(
                index,
                format!("'{line}' is not a file of the recording"),
            ));
        }
        let path = dir.join(line);
        let len = std::fs::metadata(&path)
            .map_err(|e| not(&path, e.to_string()))?
            .len();
        if len != n {
            return Err(not(
                &path,
                format!("{len} bytes, a fakenect depth file is {n}"),
            ));
        }
        files.push(FrameFile {
            path,
            format: FrameFormat::FakenectPgm,
        });
    }
    Ok(files)
}
