//! Speed and separation monitoring (clause 5.5.4): the protective
//! separation distance.

/// The terms of the protective separation distance that do not depend on
/// the speeds: times \[s\] and distances \[m\], in the standard's names.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct SsmTerms {
    /// `T_r`: the robot's reaction time, from a person's detection to the
    /// robot starting to stop \[s\]
    pub t_r: f64,
    /// `T_s`: the robot's stopping time \[s\]
    pub t_s: f64,
    /// `C`: the intrusion distance, how far a body part can reach before it
    /// is detected (ISO 13855) \[m\]
    pub c: f64,
    /// `Z_d`: the person's position uncertainty (the sensor's) \[m\]
    pub z_d: f64,
    /// `Z_r`: the robot's position uncertainty \[m\]
    pub z_r: f64,
}

/// The speed of a person approaching \[m/s\] at separation `d` \[m\] (ISO
/// 13855): 2.0 m/s within 0.5 m (an arm reaching), 1.6 m/s (walking) beyond.
pub fn human_speed(d: f64) -> f64 {
    if d <= 0.5 {
        2.0
    } else {
        1.6
    }
}

/// The protective separation distance \[m\]:
/// `S_p = v_h (T_r + T_s) + v_r T_r + S_s + C + Z_d + Z_r`, for a person
/// approaching at `v_h` \[m/s\], the robot moving toward them at `v_r`
/// \[m/s\] (negative: away; counted as 0) and stopping within `s_s` \[m\].
pub fn protective_separation_distance(v_h: f64, v_r: f64, s_s: f64, terms: &SsmTerms) -> f64 {
    v_h * (terms.t_r + terms.t_s) + v_r.max(0.0) * terms.t_r + s_s + terms.c + terms.z_d + terms.z_r
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn the_protective_separation_distance_worked_by_hand() {
        let terms = SsmTerms {
            t_r: 0.1,
            t_s: 0.3,
            c: 0.2,
            z_d: 0.05,
            z_r: 0.01,
        };
        // walking 1.6 m/s, the robot 0.5 m/s toward, stopping in 0.1 m:
        // 1.6·0.4 + 0.5·0.1 + 0.1 + 0.2 + 0.05 + 0.01 = 0.64 + 0.05 + 0.36 = 1.05 m
        let s = protective_separation_distance(1.6, 0.5, 0.1, &terms);
        assert!((s - 1.05).abs() < 1e-12, "{s}");
        // a robot moving away adds nothing for its speed
        let s = protective_separation_distance(1.6, -0.5, 0.1, &terms);
        assert!((s - 1.0).abs() < 1e-12, "{s}");
        // ISO 13855's speeds: reaching within 0.5 m, walking beyond
        assert_eq!(human_speed(0.3), 2.0);
        assert_eq!(human_speed(0.5), 2.0);
        assert_eq!(human_speed(0.51), 1.6);
    }
}
