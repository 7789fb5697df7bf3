//! Contact episodes from the ground truth, as [`ContactEvent`]s for
//! `sim/contacts`: a `begin` when a (robot object, body part) pair starts
//! touching, an `update` every [`UPDATE_NS`] while it lasts (with the peak
//! force so far) and an `end` once it has been apart for [`END_GAP_NS`]. A
//! handful per second, so that an evaluator that was stalled (its 1 kHz
//! `sim/truth` queue overflowed) still sees every episode. Preallocated:
//! [`ContactLog::step`] allocates nothing.

use phri_ipc::{ContactEvent, ContactPhase, Zeroed, MAX_CONTACTS};

use crate::sim::ContactTruth;

/// Period of the `update` events of an ongoing contact \[ns\].
pub const UPDATE_NS: u64 = 100_000_000;
/// A pair apart this long has ended its episode \[ns\] (a contact that
/// flickers across a few periods is one episode).
pub const END_GAP_NS: u64 = 50_000_000;
/// Episodes followed at once; more are counted in [`ContactLog::overflowed`].
const SLOTS: usize = 2 * MAX_CONTACTS;

#[derive(Clone, Copy, Debug, Default)]
struct Open {
    active: bool,
    robot_object: i32,
    human_part: i32,
    intended: bool,
    episode: u64,
    start_ns: u64,
    last_seen_ns: u64,
    last_event_ns: u64,
    peak: f64,
    force: [f64; 3],
    point: [f64; 3],
}

/// The episodes in progress and the events of the last step.
#[derive(Clone, Debug)]
pub struct ContactLog {
    open: [Open; SLOTS],
    events: Vec<ContactEvent>,
    seq: u64,
    episodes: u64,
    overflowed: u64,
}

impl Default for ContactLog {
    fn default() -> Self {
        ContactLog::new()
    }
}

impl ContactLog {
    /// No episode in progress, no events.
    pub fn new() -> ContactLog {
        ContactLog {
            open: [Open::default(); SLOTS],
            events: Vec::with_capacity(2 * SLOTS),
            seq: 0,
            episodes: 0,
            overflowed: 0,
        }
    }

    /// Contacts that found no free slot (more than 16 pairs at once).
    pub fn overflowed(&self) -> u64 {
        self.overflowed
    }

    fn emit(&mut self, i: usize, phase: ContactPhase, stamp_ns: u64) {
        let o = &mut self.open[i];
        o.last_event_ns = stamp_ns;
        self.seq += 1;
        let mut e = ContactEvent::zeroed();
        e.seq = self.seq;
        e.stamp_ns = stamp_ns;
        e.start_ns = o.start_ns;
        e.episode = o.episode;
        e.phase = phase as u32;
        e.robot_object = o.robot_object;
        e.human_part = o.human_part;
        e.intended = o.intended as u32;
        e.force = if phase == ContactPhase::End {
            [0.0; 3]
        } else {
            o.force
        };
        e.peak_force_n = o.peak;
        e.point = o.point;
        self.events.push(e);
    }

    /// The contacts of the state stamped `stamp_ns` [ns, robot clock]; returns
    /// the events to publish, in order.
    pub fn step(&mut self, stamp_ns: u64, contacts: &[ContactTruth]) -> &[ContactEvent] {
        self.events.clear();
        for c in contacts {
            let (obj, part) = (c.collision as i32, c.part as i32);
            let f = [c.force.x, c.force.y, c.force.z];
            let magnitude = c.force.norm();
            let slot = self
                .open
                .iter()
                .position(|o| o.active && o.robot_object == obj && o.human_part == part);
            let i = match slot {
                Some(i) => i,
                None => match self.open.iter().position(|o| !o.active) {
                    Some(i) => {
                        self.episodes += 1;
                        self.open[i] = Open {
                            active: true,
                            robot_object: obj,
                            human_part: part,
                            intended: c.intended,
                            episode: self.episodes,
                            start_ns: stamp_ns,
                            last_seen_ns: stamp_ns,
                            last_event_ns: stamp_ns,
                            peak: magnitude,
                            force: f,
                            point: [c.point.x, c.point.y, c.point.z],
                        };
                        self.emit(i, ContactPhase::Begin, stamp_ns);
                        continue;
                    }
                    None => {
                        self.overflowed += 1;
                        continue;
                    }
                },
            };
            let o = &mut self.open[i];
            o.last_seen_ns = stamp_ns;
            o.peak = o.peak.max(magnitude);
            o.force = f;
            o.point = [c.point.x, c.point.y, c.point.z];
            if stamp_ns.saturating_sub(o.last_event_ns) >= UPDATE_NS {
                self.emit(i, ContactPhase::Update, stamp_ns);
            }
        }
        for i in 0..SLOTS {
            let o = self.open[i];
            if o.active && stamp_ns.saturating_sub(o.last_seen_ns) >= END_GAP_NS {
                self.emit(i, ContactPhase::End, o.last_seen_ns);
                self.open[i].active = false;
            }
        }
        &self.events
    }

