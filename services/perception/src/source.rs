//! Where ingestion takes its frames from when not from the `camera/depth`
//! channel: a directory of 16-bit PNG depth images replayed in name order
//! ([`PngReplay`]), each stamped as a frame of the configured camera.

use std::path::{Path, PathBuf};

use phri_config::{CameraConfig, IngestConfig, Invalid};
use phri_depth::{CameraPose, DepthPngError, Intrinsics};
use phri_ipc::{FrameHeader, Zeroed};

use crate::camera::fill_camera_header;

/// Why a PNG directory cannot be replayed.
#[derive(Debug, thiserror::Error)]
pub enum SourceError {
    #[error(transparent)]
    Config(#[from] Invalid),
    #[error("perception.png_dir {}: {source}", dir.display())]
    Dir {
        dir: PathBuf,
        source: std::io::Error,
    },
    #[error("perception.png_dir {}: no .png file", dir.display())]
    Empty { dir: PathBuf },
}

/// A directory of depth PNGs replayed in name order at `[perception]
/// png_rate_hz`, as frames of the camera of `[camera]` (its intrinsics give
/// the expected image size, its pose the frame's pose).
#[derive(Debug)]
pub struct PngReplay {
    files: Vec<PathBuf>,
    next: usize,
    looping: bool,
    depth_scale_m: f64,
    period_ns: u64,
    intrinsics: Intrinsics,
    pose: CameraPose,
    seq: u64,
}

impl PngReplay {
    /// The `.png` files (any case) of `[perception] png_dir`, resolved
    /// against `config_file` ([`phri_config::resolve`]), sorted by name.
    pub fn open(
        cfg: &IngestConfig,
        camera: &CameraConfig,
        config_file: &Path,
    ) -> Result<PngReplay, SourceError> {
        cfg.validate()?;
        let dir = phri_config::resolve(config_file, &cfg.png_dir);
        let mut files: Vec<PathBuf> = std::fs::read_dir(&dir)
            .map_err(|source| SourceError::Dir {
                dir: dir.clone(),
                source,
            })?
            .filter_map(|e| e.ok().map(|e| e.path()))
            .filter(|p| p.extension().is_some_and(|x| x.eq_ignore_ascii_case("png")))
            .collect();
        files.sort();
        if files.is_empty() {
            return Err(SourceError::Empty { dir });
        }
        Self::from_files(files, cfg, camera)
    }

    /// Replay `files` in the order given (`cfg` validated here: the rate is
    /// at most 1000 Hz).
    pub fn from_files(
        files: Vec<PathBuf>,
        cfg: &IngestConfig,
        camera: &CameraConfig,
    ) -> Result<PngReplay, SourceError> {
        cfg.validate()?;
        Ok(PngReplay {
            files,
            next: 0,
            looping: cfg.png_loop,
            depth_scale_m: cfg.png_depth_scale,
            period_ns: (1e9 / cfg.png_rate_hz) as u64,
            intrinsics: camera.intrinsics,
            pose: camera.pose()?,
            seq: 0,
        })
    }

    /// Replay period [ns].
    pub fn period_ns(&self) -> u64 {
        self.period_ns
    }

    pub fn files(&self) -> &[PathBuf] {
        &self.files
    }

    /// The next file: in name order, starting over at the end when looping;
    /// `None` once the directory is done otherwise.
    pub fn next_file(&mut self) -> Option<&Path> {
        if self.next >= self.files.len() {
            if !self.looping || self.files.is_empty() {
                return None;
            }
            self.next = 0;
        }
        self.next += 1;
        Some(&self.files[self.next - 1])
    }

