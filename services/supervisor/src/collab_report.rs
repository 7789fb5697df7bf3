//! The report's `collaboration` section: what the controller's
//! `collab/state` said (requests and their answers, phases, how each
//! collaboration ended, how closely the robot followed the hand) set
//! against the simulator's ground truth (`sim/truth`: the true contact
//! force of the collaborative hand, to grade the estimate F̂ of eqs. 21-22)
//! and the scenario's script (when the person began to wave).

use std::collections::BTreeMap;

use phri_ipc::{
    BridgeRequests, CollabPart, CollabPhase, CollabReason, CollabState, HriRequest, RequestSource,
    Truth, Utterance, VoiceIntent, VoiceVerdict,
};
use serde::Serialize;

/// True forces below this are not graded \[N\] (issue 11: ≥ 5 N).
const MIN_GRADED_FORCE_N: f64 = 5.0;
/// Unmatched samples older than this are dropped \[ns\].
const MATCH_WINDOW_NS: u64 = 2_000_000_000;
/// The collaborative hand apart from the robot for less than this between
/// two contacts touched once \[ns\]: a held hand's contact bounces apart for
/// 10-300 ms (on touching, while the admittance closes in again), while a
/// hand that moved away and was followed touches again 1.0 s or more later
/// (the scenarios' second touch: 1.0-1.9 s). The simulator's episodes
/// (`contacts`, per robot link, ended after 50 ms apart) count every bounce.
const TOUCH_GAP_NS: u64 = 500_000_000;
/// The report lists at most this many requests, utterances and phase
/// changes each; the rest are counted (`*_left_out`): a flood of requests
/// or a flapping phase must not grow the report without bound.
pub const MAX_LISTED: usize = 1000;

/// `item` appended to `list` unless it holds [`MAX_LISTED`] already; then counted in `left_out`.
fn push_capped<T>(list: &mut Vec<T>, left_out: &mut u64, item: T) {
    if list.len() < MAX_LISTED {
        list.push(item);
    } else {
        *left_out += 1;
    }
}

/// `collaboration.requests[]`.
#[derive(Clone, Debug, Serialize, PartialEq)]
pub struct RequestReport {
    /// when the controller answered \[s\], the report's time base
    pub t_s: f64,
    /// who asked: `gesture`, `voice`, `cli`, `ros2`
    pub source: String,
    /// what was asked: `begin`, `end`, `stop`, `follow`, `resume`
    pub kind: String,
    /// the collaborative part named: `none`, `right_hand`, `left_hand`
    pub part: String,
    /// the request was accepted
    pub accepted: bool,
    /// the controller's reason (`accepted`, or why it refused), or the
    /// recogniser's verdict for a voice request it refused itself
    pub reason: String,
    /// the request's number (per source)
    pub seq: u64,
    /// voice: the words recognised
    #[serde(skip_serializing_if = "Option::is_none")]
    pub text: Option<String>,
    /// voice: the recogniser's score
    #[serde(skip_serializing_if = "Option::is_none")]
    pub score: Option<f64>,
    /// voice: the utterance's end → the request published \[ms\]
    #[serde(skip_serializing_if = "Option::is_none")]
    pub utterance_end_to_request_ms: Option<f64>,
    /// who refused it: `control` (the collaboration's state machine) or
    /// `voice` (the recogniser: the words, the score or the hand gate)
    pub refused_by: Option<String>,
}

/// `collaboration.utterances[]`: everything `phri-voice` heard.
#[derive(Clone, Debug, Serialize, PartialEq)]
pub struct UtteranceReport {
    /// when the verdict was reached \[s\], the report's time base
    pub t_s: f64,
    /// the words recognised (empty: none)
    pub text: String,
    /// the command recognised: `none`, `follow_right_hand`, `begin`, ...
    pub intent: String,
    /// the recogniser's score: acoustic log-likelihood per 10 ms frame
    /// against a free phone loop (higher: surer; 0 when nothing decoded)
    pub score: f64,
    /// what became of it: `accepted`, `no_match`, `low_score`, ...
    pub verdict: String,
    /// speech duration \[s\]
    pub duration_s: f64,
    /// decoding time \[ms\]
    pub decode_ms: f64,
}

/// `collaboration.phases[]`: each change of phase.
#[derive(Clone, Debug, Serialize, PartialEq)]
pub struct PhaseReport {
    /// when the controller's state said so \[s\], the report's time base
    pub t_s: f64,
    /// the new phase: `idle`, `approach`, `contact`, `follow`, `back_off`
    pub phase: String,
    /// why it changed (the controller's reason)
    pub reason: String,
}

