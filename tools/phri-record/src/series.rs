//! What `phri-plot` reads of a recording: the series its figures draw,
//! gathered message by message from `control/status`, `dynamics/residual`,
//! `sim/truth` and `collab/state` (JSON, as `phri-record` writes them).

use std::time::{Duration, Instant};

use phri_ipc::{
    residual_flags, BodyPart, COLLAB_STATE, CONTROL_STATUS, DYNAMICS_RESIDUAL, SIM_TRUTH,
};
use serde_json::Value;

use crate::progress::Progress;
use crate::{read_file, ReadError, METADATA_NAME};

/// Someone nearer than this to a control point counts as present \[m\] (ρ of eq. 16).
pub const NEAR_M: f64 = 0.4;

/// Every series of a recording's figures; times `t` \[s\] from the first
/// message read, positions \[m\] and forces \[N\] in the base frame.
#[derive(Clone, Debug)]
pub struct Series {
    /// end-effector x, y (`control/status` `ee`) and whether the person was
    /// then nearer than [`NEAR_M`] (`sim/truth` `min_distance`)
    pub ee: Vec<(f64, f64, bool)>,
    /// (t, `control/status` `min_distance`), the finite ones
    pub dist: Vec<(f64, f64)>,
    /// (t, ‖r‖ \[Nm\]) of `dynamics/residual`
    pub norm: Vec<(f64, f64)>,
    /// times at which the residual's collision flag rose
    pub rises: Vec<f64>,
    /// (t, end-effector x, y, z), one series per axis
    pub ee_t: [Vec<(f64, f64)>; 3],
    /// (t, collaborative hand's x, y, z) while collaborating, one series per axis
    pub hand_t: [Vec<(f64, f64)>; 3],
    /// (t, the collaboration's phase) at each change of phase, the first included
    pub phase_changes: Vec<(f64, String)>,
    /// (t, ‖F̂‖) of `collab/state` while collaborating
    pub f_est: Vec<(f64, f64)>,
    /// (t, ‖F‖) of the intended contacts of a hand (`sim/truth`) once collaborating
    pub f_true: Vec<(f64, f64)>,
    /// whether `collab/state` left `idle`
    pub collaborated: bool,
    /// whether the last residual flagged a collision
    prev_collision: bool,
    /// the newest true distance person ↔ arm [m] (infinite: no person)
    person_m: f64,
}

impl Default for Series {
    fn default() -> Series {
        Series {
            ee: Vec::new(),
            dist: Vec::new(),
            norm: Vec::new(),
            rises: Vec::new(),
            ee_t: Default::default(),
            hand_t: Default::default(),
            phase_changes: Vec::new(),
            f_est: Vec::new(),
            f_true: Vec::new(),
            collaborated: false,
            prev_collision: false,
            person_m: f64::INFINITY,
        }
    }
}

/// A number of a JSON object, NaN when missing.
fn num(v: &Value, k: &str) -> f64 {
    v.get(k).and_then(Value::as_f64).unwrap_or(f64::NAN)
}

impl Series {
    /// Whether the series read messages of `topic`.
    pub fn reads(topic: &str) -> bool {
        topic == CONTROL_STATUS.name
            || topic == DYNAMICS_RESIDUAL.name
            || topic == SIM_TRUTH.name
            || topic == COLLAB_STATE.name
    }

    /// Adds message `v` of `topic` (one [`Series::reads`]) logged at `t` \[s\].
    pub fn add(&mut self, topic: &str, t: f64, v: &Value) {
        if topic == COLLAB_STATE.name {
            self.collab_state(t, v);
        } else if topic == SIM_TRUTH.name {
            self.sim_truth(t, v);
        } else if topic == CONTROL_STATUS.name {
            self.control_status(t, v);
        } else {
            self.residual(t, v);
        }
    }

    /// The phase, and while collaborating the hand and the estimated force.
    fn collab_state(&mut self, t: f64, v: &Value) {
        let phase = v.get("phase").and_then(Value::as_str).unwrap_or("idle");
        if self.phase_changes.last().is_none_or(|(_, p)| p != phase) {
            self.phase_changes.push((t, phase.to_string()));
        }
        if phase == "idle" {
            return;
        }
        self.collaborated = true;
        if let Some(h) = v.get("hand").and_then(Value::as_array) {
            for (i, series) in self.hand_t.iter_mut().enumerate() {
                if let Some(x) = h.get(i).and_then(Value::as_f64) {
                    series.push((t, x));
                }
            }
        }
        let f = v["forces"][0]["force"].as_array().map(|f| {
            f.iter()
                .filter_map(Value::as_f64)
                .map(|x| x * x)
                .sum::<f64>()
                .sqrt()
        });
        if let Some(f) = f {
            self.f_est.push((t, f));
        }
    }

