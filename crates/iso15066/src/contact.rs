//! A run's contacts judged for its report: each against its body region's
//! limit (the report's `iso_ts_15066` section).

use serde::Serialize;

use crate::{judge, BodyRegion};

/// One contact judged against its body region's ISO/TS 15066 limit.
#[derive(Clone, Debug, PartialEq, Serialize)]
pub struct JudgedContact {
    /// when it began and last touched \[s\]
    pub t_start_s: f64,
    /// when it last touched \[s\]
    pub t_end_s: f64,
    /// the robot's link
    pub link: String,
    /// the person's body part (the scripted person's name)
    pub part: String,
    /// its body region (`hand_and_fingers`, …; `unknown` for a part no
    /// region covers, judged as the face: the strictest)
    pub region: &'static str,
    /// `transient` (at most 0.5 s) or `quasi_static`
    pub kind: &'static str,
    /// peak contact force \[N\]
    pub peak_force_n: f64,
    /// the region's limit for this kind \[N\] (0: no such contact allowed)
    pub limit_n: f64,
    /// `limit_n − peak_force_n` \[N\]
    pub margin_n: f64,
    /// the peak stayed within the limit
    pub within_limit: bool,
    /// a touch of the collaboration, not a collision
    pub intended: bool,
    /// where the force comes from: `truth` (the simulator's contact model)
    /// or `estimate` (F̂, where no simulator gives the truth)
    pub source: &'static str,
}

/// Every contact of a run judged, and how many were over their limit.
#[derive(Clone, Debug, Default, PartialEq, Serialize)]
pub struct Judged {
    /// every contact, in the order added
    pub contacts: Vec<JudgedContact>,
    /// contacts over their region's limit
    pub over_limit: usize,
    /// the smallest margin of any contact \[N\] (null: no contact)
    pub min_margin_n: Option<f64>,
    /// speed and separation monitoring was configured
    pub ssm_enabled: bool,
    /// the time it bounded the robot's speed \[s\]
    pub ssm_limited_s: f64,
    /// violations: runs of periods in which a control point had been moving
    /// toward the person inside the protective separation distance for
    /// longer than the robot's stopping time
    pub ssm_violations: u64,
    /// when each began \[s\] (the first [`MAX_VIOLATION_TIMES`])
    pub ssm_violation_times_s: Vec<f64>,
    /// the controller's counts last seen (limited periods, violations)
    #[serde(skip)]
    ssm_seen: (u64, u64),
}

/// Where a contact's force comes from.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum ForceSource {
    /// the simulator's contact model
    Truth,
    /// the estimated force F̂ (eqs. 21-22), where no simulator gives the truth
    Estimate,
}

impl ForceSource {
    /// `"truth"` or `"estimate"`.
    pub fn name(self) -> &'static str {
        match self {
            ForceSource::Truth => "truth",
            ForceSource::Estimate => "estimate",
        }
    }
}

/// Who touched when: ((start, end) \[s\], the robot's link, the person's
/// body part).
pub type Touching<'a> = ((f64, f64), &'a str, &'a str);

/// Violations whose times a report lists at most.
pub const MAX_VIOLATION_TIMES: usize = 100;

impl Judged {
    /// The controller's monitor at `t_s` \[s\]: configured or not, and its
    /// counts since it started (`limited_periods` of `period_s` \[s\] each,
    /// `violations`). Counts below the last seen are a restarted
    /// controller's, counted anew.
    pub fn ssm_counts(
        &mut self,
        enabled: bool,
        limited_periods: u64,
        violations: u64,
        t_s: f64,
        period_s: f64,
    ) {
        self.ssm_enabled |= enabled;
        let (limited_before, violations_before) = match self.ssm_seen {
            (l, v) if limited_periods >= l && violations >= v => (l, v),
            _ => (0, 0),
        };
        self.ssm_limited_s += (limited_periods - limited_before) as f64 * period_s;
        for _ in violations_before..violations {
            self.ssm_violation(t_s);
        }
        self.ssm_seen = (limited_periods, violations);
    }

    /// A violation of the protective separation distance began at `t_s` \[s\].
    pub fn ssm_violation(&mut self, t_s: f64) {
        self.ssm_violations += 1;
        if self.ssm_violation_times_s.len() < MAX_VIOLATION_TIMES {
            self.ssm_violation_times_s.push(t_s);
        }
    }

