//! What a lock-step run produced: contact episodes from the simulator's
//! ground truth, the closest approach, time in protective stop and braked.

use phri_control::ControlCounters;
use phri_ipc::{residual_flags, ControlMode, Residual};
use phri_sim::{LinkOutput, Simulator};

/// One contact episode between the person and the arm.
#[derive(Clone, Debug, serde::Serialize)]
pub struct ContactEpisode {
    /// start and end, robot time \[s\]
    pub t_start_s: f64,
    pub t_end_s: f64,
    pub link: String,
    pub part: String,
    pub intended: bool,
    /// largest contact force \[N\]
    pub peak_force_n: f64,
    /// the controller's mode when it began
    pub mode: String,
}

/// What a run produced.
#[derive(Clone, Debug, Default, serde::Serialize)]
pub struct CellSummary {
    pub duration_s: f64,
    pub contacts: Vec<ContactEpisode>,
    pub unintended_contacts: usize,
    /// smallest true surface distance person ↔ arm \[m\]
    pub min_distance_m: f64,
    /// when it was smallest, robot time \[s\]
    pub min_distance_t_s: f64,
    pub waypoints: u64,
    pub detections: u64,
    pub frames: u64,
    /// time spent in protective stop \[s\]
    pub protective_stop_s: f64,
    /// time the robot spent with its brakes engaged \[s\]
    pub braked_s: f64,
    /// the residual's collision flag rose while the person touched nothing
    pub false_detections: u64,
    /// requests the wave recogniser made (`phri-gesture` on the simulated
    /// tracker's skeletons)
    pub gesture_requests: Vec<GestureRequest>,
    /// what the voice recogniser heard (`phri-voice` on the scenario's speech)
    pub voice: Vec<VoiceHeard>,
    /// every change of the controller's mode: (robot time \[s\], new mode)
    pub modes: Vec<(f64, String)>,
    /// ISO/TS 15066: every contact against its body region's force limit,
    /// as the multi-process report's section
    pub iso_ts_15066: phri_iso15066::Judged,
    /// speed and separation monitoring: time it bounded some control
    /// point's approach \[s\], and violations (`iso_ts_15066`'s, repeated)
    pub ssm_limited_s: f64,
    pub ssm_violations: u64,
    /// ... the violations judged against the standard's own protective
    /// separation distance (ISO 13855's human speed), as the report's
    /// `iso_ts_15066.ssm_violations_standard`
    pub ssm_violations_standard: u64,
    /// the hot standby (null without it)
    pub standby: Option<StandbySummary>,
    /// the control-barrier filter (`[avoidance] law = "cbf"`; null under the paper's law)
    pub barrier: Option<BarrierSummary>,
    /// the largest change of the applied torque of any joint from one
    /// period to the next, the brakes off in both \[Nm\] (the first command
    /// after the brakes not counted: gravity taken up at once)
    pub max_torque_step_nm: f64,
    /// ... its 99th percentile over the periods \[Nm\]
    pub torque_step_p99_nm: f64,
}

/// What the control-barrier filter did in a lock-step run (the controller in charge's).
#[derive(Clone, Debug, Default, PartialEq, serde::Serialize)]
pub struct BarrierSummary {
    /// periods in which some barrier bound the motion \[s\]
    pub braking_s: f64,
    /// periods in which some barrier could not be kept within the joints'
    /// bounds (its slack moved the point away as well as it could) \[s\]
    pub slack_s: f64,
    /// periods its solver failed (the reference braked to rest)
    pub failed_periods: u64,
    /// the most active-set changes of one solve
    pub max_iterations: u64,
}

/// The hot standby's figures in a lock-step run (the robot link's).
#[derive(Clone, Debug, Default, PartialEq, serde::Serialize)]
pub struct StandbySummary {
    pub takeovers: u64,
    /// the largest joint difference between a command taking over and the
    /// last one applied before \[Nm\]
    pub max_takeover_diff_nm: f64,
    /// the largest joint difference between the two controllers' answers
    /// to the same state \[Nm\]
    pub max_answer_diff_nm: f64,
    /// periods each slot's fresh command was applied
    pub periods_commanded: [u64; 2],
    /// periods both slots answered the same state
    pub both_answered: u64,
    pub missed_deadlines: u64,
}

/// One wave recognised in a run.
#[derive(Clone, Debug, serde::Serialize)]
pub struct GestureRequest {
    /// capture time of the frame that completed the wave, robot time \[s\]
    pub t_s: f64,
    /// capture time of the wave's first counted reversal, robot time \[s\]
    pub onset_s: f64,
    /// the waving hand
    pub part: String,
}

/// One utterance the voice recogniser heard.
#[derive(Clone, Debug, serde::Serialize)]
pub struct VoiceHeard {
    /// when the speech ended, robot time \[s\]
    pub t_s: f64,
    pub text: String,
    pub intent: String,
    pub score: f64,
    /// `accepted`, or why not (`hand_not_tracked`, `no_match`, `low_score`, ...)
    pub verdict: String,
}

/// Running account of a run.
pub(crate) struct Accounting {
    dt_s: f64,
    s: CellSummary,
    /// (collision object, body part, episode index) in contact now
    open: Vec<(usize, usize, usize)>,
    /// the residual's collision flag in the last period
    collision: bool,
    /// the controller in charge's count of the standard's S_p violations last seen
    standard_seen: u64,
    /// the torque applied in the last period, the brakes off (empty: braked)
    last_torque: Vec<f64>,
    /// each period's largest joint torque step \[Nm\]
    torque_steps: Vec<f64>,
}