/// Relative error percentiles.
#[derive(Clone, Debug, Default, Serialize, PartialEq)]
pub struct ErrorPercentiles {
    /// median (null: no sample)
    pub p50: Option<f64>,
    /// 95th percentile (null: no sample)
    pub p95: Option<f64>,
    /// samples graded
    pub samples: usize,
}

/// `collaboration` in the report (empty lists and nulls when nothing happened).
#[derive(Clone, Debug, Default, Serialize, PartialEq)]
pub struct CollabReport {
    /// requests in time order: the controller's answers, and the voice
    /// requests the recogniser refused itself
    pub requests: Vec<RequestReport>,
    /// the utterances `phri-voice` heard, in the order of their verdicts
    pub utterances: Vec<UtteranceReport>,
    /// the changes of phase, in order
    pub phases: Vec<PhaseReport>,
    /// requests, utterances and phase changes past the first
    /// [`MAX_LISTED`] of each, counted but not listed
    pub requests_left_out: u64,
    /// requests that never reached the controller's collaboration: dropped
    /// by a full queue or by the controller's own limit per period, or by
    /// the ROS 2 bridge (over a peer's rate limit, undelivered); the run is
    /// degraded when one was
    pub requests_dropped: u64,
    /// of them, dropped by the ROS 2 bridge (`ros2/requests`)
    pub requests_dropped_ros2: u64,
    /// utterances past the first [`MAX_LISTED`], counted but not listed
    pub utterances_left_out: u64,
    /// phase changes past the first [`MAX_LISTED`], counted but not listed
    pub phases_left_out: u64,
    /// the first wave of the script → the first approach \[ms\] (null: no wave or no approach)
    pub wave_to_start_ms: Option<f64>,
    /// touches of the collaborative hand (ground truth): its contacts with
    /// any robot link, apart for less than 0.5 s, are one touch
    pub contacts_intended: usize,
    /// the simulator's intended contact episodes (per robot link and body
    /// part, the scripted pushes included; a bounce apart of 50 ms is a new one)
    pub intended_episodes: usize,
    /// `‖F̂ − F_true‖ / ‖F_true‖` over the samples with `‖F_true‖ ≥ 5 N` of
    /// the collaborative hand
    pub force_error: ErrorPercentiles,
    /// largest force of an intended contact \[N\] (ground truth)
    pub peak_intended_force_n: Option<f64>,
    /// how the last collaboration ended: `wrist_push`, `request`,
    /// `hand_lost`, `force_limit`, `collision`, `stale` (null: none ended)
    pub ended_by: Option<String>,
    /// hand ↔ robot point distance while following \[m\]
    pub follow_distance_m: Option<FollowDistance>,
}

/// The hand ↔ robot point distance while following, over the run's samples.
#[derive(Clone, Debug, Default, Serialize, PartialEq)]
pub struct FollowDistance {
    /// median \[m\]
    pub p50: f64,
}

/// The section's running evaluation.
#[derive(Clone, Debug)]
pub struct CollabEvaluator {
    t0_ns: u64,
    /// the script's wave onsets [s, scenario time = robot clock]
    wave_onsets: Vec<f64>,
    last_phase: u32,
    last_request: Option<(u32, u64)>,
    /// the first approach's state stamp [ns, robot clock]
    first_approach_ns: Option<u64>,
    /// the robot clock at scenario time 0 [ns] (from the first truth sample:
    /// the simulator steps once per period from its epoch)
    epoch_ns: Option<u64>,
    period_ns: u64,
    report: CollabReport,
    /// F̂ by the state stamp it answered [ns, robot clock], and the true
    /// force of the collaborative hand by truth stamp, until matched
    estimates: BTreeMap<u64, [f64; 3]>,
    truths: BTreeMap<u64, [f64; 3]>,
    errors: Vec<f64>,
    follow: Vec<f64>,
    part: CollabPart,
    /// touches of the collaborative hand so far, and the truth stamp it was
    /// last seen touching [ns, robot clock]
    touches: usize,
    touch_last_ns: Option<u64>,
    /// voice requests by seq: (text, score, utterance end → request [ms])
    voice: BTreeMap<u64, (String, f64, f64)>,
    /// the contact phase's touches as F̂ tells them (the last may be open)
    estimated: Vec<EstimatedContact>,
    estimating: Option<EstimatedContact>,
    /// `requests_dropped` of the controllers before the one publishing now
    /// (a restarted controller counts from 0), and the newest value
    dropped_base: u64,
    dropped_last: u64,
    /// the same for the ROS 2 bridge's drops (`ros2/requests`; a restarted
    /// bridge counts from 0): earlier bridges' and the newest value
    bridge_base: u64,
    bridge_last: u64,
    bridge_seq: u64,
}

