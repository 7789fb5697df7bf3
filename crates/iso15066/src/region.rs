//! The body regions of ISO/TS 15066 Annex A, Table A.2.

/// A body region of Annex A, Table A.2.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
pub enum BodyRegion {
    /// skull and forehead (no transient contact allowed)
    SkullAndForehead,
    /// face (no transient contact allowed)
    Face,
    /// neck
    Neck,
    /// back and shoulders
    BackAndShoulders,
    /// chest
    Chest,
    /// abdomen
    Abdomen,
    /// pelvis
    Pelvis,
    /// upper arm and elbow joint
    UpperArmAndElbow,
    /// lower arm and wrist joint
    LowerArmAndWrist,
    /// hand and fingers
    HandAndFingers,
    /// thigh and knee
    ThighAndKnee,
    /// lower leg
    LowerLeg,
}

impl BodyRegion {
    /// Every region, in the table's order (head to foot).
    pub const ALL: [BodyRegion; 12] = [
        BodyRegion::SkullAndForehead,
        BodyRegion::Face,
        BodyRegion::Neck,
        BodyRegion::BackAndShoulders,
        BodyRegion::Chest,
        BodyRegion::Abdomen,
        BodyRegion::Pelvis,
        BodyRegion::UpperArmAndElbow,
        BodyRegion::LowerArmAndWrist,
        BodyRegion::HandAndFingers,
        BodyRegion::ThighAndKnee,
        BodyRegion::LowerLeg,
    ];

