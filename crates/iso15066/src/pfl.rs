//! Power and force limiting (clause 5.5.5, Annex A): how fast the robot may
//! meet a body region, and a contact judged against the region's limit.

use crate::BodyRegion;

/// A contact lasting at most this long is transient (an impact the body
/// part can recoil from); longer, quasi-static (as the standard's figures
/// are commonly read: transient ≤ 0.5 s) \[s\].
pub const TRANSIENT_MAX_S: f64 = 0.5;

/// The reduced mass `μ = (1/m_H + 1/m_R)⁻¹` \[kg\] of a body region of
/// effective mass `m_h` and the robot of effective mass `m_r` at the point
/// of contact (an infinite `m_h`, a braced body part, gives `m_r`).
pub fn reduced_mass(m_h: f64, m_r: f64) -> f64 {
    1.0 / (1.0 / m_h + 1.0 / m_r)
}

/// The relative speed \[m/s\] at which a transient contact of reduced mass
/// `mu` \[kg\] against a body region of spring constant `k` \[N/m\] peaks at
/// `force` \[N\]: `v = F / √(μ k)` (Annex A, the energy of the impact stored
/// in the region's spring). 0 where `μ k` is no positive number.
pub fn transient_contact_speed(force: f64, k: f64, mu: f64) -> f64 {
    let stiffness_mass = mu * k;
    match stiffness_mass > 0.0 && stiffness_mass.is_finite() {
        true => force / stiffness_mass.sqrt(),
        false => 0.0,
    }
}

/// The robot's effective mass \[kg\] as Annex A's eq. A.5 gives it: half
/// the mass of its moving parts `moving_kg` plus its effective payload
/// `payload_kg` (the tool and what it carries).
pub fn robot_effective_mass(moving_kg: f64, payload_kg: f64) -> f64 {
    moving_kg / 2.0 + payload_kg
}

/// The largest relative speed \[m/s\] at which the robot, of effective mass
/// `m_r` \[kg\], may meet `region` so that a transient contact stays within
/// the region's transient limit (Annex A: `v = F_T / √(μ k)`); 0 for a
/// region where no transient contact is allowed (skull, face) and where the
/// standard gives no spring or mass.
pub fn transient_speed_limit(region: BodyRegion, m_r: f64) -> f64 {
    match (
        region.transient_n(),
        region.spring_n_per_m(),
        region.mass_kg(),
    ) {
        (Some(f), Some(k), Some(m_h)) => transient_contact_speed(f, k, reduced_mass(m_h, m_r)),
        _ => 0.0,
    }
}

/// Transient or quasi-static, by the contact's duration.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum ContactKind {
    /// at most [`TRANSIENT_MAX_S`]: an impact the body part can recoil from
    Transient,
    /// longer than [`TRANSIENT_MAX_S`]: a clamping or a pressing held
    QuasiStatic,
}

impl ContactKind {
    /// `"transient"` or `"quasi_static"`.
    pub fn name(self) -> &'static str {
        match self {
            ContactKind::Transient => "transient",
            ContactKind::QuasiStatic => "quasi_static",
        }
    }
}

/// A contact against its body region's limit.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Judgement {
    /// the body region touched
    pub region: BodyRegion,
    /// transient or quasi-static, by the contact's duration
    pub kind: ContactKind,
    /// the region's limit for this kind of contact \[N\]; 0 for a transient
    /// contact of a region where none is allowed (skull, face)
    pub limit_n: f64,
    /// `limit_n − peak` \[N\] (negative: over the limit)
    pub margin_n: f64,
    /// the peak stayed within the limit
    pub within: bool,
}