/// A touch of the collaborative hand as the estimated force F̂ tells it:
/// one run of the contact phase.
#[derive(Clone, Debug, PartialEq)]
pub struct EstimatedContact {
    /// its first and last observable estimate \[s\]
    pub t_start_s: f64,
    /// its last observable estimate \[s\]
    pub t_end_s: f64,
    /// the largest ‖F̂‖ \[N\]
    pub peak_force_n: f64,
    /// the collaborative hand (the scripted person's name: `hand_right`)
    pub part: &'static str,
}

fn norm(v: &[f64; 3]) -> f64 {
    (v[0] * v[0] + v[1] * v[1] + v[2] * v[2]).sqrt()
}

fn percentile(sorted: &[f64], p: f64) -> Option<f64> {
    if sorted.is_empty() {
        return None;
    }
    let i = ((sorted.len() - 1) as f64 * p).round() as usize;
    sorted.get(i).copied()
}

impl CollabEvaluator {
    /// `t0_ns` [ns, CLOCK_MONOTONIC]: the report's time origin; `wave_onsets`:
    /// the scenario's wave keyframes \[s\].
    pub fn new(t0_ns: u64, wave_onsets: Vec<f64>, period_ns: u64) -> CollabEvaluator {
        CollabEvaluator {
            t0_ns,
            wave_onsets,
            last_phase: CollabPhase::Idle as u32,
            last_request: None,
            first_approach_ns: None,
            epoch_ns: None,
            period_ns,
            report: CollabReport::default(),
            estimates: BTreeMap::new(),
            truths: BTreeMap::new(),
            errors: Vec::new(),
            follow: Vec::new(),
            part: CollabPart::None,
            touches: 0,
            touch_last_ns: None,
            voice: BTreeMap::new(),
            estimated: Vec::new(),
            estimating: None,
            dropped_base: 0,
            dropped_last: 0,
            bridge_base: 0,
            bridge_last: 0,
            bridge_seq: 0,
        }
    }

    fn t(&self, stamp_ns: u64) -> f64 {
        stamp_ns.saturating_sub(self.t0_ns) as f64 * 1e-9
    }

    /// What the ROS 2 bridge did with `/phri/request` (`ros2/requests`).
    pub fn on_bridge(&mut self, m: &BridgeRequests) {
        if m.seq <= self.bridge_seq || m.dropped < self.bridge_last {
            // another bridge process (restarted): its counts start at 0
            self.bridge_base += self.bridge_last;
        }
        self.bridge_seq = m.seq;
        self.bridge_last = m.dropped;
    }