    /// Read the next file ([`PngReplay::next_file`]) as a frame: its depths
    /// [mm] and `header` (the next frame number, the camera's intrinsics and
    /// pose, capture at `capture_ns` [ns, robot clock] and `capture_wall_ns`
    /// [ns, CLOCK_MONOTONIC]). A file that cannot be read is an error and
    /// takes no frame number; the replay goes on with the next file. What a
    /// file may cost is bounded before it is read
    /// ([`phri_depth::read_depth_png`]: size, then header, then data).
    pub fn next_frame(
        &mut self,
        capture_ns: u64,
        capture_wall_ns: u64,
        header: &mut FrameHeader,
    ) -> Option<Result<Vec<u16>, DepthPngError>> {
        let k = self.intrinsics;
        let scale = self.depth_scale_m;
        let path = self.next_file()?;
        let depths = match phri_depth::read_depth_png(path, k.width, k.height, scale) {
            Ok(d) => d,
            Err(e) => return Some(Err(e)),
        };
        self.seq += 1;
        *header = FrameHeader::zeroed();
        fill_camera_header(header, self.seq, &k, &self.pose);
        header.capture_ns = capture_ns;
        header.capture_wall_ns = capture_wall_ns;
        Some(Ok(depths))
    }
}

/// The replay's schedule: a tick every `period_ns` [ns, CLOCK_MONOTONIC],
/// anchored at the start. A tick handled late never makes the next ones run
/// back to back: the ticks that passed meanwhile are dropped (counted), and
/// the next tick waits at least as long as the late one worked, so that the
/// replay takes at most half the CPU whatever its rate and its files cost.
#[derive(Clone, Debug)]
pub struct Ticks {
    period_ns: u64,
    next_ns: u64,
    dropped: u64,
}

impl Ticks {
    /// Ticks every `period_ns` (at least 1 ns), the first at `start_ns + period_ns`.
    pub fn new(start_ns: u64, period_ns: u64) -> Ticks {
        let period_ns = period_ns.max(1);
        Ticks {
            period_ns,
            next_ns: start_ns.saturating_add(period_ns),
            dropped: 0,
        }
    }

    /// When the next tick is due [ns]: sleep until then.
    pub fn deadline_ns(&self) -> u64 {
        self.next_ns
    }

    /// The tick due at [`Ticks::deadline_ns`] began its work at `woke_ns`
    /// and ended it at `done_ns`: schedule the next one. On time, that is
    /// one period later; otherwise the first tick of the schedule no earlier
    /// than `done_ns + (done_ns − woke_ns)`, the ones before it dropped.
    /// Returns the new deadline.
    pub fn done(&mut self, woke_ns: u64, done_ns: u64) -> u64 {
        let earliest = done_ns.saturating_add(done_ns.saturating_sub(woke_ns));
        let mut next = self.next_ns.saturating_add(self.period_ns);
        if next < earliest {
            let behind = (earliest - next).div_ceil(self.period_ns);
            self.dropped += behind;
            next = next.saturating_add(behind.saturating_mul(self.period_ns));
        }
        self.next_ns = next;
        next
    }

    /// Ticks dropped so far.
    pub fn dropped(&self) -> u64 {
        self.dropped
    }
}

/// A repeated error logged at most once per `interval_ns`, with how many
/// occurred since the last line (a bad file replayed at 30 Hz is one line a
/// second, not thirty).
#[derive(Clone, Debug)]
pub struct RateLimited {
    interval_ns: u64,
    next_line_ns: Option<u64>,
    count: u64,
}

impl RateLimited {
    /// Once per second.
    pub const SECOND_NS: u64 = 1_000_000_000;

    pub fn new(interval_ns: u64) -> RateLimited {
        RateLimited {
            interval_ns,
            next_line_ns: None,
            count: 0,
        }
    }

    /// One more occurrence at `now_ns` [ns]: `Some(n)` when a line is due, `n`
    /// the occurrences it reports (this one and the ones not logged before it).
    pub fn hit(&mut self, now_ns: u64) -> Option<u64> {
        self.count += 1;
        if self.next_line_ns.is_some_and(|t| now_ns < t) {
            return None;
        }
        self.next_line_ns = Some(now_ns.saturating_add(self.interval_ns));
        let n = self.count;
        self.count = 0;
        Some(n)
    }
}