impl Accounting {
    pub(crate) fn new(dt_s: f64) -> Accounting {
        Accounting {
            dt_s,
            s: CellSummary {
                min_distance_m: f64::INFINITY,
                ..Default::default()
            },
            open: Vec::new(),
            collision: false,
            standard_seen: 0,
            last_torque: Vec::new(),
            torque_steps: Vec::new(),
        }
    }

    /// The controller's speed and separation monitoring after a period
    /// ending at `t_ns` \[ns\].
    pub(crate) fn ssm(&mut self, enabled: bool, c: phri_control::resolve::SsmCounters, t_ns: u64) {
        let t = t_ns as f64 * 1e-9;
        self.s
            .iso_ts_15066
            .ssm_counts(enabled, c.limited_periods, c.violations, t, self.dt_s);
        // the controller in charge's count, added as it grows (a restarted
        // one counts from 0 again)
        let (now, seen) = (c.violations_standard, self.standard_seen);
        self.s.ssm_violations_standard += now - if now >= seen { seen } else { 0 };
        self.standard_seen = now;
    }

    pub(crate) fn frame(&mut self) {
        self.s.frames += 1;
    }

    pub(crate) fn mode(&mut self, mode: ControlMode, t_ns: u64) {
        if self.s.modes.last().is_none_or(|(_, m)| m != mode.name()) {
            self.s
                .modes
                .push((t_ns as f64 * 1e-9, mode.name().to_string()));
        }
    }

    pub(crate) fn gesture(&mut self, w: &phri_gesture::Wave) {
        self.s.gesture_requests.push(GestureRequest {
            t_s: w.detected_ns as f64 * 1e-9,
            onset_s: w.onset_ns as f64 * 1e-9,
            part: w.part.name().to_string(),
        });
    }

    pub(crate) fn voice(&mut self, u: &phri_ipc::Utterance) {
        self.s.voice.push(VoiceHeard {
            t_s: u.end_ns as f64 * 1e-9,
            text: phri_ipc::json::c_str(&u.text),
            intent: phri_ipc::VoiceIntent::name_of(u.intent).to_string(),
            score: u.score,
            verdict: phri_ipc::VoiceVerdict::name_of(u.verdict).to_string(),
        });
    }

    pub(crate) fn account(
        &mut self,
        sim: &Simulator,
        mode: ControlMode,
        link: &LinkOutput,
        residual: Option<&Residual>,
        t_ns: u64,
    ) {
        let t = sim.truth();
        let s = &mut self.s;
        let collision = residual.is_some_and(|r| r.flags & residual_flags::COLLISION != 0);
        if collision && !self.collision && t.contacts.is_empty() && !sim.has_external_force() {
            s.false_detections += 1;
        }
        self.collision = collision;
        let now_s = t_ns as f64 * 1e-9;
        s.duration_s += self.dt_s;
        if t.min_distance < s.min_distance_m {
            s.min_distance_m = t.min_distance;
            s.min_distance_t_s = now_s;
        }
        if mode == ControlMode::ProtectiveStop {
            s.protective_stop_s += self.dt_s;
        }
        if link.brake {
            s.braked_s += self.dt_s;
            self.last_torque.clear();
        } else {
            let tau = link.torque();
            if self.last_torque.len() == tau.len() {
                let step = tau
                    .iter()
                    .zip(&self.last_torque)
                    .map(|(a, b)| (a - b).abs())
                    .fold(0.0, f64::max);
                s.max_torque_step_nm = s.max_torque_step_nm.max(step);
                self.torque_steps.push(step);
            }
            self.last_torque.clear();
            self.last_torque.extend_from_slice(tau);
        }
        let mut still = Vec::with_capacity(t.contacts.len());
        for c in &t.contacts {
            let key = (c.collision, c.part as usize);
            let idx = match self.open.iter().find(|o| (o.0, o.1) == key) {
                Some(o) => o.2,
                None => {
                    s.contacts.push(ContactEpisode {
                        t_start_s: now_s,
                        t_end_s: now_s,
                        link: c.link(sim.model()).to_string(),
                        part: c.part.name().to_string(),
                        intended: c.intended,
                        peak_force_n: 0.0,
                        mode: mode.name().to_string(),
                    });
                    if !c.intended {
                        s.unintended_contacts += 1;
                    }
                    s.contacts.len() - 1
                }
            };
            let e = &mut s.contacts[idx];
            e.t_end_s = now_s;
            e.peak_force_n = e.peak_force_n.max(c.force.norm());
            still.push((key.0, key.1, idx));
        }
        self.open = still;
    }

    pub(crate) fn summary(&self, _sim: &Simulator, counters: &ControlCounters) -> CellSummary {
        let mut s = self.s.clone();
        s.ssm_limited_s = s.iso_ts_15066.ssm_limited_s;
        s.ssm_violations = s.iso_ts_15066.ssm_violations;
        s.waypoints = counters.waypoints_reached;
        s.detections = counters.detections;
        let mut steps = self.torque_steps.clone();
        steps.sort_by(f64::total_cmp);
        s.torque_step_p99_nm = steps
            .get((steps.len() as f64 * 0.99) as usize)
            .or(steps.last())
            .copied()
            .unwrap_or(0.0);
        for c in &s.contacts {
            let touching = ((c.t_start_s, c.t_end_s), c.link.as_str(), c.part.as_str());
            let truth = phri_iso15066::ForceSource::Truth;
            s.iso_ts_15066
                .contact(touching, c.peak_force_n, c.intended, truth);
        }
        s
    }
}
