//! Inputs cut at the state: with a hot standby, a message published after
//! the robot state the controllers answer waits for the next state. Two
//! controllers answering the same state then act on the same perception,
//! however late in the period each of them woke, and a takeover near a
//! person is as bumpless as one in free space. The price: a result
//! published during a period is acted on from the next state on (at most
//! one period, 1 ms, on 33 ms frames).
//!
//! The cut is the state's publication time [ns, CLOCK_MONOTONIC]: whatever
//! was published before it is in shared memory when either controller
//! wakes for that state. `u64::MAX` cuts nothing (one controller alone).

/// A message stamped with its publication time.
pub trait Published: Copy {
    /// publication time [ns, CLOCK_MONOTONIC]
    fn published_ns(&self) -> u64;
}

impl Published for phri_ipc::RepulsionResult {
    fn published_ns(&self) -> u64 {
        self.published_ns
    }
}

impl Published for phri_ipc::Skeleton {
    fn published_ns(&self) -> u64 {
        self.published_ns
    }
}

impl Published for phri_ipc::HandObservation {
    fn published_ns(&self) -> u64 {
        self.published_ns
    }
}

/// The messages of draining channels (every one counts: the repulsion
/// workers' results), each tagged with its source (the camera), held back
/// until a state published after them. Preallocated; nothing allocates
/// after construction.
#[derive(Clone, Debug)]
pub struct HeldBack<T> {
    held: Vec<(usize, T)>,
    /// messages handed over before their cut because the store was full
    forced: u64,
}

impl<T: Published> HeldBack<T> {
    /// Room for `capacity` held messages (at least one).
    pub fn with_capacity(capacity: usize) -> HeldBack<T> {
        HeldBack {
            held: Vec::with_capacity(capacity.max(1)),
            forced: 0,
        }
    }

    /// Hand `take` every held message published by `cut_ns`, oldest first;
    /// keep the rest.
    pub fn release(&mut self, cut_ns: u64, mut take: impl FnMut(usize, &T)) {
        self.held.retain(|(source, m)| {
            let due = m.published_ns() <= cut_ns;
            if due {
                take(*source, m);
            }
            !due
        });
    }

    /// A new message from `source`: handed to `take` now when published by
    /// `cut_ns`, else held for a later state. When the store is full its
    /// oldest message is handed over first (counted in
    /// [`HeldBack::forced`]: the two controllers may differ for a period).
    pub fn offer(&mut self, source: usize, msg: &T, cut_ns: u64, mut take: impl FnMut(usize, &T)) {
        if msg.published_ns() <= cut_ns {
            take(source, msg);
            return;
        }
        if self.held.len() == self.held.capacity() {
            let (s, m) = self.held.remove(0);
            take(s, &m);
            self.forced += 1;
        }
        self.held.push((source, *msg));
    }

    /// Messages held now.
    pub fn len(&self) -> usize {
        self.held.len()
    }

    /// Nothing held.
    pub fn is_empty(&self) -> bool {
        self.held.is_empty()
    }

    /// Messages handed over before their cut (the store was full).
    pub fn forced(&self) -> u64 {
        self.forced
    }
}

/// The newest message of a channel read for its latest value (a camera's
/// skeleton, its refined hand), as of the cut: a newer one published after
/// the cut is held until the next state.
#[derive(Clone, Copy, Debug)]
pub struct CutLatest<T> {
    current: Option<T>,
    held: Option<T>,
}

impl<T> Default for CutLatest<T> {
    fn default() -> Self {
        CutLatest {
            current: None,
            held: None,
        }
    }
}

impl<T: Published> CutLatest<T> {
    /// The state published at `cut_ns`: a held message published by then
    /// becomes current.
    pub fn release(&mut self, cut_ns: u64) {
        if let Some(h) = self.held.filter(|h| h.published_ns() <= cut_ns) {
            self.current = Some(h);
            self.held = None;
        }
    }

    /// The channel's newest message (offered again every period, or only
    /// when new: the same message twice changes nothing). One older than
    /// what is current or held is ignored.
    pub fn offer(&mut self, msg: &T, cut_ns: u64) {
        let t = msg.published_ns();
        let newer = |x: &Option<T>| x.is_none_or(|x| t > x.published_ns());
        if t <= cut_ns {
            if newer(&self.current) {
                self.current = Some(*msg);
            }
        } else if newer(&self.held) {
            self.held = Some(*msg);
        }
    }

