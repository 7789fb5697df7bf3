//! ISO/TS 15066 (collaborative robots) in numbers, for the controller and
//! the run's report:
//! - [`region`]: the body regions of Annex A, Table A.2, with their
//!   quasi-static and transient force limits, effective spring constants
//!   and masses, and the scripted person's parts mapped onto them;
//! - [`pfl`]: power and force limiting: the transient-contact speed
//!   `v = F / √(μ k)` and a contact judged against its region's limit;
//! - [`ssm`]: speed and separation monitoring: the protective separation
//!   distance `S_p` (clause 5.5.4) with the human speed of ISO 13855.
//!
//! The figures are as two independent public transcriptions give them
//! (REFERENCE §11): check a licensed copy of the standard before any safety
//! claim rests on them.

#![deny(missing_docs)]

pub mod contact;
pub mod pfl;
pub mod region;
pub mod ssm;

pub use contact::{ForceSource, Judged, JudgedContact, Touching, MAX_VIOLATION_TIMES};
pub use pfl::{
    judge, reduced_mass, robot_effective_mass, transient_contact_speed, transient_speed_limit,
    ContactKind, Judgement, TRANSIENT_MAX_S,
};
pub use region::BodyRegion;
pub use ssm::{human_speed, protective_separation_distance, SsmTerms};
