//! Several cameras' views of the same people as one: body trackers'
//! [`Skeleton`]s merged (a joint either camera sees is seen, a person
//! either tracks is tracked), and of the collaborative hand each camera's
//! ingestion refined, the one to act on ([`best_hand`]). Every reader (ingestion's
//! mask, the wave recogniser, the controller's collaboration, the lock-step
//! cell) chooses the same way. Nothing here allocates.

use crate::messages::{HandObservation, Skeleton, SKELETON_JOINTS};

/// Another camera's view of the same people (`other`, the same tracker
/// ids) merged into `into`: a joint seen by either camera is seen, with the
/// position of the camera that sees it more surely; a person tracked by
/// either is tracked. People `into` lacks are added.
pub fn merge_views(into: &mut Skeleton, other: &Skeleton) {
    let n_other = (other.n_people as usize).min(other.people.len());
    for theirs in &other.people[..n_other] {
        let n = (into.n_people as usize).min(into.people.len());
        let capacity = into.people.len();
        match into.people[..n].iter().position(|p| p.id == theirs.id) {
            Some(k) => {
                let mine = &mut into.people[k];
                if theirs.tracked == 0 {
                    continue;
                }
                if mine.tracked == 0 {
                    *mine = *theirs;
                    continue;
                }
                for j in 0..SKELETON_JOINTS {
                    if theirs.confidence[j] > mine.confidence[j] {
                        mine.confidence[j] = theirs.confidence[j];
                        mine.joints[j] = theirs.joints[j];
                    }
                }
            }
            None if n < capacity => {
                into.people[n] = *theirs;
                into.n_people += 1;
            }
            None => {}
        }
    }
}

/// The newest of `views` (by capture time), with every other view captured
/// at most `spread_ns` before it merged in ([`merge_views`]), into `out`: its
/// stamps are the newest view's. A camera whose tracker stopped leaves an
/// old view behind, which then takes no part. False (and `out` untouched)
/// when there is no view.
pub fn merge_newest(views: &[Option<&Skeleton>], spread_ns: u64, out: &mut Skeleton) -> bool {
    let Some(newest) = views.iter().flatten().max_by_key(|s| s.capture_ns).copied() else {
        return false;
    };
    *out = *newest;
    let mut merged_self = false;
    for v in views.iter().flatten() {
        if std::ptr::eq(*v, newest) && !merged_self {
            merged_self = true;
            continue;
        }
        if newest.capture_ns.saturating_sub(v.capture_ns) <= spread_ns {
            merge_views(out, v);
        }
    }
    true
}

/// Of the cameras' observations of the collaborative hand (`None`: that
/// camera has none), in camera order, the one to act on among those
/// captured at most `spread_ns` before the newest: the first camera's that
/// has one, refined or not. A later camera's refinement is taken only when
/// no earlier camera observes the hand (a camera down): each camera's
/// refinement is biased toward its own side of the hand, and in
/// `collaboration-mirrored` the second camera's, taken whenever it had more
/// pixels, declared the contact 4 s before the hand was there (the robot's
/// flange beside the hand in its mask). `None` without any.
pub fn best_hand<'a>(
    hands: &[Option<&'a HandObservation>],
    spread_ns: u64,
) -> Option<&'a HandObservation> {
    let newest = hands.iter().flatten().map(|h| h.capture_ns).max()?;
    hands
        .iter()
        .flatten()
        .find(|h| newest.saturating_sub(h.capture_ns) <= spread_ns)
        .copied()
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::messages::Zeroed;

    fn view(capture_ms: u64, joint: usize, confidence: f64) -> Skeleton {
        let mut s = Skeleton::zeroed();
        s.capture_ns = capture_ms * 1_000_000;
        s.n_people = 1;
        let mut p = s.people[0];
        p.id = 7;
        p.tracked = 1;
        p.confidence[joint] = confidence;
        p.joints[joint] = [capture_ms as f64, 0.0, 0.0];
        s.people[0] = p;
        s
    }

    #[test]
    fn a_joint_either_camera_sees_is_seen() {
        let mut a = Skeleton::zeroed();
        a.n_people = 1;
        a.people[0].id = 7;
        a.people[0].tracked = 1;
        a.people[0].confidence[3] = 0.9;
        a.people[0].joints[3] = [1.0, 0.0, 0.0];
        let mut b = a;
        b.people[0].confidence = [0.0; crate::messages::SKELETON_JOINTS];
        b.people[0].confidence[5] = 0.9;
        b.people[0].joints[5] = [0.0, 2.0, 0.0];
        b.people[0].joints[3] = [9.0, 9.0, 9.0];
        merge_views(&mut a, &b);
        let p = a.people[0];
        assert_eq!((p.confidence[3], p.joints[3]), (0.9, [1.0, 0.0, 0.0]));
        assert_eq!((p.confidence[5], p.joints[5]), (0.9, [0.0, 2.0, 0.0]));
        assert_eq!(p.confidence[0], 0.0);
        // lost by the first camera, tracked by the other: the other's
        let mut lost = a;
        lost.people[0].tracked = 0;
        merge_views(&mut lost, &b);
        assert_eq!(lost.people[0].tracked, 1);
        assert_eq!(lost.people[0].confidence[3], 0.0);
        // someone only the other camera sees is added
        let mut none = Skeleton::zeroed();
        merge_views(&mut none, &b);
        assert_eq!(none.n_people, 1);
        assert_eq!(none.people[0].id, 7);
    }

    #[test]
    fn a_joint_either_camera_sees_is_seen_and_an_old_view_takes_no_part() {
        let a = view(100, 3, 1.0); // sees joint 3
        let b = view(110, 5, 1.0); // sees joint 5, newer
        let mut out = Skeleton::zeroed();
        assert!(merge_newest(&[Some(&a), Some(&b)], 50_000_000, &mut out));
        assert_eq!(out.capture_ns, b.capture_ns, "the newest view's stamps");
        assert_eq!(out.n_people, 1);
        assert_eq!(out.people[0].confidence[3], 1.0);
        assert_eq!(out.people[0].confidence[5], 1.0);
        // a dead camera's view 200 ms old is left out
        let old = view(0, 3, 1.0);
        let mut out = Skeleton::zeroed();
        assert!(merge_newest(&[Some(&old), Some(&b)], 50_000_000, &mut out));
        assert_eq!(out.people[0].confidence[3], 0.0);
        assert!(!merge_newest(&[None, None], 50_000_000, &mut out));
    }

    #[test]
    fn the_first_camera_that_observes_the_hand_is_taken() {
        let hand = |capture_ms: u64, refined: u32, pixels: u32| {
            let mut h = HandObservation::zeroed();
            h.capture_ns = capture_ms * 1_000_000;
            h.refined = refined;
            h.masked_pixels = pixels;
            h
        };
        let hidden = hand(100, 0, 3); // the robot hides it from camera 0
        let seen = hand(90, 1, 400);
        let spread = 50_000_000;
        let best = best_hand(&[Some(&hidden), Some(&seen)], spread);
        assert_eq!(best.map(|h| h.masked_pixels), Some(3));
        // camera 0 down: the next camera's
        let best = best_hand(&[None, Some(&seen)], spread);
        assert_eq!(best.map(|h| h.masked_pixels), Some(400));
        // an old observation of a dead camera takes no part
        let old = hand(10, 1, 900);
        let best = best_hand(&[Some(&old), Some(&hidden)], spread);
        assert_eq!(best.map(|h| h.masked_pixels), Some(3));
        assert!(best_hand(&[None, None], spread).is_none());
    }
}