    /// The newest message published by the last cut.
    pub fn get(&self) -> Option<&T> {
        self.current.as_ref()
    }

    /// One state's step: the state published at `cut_ns`, the channel's
    /// newest message `newest` (if any); the newest published by the cut.
    pub fn take(&mut self, newest: Option<&T>, cut_ns: u64) -> Option<&T> {
        self.release(cut_ns);
        if let Some(m) = newest {
            self.offer(m, cut_ns);
        }
        self.get()
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[derive(Clone, Copy, Debug, PartialEq)]
    struct M(u64, u32);

    impl Published for M {
        fn published_ns(&self) -> u64 {
            self.0
        }
    }

    /// Two controllers woken at different moments of the same period see
    /// different sets of messages; after the cut they act on the same ones.
    #[test]
    fn two_controllers_woken_apart_take_the_same_messages() {
        // messages published at 100, 900 (before the state at 1000) and
        // 1100 (after it); the next state is published at 2000
        let before = [M(100, 0), M(900, 1)];
        let after = M(1100, 2);
        let (mut early, mut late) = (HeldBack::with_capacity(4), HeldBack::with_capacity(4));
        let (mut took_early, mut took_late) = (vec![], vec![]);
        // the early one woke before 1100: it sees only the first two
        for m in &before {
            early.offer(0, m, 1000, |_, m| took_early.push(*m));
        }
        // the late one woke after 1100: it sees all three
        for m in before.iter().chain([&after]) {
            late.offer(0, m, 1000, |_, m| took_late.push(*m));
        }
        assert_eq!(took_early, took_late, "the same messages for state 1000");
        assert_eq!(late.len(), 1);
        // next state: the early one now receives the third, the late one releases it
        early.release(2000, |_, m| took_early.push(*m));
        early.offer(0, &after, 2000, |_, m| took_early.push(*m));
        late.release(2000, |_, m| took_late.push(*m));
        assert_eq!(took_early, took_late, "the same messages for state 2000");
        assert!(early.is_empty() && late.is_empty());
        assert_eq!(took_late, vec![M(100, 0), M(900, 1), M(1100, 2)]);
    }

    #[test]
    fn nothing_is_cut_at_the_end_of_time_and_a_full_store_hands_the_oldest_over() {
        let mut h = HeldBack::with_capacity(2);
        let mut took = vec![];
        h.offer(1, &M(5, 0), u64::MAX, |s, m| took.push((s, *m)));
        assert_eq!(took, vec![(1, M(5, 0))]);
        took.clear();
        for k in 0..3 {
            h.offer(k, &M(10 + k as u64, 0), 1, |s, m| took.push((s, *m)));
        }
        assert_eq!(took, vec![(0, M(10, 0))], "the oldest, forced");
        assert_eq!((h.len(), h.forced()), (2, 1));
        // the sources travel with the messages
        h.release(11, |s, m| took.push((s, *m)));
        assert_eq!(took.last(), Some(&(1, M(11, 0))));
        assert_eq!(h.len(), 1);
    }

    #[test]
    fn the_latest_as_of_the_cut() {
        let mut l = CutLatest::default();
        assert_eq!(l.get(), None);
        l.offer(&M(900, 1), 1000);
        l.offer(&M(1100, 2), 1000);
        assert_eq!(l.get(), Some(&M(900, 1)), "1100 waits for the next state");
        // offered again: nothing changes; an older one is ignored
        l.offer(&M(1100, 2), 1000);
        l.offer(&M(500, 0), 1000);
        assert_eq!(l.get(), Some(&M(900, 1)));
        l.release(2000);
        assert_eq!(l.get(), Some(&M(1100, 2)));
        // a controller that first sees 1100 at state 2000 agrees
        let mut m = CutLatest::default();
        assert_eq!(m.take(Some(&M(900, 1)), 1000), Some(&M(900, 1)));
        assert_eq!(m.take(Some(&M(1100, 2)), 2000), l.get());
        assert_eq!(m.take(None, 3000), Some(&M(1100, 2)));
    }
}
