//! After a restart of the controller (the old one crashed or froze, perhaps
//! with a collaborating hand on the end effector): the new controller cannot
//! know what its predecessor was doing, so it judges what it sees. While a
//! tracked hand is at the robot it holds in a protective stop; it lets the
//! arm recover and resume its task only once every hand has stayed away for
//! a while, also when none was ever seen near (one skeleton in which the
//! tracker lost the person, or the hand hidden by the arm it touches, is no
//! proof that the hand is gone). Without a fresh skeleton it has judged
//! nothing yet (and stays in `sync`), or it keeps holding a hand it has seen
//! near.

use crate::snapshot::{snapshot_fields, Reader, Snapshot, Writer};

/// The judgement of one period.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub enum Hold {
    /// no restart hold (none, or over)
    #[default]
    Clear,
    /// restarted, and no fresh skeleton judged yet
    Judging,
    /// restarted, a hand at the robot (or one seen there, since unseen or
    /// not yet away for long enough)
    HandNear,
}

/// As a byte: 0 clear, 1 judging, 2 a hand near.
impl Snapshot for Hold {
    fn save(&self, w: &mut Writer<'_>) {
        w.u8(match self {
            Hold::Clear => 0,
            Hold::Judging => 1,
            Hold::HandNear => 2,
        });
    }
    fn load(&mut self, r: &mut Reader<'_>) {
        let v = match r.u8() {
            0 => Hold::Clear,
            1 => Hold::Judging,
            2 => Hold::HandNear,
            _ => {
                r.fail();
                Hold::Clear
            }
        };
        r.store(self, v);
    }
}

/// The hold of a restarted controller.
#[derive(Clone, Debug, PartialEq)]
pub struct RestartHold {
    /// a hand nearer than this to the robot's surface is at the robot \[m\]
    clear_m: f64,
    /// every hand farther for this long releases the hold \[s\]
    clear_s: f64,
    /// a skeleton was judged
    judged: bool,
    /// a hand was seen at the robot
    near: bool,
    /// every hand away since \[s\]
    clear_since: Option<f64>,
}

// the distance and time are configuration
snapshot_fields!(RestartHold {
    judged,
    near,
    clear_since
});

impl RestartHold {
    /// A hold with `[collaboration] restart_clear_m` and `release_s`.
    pub fn new(clear_m: f64, clear_s: f64) -> RestartHold {
        RestartHold {
            clear_m,
            clear_s,
            judged: false,
            near: false,
            clear_since: None,
        }
    }

    /// One period at controller time `t` \[s\]: `gap` is the smallest
    /// surface gap between a tracked hand and the robot \[m\] (∞: nobody's
    /// hand tracked), `None` without a fresh skeleton.
    pub fn step(&mut self, t: f64, gap: Option<f64>) -> Hold {
        // still judging, or holding a hand seen near
        let waiting = match self.near {
            true => Hold::HandNear,
            false => Hold::Judging,
        };
        let Some(gap) = gap else {
            // unseen: nothing judged yet, or a hand seen near may still be
            // there; either way the time away starts again
            self.clear_since = None;
            return waiting;
        };
        self.judged = true;
        if gap <= self.clear_m {
            self.near = true;
            self.clear_since = None;
            return Hold::HandNear;
        }
        let since = *self.clear_since.get_or_insert(t);
        match t - since >= self.clear_s {
            true => Hold::Clear,
            false => waiting,
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn no_hand_near_releases_once_every_hand_stayed_away() {
        let mut h = RestartHold::new(0.1, 0.25);
        assert_eq!(h.step(0.0, None), Hold::Judging);
        assert_eq!(h.step(0.1, None), Hold::Judging);
        // nobody tracked in one skeleton: no proof yet, still judging
        assert_eq!(h.step(0.2, Some(f64::INFINITY)), Hold::Judging);
        assert_eq!(h.step(0.3, Some(f64::INFINITY)), Hold::Judging);
        assert_eq!(h.step(0.45, Some(f64::INFINITY)), Hold::Clear);
        // a hand far away at first sight, for release_s
        let mut h = RestartHold::new(0.1, 0.25);
        assert_eq!(h.step(0.0, Some(0.3)), Hold::Judging);
        // a skeleton missing restarts the time away
        assert_eq!(h.step(0.2, None), Hold::Judging);
        assert_eq!(h.step(0.3, Some(0.3)), Hold::Judging);
        assert_eq!(h.step(0.55, Some(0.3)), Hold::Clear);
        // the tracker lost the person in the first skeleton, then the hand
        // at the robot shows: held, as it always was
        let mut h = RestartHold::new(0.1, 0.25);
        assert_eq!(h.step(0.0, Some(f64::INFINITY)), Hold::Judging);
        assert_eq!(h.step(0.03, Some(0.02)), Hold::HandNear);
        assert_eq!(h.step(0.4, Some(0.02)), Hold::HandNear);
    }

    #[test]
    fn a_hand_at_the_robot_holds_until_it_stayed_away() {
        let mut h = RestartHold::new(0.1, 0.25);
        assert_eq!(h.step(0.0, Some(-0.01)), Hold::HandNear);
        // away, but not for long enough; back; unseen (the timer restarts)
        assert_eq!(h.step(0.1, Some(0.2)), Hold::HandNear);
        assert_eq!(h.step(0.3, Some(0.05)), Hold::HandNear);
        assert_eq!(h.step(0.4, Some(0.2)), Hold::HandNear);
        assert_eq!(h.step(0.5, None), Hold::HandNear);
        assert_eq!(h.step(0.6, Some(0.2)), Hold::HandNear);
        assert_eq!(h.step(0.8, Some(0.2)), Hold::HandNear);
        assert_eq!(h.step(0.85, Some(0.2)), Hold::Clear);
    }

    #[test]
    fn the_boundary_counts_as_near() {
        let mut h = RestartHold::new(0.1, 0.0);
        assert_eq!(h.step(0.0, Some(0.1)), Hold::HandNear);
        assert_eq!(h.step(0.0, Some(0.1 + 1e-9)), Hold::Clear);
    }
}
