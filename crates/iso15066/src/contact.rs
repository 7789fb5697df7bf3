//! A run's contacts judged for its report: each against its body region's
//! limit (the report's `iso_ts_15066` section).

use serde::Serialize;

use crate::{judge, BodyRegion};

/// One contact judged against its body region's ISO/TS 15066 limit.
#[derive(Clone, Debug, PartialEq, Serialize)]
pub struct JudgedContact {
    /// when it began and last touched \[s\]
    pub t_start_s: f64,
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
    pub within_limit: bool,
    /// a touch of the collaboration, not a collision
    pub intended: bool,
    /// where the force comes from: `truth` (the simulator's contact model)
    pub source: &'static str,
}

/// Every contact of a run judged, and how many were over their limit.
#[derive(Clone, Debug, Default, PartialEq, Serialize)]
pub struct Judged {
    pub contacts: Vec<JudgedContact>,
    /// contacts over their region's limit
    pub over_limit: usize,
    /// the smallest margin of any contact \[N\] (null: no contact)
    pub min_margin_n: Option<f64>,
}

impl Judged {
    /// Add a contact of the simulator's truth: `part` touched `link` from
    /// `t_start_s` to `t_end_s` \[s\], peaking at `peak_force_n` \[N\].
    pub fn truth(
        &mut self,
        (t_start_s, t_end_s): (f64, f64),
        link: &str,
        part: &str,
        peak_force_n: f64,
        intended: bool,
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
            source: "truth",
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
        j.truth((10.0, 10.05), "lwr_link_6", "hand_right", 180.0, false);
        // a collaboration's touch held 1.5 s at 40 N: within 140 N
        j.truth((12.0, 13.5), "lwr_link_7", "hand_left", 40.0, true);
        // a forearm clamped 2 s at 170 N: over the lower arm's 160 N
        j.truth((20.0, 22.0), "lwr_link_4", "forearm_left", 170.0, false);
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
        j.truth((30.0, 30.01), "lwr_link_7", "#42", 1.0, false);
        assert_eq!(
            (j.contacts[3].region, j.contacts[3].within_limit),
            ("unknown", false)
        );
    }
}