    /// Add a contact: `part` touched `link` from `t_start_s` to `t_end_s`
    /// \[s\], peaking at `peak_force_n` \[N\] as `source` tells it.
    pub fn contact(
        &mut self,
        ((t_start_s, t_end_s), link, part): Touching<'_>,
        peak_force_n: f64,
        intended: bool,
        source: ForceSource,
    ) {
        let known = BodyRegion::of_part(part);
        let region = known.unwrap_or(BodyRegion::Face);
        let j = judge(region, peak_force_n, t_end_s - t_start_s);
        if !j.within {
            self.over_limit += 1;
        }
        self.min_margin_n = Some(self.min_margin_n.map_or(j.margin_n, |m| m.min(j.margin_n)));
        self.contacts.push(JudgedContact {
            t_start_s,
            t_end_s,
            link: link.to_string(),
            part: part.to_string(),
            region: known.map_or("unknown", BodyRegion::name),
            kind: j.kind.name(),
            peak_force_n,
            limit_n: j.limit_n,
            margin_n: j.margin_n,
            within_limit: j.within,
            intended,
            source: source.name(),
        });
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn contacts_are_judged_and_the_worst_margin_kept() {
        let mut j = Judged::default();
        assert_eq!(j.min_margin_n, None);
        // a thrown hand's impact, 0.05 s, 180 N: within the hand's 280 N
        j.contact(
            ((10.0, 10.05), "lwr_link_6", "hand_right"),
            180.0,
            false,
            ForceSource::Truth,
        );
        // a collaboration's touch held 1.5 s at 40 N: within 140 N
        j.contact(
            ((12.0, 13.5), "lwr_link_7", "hand_left"),
            40.0,
            true,
            ForceSource::Truth,
        );
        // a forearm clamped 2 s at 170 N: over the lower arm's 160 N
        j.contact(
            ((20.0, 22.0), "lwr_link_4", "forearm_left"),
            170.0,
            false,
            ForceSource::Truth,
        );
        assert_eq!(j.contacts.len(), 3);
        assert_eq!(j.over_limit, 1);
        assert_eq!(j.min_margin_n, Some(-10.0));
        let c = &j.contacts[0];
        assert_eq!(
            (c.region, c.kind, c.limit_n, c.margin_n),
            ("hand_and_fingers", "transient", 280.0, 100.0)
        );
        assert_eq!(j.contacts[2].region, "lower_arm_and_wrist");
        // an unknown part is judged as the face, the strictest
        j.contact(
            ((30.0, 30.01), "lwr_link_7", "#42"),
            1.0,
            false,
            ForceSource::Truth,
        );
        assert_eq!(
            (j.contacts[3].region, j.contacts[3].within_limit),
            ("unknown", false)
        );
        // an estimated touch of the collaboration, held 2 s at 30 N
        j.contact(
            ((40.0, 42.0), "lwr_link_7", "hand_right"),
            30.0,
            true,
            ForceSource::Estimate,
        );
        let c = &j.contacts[4];
        assert_eq!(
            (c.source, c.kind, c.margin_n),
            ("estimate", "quasi_static", 110.0)
        );
    }

    #[test]
    fn violations_are_counted_and_only_the_first_timed() {
        let mut j = Judged::default();
        for k in 0..MAX_VIOLATION_TIMES + 5 {
            j.ssm_violation(k as f64);
        }
        assert_eq!(j.ssm_violations, MAX_VIOLATION_TIMES as u64 + 5);
        assert_eq!(j.ssm_violation_times_s.len(), MAX_VIOLATION_TIMES);
        assert_eq!(j.ssm_violation_times_s[3], 3.0);
    }

    #[test]
    fn a_restarted_controllers_counts_add_to_its_predecessors() {
        let mut j = Judged::default();
        j.ssm_counts(true, 10, 0, 1.0, 0.001);
        j.ssm_counts(true, 30, 1, 2.0, 0.001);
        // restarted: counting from 0 again
        j.ssm_counts(true, 5, 0, 3.0, 0.001);
        j.ssm_counts(true, 5, 2, 4.0, 0.001);
        assert!(
            (j.ssm_limited_s - 0.035).abs() < 1e-12,
            "{}",
            j.ssm_limited_s
        );
        assert_eq!(j.ssm_violations, 3);
        assert_eq!(j.ssm_violation_times_s, [2.0, 4.0, 4.0]);
        assert!(j.ssm_enabled);
    }
}