    /// The true distance, and once collaborating the hands' intended contact force.
    fn sim_truth(&mut self, t: f64, v: &Value) {
        self.person_m = num(v, "min_distance");
        if !self.collaborated {
            return;
        }
        let hands = [BodyPart::HandRight as i64, BodyPart::HandLeft as i64];
        let mut sum = [0.0; 3];
        for c in v["contacts"].as_array().into_iter().flatten() {
            let intended = c["intended"].as_bool().unwrap_or(false);
            let hand = c["human_part"].as_i64().is_some_and(|p| hands.contains(&p));
            if intended && hand {
                for (k, x) in c["force"].as_array().into_iter().flatten().enumerate() {
                    if k < 3 {
                        sum[k] += x.as_f64().unwrap_or(0.0);
                    }
                }
            }
        }
        let norm = (sum[0] * sum[0] + sum[1] * sum[1] + sum[2] * sum[2]).sqrt();
        self.f_true.push((t, norm));
    }

    /// The end effector's position and the minimum distance.
    fn control_status(&mut self, t: f64, v: &Value) {
        if let Some(p) = v.get("ee").and_then(Value::as_array) {
            for (i, series) in self.ee_t.iter_mut().enumerate() {
                if let Some(x) = p.get(i).and_then(Value::as_f64) {
                    series.push((t, x));
                }
            }
            let c = |i: usize| p.get(i).and_then(Value::as_f64).unwrap_or(f64::NAN);
            self.ee.push((c(0), c(1), self.person_m < NEAR_M));
        }
        let d = num(v, "min_distance");
        if d.is_finite() {
            self.dist.push((t, d));
        }
    }

    /// The residual's norm and the rises of its collision flag.
    fn residual(&mut self, t: f64, v: &Value) {
        self.norm.push((t, num(v, "norm")));
        let flags = v.get("flags").and_then(Value::as_u64).unwrap_or(0) as u32;
        let c = flags & residual_flags::COLLISION != 0;
        if c && !self.prev_collision {
            self.rises.push(t);
        }
        self.prev_collision = c;
    }
}

/// The collision norm threshold \[Nm\] from the metadata of the recording
/// `buf` (read from `file`), and its message count, each when recorded.
pub fn summary(buf: &[u8], file: &str) -> Result<(Option<f64>, Option<u64>), ReadError> {
    let mut threshold = None;
    let summary = mcap::Summary::read(buf).map_err(ReadError::mcap(file))?;
    let total = summary
        .as_ref()
        .and_then(|s| s.stats.as_ref())
        .map(|s| s.message_count);
    if let Some(summary) = summary {
        for idx in &summary.metadata_indexes {
            if idx.name == METADATA_NAME {
                let m = mcap::read::metadata(buf, idx).map_err(ReadError::mcap(file))?;
                threshold = m
                    .metadata
                    .get("collision_norm_threshold")
                    .and_then(|s| s.parse().ok());
            }
        }
    }
    Ok((threshold, total))
}

/// The series of the recording `buf` (read from `file`) and the number of
/// messages read; `progress` counts them (without a bar on the terminal,
/// one line on stderr each second).
pub fn read_series(
    buf: &[u8],
    file: &str,
    progress: &Progress,
) -> Result<(Series, u64), ReadError> {
    let mut series = Series::default();
    let mut t0: Option<u64> = None;
    let mut next_report = Instant::now() + Duration::from_secs(1);
    let mut n = 0u64;
    let stream = mcap::MessageStream::new(buf).map_err(ReadError::mcap(file))?;
    for m in stream {
        let m = m.map_err(ReadError::mcap(file))?;
        n += 1;
        progress.inc(1);
        if !progress.shown() && Instant::now() >= next_report {
            next_report += Duration::from_secs(1);
            eprintln!("phri-plot: {n} messages read");
        }
        let topic = m.channel.topic.as_str();
        if !Series::reads(topic) {
            continue;
        }
        let v: Value = serde_json::from_slice(&m.data).map_err(|source| ReadError::Json {
            path: file.to_string(),
            topic: topic.to_string(),
            sequence: m.sequence,
            source,
        })?;
        let t0 = *t0.get_or_insert(m.log_time);
        series.add(topic, (m.log_time as f64 - t0 as f64) * 1e-9, &v);
    }
    Ok((series, n))
}

