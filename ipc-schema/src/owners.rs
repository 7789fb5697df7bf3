//! Who may publish the channels a safety decision reads, and how late or
//! early a stamp may be: the gate every reader of those channels applies.
//!
//! Each sample carries the process id of the node that sent it (iceoryx2's
//! node id encodes it), so a reader knows the sender of every sample. The
//! supervisor names the process of each service it started (`supervisor/
//! health`); a sample on an owned channel counts only when its sender is a
//! service whose binary publishes that channel ([`PUBLISHERS`]), and a
//! repulsion result only for the points its worker owns. The table is
//! filled by a thread at normal priority and read by the real-time loop:
//! atomics only, no lock, no allocation.

use std::sync::atomic::{AtomicI32, AtomicU64, Ordering};

use crate::messages::MAX_SERVICES;

/// Services whose pids an [`OwnerTable`] holds: as many as
/// `supervisor/health` and `supervisor/health/more` list together (the
/// supervisor's roster holds no more).
pub const MAX_OWNERS: usize = 2 * MAX_SERVICES;

/// The channels whose publishers are owned: what the controller, the
/// residual and the voice recogniser act on, each with the binaries
/// allowed to publish it.
pub const PUBLISHERS: &[(&str, &[&str])] = &[
    ("robot/state", &["phri-sim", "phri-franka"]),
    ("dynamics/residual", &["phri-dynamics"]),
    ("perception/repulsion", &["phri-repulsion"]),
    // the simulated camera's stand-in body tracker, and the tracker on depth
    ("perception/skeleton", &["phri-camera", "phri-tracker"]),
    ("perception/hand", &["phri-perception"]),
    ("hri/request", &["phri-gesture", "phri-voice", "phri-ros2"]),
    ("audio/mic", &["phri-mic"]),
    // the controller in charge's behaviour, adopted by the standby (the
    // standby's own, `control/standby/behaviour`, is owned as this one)
    ("control/behaviour", &["phri-control"]),
];

/// An owned channel by its index in [`PUBLISHERS`].
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct Owned(usize);

impl Owned {
    /// `robot/state`: the joint states
    pub const ROBOT_STATE: Owned = Owned(0);
    /// `dynamics/residual` (and its standby's): the momentum residual
    pub const DYNAMICS_RESIDUAL: Owned = Owned(1);
    /// `perception/repulsion`: the repulsion workers' results
    pub const PERCEPTION_REPULSION: Owned = Owned(2);
    /// `perception/skeleton`: the body tracker's people
    pub const PERCEPTION_SKELETON: Owned = Owned(3);
    /// `perception/hand`: the collaborative hand
    pub const PERCEPTION_HAND: Owned = Owned(4);
    /// `hri/request`: people's requests
    pub const HRI_REQUEST: Owned = Owned(5);
    /// `audio/mic`: the microphone's audio
    pub const AUDIO_MIC: Owned = Owned(6);
    /// `control/behaviour` (and the standby's): the controller's behaviour state
    pub const CONTROL_BEHAVIOUR: Owned = Owned(7);

    /// The owned channel named `name`, if it is one. A further camera's
    /// channel (`perception/1/repulsion`) is owned as the first camera's
    /// (its publishers are the same binaries; its refusals count there).
    pub fn of(name: &str) -> Option<Owned> {
        let name = crate::channels::camera_of_channel(name).map_or(name, |(_, first)| first);
        let name = match name {
            n if n == crate::channels::CONTROL_STANDBY_BEHAVIOUR.name => {
                crate::channels::CONTROL_BEHAVIOUR.name
            }
            n if n == crate::channels::DYNAMICS_RESIDUAL_STANDBY.name => {
                crate::channels::DYNAMICS_RESIDUAL.name
            }
            n if n == crate::channels::ROBOT_STATE_STANDBY.name => {
                crate::channels::ROBOT_STATE.name
            }
            // the controllers' call for the standby's residual
            n if n == crate::channels::DYNAMICS_RESIDUAL_CALL.name => {
                crate::channels::CONTROL_BEHAVIOUR.name
            }
            n => n,
        };
        PUBLISHERS.iter().position(|(c, _)| *c == name).map(Owned)
    }