    /// The region's name in reports (`"hand_and_fingers"`, …).
    pub fn name(self) -> &'static str {
        match self {
            BodyRegion::SkullAndForehead => "skull_and_forehead",
            BodyRegion::Face => "face",
            BodyRegion::Neck => "neck",
            BodyRegion::BackAndShoulders => "back_and_shoulders",
            BodyRegion::Chest => "chest",
            BodyRegion::Abdomen => "abdomen",
            BodyRegion::Pelvis => "pelvis",
            BodyRegion::UpperArmAndElbow => "upper_arm_and_elbow",
            BodyRegion::LowerArmAndWrist => "lower_arm_and_wrist",
            BodyRegion::HandAndFingers => "hand_and_fingers",
            BodyRegion::ThighAndKnee => "thigh_and_knee",
            BodyRegion::LowerLeg => "lower_leg",
        }
    }

    /// Maximum permissible quasi-static contact force \[N\] (Table A.2).
    pub fn quasi_static_n(self) -> f64 {
        match self {
            BodyRegion::SkullAndForehead => 130.0,
            BodyRegion::Face => 65.0,
            BodyRegion::Neck => 150.0,
            BodyRegion::BackAndShoulders => 210.0,
            BodyRegion::Chest => 140.0,
            BodyRegion::Abdomen => 110.0,
            BodyRegion::Pelvis => 180.0,
            BodyRegion::UpperArmAndElbow => 150.0,
            BodyRegion::LowerArmAndWrist => 160.0,
            BodyRegion::HandAndFingers => 140.0,
            BodyRegion::ThighAndKnee => 220.0,
            BodyRegion::LowerLeg => 130.0,
        }
    }

    /// Maximum permissible transient contact force \[N\]: twice the
    /// quasi-static one; `None` for the skull and the face, where no
    /// transient contact is allowed (Table A.2).
    pub fn transient_n(self) -> Option<f64> {
        match self {
            BodyRegion::SkullAndForehead | BodyRegion::Face => None,
            r => Some(2.0 * r.quasi_static_n()),
        }
    }

    /// Effective spring constant \[N/m\] where Annex A gives one (hand 75,
    /// lower arm 40, upper arm 30, chest 25, skull 150 N/mm).
    pub fn spring_n_per_m(self) -> Option<f64> {
        let n_per_mm = match self {
            BodyRegion::HandAndFingers => 75.0,
            BodyRegion::LowerArmAndWrist => 40.0,
            BodyRegion::UpperArmAndElbow => 30.0,
            BodyRegion::Chest => 25.0,
            BodyRegion::SkullAndForehead => 150.0,
            _ => return None,
        };
        Some(n_per_mm * 1000.0)
    }

    /// Effective mass of the body region \[kg\] where Annex A gives one
    /// (hand 0.6, lower arm 2, upper arm 3, chest 40, skull 4.4).
    pub fn mass_kg(self) -> Option<f64> {
        match self {
            BodyRegion::HandAndFingers => Some(0.6),
            BodyRegion::LowerArmAndWrist => Some(2.0),
            BodyRegion::UpperArmAndElbow => Some(3.0),
            BodyRegion::Chest => Some(40.0),
            BodyRegion::SkullAndForehead => Some(4.4),
            _ => None,
        }
    }

    /// The region of a body part of the scripted person, by the part's name
    /// (`phri_ipc::BodyPart::name`): `hand_*` hand and fingers, `forearm_*`
    /// lower arm and wrist, `upper_arm_*` upper arm and elbow, `torso` chest,
    /// `thigh_*` thigh and knee, `shin_*` lower leg; the person's one head
    /// capsule counts as the face and the pelvis capsule as the abdomen, the
    /// stricter of the regions each covers. `None` for an unknown name.
    pub fn of_part(name: &str) -> Option<BodyRegion> {
        let region = match name {
            "head" => BodyRegion::Face,
            "torso" => BodyRegion::Chest,
            "pelvis" => BodyRegion::Abdomen,
            n if n.starts_with("upper_arm_") => BodyRegion::UpperArmAndElbow,
            n if n.starts_with("forearm_") => BodyRegion::LowerArmAndWrist,
            n if n.starts_with("hand_") => BodyRegion::HandAndFingers,
            n if n.starts_with("thigh_") => BodyRegion::ThighAndKnee,
            n if n.starts_with("shin_") => BodyRegion::LowerLeg,
            _ => return None,
        };
        Some(region)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Table A.2 as REFERENCE §11 transcribes it: (region, quasi-static,
    /// transient) [N].
    const TABLE_A2: [(BodyRegion, f64, Option<f64>); 12] = [
        (BodyRegion::SkullAndForehead, 130.0, None),
        (BodyRegion::Face, 65.0, None),
        (BodyRegion::Neck, 150.0, Some(300.0)),
        (BodyRegion::BackAndShoulders, 210.0, Some(420.0)),
        (BodyRegion::Chest, 140.0, Some(280.0)),
        (BodyRegion::Abdomen, 110.0, Some(220.0)),
        (BodyRegion::Pelvis, 180.0, Some(360.0)),
        (BodyRegion::UpperArmAndElbow, 150.0, Some(300.0)),
        (BodyRegion::LowerArmAndWrist, 160.0, Some(320.0)),
        (BodyRegion::HandAndFingers, 140.0, Some(280.0)),
        (BodyRegion::ThighAndKnee, 220.0, Some(440.0)),
        (BodyRegion::LowerLeg, 130.0, Some(260.0)),
    ];

    #[test]
    fn every_region_has_table_a2_s_limits() {
        assert_eq!(BodyRegion::ALL.len(), TABLE_A2.len());
        for (region, quasi, transient) in TABLE_A2 {
            assert!(BodyRegion::ALL.contains(&region));
            assert_eq!(region.quasi_static_n(), quasi, "{}", region.name());
            assert_eq!(region.transient_n(), transient, "{}", region.name());
        }
        let mut names: Vec<&str> = BodyRegion::ALL.iter().map(|r| r.name()).collect();
        names.sort_unstable();
        names.dedup();
        assert_eq!(names.len(), 12, "names are unique");
    }

    #[test]
    fn springs_and_masses_of_annex_a() {
        let h = BodyRegion::HandAndFingers;
        assert_eq!(
            (h.spring_n_per_m(), h.mass_kg()),
            (Some(75_000.0), Some(0.6))
        );
        let s = BodyRegion::SkullAndForehead;
        assert_eq!(
            (s.spring_n_per_m(), s.mass_kg()),
            (Some(150_000.0), Some(4.4))
        );
        assert_eq!(BodyRegion::Chest.mass_kg(), Some(40.0));
        assert_eq!(BodyRegion::Neck.spring_n_per_m(), None);
    }

    #[test]
    fn every_part_of_the_scripted_person_has_a_region() {
        let parts = [
            ("head", BodyRegion::Face),
            ("torso", BodyRegion::Chest),
            ("pelvis", BodyRegion::Abdomen),
            ("upper_arm_left", BodyRegion::UpperArmAndElbow),
            ("upper_arm_right", BodyRegion::UpperArmAndElbow),
            ("forearm_left", BodyRegion::LowerArmAndWrist),
            ("forearm_right", BodyRegion::LowerArmAndWrist),
            ("hand_left", BodyRegion::HandAndFingers),
            ("hand_right", BodyRegion::HandAndFingers),
            ("thigh_left", BodyRegion::ThighAndKnee),
            ("thigh_right", BodyRegion::ThighAndKnee),
            ("shin_left", BodyRegion::LowerLeg),
            ("shin_right", BodyRegion::LowerLeg),
        ];
        for (name, region) in parts {
            assert_eq!(BodyRegion::of_part(name), Some(region), "{name}");
        }
        assert_eq!(BodyRegion::of_part("#99"), None);
        // the head's stricter region: no transient contact at all
        assert_eq!(BodyRegion::of_part("head").unwrap().transient_n(), None);
    }
}
