//! Who publishes on the robot's command channels and on the owned ones:
//! each channel's service opened once, then only its publisher list read.

use phri_ipc::{IpcError, IpcNode, PublisherWatch, ROBOT_COMMAND, ROBOT_COMMAND_STANDBY};

use super::procfs::{alive, cmdline_of};
use crate::owned;
use crate::supervision::{Event, Supervision};

/// The watches over the command and owned channels.
pub struct Publishers {
    commands: [PublisherWatch; 2],
    owned: Vec<PublisherWatch>,
    /// channels that could not be read so far
    errors: u64,
}

impl Publishers {
    /// Watches over the command channels and every owned channel (the
    /// further cameras' too, of `cameras`).
    pub fn new(cameras: usize) -> Publishers {
        Publishers {
            commands: [
                ROBOT_COMMAND.publisher_watch(),
                ROBOT_COMMAND_STANDBY.publisher_watch(),
            ],
            owned: owned_watches(cameras),
            errors: 0,
        }
    }

    /// Read the publishers: a process on a command channel that the
    /// supervision does not run (the first found), then each stranger on an
    /// owned channel not reported yet. A channel that cannot be read now
    /// (being removed as its last user exits) is read again at the next watch.
    pub fn read(&mut self, node: &IpcNode, sup: &Supervision, me: i32) -> Vec<Event> {
        let mut events = Vec::new();
        let mut intruder = None;
        for channel in self.commands.iter_mut() {
            let pid = channel
                .publisher_pids(node)
                .unwrap_or_else(|e| watch_error(e, &mut self.errors))
                .unwrap_or_default()
                .into_iter()
                .find(|&p| p > 0 && !sup.roster().runs(p as u32) && alive(p));
            if let Some(pid) = pid {
                intruder.get_or_insert((pid, channel.name()));
            }
        }
        if let Some((pid, channel)) = intruder {
            events.push(Event::CommandIntruder {
                pid,
                who: cmdline_of(pid),
                channel,
            });
        }
        // the owned channels: a stranger's messages are refused by their
        // readers; it is reported once per channel and process
        for watch in self.owned.iter_mut() {
            let channel = watch.name();
            let pids = watch
                .publisher_pids(node)
                .unwrap_or_else(|e| watch_error(e, &mut self.errors))
                .unwrap_or_default();
            for pid in owned::strangers(channel, &pids, sup.roster(), me) {
                let reported = events
                    .iter()
                    .any(|e| matches!(e, Event::Stranger { channel: c, pid: p, .. } if *c == channel && *p == pid));
                if reported || sup.stranger_known(channel, pid) || !alive(pid) {
                    continue;
                }
                events.push(Event::Stranger {
                    channel,
                    pid,
                    who: cmdline_of(pid),
                });
            }
        }
        events
    }
}

/// A watch over each owned channel (the further cameras' too) that the
/// supervisor reads for strangers.
fn owned_watches(n_cameras: usize) -> Vec<PublisherWatch> {
    use phri_ipc::*;
    let mut watches = Vec::new();
    for (name, _) in owners::PUBLISHERS {
        let watch = match *name {
            n if n == ROBOT_STATE.name => ROBOT_STATE.publisher_watch(),
            n if n == DYNAMICS_RESIDUAL.name => DYNAMICS_RESIDUAL.publisher_watch(),
            n if n == PERCEPTION_REPULSION.name => PERCEPTION_REPULSION.publisher_watch(),
            n if n == PERCEPTION_SKELETON.name => PERCEPTION_SKELETON.publisher_watch(),
            n if n == PERCEPTION_HAND.name => PERCEPTION_HAND.publisher_watch(),
            n if n == HRI_REQUEST.name => HRI_REQUEST.publisher_watch(),
            n if n == AUDIO_MIC.name => AUDIO_MIC.publisher_watch(),
            _ => continue,
        };
        watches.push(watch);
    }
    // the robot's call to the resting standby, owned as its states
    watches.push(ROBOT_STATE_STANDBY.publisher_watch());
    // the controllers' call for the standby's residual, owned as their behaviour
    watches.push(DYNAMICS_RESIDUAL_CALL.publisher_watch());
    for c in CAMERAS.iter().take(n_cameras).skip(1) {
        watches.push(c.repulsion.publisher_watch());
        watches.push(c.skeleton.publisher_watch());
        watches.push(c.hand.publisher_watch());
    }
    watches
}

/// A channel the supervisor's watch could not read: logged (the first and
/// then every 100th), the channel taken as having no publisher this time.
fn watch_error(e: IpcError, count: &mut u64) -> Option<Vec<i32>> {
    *count += 1;
    if *count == 1 || count.is_multiple_of(100) {
        tracing::warn!("watch ({count} so far): {e}");
    }
    None
}
