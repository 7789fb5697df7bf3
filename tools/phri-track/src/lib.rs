//! `phri-track`: the model-free person tracker of `phri-people` over recorded
//! depth frames. Frames are tracked in the order given (a directory: its files
//! in name order, notes `*.md` and `*.txt` and hidden files skipped) as a
//! 30 Hz sequence, or each on its own with `--independent`. Per frame, with
//! `--json`, one line
//! `{"file": …, "ms": …, "people": [{"id": …, "joints": {"head": [x, y, z], …}, "confidence": {"head": …, …}}]}`
//! in metres in the camera's optical frame (x right, y down, z forward), the
//! 15 joints in snake case, a joint not found left out; without it a readable
//! table. A file that cannot be read or has the wrong size is one line on
//! stderr naming it; the rest are tracked. At the end (stderr) the median and
//! p99 time per frame. Exit status 1 only when no frame could be tracked
//! (2 for a bad command line).

use std::io::Write;
use std::path::{Path, PathBuf};
use std::time::Instant;

use clap::{Parser, ValueEnum};
use phri_people::{Intrinsics, Person, Tracker, TrackerConfig, JOINT_NAMES, MAX_PEOPLE};

/// Depth file formats.
#[derive(Debug, Clone, Copy, PartialEq, Eq, ValueEnum)]
pub enum Format {
    /// headerless little-endian unsigned 16-bit, row-major, `width × height`
    Raw16,
    /// 16-bit grayscale PNG
    Png16,
}

/// The command line.
#[derive(Debug, Clone, Parser)]
#[command(
    name = "phri-track",
    version,
    about = "Track people (15-joint skeletons, stable ids) in recorded depth frames, with no learned model"
)]
pub struct Args {
    /// depth frames, or directories of them (tracked in name order)
    #[arg(required = true)]
    pub inputs: Vec<PathBuf>,
    /// the files' format
    #[arg(long, value_enum)]
    pub format: Format,
    /// the depth camera's intrinsics in pixels: FX,FY,CX,CY
    #[arg(long, value_parser = parse_intrinsics)]
    pub intrinsics: [f64; 4],
    /// metres per depth unit
    #[arg(long, default_value_t = 0.001)]
    pub depth_scale_m: f64,
    /// frame width \[px\]
    #[arg(long, default_value_t = 640)]
    pub width: u32,
    /// frame height \[px\]
    #[arg(long, default_value_t = 480)]
    pub height: u32,
    /// track each frame on its own (no ids or smoothing across frames)
    #[arg(long)]
    pub independent: bool,
    /// one JSON line per frame instead of a table
    #[arg(long)]
    pub json: bool,
}

fn parse_intrinsics(s: &str) -> Result<[f64; 4], String> {
    let v: Vec<f64> = s
        .split(',')
        .map(|x| x.trim().parse::<f64>().map_err(|e| format!("{x:?}: {e}")))
        .collect::<Result<_, _>>()?;
    match v[..] {
        [fx, fy, cx, cy] => Ok([fx, fy, cx, cy]),
        _ => Err(format!("expected FX,FY,CX,CY (4 numbers), got {}", v.len())),
    }
}

/// The files to track, in order, and one message per input that is not one.
pub fn list_inputs(inputs: &[PathBuf]) -> (Vec<PathBuf>, Vec<String>) {
    let mut files = Vec::new();
    let mut bad = Vec::new();
    for input in inputs {
        if input.is_dir() {
            match std::fs::read_dir(input) {
                Ok(entries) => {
                    let mut inside: Vec<PathBuf> = entries
                        .filter_map(|e| e.ok().map(|e| e.path()))
                        .filter(|p| !is_note(p))
                        .collect();
                    inside.sort();
                    files.extend(inside);
                }
                Err(e) => bad.push(format!("{}: cannot list: {e}", input.display())),
            }
        } else if input.exists() {
            files.push(input.clone());
        } else {
            bad.push(format!("{}: no such file or directory", input.display()));
        }
    }
    (files, bad)
}

/// Notes and hidden files in a directory of frames.
fn is_note(p: &Path) -> bool {
    let name = p
        .file_name()
        .map(|n| n.to_string_lossy().to_lowercase())
        .unwrap_or_default();
    name.starts_with('.') || name.ends_with(".md") || name.ends_with(".txt")
}

