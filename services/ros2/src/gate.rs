//! `/phri/request` on its way to `hri/request`: stops first, every other
//! request rate-limited per peer (the DDS writer that sent it), every
//! refusal counted and logged at most once a second, each text shown cut
//! and escaped. Pure: the caller passes the time.

use std::collections::HashMap;

/// A ROS 2 peer: the GID (16 bytes of the DDS writer's GUID) of the writer
/// that sent a sample.
pub type PeerId = [u8; 16];

/// Characters of a received text a log line shows at most.
pub const TEXT_SHOWN: usize = 64;

/// Peers with a bucket of their own; a peer beyond them (a flood of new
/// writers) shares one bucket with every other such peer.
pub const MAX_PEERS: usize = 64;

/// All peers together: at most this many times one peer's rate and burst.
pub const TOTAL_FACTOR: f64 = 4.0;

/// Nanoseconds between two refusal lines.
pub const LOG_PERIOD_NS: u64 = 1_000_000_000;

/// `text` for a log line: at most [`TEXT_SHOWN`] characters, each control
/// character, quote and backslash escaped (`escape_debug`: a newline shows
/// as `\n` and cannot forge a line), and how long it was when cut.
pub fn shown(text: &str) -> String {
    let mut out = String::new();
    let mut chars = text.chars();
    for c in chars.by_ref().take(TEXT_SHOWN) {
        out.extend(c.escape_debug());
    }
    if chars.next().is_some() {
        out.push_str(&format!("… ({} bytes)", text.len()));
    }
    out
}

/// A token bucket: `burst` tokens at most, refilled at a rate [tokens/s].
#[derive(Clone, Copy, Debug)]
struct Bucket {
    tokens: f64,
    /// when `tokens` was last brought up to date [ns]
    at_ns: u64,
}

impl Bucket {
    fn full(burst: f64, now_ns: u64) -> Bucket {
        Bucket {
            tokens: burst,
            at_ns: now_ns,
        }
    }

    fn refill(&mut self, per_s: f64, burst: f64, now_ns: u64) {
        let dt_s = now_ns.saturating_sub(self.at_ns) as f64 / 1e9;
        self.tokens = (self.tokens + dt_s * per_s).min(burst);
        self.at_ns = self.at_ns.max(now_ns);
    }

    fn is_full(&self, per_s: f64, burst: f64, now_ns: u64) -> bool {
        let mut b = *self;
        b.refill(per_s, burst, now_ns);
        b.tokens >= burst
    }

    fn has_token(&mut self, per_s: f64, burst: f64, now_ns: u64) -> bool {
        self.refill(per_s, burst, now_ns);
        self.tokens >= 1.0
    }
}

/// Requests per peer: a token bucket each ([`MAX_PEERS`] of them, then one
/// shared), and one for all of them together ([`TOTAL_FACTOR`]).
#[derive(Debug)]
pub struct RateLimit {
    /// one peer's sustained rate [requests/s]
    per_s: f64,
    /// one peer's burst [requests]
    burst: f64,
    peers: HashMap<PeerId, Bucket>,
    /// the peers beyond [`MAX_PEERS`]
    others: Option<Bucket>,
    total: Option<Bucket>,
}

impl RateLimit {
    /// `per_s` [requests/s] sustained and `burst` \[requests\] per peer.
    pub fn new(per_s: f64, burst: u32) -> RateLimit {
        RateLimit {
            per_s,
            burst: f64::from(burst.max(1)),
            peers: HashMap::new(),
            others: None,
            total: None,
        }
    }

    /// May `peer` send one more request at `now_ns` [ns, any monotonic
    /// clock]? Takes its token when it may.
    pub fn admit(&mut self, peer: PeerId, now_ns: u64) -> bool {
        let (per_s, burst) = (self.per_s, self.burst);
        let (total_per_s, total_burst) = (per_s * TOTAL_FACTOR, burst * TOTAL_FACTOR);
        if !self.peers.contains_key(&peer) && self.peers.len() >= MAX_PEERS {
            // a peer whose bucket has refilled is as good as new: forget it
            self.peers.retain(|_, b| !b.is_full(per_s, burst, now_ns));
        }
        let own = if self.peers.len() < MAX_PEERS || self.peers.contains_key(&peer) {
            self.peers
                .entry(peer)
                .or_insert_with(|| Bucket::full(burst, now_ns))
        } else {
            self.others
                .get_or_insert_with(|| Bucket::full(burst, now_ns))
        };
        let total = self
            .total
            .get_or_insert_with(|| Bucket::full(total_burst, now_ns));
        if own.has_token(per_s, burst, now_ns) && total.has_token(total_per_s, total_burst, now_ns)
        {
            own.tokens -= 1.0;
            total.tokens -= 1.0;
            true
        } else {
            false
        }
    }