/// Why `phri-plot` found nothing to draw, or could not read or write.
#[derive(Debug, thiserror::Error)]
pub enum PlotError {
    #[error(transparent)]
    Read(#[from] ReadError),
    /// a recording without the messages a figure needs
    #[error("{file}: no {what} messages")]
    NoMessages { file: String, what: String },
}

/// The end-effector x-y path \[m\] of the recording `file`'s `control/status`.
pub fn ee_path(file: &str) -> Result<Vec<(f64, f64)>, PlotError> {
    let buf = read_file(file)?;
    let mut out = Vec::new();
    for m in mcap::MessageStream::new(&buf).map_err(ReadError::mcap(file))? {
        let m = m.map_err(ReadError::mcap(file))?;
        if m.channel.topic != CONTROL_STATUS.name {
            continue;
        }
        let v: Value = serde_json::from_slice(&m.data).map_err(|source| ReadError::Json {
            path: file.to_string(),
            topic: CONTROL_STATUS.name.to_string(),
            sequence: m.sequence,
            source,
        })?;
        if let Some(p) = v.get("ee").and_then(Value::as_array) {
            let c = |i: usize| p.get(i).and_then(Value::as_f64).unwrap_or(f64::NAN);
            out.push((c(0), c(1)));
        }
    }
    if out.is_empty() {
        return Err(PlotError::NoMessages {
            file: file.to_string(),
            what: CONTROL_STATUS.name.to_string(),
        });
    }
    Ok(out)
}

#[cfg(test)]
mod tests {
    use super::*;
    use serde_json::json;

    #[test]
    fn colours_the_path_by_the_person_s_distance() {
        let mut s = Series::default();
        s.add(
            CONTROL_STATUS.name,
            0.0,
            &json!({"ee": [1.0, 2.0, 3.0], "min_distance": 0.5}),
        );
        s.add(SIM_TRUTH.name, 0.1, &json!({"min_distance": 0.3}));
        s.add(
            CONTROL_STATUS.name,
            0.2,
            &json!({"ee": [1.5, 2.5, 3.5], "min_distance": null}),
        );
        assert_eq!(s.ee, [(1.0, 2.0, false), (1.5, 2.5, true)]);
        assert_eq!(s.dist, [(0.0, 0.5)]);
        assert_eq!(s.ee_t[2], [(0.0, 3.0), (0.2, 3.5)]);
    }

    #[test]
    fn marks_where_the_collision_flag_rises() {
        let mut s = Series::default();
        let c = residual_flags::COLLISION;
        for (t, flags) in [(0.0, 0), (1.0, c), (2.0, c), (3.0, 0), (4.0, c)] {
            s.add(
                DYNAMICS_RESIDUAL.name,
                t,
                &json!({"norm": t, "flags": flags}),
            );
        }
        assert_eq!(s.rises, [1.0, 4.0]);
        assert_eq!(s.norm.len(), 5);
    }

    #[test]
    fn follows_the_collaboration_and_its_forces() {
        let mut s = Series::default();
        let hand = BodyPart::HandRight as i64;
        let truth = json!({"min_distance": 1.0, "contacts": [
            {"intended": true, "human_part": hand, "force": [3.0, 4.0, 0.0]},
            {"intended": false, "human_part": hand, "force": [10.0, 0.0, 0.0]}]});
        s.add(SIM_TRUTH.name, 0.0, &truth);
        s.add(COLLAB_STATE.name, 0.0, &json!({"phase": "idle"}));
        let state = json!({"phase": "approach", "hand": [0.1, 0.2, 0.3],
                           "forces": [{"force": [0.0, 6.0, 8.0]}]});
        s.add(COLLAB_STATE.name, 1.0, &state);
        s.add(COLLAB_STATE.name, 2.0, &state);
        s.add(SIM_TRUTH.name, 2.5, &truth);
        assert!(s.collaborated);
        assert_eq!(
            s.phase_changes,
            [(0.0, "idle".to_string()), (1.0, "approach".to_string())]
        );
        assert_eq!(s.hand_t[1], [(1.0, 0.2), (2.0, 0.2)]);
        assert_eq!(s.f_est, [(1.0, 10.0), (2.0, 10.0)]);
        // the true force only once collaborating, intended contacts only
        assert_eq!(s.f_true, [(2.5, 5.0)]);
    }
}