/// Reads one frame as raw depth units (`raw16`: as stored, `png16`: millimetres).
pub fn load_frame(
    path: &Path,
    format: Format,
    width: u32,
    height: u32,
    scale_m: f64,
) -> Result<Vec<u16>, String> {
    let expected = width as usize * height as usize;
    match format {
        Format::Raw16 => {
            if path.is_dir() {
                return Err(format!("{}: a directory, not a frame", path.display()));
            }
            let bytes =
                std::fs::read(path).map_err(|e| format!("{}: cannot read: {e}", path.display()))?;
            if bytes.len() != expected * 2 {
                return Err(format!(
                    "{}: {} bytes, a {width}x{height} raw16 frame has {}",
                    path.display(),
                    bytes.len(),
                    expected * 2
                ));
            }
            Ok(bytes
                .chunks_exact(2)
                .map(|b| u16::from_le_bytes([b[0], b[1]]))
                .collect())
        }
        Format::Png16 => {
            phri_depth::read_depth_png(path, width, height, scale_m).map_err(|e| e.to_string())
        }
    }
}

/// One frame's JSON line (without the newline).
pub fn json_line(file: &str, ms: f64, people: &[Person]) -> String {
    let mut s = String::with_capacity(256 + 700 * people.len());
    s.push_str("{\"file\":");
    s.push_str(&serde_json::to_string(file).unwrap_or_else(|_| "\"?\"".into()));
    s.push_str(&format!(",\"ms\":{},\"people\":[", round(ms, 3)));
    for (k, p) in people.iter().enumerate() {
        if k > 0 {
            s.push(',');
        }
        s.push_str(&format!("{{\"id\":{},\"joints\":{{", p.id));
        let mut first = true;
        for (j, name) in JOINT_NAMES.iter().enumerate() {
            if p.confidence[j] > 0.0 {
                let [x, y, z] = p.joints[j];
                if !first {
                    s.push(',');
                }
                first = false;
                s.push_str(&format!(
                    "\"{name}\":[{},{},{}]",
                    round(x, 4),
                    round(y, 4),
                    round(z, 4)
                ));
            }
        }
        s.push_str("},\"confidence\":{");
        let mut first = true;
        for (j, name) in JOINT_NAMES.iter().enumerate() {
            if p.confidence[j] > 0.0 {
                if !first {
                    s.push(',');
                }
                first = false;
                s.push_str(&format!("\"{name}\":{}", round(p.confidence[j], 3)));
            }
        }
        s.push_str("}}");
    }
    s.push_str("]}");
    s
}

/// `x` rounded to `digits` decimals, as a finite JSON number.
fn round(x: f64, digits: i32) -> f64 {
    let k = 10f64.powi(digits);
    let r = (x * k).round() / k;
    if r.is_finite() {
        r
    } else {
        0.0
    }
}

/// One frame as readable lines: per person its id and the joints found.
pub fn table(file: &str, ms: f64, people: &[Person]) -> String {
    let mut s = format!("{file}  {ms:.2} ms  {} people\n", people.len());
    for p in people {
        s.push_str(&format!("  person {}\n", p.id));
        for (j, name) in JOINT_NAMES.iter().enumerate() {
            if p.confidence[j] > 0.0 {
                let [x, y, z] = p.joints[j];
                s.push_str(&format!(
                    "    {name:<15} x {x:>7.3}  y {y:>7.3}  z {z:>7.3} m  conf {:.2}\n",
                    p.confidence[j]
                ));
            }
        }
    }
    s
}

/// Percentile `q` of sorted times.
fn percentile(sorted: &[f64], q: f64) -> f64 {
    if sorted.is_empty() {
        return 0.0;
    }
    let i = ((sorted.len() as f64 - 1.0) * q).round() as usize;
    sorted[i.min(sorted.len() - 1)]
}

