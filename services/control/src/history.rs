//! The recent joint references of the task with their path time, one entry
//! per control period, for the retreat back along the path.

/// A ring of `(s, q_ref)` entries: path time \[s\] and joint reference \[rad\].
/// Preallocated; `push` and `at` allocate nothing.
#[derive(Clone, Debug)]
pub struct PathHistory {
    n: usize,
    cap: usize,
    data: Vec<f64>,
    /// the slot the next entry goes to
    head: usize,
    /// entries held (at most `cap`), the newest in the slot before `head`
    len: usize,
    /// entries pushed since the start (a peer's count tells which of its
    /// entries this history holds: [`PathHistory::follow`])
    pushes: u64,
}

impl PathHistory {
    /// Room for `cap` entries of `n` joints.
    pub fn new(n: usize, cap: usize) -> PathHistory {
        let cap = cap.max(1);
        PathHistory {
            n,
            cap,
            data: vec![0.0; cap * (n + 1)],
            head: 0,
            len: 0,
            pushes: 0,
        }
    }

    /// Room for `span_s` \[s\] of entries one `period_s` \[s\] apart (and two more).
    pub fn for_span(n: usize, span_s: f64, period_s: f64) -> PathHistory {
        PathHistory::new(n, (span_s.max(0.0) / period_s).ceil() as usize + 2)
    }

    /// Add the newest entry: path time `s` \[s\], reference `q` \[rad\].
    pub fn push(&mut self, s: f64, q: &[f64]) {
        let at = self.head * (self.n + 1);
        self.data[at] = s;
        self.data[at + 1..at + 1 + self.n].copy_from_slice(q);
        self.head = (self.head + 1) % self.cap;
        self.len = (self.len + 1).min(self.cap);
        self.pushes += 1;
    }

    /// Entries pushed since the start.
    pub fn pushes(&self) -> u64 {
        self.pushes
    }

    /// Set the count of entries pushed (a peer's, adopted with its state).
    pub fn set_pushes(&mut self, pushes: u64) {
        self.pushes = pushes;
    }

    /// Mirror a peer's history from its newest entry (`s` \[s\], `q`
    /// \[rad\]) and its count of entries pushed: the entry is taken when it
    /// is the one after this history's newest; one already held changes
    /// nothing; after entries missed (or a peer that started afresh) the
    /// history holds that entry alone, for entries are one period apart. A
    /// hot standby resting through the periods its peer answers keeps the
    /// same entries this way, so that a retreat after its takeover walks the
    /// path back at the path's own pace.
    pub fn follow(&mut self, pushes: u64, s: f64, q: &[f64]) {
        if pushes == self.pushes || pushes == 0 || q.len() != self.n {
            return;
        }
        if pushes != self.pushes + 1 {
            self.len = 0;
        }
        self.push(s, q);
        self.pushes = pushes;
    }

    /// The newest entry: path time \[s\] and reference \[rad\] (`None`: empty).
    pub fn newest(&self) -> Option<(f64, &[f64])> {
        (self.len > 0).then(|| {
            let at = ((self.head + self.cap - 1) % self.cap) * (self.n + 1);
            (self.data[at], &self.data[at + 1..at + 1 + self.n])
        })
    }

    /// Entries held.
    pub fn available(&self) -> usize {
        self.len
    }

    /// Room for this many entries.
    pub fn capacity(&self) -> usize {
        self.cap
    }

    /// Forget all entries.
    pub fn clear(&mut self) {
        self.len = 0;
    }

    /// Forget all but the newest `count` entries.
    pub fn keep_newest(&mut self, count: usize) {
        self.len = self.len.min(count);
    }

