//! The voice scenario in lock-step: the scenario's recorded speech in 20 ms
//! chunks on robot time, through the same recogniser `phri-voice` runs (its
//! segmenter, pocketsphinx, the hand gate on the simulated tracker's
//! skeleton), into the controller. Deterministic: the same verdicts and
//! phases on every run.

use crate::common;

use phri_cell::CellOptions;

#[test]
fn voice_starts_and_ends_the_collaboration_and_the_rest_is_refused() {
    let s = common::run("voice-collaboration", 22.0, &CellOptions::default(), &[]);
    let heard: Vec<(&str, &str)> = s
        .voice
        .iter()
        .map(|v| (v.intent.as_str(), v.verdict.as_str()))
        .collect();
    eprintln!("heard: {:?}", s.voice);
    eprintln!("modes: {:?}", s.modes);
    assert_eq!(heard.len(), 4, "{heard:?}");
    // out of the camera's view: the gate; "hand me the wrench": no command
    assert_eq!(heard[0], ("follow_right_hand", "hand_not_tracked"));
    assert!(["no_match", "low_score"].contains(&heard[1].1), "{heard:?}");
    assert_eq!(heard[2], ("follow_left_hand", "accepted"));
    assert_eq!(heard[3], ("end", "accepted"));
    let (follow_t, end_t) = (s.voice[2].t_s, s.voice[3].t_s);
    // the speech is where the scenario puts it (7.5 s + 1.5 s, 14.5 s + 1.4 s)
    assert!(
        (8.5..9.8).contains(&follow_t) && (15.3..16.6).contains(&end_t),
        "{heard:?}"
    );
    let first = |mode: &str, after: f64| {
        s.modes
            .iter()
            .find(|(t, m)| m == mode && *t >= after)
            .map(|(t, _)| *t)
    };
    let approach = first("approach", 0.0).expect("an approach");
    assert!(
        approach >= follow_t && approach < follow_t + 1.0,
        "{:?}",
        s.modes
    );
    let contact = first("contact", approach).expect("a contact");
    // nothing collaborates before the follow, and the collaboration is over
    // within a second of "end collaboration"; then the task resumes
    let collab = ["approach", "contact", "follow", "back_off"];
    assert!(s
        .modes
        .iter()
        .all(|(t, m)| !collab.contains(&m.as_str()) || *t >= follow_t));
    let over = s
        .modes
        .iter()
        .find(|(t, m)| *t >= end_t && !collab.contains(&m.as_str()))
        .map(|(t, _)| *t)
        .expect("the collaboration ends");
    assert!(over < end_t + 1.0, "{:?}", s.modes);
    assert!(
        s.modes
            .iter()
            .all(|(t, m)| !collab.contains(&m.as_str()) || *t < over),
        "{:?}",
        s.modes
    );
    assert!(first("task", end_t).is_some(), "{:?}", s.modes);
    // the left hand touched, nothing else, no force above the hand's limit
    assert_eq!(s.unintended_contacts, 0, "{:?}", s.contacts);
    assert!(
        s.contacts
            .iter()
            .any(|c| c.part == "hand_left" && c.t_start_s >= contact - 0.5),
        "{:?}",
        s.contacts
    );
    // the collaboration's force limit (0.5 × 140 N) where F̂ is estimated,
    // on link 7; on the wrist, which this hand, still coming in at 0.3 m/s
    // when the approach starts, meets first, F̂ sees the force late (known,
    // BENCHMARKS.md: over 70 N in 6 of the 9 phases of the sweep; 102 N
    // at this one, 115 N with deploy/points-8.toml): there ISO/TS 15066's
    // quasi-static hand limit itself, as tests/system.rs bounds it
    for c in &s.contacts {
        let limit = if c.link == "lwr_link_7" { 70.0 } else { 140.0 };
        assert!(c.peak_force_n <= limit, "{c:?} above {limit} N");
    }
}