    /// The controller's `collab/state`: requests answered, phase changes,
    /// F̂ in contact, the hand's distance while following.
    pub fn on_state(&mut self, s: &CollabState) {
        let t = self.t(s.stamp_ns);
        let dropped = u64::from(s.requests_dropped);
        if dropped < self.dropped_last {
            // another controller (restarted, or the standby after a takeover)
            self.dropped_base += self.dropped_last;
        }
        self.dropped_last = dropped;
        if s.request_source != 0 && self.last_request != Some((s.request_source, s.request_seq)) {
            self.last_request = Some((s.request_source, s.request_seq));
            push_capped(
                &mut self.report.requests,
                &mut self.report.requests_left_out,
                RequestReport {
                    t_s: t,
                    source: RequestSource::name_of(s.request_source).into(),
                    kind: phri_ipc::RequestKind::name_of(s.request_kind).into(),
                    part: CollabPart::name_of(s.request_part).into(),
                    accepted: s.request_accepted != 0,
                    reason: CollabReason::name_of(s.request_reason).into(),
                    seq: s.request_seq,
                    text: None,
                    score: None,
                    utterance_end_to_request_ms: None,
                    refused_by: (s.request_accepted == 0).then(|| "control".into()),
                },
            );
        }
        if s.phase != self.last_phase {
            let phase = CollabPhase::try_from(s.phase).unwrap_or(CollabPhase::Idle);
            push_capped(
                &mut self.report.phases,
                &mut self.report.phases_left_out,
                PhaseReport {
                    t_s: t,
                    phase: phase.name().into(),
                    reason: CollabReason::name_of(s.reason).into(),
                },
            );
            if phase == CollabPhase::Approach && self.first_approach_ns.is_none() {
                self.first_approach_ns = Some(s.state_stamp_ns);
            }
            if phase == CollabPhase::Idle && self.last_phase != CollabPhase::Idle as u32 {
                let ended = match CollabReason::try_from(s.reason) {
                    Ok(CollabReason::EndRequest | CollabReason::StopRequest) => "request",
                    Ok(r) => r.name(),
                    Err(_) => "unknown",
                };
                self.report.ended_by = Some(ended.into());
            }
            self.last_phase = s.phase;
        }
        if let Ok(p) = CollabPart::try_from(s.human_part) {
            if p != CollabPart::None {
                self.part = p;
            }
        }
        let phase = CollabPhase::try_from(s.phase).unwrap_or(CollabPhase::Idle);
        if s.n_forces > 0 && phase != CollabPhase::Idle {
            let f = s.forces[0];
            if phase == CollabPhase::Follow {
                let d = [
                    s.hand[0] - f.point[0],
                    s.hand[1] - f.point[1],
                    s.hand[2] - f.point[2],
                ];
                self.follow.push(norm(&d));
            }
            if phase == CollabPhase::Contact && f.observable != 0 {
                self.estimates.insert(s.state_stamp_ns, f.force);
                self.match_up(s.state_stamp_ns);
                let (force, part) = (norm(&f.force), self.part.body_part());
                match self.estimating.as_mut() {
                    Some(e) => {
                        e.t_end_s = t;
                        e.peak_force_n = e.peak_force_n.max(force);
                    }
                    None => {
                        self.estimating = part.map(|p| EstimatedContact {
                            t_start_s: t,
                            t_end_s: t,
                            peak_force_n: force,
                            part: p.name(),
                        })
                    }
                }
            }
        }
        if phase != CollabPhase::Contact {
            if let Some(e) = self.estimating.take() {
                if self.estimated.len() < MAX_LISTED {
                    self.estimated.push(e);
                }
            }
        }
    }

    /// The collaboration's touches as F̂ tells them, for a run without the
    /// simulator's truth.
    pub fn estimated_contacts(&self) -> impl Iterator<Item = &EstimatedContact> {
        self.estimated.iter().chain(self.estimating.as_ref())
    }

    /// A run without the simulator's truth (a real arm): judge the
    /// collaboration's touches as F̂ tells them, on the collaborative robot
    /// part's `link`, into `iso`.
    pub fn judge_estimated(&self, iso: &mut phri_iso15066::Judged, link: &str) {
        for c in self.estimated_contacts() {
            let touching = ((c.t_start_s, c.t_end_s), link, c.part);
            let estimate = phri_iso15066::ForceSource::Estimate;
            iso.contact(touching, c.peak_force_n, true, estimate);
        }
    }

    /// A request on `hri/request`: voice requests' words and timing.
    pub fn on_request(&mut self, r: &HriRequest) {
        if r.source == RequestSource::Voice as u32 {
            let latency = r.stamp_ns.saturating_sub(r.utterance_end_ns) as f64 * 1e-6;
            self.voice
                .insert(r.seq, (phri_ipc::json::c_str(&r.text), r.score, latency));
            // the words of the newest requests only (a flood keeps no more)
            while self.voice.len() > MAX_LISTED {
                self.voice.pop_first();
            }
        }
    }

    /// An utterance `phri-voice` heard; one it refused is a refused request.
    pub fn on_utterance(&mut self, u: &Utterance) {
        let t = self.t(u.decoded_ns);
        let text = phri_ipc::json::c_str(&u.text);
        let intent = VoiceIntent::try_from(u.intent).unwrap_or(VoiceIntent::None);
        push_capped(
            &mut self.report.utterances,
            &mut self.report.utterances_left_out,
            UtteranceReport {
                t_s: t,
                text: text.clone(),
                intent: intent.name().into(),
                score: u.score,
                verdict: VoiceVerdict::name_of(u.verdict).into(),
                duration_s: u.end_ns.saturating_sub(u.start_ns) as f64 * 1e-9,
                decode_ms: u.decode_ms,
            },
        );
        if u.verdict != VoiceVerdict::Accepted as u32 {
            let (kind, part) = match intent.request() {
                Some((k, p)) => (k.name(), p.name()),
                None => ("none", "none"),
            };
            push_capped(
                &mut self.report.requests,
                &mut self.report.requests_left_out,
                RequestReport {
                    t_s: t,
                    source: RequestSource::Voice.name().into(),
                    kind: kind.into(),
                    part: part.into(),
                    accepted: false,
                    reason: VoiceVerdict::name_of(u.verdict).into(),
                    seq: 0,
                    text: Some(text),
                    score: Some(u.score),
                    utterance_end_to_request_ms: None,
                    refused_by: Some("voice".into()),
                },
            );
        }
    }

