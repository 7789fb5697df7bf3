//! Watching the controller's `hri/request` queue for requests it may have
//! lost. The queue never drops a request for a newer one; a publisher that
//! finds it full waits [`DELIVERY_WAIT`] and then leaves this reader out.
//! A queue found full after going unread for that whole wait is therefore
//! the one sign that a request (maybe a `stop`) passed this controller by.

use phri_ipc::{DELIVERY_WAIT, HRI_REQUEST};

/// The depth of a controller's `hri/request` queue.
pub const REQUEST_QUEUE: usize = HRI_REQUEST.qos.subscriber_max_buffer;
/// Requests taken per period at most: twice the queue, so that every
/// period empties it (more, arrived while it was read, wait for the next).
pub const MAX_REQUESTS: usize = 2 * REQUEST_QUEUE;

/// How long a loss seen while this controller is not in charge still stops
/// it when it takes charge \[s\]: both controllers of a hot standby stalled
/// together, the one that read its full queue first may still be the
/// standby while the robot hands the charge over to it.
pub const LOSS_HOLD: std::time::Duration = std::time::Duration::from_secs(1);

/// When the queue was last read and how often it may have lost requests.
/// Allocates nothing.
#[derive(Clone, Copy, Debug, Default)]
pub struct RequestQueueWatch {
    /// when the queue was last read [ns, CLOCK_MONOTONIC]
    read_ns: Option<u64>,
    /// occasions on which requests may have been lost (`collab/state`'s
    /// `requests_dropped`)
    dropped: u32,
    /// the last loss not yet acted on, when it was seen [ns, CLOCK_MONOTONIC]
    unanswered_ns: Option<u64>,
}

impl RequestQueueWatch {
    /// The queue was just read at `now_ns`, `taken` requests from it: true
    /// when it was full after going unread for the publishers' whole wait,
    /// so that a publisher may have left this controller out (counted once).
    pub fn read(&mut self, taken: usize, now_ns: u64) -> bool {
        let unread_ns = self.read_ns.map_or(0, |t| now_ns.saturating_sub(t));
        self.read_ns = Some(now_ns);
        let lost = taken >= REQUEST_QUEUE && unread_ns >= DELIVERY_WAIT.as_nanos() as u64;
        if lost {
            self.dropped = self.dropped.saturating_add(1);
            self.unanswered_ns = Some(now_ns);
        }
        lost
    }

    /// After [`read`](Self::read) at `now_ns`: must the controller stop as
    /// if a lost request had been a stop? Yes once, the first time it is in
    /// charge within [`LOSS_HOLD`] of a loss (a loss seen as the standby is
    /// the one in charge's to answer, unless the charge comes here).
    pub fn stop_for_loss(&mut self, in_charge: bool, now_ns: u64) -> bool {
        let Some(seen) = self.unanswered_ns else {
            return false;
        };
        if now_ns.saturating_sub(seen) > LOSS_HOLD.as_nanos() as u64 {
            self.unanswered_ns = None;
            return false;
        }
        if in_charge {
            self.unanswered_ns = None;
        }
        in_charge
    }

    /// Occasions on which requests may have been lost since the start.
    pub fn dropped(&self) -> u32 {
        self.dropped
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    const WAIT: u64 = DELIVERY_WAIT.as_nanos() as u64;

    #[test]
    fn a_full_queue_counts_only_after_the_publishers_whole_wait() {
        let mut w = RequestQueueWatch::default();
        // the first read has nothing to compare with
        assert!(!w.read(REQUEST_QUEUE, 1_000));
        // full, but read again within the wait: the publishers still wait
        assert!(!w.read(REQUEST_QUEUE, 1_000 + WAIT - 1));
        // unread for the whole wait, but not full: nothing was left out
        assert!(!w.read(REQUEST_QUEUE - 1, 1_000 + 2 * WAIT));
        // full after the whole wait: counted, once per occasion
        assert!(w.read(REQUEST_QUEUE, 1_000 + 3 * WAIT));
        assert!(!w.read(REQUEST_QUEUE, 1_000 + 3 * WAIT + 1));
        assert_eq!(w.dropped(), 1);
    }

    #[test]
    fn a_loss_stops_the_controller_in_charge_once_even_if_the_charge_comes_later() {
        const HOLD: u64 = LOSS_HOLD.as_nanos() as u64;
        let mut w = RequestQueueWatch::default();
        assert!(!w.stop_for_loss(true, 0));
        w.read(0, 1_000);
        assert!(w.read(REQUEST_QUEUE, 1_000 + WAIT));
        // seen as the standby: nothing yet; in charge a period later: stop, once
        assert!(!w.stop_for_loss(false, 1_000 + WAIT));
        assert!(w.stop_for_loss(true, 1_000 + WAIT + 1_000_000));
        assert!(!w.stop_for_loss(true, 1_000 + WAIT + 2_000_000));
        // a loss whose hold ran out as the standby stops nobody
        let t = 1_000 + 2 * WAIT + HOLD;
        w.read(0, t);
        assert!(w.read(REQUEST_QUEUE, t + WAIT));
        assert!(!w.stop_for_loss(false, t + WAIT));
        assert!(!w.stop_for_loss(true, t + WAIT + HOLD + 1));
        assert_eq!(w.dropped(), 2);
    }
}