/// Judge a contact of `region` that peaked at `peak_n` \[N\] and lasted
/// `duration_s` \[s\] (≤ [`TRANSIENT_MAX_S`]: transient). A peak that is no
/// number is never within the limit.
pub fn judge(region: BodyRegion, peak_n: f64, duration_s: f64) -> Judgement {
    let kind = match duration_s <= TRANSIENT_MAX_S {
        true => ContactKind::Transient,
        false => ContactKind::QuasiStatic,
    };
    let limit_n = match kind {
        ContactKind::Transient => region.transient_n().unwrap_or(0.0),
        ContactKind::QuasiStatic => region.quasi_static_n(),
    };
    let margin_n = limit_n - peak_n;
    Judgement {
        region,
        kind,
        limit_n,
        margin_n,
        within: margin_n >= 0.0 && (kind == ContactKind::QuasiStatic || limit_n > 0.0),
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn the_transient_speed_of_a_hand_worked_by_hand() {
        // hand: 280 N transient, 75 N/mm, 0.6 kg; robot 10 kg at the point:
        // μ = 0.6·10/10.6 = 0.566 kg, √(μ k) = √42 452.8 = 206.04 N s/m,
        // v = 280 / 206.04 = 1.359 m/s
        let mu = reduced_mass(0.6, 10.0);
        assert!((mu - 0.566_037_7).abs() < 1e-6, "{mu}");
        let v = transient_contact_speed(280.0, 75_000.0, mu);
        assert!((v - 1.358_96).abs() < 1e-4, "{v}");
        // a braced hand (infinite mass) meets the robot's mass alone
        assert_eq!(reduced_mass(f64::INFINITY, 10.0), 10.0);
        // 140 N on the hand against a braced 10 kg: 140 / √750 000 = 0.1617 m/s
        let v = transient_contact_speed(140.0, 75_000.0, 10.0);
        assert!((v - 0.161_658).abs() < 1e-5, "{v}");
        assert_eq!(transient_contact_speed(100.0, 75_000.0, 0.0), 0.0);
        assert_eq!(transient_contact_speed(100.0, 75_000.0, f64::NAN), 0.0);
    }

    #[test]
    fn the_speed_limit_toward_a_hand_worked_by_hand() {
        // eq. A.5: an arm whose moving parts weigh 15 kg, 1 kg of tool: 8.5 kg
        let m_r = robot_effective_mass(15.0, 1.0);
        assert_eq!(m_r, 8.5);
        // hand: μ = 0.6·8.5/9.1 = 0.56044 kg, √(μ·75 000) = 205.02 N s/m,
        // v = 280 / 205.02 = 1.3657 m/s
        let v = transient_speed_limit(BodyRegion::HandAndFingers, m_r);
        assert!((v - 1.3657).abs() < 1e-3, "{v}");
        // a heavier robot meets the hand slower
        assert!(transient_speed_limit(BodyRegion::HandAndFingers, 50.0) < v);
        // the face: no transient contact at all
        assert_eq!(transient_speed_limit(BodyRegion::Face, m_r), 0.0);
    }

    #[test]
    fn a_contact_is_judged_by_its_kind_and_region() {
        let hand = BodyRegion::HandAndFingers;
        // a 0.1 s impact of 200 N on the hand: transient, 280 N, 80 N to spare
        let j = judge(hand, 200.0, 0.1);
        assert_eq!(
            (j.kind, j.limit_n, j.margin_n, j.within),
            (ContactKind::Transient, 280.0, 80.0, true)
        );
        // the same force held 2 s: quasi-static, 60 N over
        let j = judge(hand, 200.0, 2.0);
        assert_eq!(
            (j.kind, j.limit_n, j.margin_n, j.within),
            (ContactKind::QuasiStatic, 140.0, -60.0, false)
        );
        // exactly 0.5 s is still transient
        assert_eq!(
            judge(hand, 1.0, TRANSIENT_MAX_S).kind,
            ContactKind::Transient
        );
        // no transient contact of the face is allowed, however light
        let j = judge(BodyRegion::Face, 5.0, 0.05);
        assert_eq!((j.limit_n, j.within), (0.0, false));
        // a held 50 N on the face is within its 65 N
        assert!(judge(BodyRegion::Face, 50.0, 1.0).within);
        assert!(!judge(hand, f64::NAN, 1.0).within);
    }
}