    /// A `sim/truth` sample: the true force of the collaborative hand and
    /// its touches, and the robot clock's epoch.
    pub fn on_truth(&mut self, m: &Truth) {
        if self.epoch_ns.is_none() && m.seq > 0 {
            self.epoch_ns = Some(m.stamp_ns.saturating_sub((m.seq - 1) * self.period_ns));
        }
        let Some(hand) = self.part.body_part() else {
            return;
        };
        let n = (m.n_contacts as usize).min(m.contacts.len());
        let mut f = [0.0; 3];
        let mut any = false;
        for c in &m.contacts[..n] {
            if c.human_part == hand as i32 && c.intended != 0 {
                for (a, b) in f.iter_mut().zip(&c.force) {
                    *a += b;
                }
                any = true;
            }
        }
        if any {
            // a touch begins after the hand was apart for TOUCH_GAP_NS
            if self
                .touch_last_ns
                .is_none_or(|t| m.stamp_ns.saturating_sub(t) > TOUCH_GAP_NS)
            {
                self.touches += 1;
            }
            self.touch_last_ns = Some(m.stamp_ns);
            self.truths.insert(m.stamp_ns, f);
            self.match_up(m.stamp_ns);
        }
    }

    fn match_up(&mut self, stamp: u64) {
        if let (Some(e), Some(t)) = (self.estimates.get(&stamp), self.truths.get(&stamp)) {
            let truth = norm(t);
            if truth >= MIN_GRADED_FORCE_N {
                let d = [e[0] - t[0], e[1] - t[1], e[2] - t[2]];
                self.errors.push(norm(&d) / truth);
            }
            self.estimates.remove(&stamp);
            self.truths.remove(&stamp);
        }
        let keep_from = stamp.saturating_sub(MATCH_WINDOW_NS);
        self.estimates = self.estimates.split_off(&keep_from);
        self.truths = self.truths.split_off(&keep_from);
    }