    /// The channel's name as [`PUBLISHERS`] lists it (a further camera's or a
    /// standby's channel is owned under that name).
    pub fn name(self) -> &'static str {
        PUBLISHERS[self.0].0
    }

    fn binaries(self) -> &'static [&'static str] {
        PUBLISHERS[self.0].1
    }
}

/// Who sent a sample, as far as the gate can tell.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Sender {
    /// a service the supervisor started to publish this channel: its name's
    /// index in the table and, for a repulsion worker, its worker number
    Owner {
        /// the service's index in the table's roles ([`OwnerTable::roles`])
        slot: usize,
        /// its worker number (repulsion workers; `None` for the others)
        worker: Option<u32>,
    },
    /// any other process
    Stranger,
    /// no supervisor: every sender is taken as it is (a service run by
    /// hand, a test, the lock-step cell)
    Unchecked,
}

impl Sender {
    /// Not refused.
    pub fn accepted(self) -> bool {
        self != Sender::Stranger
    }
}

/// Why a reader refused a sample (counted per owned channel).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Refusal {
    /// sent by a process the supervisor did not start for the channel
    Stranger = 0,
    /// stamped later than now plus [`FUTURE_MARGIN_NS`]
    Future = 1,
    /// older than the input's staleness bound
    Stale = 2,
    /// a repulsion result for a point its worker does not own
    NotItsPoint = 3,
}

/// Kinds of [`Refusal`].
pub const REFUSALS: usize = 4;

/// A stamp may be this much later than the reader's present (clocks of
/// the same machine: the order of wake-ups) \[ns\].
pub const FUTURE_MARGIN_NS: u64 = 5_000_000;

/// A stamp later than `now_ns` plus [`FUTURE_MARGIN_NS`] (a forged or
/// broken clock): refused, never latched.
pub fn from_the_future(stamp_ns: u64, now_ns: u64) -> bool {
    stamp_ns > now_ns.saturating_add(FUTURE_MARGIN_NS)
}

/// One configured service: its binary and (repulsion workers) its worker number.
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct ServiceRole {
    /// the service's name in the roster
    pub name: String,
    /// the binary it runs (`phri-repulsion`)
    pub binary: String,
    /// its worker number (repulsion workers; `None` for the others)
    pub worker: Option<u32>,
}

/// The owners of the owned channels: per configured service its role
/// (fixed at start) and its process id (0: down or unknown), kept up to
/// date from `supervisor/health`; and what each owned channel refused.
#[derive(Debug)]
pub struct OwnerTable {
    supervised: bool,
    roles: Vec<ServiceRole>,
    pids: [AtomicI32; MAX_OWNERS],
    refused: [[AtomicU64; REFUSALS]; PUBLISHERS.len()],
    /// the newest stranger's pid per owned channel
    stranger_pid: [AtomicI32; PUBLISHERS.len()],
}

impl OwnerTable {
    /// A table for the configured `roles` (at most [`MAX_OWNERS`]; the
    /// rest are never owners). `supervised`: false accepts every sender.
    pub fn new(mut roles: Vec<ServiceRole>, supervised: bool) -> OwnerTable {
        roles.truncate(MAX_OWNERS);
        OwnerTable {
            supervised,
            roles,
            pids: std::array::from_fn(|_| AtomicI32::new(0)),
            refused: std::array::from_fn(|_| std::array::from_fn(|_| AtomicU64::new(0))),
            stranger_pid: std::array::from_fn(|_| AtomicI32::new(0)),
        }
    }

    /// Every sender accepted (no supervisor).
    pub fn unchecked() -> OwnerTable {
        OwnerTable::new(Vec::new(), false)
    }

    /// Whether senders are checked (false: every sender is
    /// [`Sender::Unchecked`]).
    pub fn supervised(&self) -> bool {
        self.supervised
    }