    /// The entry `back` entries before the newest (0 = newest; fractional:
    /// interpolated; clamped to the entries held): writes the reference into
    /// `q` \[rad\], returns the path time \[s\]. `None` (and `q` untouched) when
    /// the history is empty.
    pub fn at(&self, back: f64, q: &mut [f64]) -> Option<f64> {
        if self.len == 0 {
            return None;
        }
        let max_back = (self.len - 1) as f64;
        let back = back.clamp(0.0, max_back);
        let (i0, frac) = (back.floor() as usize, back.fract());
        let i1 = (i0 + 1).min(max_back as usize);
        let slot = |i: usize| ((self.head + self.cap - 1 - i) % self.cap) * (self.n + 1);
        let (a, b) = (slot(i0), slot(i1));
        for k in 0..self.n {
            q[k] = self.data[a + 1 + k] * (1.0 - frac) + self.data[b + 1 + k] * frac;
        }
        Some(self.data[a] * (1.0 - frac) + self.data[b] * frac)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn walks_back_interpolating_and_forgets_the_oldest() {
        let mut h = PathHistory::new(1, 4);
        let mut q = [7.0];
        assert_eq!(h.at(0.0, &mut q), None);
        assert_eq!(q, [7.0], "empty: the reference is left alone");
        for k in 0..6 {
            h.push(k as f64, &[10.0 * k as f64]);
        }
        assert_eq!(h.available(), 4);
        assert_eq!(h.at(0.0, &mut q), Some(5.0));
        assert_eq!(q, [50.0]);
        assert_eq!(h.at(1.5, &mut q), Some(3.5));
        assert_eq!(q, [35.0]);
        // clamped to the oldest held (2)
        assert_eq!(h.at(10.0, &mut q), Some(2.0));
    }

    #[test]
    fn a_follower_holds_the_peer_s_entries_one_period_apart() {
        let (mut peer, mut follower) = (PathHistory::new(1, 8), PathHistory::new(1, 8));
        let mut q = [0.0];
        for k in 0..5 {
            peer.push(k as f64, &[10.0 * k as f64]);
            let (s, newest) = peer.newest().unwrap();
            let newest = [newest[0]];
            follower.follow(peer.pushes(), s, &newest);
            // the same message twice (or the follower's own step of it)
            follower.follow(peer.pushes(), s, &newest);
        }
        assert_eq!((follower.available(), follower.pushes()), (5, 5));
        for back in 0..5 {
            assert_eq!(
                follower.at(back as f64, &mut q),
                peer.at(back as f64, &mut q)
            );
        }
        // two entries missed: never a history with a gap, walked back as if
        // its entries were one period apart
        peer.push(5.0, &[50.0]);
        peer.push(6.0, &[60.0]);
        peer.push(7.0, &[70.0]);
        follower.follow(peer.pushes(), 7.0, &[70.0]);
        assert_eq!((follower.available(), follower.pushes()), (1, 8));
        assert_eq!(follower.at(3.0, &mut q), Some(7.0));
        // a peer that started afresh
        follower.follow(1, 0.5, &[1.0]);
        assert_eq!((follower.available(), follower.pushes()), (1, 1));
        assert_eq!(follower.newest().map(|(s, _)| s), Some(0.5));
    }

    #[test]
    fn keeping_the_newest_keeps_the_newest() {
        let mut h = PathHistory::new(1, 4);
        let mut q = [0.0];
        for k in 0..6 {
            h.push(k as f64, &[10.0 * k as f64]);
        }
        h.keep_newest(9);
        assert_eq!(h.available(), 4);
        h.keep_newest(2);
        assert_eq!(h.available(), 2);
        assert_eq!(h.at(0.0, &mut q), Some(5.0));
        assert_eq!(h.at(5.0, &mut q), Some(4.0), "the older ones are gone");
        // the ring goes on from there
        h.push(6.0, &[60.0]);
        assert_eq!(
            (h.available(), h.at(0.0, &mut q), q),
            (3, Some(6.0), [60.0])
        );
        assert_eq!(h.at(2.0, &mut q), Some(4.0));
        h.keep_newest(0);
        assert_eq!(h.at(0.0, &mut q), None);
    }

    #[test]
    fn capacity_follows_the_period() {
        assert_eq!(PathHistory::for_span(7, 1.1, 0.001).cap, 1102);
        assert_eq!(PathHistory::for_span(7, 1.1, 0.002).cap, 552);
    }
}
