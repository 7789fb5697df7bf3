//! Contact / collision thresholds and isolation of the colliding link.

/// Outcome for one residual sample.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub struct Detection {
    /// some |r_i| passed its contact threshold
    pub contact: bool,
    /// some |r_i| passed its collision threshold, or ‖r‖ the norm threshold
    pub collision: bool,
    /// last joint over its contact threshold: a force on link k shows only in
    /// components 1..k (paper eq. 3), so the colliding link is this one or later
    pub isolated_joint: Option<usize>,
}

/// Per-joint two-level thresholds (as Franka's contact/collision levels).
#[derive(Clone, Debug)]
pub struct Detector {
    /// contact threshold on each `|r_i|` \[Nm\], one per joint
    pub contact: Vec<f64>,
    /// collision threshold on each `|r_i|` \[Nm\], one per joint
    pub collision: Vec<f64>,
    /// collision threshold on `‖r‖` \[Nm\]
    pub norm: f64,
}

impl Detector {
    /// Judge the residual `r` \[Nm\] (one per joint, at most as many as
    /// thresholds) against both levels and the norm threshold.
    pub fn classify(&self, r: &[f64]) -> Detection {
        let mut d = Detection::default();
        let mut sq = 0.0;
        for (i, &ri) in r.iter().enumerate() {
            sq += ri * ri;
            if ri.abs() > self.contact[i] {
                d.contact = true;
                d.isolated_joint = Some(i);
            }
            if ri.abs() > self.collision[i] {
                d.collision = true;
            }
        }
        if sq.sqrt() > self.norm {
            d.collision = true;
        }
        d
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn levels_and_isolation() {
        let d = Detector {
            contact: vec![1.0; 4],
            collision: vec![3.0; 4],
            norm: 10.0,
        };
        assert_eq!(d.classify(&[0.5, 0.0, 0.0, 0.0]), Detection::default());
        let c = d.classify(&[2.0, 1.5, 0.2, 0.0]);
        assert!(c.contact && !c.collision);
        assert_eq!(c.isolated_joint, Some(1));
        assert!(d.classify(&[0.0, 0.0, 4.0, 0.0]).collision);
        assert!(d.classify(&[2.9, 2.9, 2.9, 2.9]).contact);
        assert!(!d.classify(&[2.9, 2.9, 2.9, 2.9]).collision); // norm 5.8 < 10
        assert!(d.classify(&[2.9; 4].map(|x| x * 1.0)).contact);
    }
}