    /// Peers with a bucket of their own now.
    pub fn peers(&self) -> usize {
        self.peers.len()
    }
}

/// Why a `/phri/request` sample did not reach `hri/request`, by kind.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum RefusalKind {
    /// `[ros2] accept_requests = false`
    NotAccepted,
    /// its text is not a request the cell takes from ROS 2
    NotARequest,
    /// its peer sent more than its rate allows
    RateLimited,
    /// DDS could not make a `std_msgs/String` of it
    Malformed,
}

/// Refusals per kind.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub struct Refusals {
    /// `[ros2] accept_requests = false`
    pub not_accepted: u64,
    /// not a request the cell takes from ROS 2
    pub not_a_request: u64,
    /// over their peer's rate limit
    pub rate_limited: u64,
    /// samples DDS could not make a `std_msgs/String` of
    pub malformed: u64,
}

impl Refusals {
    /// Count one refusal of `kind`.
    pub fn add(&mut self, kind: RefusalKind) {
        let n = match kind {
            RefusalKind::NotAccepted => &mut self.not_accepted,
            RefusalKind::NotARequest => &mut self.not_a_request,
            RefusalKind::RateLimited => &mut self.rate_limited,
            RefusalKind::Malformed => &mut self.malformed,
        };
        *n += 1;
    }

    /// Refusals of every kind together.
    pub fn total(&self) -> u64 {
        self.not_accepted + self.not_a_request + self.rate_limited + self.malformed
    }
}

/// Refusals as log lines: at most one per [`LOG_PERIOD_NS`], with the
/// counts since the previous line and the newest refusal (its text
/// [`shown`]).
#[derive(Debug, Default)]
pub struct RefusalLog {
    /// when the last line was given [ns]
    last_ns: Option<u64>,
    pending: Refusals,
    /// the newest refusal not yet in a line, as shown
    newest: Option<String>,
}

impl RefusalLog {
    /// A refusal at `now_ns`: `why` names it, `text` is what was received
    /// (shown cut and escaped). Returns the line to log now, if one is due.
    pub fn note(
        &mut self,
        kind: RefusalKind,
        text: &str,
        why: &str,
        now_ns: u64,
    ) -> Option<String> {
        self.pending.add(kind);
        self.newest = Some(format!("'{}': {why}", shown(text)));
        self.flush(now_ns)
    }