    /// The configured services.
    pub fn roles(&self) -> &[ServiceRole] {
        &self.roles
    }

    /// The binary of the service in `slot` (see [`Sender::Owner`]).
    pub fn binary(&self, slot: usize) -> &str {
        self.roles.get(slot).map_or("", |r| r.binary.as_str())
    }

    /// Service `name` now runs as `pid` (0: down). Unknown names are ignored.
    pub fn set_pid(&self, name: &str, pid: i32) {
        if let Some(i) = self.roles.iter().position(|r| r.name == name) {
            self.pids[i].store(pid.max(0), Ordering::Release);
        }
    }

    /// The pid the table holds for service `name` (0: none).
    pub fn pid_of(&self, name: &str) -> i32 {
        self.roles
            .iter()
            .position(|r| r.name == name)
            .map_or(0, |i| self.pids[i].load(Ordering::Acquire))
    }

    /// Who `pid` is for `channel`. Allocates nothing, locks nothing.
    pub fn sender(&self, channel: Owned, pid: i32) -> Sender {
        if !self.supervised {
            return Sender::Unchecked;
        }
        if pid <= 0 {
            return Sender::Stranger;
        }
        for (i, role) in self.roles.iter().enumerate() {
            if self.pids[i].load(Ordering::Acquire) == pid
                && channel.binaries().contains(&role.binary.as_str())
            {
                return Sender::Owner {
                    slot: i,
                    worker: role.worker,
                };
            }
        }
        Sender::Stranger
    }

    /// Count a refusal on `channel` (`pid`: the sender, for strangers).
    pub fn refuse(&self, channel: Owned, why: Refusal, pid: i32) {
        self.refused[channel.0][why as usize].fetch_add(1, Ordering::Relaxed);
        if why == Refusal::Stranger {
            self.stranger_pid[channel.0].store(pid, Ordering::Relaxed);
        }
    }

    /// `pid`'s verdict for `channel`, counting a stranger.
    pub fn admit(&self, channel: Owned, pid: i32) -> Sender {
        let s = self.sender(channel, pid);
        if s == Sender::Stranger {
            self.refuse(channel, Refusal::Stranger, pid);
        }
        s
    }

    /// What `channel` refused so far, by [`Refusal`] kind, and the newest
    /// stranger's pid (0: none).
    pub fn refused(&self, channel: Owned) -> ([u64; REFUSALS], i32) {
        (
            std::array::from_fn(|k| self.refused[channel.0][k].load(Ordering::Relaxed)),
            self.stranger_pid[channel.0].load(Ordering::Relaxed),
        )
    }
}

/// The worker number a repulsion worker's arguments give (`--worker N`).
pub fn worker_of(args: &[String]) -> Option<u32> {
    args.windows(2)
        .find(|w| w[0] == "--worker")
        .and_then(|w| w[1].parse().ok())
        .or_else(|| {
            args.iter()
                .find_map(|a| a.strip_prefix("--worker=")?.parse().ok())
        })
}

#[cfg(test)]
mod tests {
    use super::*;

    fn table() -> OwnerTable {
        let role = |name: &str, binary: &str, worker| ServiceRole {
            name: name.into(),
            binary: binary.into(),
            worker,
        };
        let t = OwnerTable::new(
            vec![
                role("sim", "phri-sim", None),
                role("dynamics", "phri-dynamics", None),
                role("repulsion0", "phri-repulsion", Some(0)),
                role("repulsion1", "phri-repulsion", Some(1)),
                role("voice", "phri-voice", None),
            ],
            true,
        );
        t.set_pid("sim", 100);
        t.set_pid("dynamics", 101);
        t.set_pid("repulsion0", 102);
        t.set_pid("repulsion1", 103);
        t.set_pid("voice", 104);
        t
    }

