//! A channel with two publishers read in the order they published: the
//! controller in charge and its hot standby take turns on `control/status`,
//! `collab/state`, `control/ssm` and `control/barrier`, and a subscriber
//! hands a drain's samples over publisher by publisher, so after the
//! standby's takeover the one now in charge's new samples could come before
//! the other's last ones (a status number going back: a controller restart
//! that never was).

use phri_ipc::{IpcError, Message, Subscriber};

/// A subscriber and the buffer a drain is sorted in (grown once, kept).
pub struct Ordered<T: Message> {
    subscriber: Subscriber<T>,
    /// a sample's publication time [ns]
    stamp: fn(&T) -> u64,
    buffer: Vec<T>,
}

impl<T: Message> Ordered<T> {
    /// Reads `subscriber` in the order of `stamp` (each sample's
    /// publication time).
    pub fn new(subscriber: Subscriber<T>, stamp: fn(&T) -> u64) -> Ordered<T> {
        Ordered {
            subscriber,
            stamp,
            buffer: Vec::new(),
        }
    }

    /// Hand every queued sample to `f` in publication order (samples
    /// stamped alike keep the order they came in); returns how many.
    pub fn drain(&mut self, mut f: impl FnMut(&T)) -> Result<usize, IpcError> {
        self.buffer.clear();
        let buffer = &mut self.buffer;
        let n = self.subscriber.drain(|m| buffer.push(*m))?;
        in_stamp_order(buffer, self.stamp);
        self.buffer.iter().for_each(&mut f);
        Ok(n)
    }
}

/// Sorts `samples` by `stamp`, stably.
fn in_stamp_order<T>(samples: &mut [T], stamp: impl Fn(&T) -> u64) {
    samples.sort_by_key(|m| stamp(m));
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_drain_publisher_by_publisher_is_put_back_in_publication_order() {
        // (stamp, seq): the new one in charge's two samples first, then the
        // other's last two, as a subscriber hands them over
        let mut drained = [(30, 3), (40, 4), (10, 1), (20, 2), (40, 5)];
        in_stamp_order(&mut drained, |m| m.0);
        assert_eq!(drained, [(10, 1), (20, 2), (30, 3), (40, 4), (40, 5)]);
    }
}