    /// The section, with the run's ground-truth contact episodes
    /// (`(intended, peak force [N])` each).
    pub fn report(&self, contacts: impl Iterator<Item = (bool, f64)>) -> CollabReport {
        let mut r = self.report.clone();
        for q in r
            .requests
            .iter_mut()
            .filter(|q| q.source == "voice" && q.seq != 0)
        {
            if let Some((text, score, latency)) = self.voice.get(&q.seq) {
                q.text = Some(text.clone());
                q.score = Some(*score);
                q.utterance_end_to_request_ms = Some(*latency);
            }
        }
        r.requests.sort_by(|a, b| a.t_s.total_cmp(&b.t_s));
        let mut intended = 0;
        let mut peak: Option<f64> = None;
        for (i, f) in contacts {
            if i {
                intended += 1;
                peak = Some(peak.map_or(f, |p| p.max(f)));
            }
        }
        r.requests_dropped_ros2 = self.bridge_base + self.bridge_last;
        r.requests_dropped = self.dropped_base + self.dropped_last + r.requests_dropped_ros2;
        r.contacts_intended = self.touches;
        r.intended_episodes = intended;
        r.peak_intended_force_n = peak;
        let mut e = self.errors.clone();
        e.sort_by(f64::total_cmp);
        r.force_error = ErrorPercentiles {
            p50: percentile(&e, 0.5),
            p95: percentile(&e, 0.95),
            samples: e.len(),
        };
        let mut f = self.follow.clone();
        f.sort_by(f64::total_cmp);
        r.follow_distance_m = percentile(&f, 0.5).map(|p50| FollowDistance { p50 });
        r.wave_to_start_ms = match (
            self.wave_onsets.first(),
            self.first_approach_ns,
            self.epoch_ns,
        ) {
            (Some(w), Some(a), Some(e)) => {
                let a = a.saturating_sub(e) as f64 * 1e-9;
                (a >= *w).then_some((a - w) * 1e3)
            }
            _ => None,
        };
        r
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use phri_ipc::{BodyPart, ContactTruth, Zeroed};

    fn state(t_ms: u64, phase: CollabPhase, reason: CollabReason) -> CollabState {
        let mut s = CollabState::zeroed();
        s.stamp_ns = 1_000_000_000 + t_ms * 1_000_000;
        s.state_stamp_ns = t_ms * 1_000_000;
        s.phase = phase as u32;
        s.reason = reason as u32;
        s.human_part = CollabPart::RightHand as u32;
        s
    }

    /// The requests the controllers may have lost add up across a
    /// controller that restarted (its count starts from 0 again).
    #[test]
    fn requests_dropped_add_up_across_controllers() {
        let mut e = CollabEvaluator::new(1_000_000_000, vec![], 1_000_000);
        for (t, dropped) in [
            (1000, 0),
            (1001, 2),
            (1002, 3),
            (1003, 3),
            (1004, 0),
            (1005, 1),
        ] {
            let mut s = state(t, CollabPhase::Idle, CollabReason::None);
            s.requests_dropped = dropped;
            e.on_state(&s);
        }
        assert_eq!(e.report(std::iter::empty()).requests_dropped, 4);
    }

    /// The ROS 2 bridge's drops count among the requests dropped, added
    /// up across a bridge that restarted (its counts start from 0 again).
    #[test]
    fn the_bridges_drops_add_up_across_restarts() {
        let mut e = CollabEvaluator::new(1_000_000_000, vec![], 1_000_000);
        let mut s = state(1000, CollabPhase::Idle, CollabReason::None);
        s.requests_dropped = 1;
        e.on_state(&s);
        for (seq, dropped) in [(1, 0), (2, 5), (3, 7), (1, 0), (2, 2)] {
            e.on_bridge(&BridgeRequests {
                seq,
                dropped,
                ..BridgeRequests::default()
            });
        }
        let r = e.report(std::iter::empty());
        assert_eq!((r.requests_dropped_ros2, r.requests_dropped), (9, 10));
    }

    #[test]
    fn the_touches_as_the_estimate_tells_them() {
        let mut e = CollabEvaluator::new(1_000_000_000, vec![], 1_000_000);
        e.on_state(&state(1000, CollabPhase::Approach, CollabReason::Accepted));
        let touch = |t_ms: u64, f: f64, observable: u32| {
            let mut c = state(t_ms, CollabPhase::Contact, CollabReason::ContactMade);
            c.n_forces = 1;
            c.forces[0].force = [0.0, f, 0.0];
            c.forces[0].observable = observable;
            c
        };
        e.on_state(&touch(2000, 10.0, 1));
        e.on_state(&touch(2500, 35.0, 1));
        // not observable: not counted
        e.on_state(&touch(2600, 90.0, 0));
        e.on_state(&touch(3000, 20.0, 1));
        e.on_state(&state(
            3100,
            CollabPhase::Follow,
            CollabReason::HandMovedAway,
        ));
        // the second touch is still on when the run ends
        e.on_state(&touch(4000, 15.0, 1));
        let c: Vec<_> = e.estimated_contacts().cloned().collect();
        assert_eq!(c.len(), 2, "{c:?}");
        assert_eq!(
            (c[0].t_start_s, c[0].t_end_s, c[0].peak_force_n),
            (2.0, 3.0, 35.0)
        );
        assert_eq!((c[1].part, c[1].peak_force_n), ("hand_right", 15.0));
        // judged as the hand's: 1 s at 35 N quasi-static, 105 N to spare
        let mut iso = phri_iso15066::Judged::default();
        e.judge_estimated(&mut iso, "lwr_link_7");
        let j = &iso.contacts[0];
        assert_eq!(iso.contacts.len(), 2);
        assert_eq!(
            (j.source, j.region, j.kind, j.margin_n, j.intended),
            ("estimate", "hand_and_fingers", "quasi_static", 105.0, true)
        );
    }

    #[test]
    fn phases_requests_wave_latency_force_error_and_the_end() {
        let mut e = CollabEvaluator::new(1_000_000_000, vec![3.0], 1_000_000);
        let mut s = state(4500, CollabPhase::Approach, CollabReason::Accepted);
        s.request_source = RequestSource::Gesture as u32;
        s.request_seq = 7;
        s.request_accepted = 1;
        s.request_kind = phri_ipc::RequestKind::Follow as u32;
        s.request_part = CollabPart::RightHand as u32;
        s.request_reason = CollabReason::Accepted as u32;
        e.on_state(&s);
        e.on_state(&s); // the same request is reported once
                        // contact: F̂ = (10, 0, 0) against a true (8, 0, 6) → error ‖(2, 0, −6)‖/10
        let mut c = state(9000, CollabPhase::Contact, CollabReason::ContactMade);
        c.n_forces = 1;
        c.forces[0].force = [10.0, 0.0, 0.0];
        c.forces[0].observable = 1;
        e.on_state(&c);
        let mut t = Truth::zeroed();
        t.stamp_ns = 9000 * 1_000_000;
        t.seq = 9001; // the simulator's epoch: robot clock 0
        t.n_contacts = 2;
        t.contacts[0] = ContactTruth {
            human_part: BodyPart::HandRight as i32,
            intended: 1,
            force: [8.0, 0.0, 2.0],
            ..Default::default()
        };
        t.contacts[1] = ContactTruth {
            human_part: BodyPart::HandRight as i32,
            intended: 1,
            force: [0.0, 0.0, 4.0],
            ..Default::default()
        };
        e.on_truth(&t);
        // a small true force is not graded
        let mut c2 = c;
        c2.state_stamp_ns += 1_000_000;
        e.on_state(&c2);
        let mut t2 = t;
        t2.stamp_ns += 1_000_000;
        t2.n_contacts = 1;
        t2.contacts[0].force = [1.0, 0.0, 0.0];
        e.on_truth(&t2);
        e.on_state(&state(16300, CollabPhase::Idle, CollabReason::WristPush));
        let r = e.report([(true, 40.0), (false, 90.0), (true, 12.0)].into_iter());
        assert_eq!(r.requests.len(), 1);
        assert!(r.requests[0].accepted && r.requests[0].source == "gesture");
        let phases: Vec<&str> = r.phases.iter().map(|p| p.phase.as_str()).collect();
        assert_eq!(phases, ["approach", "contact", "idle"]);
        assert!((r.phases[0].t_s - 4.5).abs() < 1e-9);
        assert!((r.wave_to_start_ms.unwrap() - 1500.0).abs() < 1e-6);
        assert_eq!(r.force_error.samples, 1);
        let want = (4.0f64 + 36.0).sqrt() / 10.0;
        assert!((r.force_error.p50.unwrap() - want).abs() < 1e-12);
        assert_eq!(r.ended_by.as_deref(), Some("wrist_push"));
        // the simulator's two intended episodes; the truth saw the hand touch once
        assert_eq!(r.intended_episodes, 2);
        assert_eq!(r.contacts_intended, 1);
        assert_eq!(r.peak_intended_force_n, Some(40.0));
    }

    /// A truth sample at `t_ms` with the right hand touching `link` (or nothing).
    fn touching(t_ms: u64, link: Option<i32>) -> Truth {
        let mut t = Truth::zeroed();
        t.stamp_ns = t_ms * 1_000_000;
        t.seq = t_ms + 1;
        if let Some(l) = link {
            t.n_contacts = 1;
            t.contacts[0] = ContactTruth {
                robot_object: l,
                human_part: BodyPart::HandRight as i32,
                intended: 1,
                force: [0.0, 0.0, 20.0],
                ..Default::default()
            };
        }
        t
    }

    #[test]
    fn a_touch_is_one_however_it_bounces_and_whichever_links_it_meets() {
        let mut e = CollabEvaluator::new(0, vec![], 1_000_000);
        e.on_state(&state(1000, CollabPhase::Approach, CollabReason::Accepted));
        // touch 1 (2.0-4.0 s): on link 7, a 20 ms and a 300 ms bounce apart,
        // then on link 6 as well as link 7
        let mut samples: Vec<(u64, Option<i32>)> = Vec::new();
        for t in (2000..4000).step_by(1) {
            let apart = (2100..2120).contains(&t) || (2500..2800).contains(&t);
            let link = match (apart, t >= 3000 && t % 2 == 0) {
                (true, _) => None,
                (false, true) => Some(5),
                (false, false) => Some(6),
            };
            samples.push((t, link));
        }
        // apart 1.0 s (the hand moved away, the robot followed): touch 2
        samples.extend((4000..5000).map(|t| (t, None)));
        samples.extend((5000..6000).map(|t| (t, Some(6))));
        for (t, link) in samples {
            e.on_truth(&touching(t, link));
        }
        // another part's contact (the other hand's push) is no touch of the
        // collaborative hand
        let mut push = touching(7000, Some(5));
        push.contacts[0].human_part = BodyPart::HandLeft as i32;
        e.on_truth(&push);
        let r = e.report(std::iter::empty());
        assert_eq!(r.contacts_intended, 2);
    }

    #[test]
    fn nothing_happened_is_empty() {
        let e = CollabEvaluator::new(0, vec![], 1_000_000);
        let r = e.report(std::iter::empty());
        assert_eq!(r, CollabReport::default());
    }

    #[test]
    fn voice_requests_carry_words_score_and_latency_and_its_refusals_are_listed() {
        let mut e = CollabEvaluator::new(1_000_000_000, vec![], 1_000_000);
        // refused by the recogniser at 3 s: a follow for an untracked hand
        let mut u = phri_ipc::Utterance::zeroed();
        u.start_ns = 2_000_000_000;
        u.end_ns = 3_300_000_000;
        u.decoded_ns = 4_000_000_000;
        u.intent = VoiceIntent::FollowRightHand as u32;
        u.verdict = VoiceVerdict::HandNotTracked as u32;
        u.score = 7.5;
        u.text = phri_ipc::json::to_c_str("follow the right hand");
        e.on_utterance(&u);
        // accepted at 9 s: the request, then the controller's answer
        let mut r = HriRequest::zeroed();
        r.seq = 77;
        r.source = RequestSource::Voice as u32;
        r.stamp_ns = 9_600_000_000;
        r.utterance_end_ns = 9_000_000_000;
        r.score = 9.25;
        r.text = phri_ipc::json::to_c_str("follow the left hand");
        e.on_request(&r);
        let mut s = state(8700, CollabPhase::Approach, CollabReason::Accepted);
        s.request_source = RequestSource::Voice as u32;
        s.request_seq = 77;
        s.request_accepted = 1;
        s.request_kind = phri_ipc::RequestKind::Follow as u32;
        s.request_part = CollabPart::LeftHand as u32;
        e.on_state(&s);
        let rep = e.report(std::iter::empty());
        assert_eq!(rep.requests.len(), 2);
        let (refused, accepted) = (&rep.requests[0], &rep.requests[1]);
        assert!(!refused.accepted && refused.reason == "hand_not_tracked");
        assert_eq!(refused.refused_by.as_deref(), Some("voice"));
        assert_eq!(
            (refused.kind.as_str(), refused.part.as_str()),
            ("follow", "right_hand")
        );
        assert_eq!(refused.text.as_deref(), Some("follow the right hand"));
        assert!(accepted.accepted && accepted.refused_by.is_none());
        assert_eq!(accepted.text.as_deref(), Some("follow the left hand"));
        assert_eq!(accepted.score, Some(9.25));
        assert!((accepted.utterance_end_to_request_ms.unwrap() - 600.0).abs() < 1e-6);
        assert_eq!(rep.utterances.len(), 1);
        assert!((rep.utterances[0].duration_s - 1.3).abs() < 1e-9);
    }

    /// A flood of requests (each answered) and of refused utterances keeps
    /// the first MAX_LISTED of each and counts the rest.
    #[test]
    fn a_flood_is_listed_up_to_the_cap_and_counted() {
        let mut e = CollabEvaluator::new(0, vec![], 1_000_000);
        let flood = MAX_LISTED as u64 + 250;
        for k in 0..flood {
            let mut s = state(1000 + k, CollabPhase::Idle, CollabReason::None);
            s.request_source = RequestSource::Cli as u32;
            s.request_seq = k + 1;
            s.request_kind = phri_ipc::RequestKind::End as u32;
            s.request_reason = CollabReason::NotCollaborating as u32;
            e.on_state(&s);
            let mut u = phri_ipc::Utterance::zeroed();
            u.verdict = VoiceVerdict::NotSpeech as u32;
            e.on_utterance(&u);
            let mut r = HriRequest::zeroed();
            r.seq = k;
            r.source = RequestSource::Voice as u32;
            e.on_request(&r);
        }
        assert!(e.voice.len() <= MAX_LISTED);
        let rep = e.report(std::iter::empty());
        assert_eq!(rep.requests.len(), MAX_LISTED);
        assert_eq!(rep.utterances.len(), MAX_LISTED);
        // answered requests and the refused utterances' requests share the list
        assert_eq!(rep.requests_left_out, 2 * flood - MAX_LISTED as u64);
        assert_eq!(rep.utterances_left_out, flood - MAX_LISTED as u64);
    }
}