    /// The line for the refusals not yet logged, if a period has passed
    /// since the last one (call it now and then: the last refusals of a
    /// burst are logged once their period is over).
    pub fn flush(&mut self, now_ns: u64) -> Option<String> {
        let n = self.pending.total();
        if n == 0
            || self
                .last_ns
                .is_some_and(|t| now_ns.saturating_sub(t) < LOG_PERIOD_NS)
        {
            return None;
        }
        let p = std::mem::take(&mut self.pending);
        let newest = self.newest.take().unwrap_or_default();
        let since = match self.last_ns {
            Some(t) => format!(" in {:.1} s", now_ns.saturating_sub(t) as f64 * 1e-9),
            None => String::new(),
        };
        self.last_ns = Some(now_ns);
        Some(if n == 1 {
            format!("/phri/request {newest}")
        } else {
            format!(
                "/phri/request: {n} refused{since} (not accepted {}, not a request {}, over the rate limit {}, malformed {}); the last {newest}",
                p.not_accepted, p.not_a_request, p.rate_limited, p.malformed
            )
        })
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    const S: u64 = 1_000_000_000;

    #[test]
    fn a_shown_text_is_cut_and_its_control_characters_escaped() {
        assert_eq!(shown("follow left_hand"), "follow left_hand");
        let forged = shown("stop\n2026-12-02T00:00:00Z INFO phri-supervisor: all clear\r\x1b[2J");
        assert!(!forged.chars().any(char::is_control), "{forged}");
        assert!(forged.starts_with("stop\\n2026"), "{forged}");
        assert!(forged.contains("\\r\\u{1b}[2J"), "{forged}");
        let huge = "x".repeat(10 * 1024 * 1024);
        let s = shown(&huge);
        assert!(s.len() < 100, "{} bytes shown", s.len());
        assert!(s.starts_with(&"x".repeat(TEXT_SHOWN)));
        assert!(s.ends_with("(10485760 bytes)"), "{s}");
        // cut by characters, never inside one
        let wide = "é".repeat(TEXT_SHOWN + 1);
        assert!(shown(&wide).starts_with(&"é".repeat(TEXT_SHOWN)));
        assert_eq!(shown(&"é".repeat(TEXT_SHOWN)), "é".repeat(TEXT_SHOWN));
    }

    #[test]
    fn each_peer_gets_its_burst_then_its_rate() {
        let mut r = RateLimit::new(2.0, 3);
        let (a, b) = ([1; 16], [2; 16]);
        let t0 = 10 * S;
        let passed = (0..10).filter(|_| r.admit(a, t0)).count();
        assert_eq!(passed, 3, "the burst");
        // another peer is not limited by the first one
        assert!(r.admit(b, t0));
        // 2 per second after that: one more every 0.5 s
        assert!(!r.admit(a, t0 + S / 4));
        assert!(r.admit(a, t0 + S / 2));
        assert!(!r.admit(a, t0 + S / 2));
        assert!(r.admit(a, t0 + S));
        // over 10 s of a flood, the burst refilled no further than it holds
        let mut passed = 0;
        for ms in 0..10_000u64 {
            passed += u64::from(r.admit(a, t0 + 2 * S + ms * 1_000_000));
        }
        assert!(
            (20..=23).contains(&passed),
            "{passed} passed in 10 s at 2/s"
        );
    }

    #[test]
    fn a_flood_of_new_peers_shares_one_bucket_and_all_peers_one_total() {
        let mut r = RateLimit::new(1.0, 1);
        let t = 5 * S;
        let mut passed = 0;
        for i in 0..1000u32 {
            let mut peer = [0u8; 16];
            peer[..4].copy_from_slice(&i.to_le_bytes());
            passed += u32::from(r.admit(peer, t));
        }
        // all peers together: TOTAL_FACTOR × the burst
        assert_eq!(passed, TOTAL_FACTOR as u32);
        assert!(r.peers() <= MAX_PEERS);
        // much later every bucket is full again: an idle peer is forgotten,
        // a new one gets a bucket of its own
        assert!(r.admit([0xff; 16], t + 100 * S));
        assert!(r.peers() <= MAX_PEERS);
    }

    #[test]
    fn refusals_are_logged_at_most_once_a_second_with_their_counts() {
        let mut log = RefusalLog::default();
        let t = 100 * S;
        // the first at once, with its text
        let line = log
            .note(RefusalKind::NotAccepted, "begin", "refused", t)
            .unwrap();
        assert_eq!(line, "/phri/request 'begin': refused");
        // a burst within the second: no line
        for k in 0..1000u64 {
            let kind = if k % 2 == 0 {
                RefusalKind::RateLimited
            } else {
                RefusalKind::NotARequest
            };
            assert_eq!(
                log.note(kind, "dance\nforged line", "no", t + k * 100_000),
                None
            );
        }
        assert_eq!(
            log.note(RefusalKind::Malformed, "", "malformed", t + S / 2),
            None
        );
        assert_eq!(log.flush(t + S - 1), None);
        let line = log.flush(t + S).unwrap();
        assert!(
            line.starts_with("/phri/request: 1001 refused in 1.0 s"),
            "{line}"
        );
        assert!(
            line.contains(
                "not accepted 0, not a request 500, over the rate limit 500, malformed 1"
            ),
            "{line}"
        );
        assert!(!line.contains('\n'));
        // nothing new: nothing to log
        assert_eq!(log.flush(t + 5 * S), None);
    }
}