    /// End every episode in progress (the simulator stops): the events to publish.
    pub fn finish(&mut self) -> &[ContactEvent] {
        self.events.clear();
        for i in 0..SLOTS {
            if self.open[i].active {
                let at = self.open[i].last_seen_ns;
                self.emit(i, ContactPhase::End, at);
                self.open[i].active = false;
            }
        }
        &self.events
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use nalgebra::Vector3;
    use phri_ipc::BodyPart;

    fn contact(obj: usize, part: BodyPart, f: f64) -> ContactTruth {
        ContactTruth {
            collision: obj,
            part,
            intended: part == BodyPart::HandRight,
            force: Vector3::new(f, 0.0, 0.0),
            point: Vector3::new(0.5, 0.0, 0.5),
            depth: 0.001,
        }
    }

    fn phases(e: &[ContactEvent]) -> Vec<(u64, ContactPhase)> {
        e.iter()
            .map(|e| (e.episode, ContactPhase::try_from(e.phase).unwrap()))
            .collect()
    }

    #[test]
    fn an_episode_begins_updates_and_ends_with_its_peak() {
        let mut log = ContactLog::new();
        let ms = 1_000_000u64;
        assert!(log.step(ms, &[]).is_empty());
        let c = contact(3, BodyPart::ForearmLeft, 10.0);
        assert_eq!(phases(log.step(2 * ms, &[c])), [(1, ContactPhase::Begin)]);
        let mut updates = 0;
        for k in 3..=350u64 {
            let f = if k == 200 { 80.0 } else { 10.0 };
            let e = log
                .step(k * ms, &[contact(3, BodyPart::ForearmLeft, f)])
                .to_vec();
            updates += e.len();
            for e in &e {
                assert_eq!(ContactPhase::try_from(e.phase), Ok(ContactPhase::Update));
                assert_eq!(e.start_ns, 2 * ms);
            }
        }
        assert_eq!(updates, 3, "every 100 ms over 348 ms");
        // a short gap is the same episode
        for k in 351..=380u64 {
            assert!(log.step(k * ms, &[]).is_empty());
        }
        assert!(log.step(381 * ms, &[c]).is_empty());
        for k in 382..431u64 {
            assert!(log.step(k * ms, &[]).is_empty(), "{k}");
        }
        let end = log.step(431 * ms, &[]).to_vec();
        assert_eq!(phases(&end), [(1, ContactPhase::End)]);
        assert_eq!(end[0].peak_force_n, 80.0);
        assert_eq!(end[0].stamp_ns, 381 * ms, "ends when last seen");
        assert_eq!(end[0].force, [0.0; 3]);
        // the next contact is a new episode; several pairs at once are separate
        let e = log
            .step(500 * ms, &[c, contact(4, BodyPart::HandRight, 5.0)])
            .to_vec();
        assert_eq!(
            phases(&e),
            [(2, ContactPhase::Begin), (3, ContactPhase::Begin)]
        );
        assert_eq!(e[1].intended, 1);
        assert_eq!(
            phases(log.finish()),
            [(2, ContactPhase::End), (3, ContactPhase::End)]
        );
        // sequence numbers count every event
        assert_eq!(log.seq, 1 + 3 + 1 + 2 + 2);
    }
}