    #[test]
    fn only_the_services_started_for_a_channel_own_it() {
        let t = table();
        let rep = Owned::of("perception/repulsion").unwrap();
        let res = Owned::of("dynamics/residual").unwrap();
        assert_eq!(
            t.sender(rep, 103),
            Sender::Owner {
                slot: 3,
                worker: Some(1)
            }
        );
        // the residual's process may not publish repulsion results, nor a stranger
        assert_eq!(t.sender(rep, 101), Sender::Stranger);
        assert_eq!(t.sender(rep, 999), Sender::Stranger);
        assert!(t.sender(res, 101).accepted());
        assert!(!t.sender(res, 0).accepted());
        // a restart: the old pid is no longer the owner
        t.set_pid("dynamics", 201);
        assert_eq!(t.sender(res, 101), Sender::Stranger);
        assert!(t.sender(res, 201).accepted());
        // down
        t.set_pid("dynamics", 0);
        assert_eq!(t.sender(res, 0), Sender::Stranger);
        // unsupervised: everyone
        assert_eq!(OwnerTable::unchecked().sender(res, 999), Sender::Unchecked);
        assert!(Owned::of("camera/depth").is_none());
        assert_eq!(Owned::of("perception/1/repulsion"), Some(rep));
        assert!(Owned::of("camera/1/depth").is_none());
    }

    #[test]
    fn refusals_are_counted_per_channel_and_kind() {
        let t = table();
        let rep = Owned::of("perception/repulsion").unwrap();
        assert_eq!(t.admit(rep, 4242), Sender::Stranger);
        t.refuse(rep, Refusal::Future, 102);
        t.refuse(rep, Refusal::Future, 102);
        let (counts, pid) = t.refused(rep);
        assert_eq!(counts, [1, 2, 0, 0]);
        assert_eq!(pid, 4242);
        let (other, _) = t.refused(Owned::of("robot/state").unwrap());
        assert_eq!(other, [0; REFUSALS]);
    }

    #[test]
    fn future_stamps_past_the_margin_are_refused() {
        let now = 10_000_000_000u64;
        assert!(!from_the_future(now, now));
        assert!(!from_the_future(now + FUTURE_MARGIN_NS, now));
        assert!(from_the_future(now + FUTURE_MARGIN_NS + 1, now));
        assert!(from_the_future(1 << 63, now));
        assert!(!from_the_future(u64::MAX, u64::MAX));
    }

    #[test]
    fn the_constants_name_their_channels() {
        use crate::channels::*;
        for (o, c) in [
            (Owned::ROBOT_STATE, ROBOT_STATE.name),
            (Owned::DYNAMICS_RESIDUAL, DYNAMICS_RESIDUAL.name),
            (Owned::PERCEPTION_REPULSION, PERCEPTION_REPULSION.name),
            (Owned::PERCEPTION_SKELETON, PERCEPTION_SKELETON.name),
            (Owned::PERCEPTION_HAND, PERCEPTION_HAND.name),
            (Owned::HRI_REQUEST, HRI_REQUEST.name),
            (Owned::AUDIO_MIC, AUDIO_MIC.name),
            (Owned::CONTROL_BEHAVIOUR, CONTROL_BEHAVIOUR.name),
        ] {
            assert_eq!(o.name(), c);
            assert_eq!(Owned::of(c), Some(o));
        }
        let standby = Owned::of(CONTROL_STANDBY_BEHAVIOUR.name);
        assert_eq!(standby, Some(Owned::CONTROL_BEHAVIOUR));
        let residual = Owned::of(DYNAMICS_RESIDUAL_STANDBY.name);
        assert_eq!(residual, Some(Owned::DYNAMICS_RESIDUAL));
        assert_eq!(PUBLISHERS.len(), 8);
    }

    #[test]
    fn worker_numbers_come_from_the_arguments() {
        let a = |v: &[&str]| v.iter().map(|s| s.to_string()).collect::<Vec<_>>();
        assert_eq!(worker_of(&a(&["--worker", "3"])), Some(3));
        assert_eq!(worker_of(&a(&["--worker=2"])), Some(2));
        assert_eq!(worker_of(&a(&["--worker", "x"])), None);
        assert_eq!(worker_of(&a(&[])), None);
    }
}