/// Runs the command; returns the exit status.
pub fn run(args: &Args, out: &mut dyn Write, err: &mut dyn Write) -> u8 {
    let [fx, fy, cx, cy] = args.intrinsics;
    let intrinsics = Intrinsics {
        width: args.width,
        height: args.height,
        fx,
        fy,
        cx,
        cy,
    };
    // png16 frames are read as millimetres
    let scale = match args.format {
        Format::Raw16 => args.depth_scale_m,
        Format::Png16 => 0.001,
    };
    let cfg = TrackerConfig {
        depth_scale_m: scale,
        ..TrackerConfig::default()
    };
    let mut tracker = match Tracker::new(intrinsics, cfg) {
        Ok(t) => t,
        Err(e) => {
            let _ = writeln!(err, "phri-track: {e}");
            return 2;
        }
    };
    let (files, bad) = list_inputs(&args.inputs);
    for b in &bad {
        let _ = writeln!(err, "{b}");
    }
    let mut people = [Person::default(); MAX_PEOPLE];
    let mut times = Vec::with_capacity(files.len());
    let mut first = true;
    for path in &files {
        let frame = match load_frame(
            path,
            args.format,
            args.width,
            args.height,
            args.depth_scale_m,
        ) {
            Ok(f) => f,
            Err(e) => {
                let _ = writeln!(err, "{e}");
                continue;
            }
        };
        if args.independent {
            tracker.reset();
        }
        let dt = if first || args.independent {
            0.0
        } else {
            1.0 / 30.0
        };
        let t0 = Instant::now();
        let n = match tracker.step(&frame, dt, &mut people) {
            Ok(n) => n,
            Err(e) => {
                let _ = writeln!(err, "{}: {e}", path.display());
                continue;
            }
        };
        let ms = t0.elapsed().as_secs_f64() * 1e3;
        first = false;
        times.push(ms);
        let name = path.display().to_string();
        let text = if args.json {
            json_line(&name, ms, &people[..n]) + "\n"
        } else {
            table(&name, ms, &people[..n])
        };
        if out.write_all(text.as_bytes()).is_err() {
            return 1;
        }
    }
    if times.is_empty() {
        let _ = writeln!(err, "phri-track: no frame could be tracked");
        return 1;
    }
    times.sort_by(f64::total_cmp);
    let _ = writeln!(
        err,
        "phri-track: {} frames, time per frame median {:.3} ms, p99 {:.3} ms",
        times.len(),
        percentile(&times, 0.5),
        percentile(&times, 0.99)
    );
    0
}

#[cfg(test)]
mod tests {
    use super::*;

    fn args(inputs: Vec<PathBuf>, json: bool) -> Args {
        Args {
            inputs,
            format: Format::Raw16,
            intrinsics: [580.0, 580.0, 320.0, 240.0],
            depth_scale_m: 0.001,
            width: 64,
            height: 48,
            independent: false,
            json,
        }
    }

    #[test]
    fn intrinsics_parse() {
        assert_eq!(
            parse_intrinsics("580,580,320,240").unwrap(),
            [580.0, 580.0, 320.0, 240.0]
        );
        assert!(parse_intrinsics("580,580,320").is_err());
        assert!(parse_intrinsics("a,b,c,d").is_err());
    }

    #[test]
    fn bad_files_are_one_line_each_and_the_rest_tracked() {
        let dir = std::env::temp_dir().join(format!("phri-track-test-{}", std::process::id()));
        std::fs::create_dir_all(&dir).unwrap();
        std::fs::write(dir.join("a.raw"), vec![0u8; 64 * 48 * 2]).unwrap();
        std::fs::write(dir.join("b.raw"), vec![0u8; 10]).unwrap();
        std::fs::write(dir.join("README.md"), b"notes").unwrap();
        let (mut out, mut err) = (Vec::new(), Vec::new());
        let code = run(
            &args(vec![dir.clone(), dir.join("missing")], true),
            &mut out,
            &mut err,
        );
        let out = String::from_utf8(out).unwrap();
        let err = String::from_utf8(err).unwrap();
        assert_eq!(code, 0, "{err}");
        assert_eq!(out.lines().count(), 1, "{out}");
        assert!(
            out.starts_with("{\"file\":") && out.contains("\"people\":[]"),
            "{out}"
        );
        assert!(
            err.contains("b.raw") && err.contains("missing") && !err.contains("README"),
            "{err}"
        );
        // nothing trackable: non-zero
        let (mut o, mut e) = (Vec::new(), Vec::new());
        assert_eq!(
            run(&args(vec![dir.join("b.raw")], false), &mut o, &mut e),
            1
        );
        std::fs::remove_dir_all(&dir).unwrap();
    }

    #[test]
    fn json_names_only_found_joints() {
        let mut p = Person {
            id: 3,
            ..Person::default()
        };
        p.confidence[0] = 1.0;
        p.joints[0] = [0.1, -0.2, 1.5];
        let line = json_line("f", 1.25, &[p]);
        let v: serde_json::Value = serde_json::from_str(&line).unwrap();
        assert_eq!(v["people"][0]["id"], 3);
        assert_eq!(v["people"][0]["joints"]["head"][2], 1.5);
        assert!(v["people"][0]["joints"].get("neck").is_none());
        assert_eq!(v["people"][0]["confidence"]["head"], 1.0);
    }
}
