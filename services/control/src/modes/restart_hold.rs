//! After a restart of the controller (the old one crashed or froze, perhaps
//! with a collaborating hand on the end effector): the new controller cannot
//! know what its predecessor was doing, so it judges what it sees. While a
//! tracked hand is at the robot it holds in a protective stop; it lets the
//! arm recover and resume its task only once every hand has stayed away for
//! a while. Without a fresh skeleton it has judged nothing yet (and stays in
//! `sync`), or it keeps holding a hand it has seen near.

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
        let Some(gap) = gap else {
            // unseen: nothing judged yet, or a hand seen near may still be there
            self.clear_since = None;
            return match (self.judged, self.near) {
                (false, _) => Hold::Judging,
                (true, true) => Hold::HandNear,
                (true, false) => Hold::Clear,
            };
        };
        self.judged = true;
        if gap <= self.clear_m {
            self.near = true;
            self.clear_since = None;
            return Hold::HandNear;
        }
        if !self.near {
            return Hold::Clear;
        }
        let since = *self.clear_since.get_or_insert(t);
        match t - since >= self.clear_s {
            true => Hold::Clear,
            false => Hold::HandNear,
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn no_hand_near_at_the_first_sight_releases_at_once() {
        let mut h = RestartHold::new(0.1, 0.25);
        assert_eq!(h.step(0.0, None), Hold::Judging);
        assert_eq!(h.step(0.1, None), Hold::Judging);
        assert_eq!(h.step(0.2, Some(f64::INFINITY)), Hold::Clear);
        let mut h = RestartHold::new(0.1, 0.25);
        assert_eq!(h.step(0.0, Some(0.3)), Hold::Clear);
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
