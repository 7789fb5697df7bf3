//! One period's inputs gathered from the channels: the newest residual, every
//! camera's repulsion results, the pending requests and the collaboration's
//! skeleton and hand; with a hot standby, the perception as of the state's
//! publication ([`crate::cut`]), so both controllers act on the same inputs.

use phri_ipc::{
    HandObservation, HriRequest, IpcError, JointState, LatestReader, Skeleton, Subscriber, Zeroed,
    MAX_CAMERAS,
};

use super::channels::InputChannels;
use crate::cut::{CutLatest, HeldBack};
use crate::requests::{RequestQueueWatch, MAX_REQUESTS};
use crate::standby::{fresher_residual, residual_wanted};
use crate::{CollabInput, ControlInput, InputError, InputGate, RepulsionInputs};

/// The buffers one period's inputs are gathered into, allocated once.
pub struct Intake {
    /// every camera's results, fused point by point
    repulsion: RepulsionInputs,
    /// whether the controller avoids obstacles (perception given to it)
    avoidance: bool,
    /// whether the collaboration reads skeletons and hands
    collaborating: bool,
    /// the model's degrees of freedom
    n: usize,
    /// whether a hot standby answers the same states
    with_standby: bool,
    /// the widest spread of capture times merged [ns]
    spread_ns: u64,
    /// with a standby, results published after the state, held back
    held_results: HeldBack<phri_ipc::RepulsionResult>,
    cut_skeletons: [CutLatest<Skeleton>; MAX_CAMERAS],
    cut_hands: [CutLatest<HandObservation>; MAX_CAMERAS],
    /// the cameras' skeletons merged
    skeleton: Skeleton,
    /// this period's requests
    pending: Vec<HriRequest>,
    /// the requests this controller may have lost (collab/state's requests_dropped)
    pub request_watch: RequestQueueWatch,
}

/// One period's inputs, and whether a lost request calls for a stop.
pub struct Gathered<'a> {
    /// the step's input for this state
    pub input: ControlInput<'a>,
    /// a request lost may have been a stop: the controller in charge stops
    pub requests_lost: bool,
    /// with a standby, `dynamics/residual` is missing, not valid or behind:
    /// the one in charge calls the standby's ([`residual_wanted`])
    pub residual_late: bool,
}

impl Intake {
    /// The buffers of a cell as `cfg` describes it, `repulsion` its cameras'
    /// accumulator, for an `n`-joint model.
    pub fn new(
        cfg: &phri_config::Config,
        repulsion: RepulsionInputs,
        n: usize,
        with_standby: bool,
    ) -> Intake {
        let cameras = phri_ipc::cameras(repulsion.cameras()).len();
        Intake {
            avoidance: cfg.control.avoidance,
            collaborating: cfg.collaboration.enabled,
            n,
            with_standby,
            spread_ns: (cfg.control.perception_max_age_ms * 1e6) as u64,
            held_results: HeldBack::with_capacity(
                4 * cfg.repulsion.workers.max(1) as usize * cameras,
            ),
            cut_skeletons: [CutLatest::default(); MAX_CAMERAS],
            cut_hands: [CutLatest::default(); MAX_CAMERAS],
            skeleton: Skeleton::zeroed(),
            pending: vec![HriRequest::zeroed(); MAX_REQUESTS],
            request_watch: RequestQueueWatch::default(),
            repulsion,
        }
    }

    /// The inputs of `state` from `ch`, each message through `gate`;
    /// `in_charge`: whether this controller is (or, as the standby, may
    /// become) the one in charge. `Ok(Err)`: the state is refused (then no
    /// request is taken).
    pub fn gather<'a>(
        &'a mut self,
        ch: &'a mut InputChannels,
        gate: &InputGate,
        state: &'a JointState,
        in_charge: bool,
    ) -> Result<Result<Gathered<'a>, InputError>, IpcError> {
        let now = state.stamp_ns;
        // two controllers answering this state act on what was published before it
        let cut = match self.with_standby {
            true => state.published_ns,
            false => u64::MAX,
        };
        let n = self.n;
        // the newest residual of this robot's dof; an older one stays until then
        ch.residuals
            .update_from(|pid, r| r.dof as usize == n && gate.residual(pid, r, now))?;
        if let Some(s) = ch.standby_residuals.as_mut() {
            s.update_from(|pid, r| r.dof as usize == n && gate.residual(pid, r, now))?;
        }
        self.gather_repulsion(ch, gate, now, cut)?;
        let residual_late = self.with_standby && residual_wanted(ch.residuals.get(), state);
        let residual = fresher_residual(
            ch.residuals.get(),
            ch.standby_residuals.as_ref().and_then(|s| s.get()),
        );
        let perception = self.avoidance.then_some(&self.repulsion);
        let mut input = match ControlInput::from_messages(state, residual, perception, n) {
            Ok(input) => input,
            Err(e) => return Ok(Err(e)),
        };
        // every pending request, stops acted on wherever they are among them
        // (phri_control's collaboration; without one, a stop all the same)
        let mono = phri_runtime::now_ns();
        let (k, taken) = take_requests(&ch.requests, gate, &mut self.pending, mono)?;
        // a request lost may have been a stop: the controller in charge stops
        // (seen as the standby, when the charge comes here within the hold)
        self.request_watch.read(taken, mono);
        let requests_lost = self
            .request_watch
            .stop_for_loss(!self.with_standby || in_charge, mono);
        input.collab.requests = &self.pending[..k];
        if self.collaborating {
            let (seen, hand) = collab_views(
                (&mut ch.skeletons, &mut ch.hands),
                gate,
                now,
                cut,
                self.spread_ns,
                (&mut self.cut_skeletons, &mut self.cut_hands),
                &mut self.skeleton,
            )?;
            input.collab = CollabInput {
                requests: &self.pending[..k],
                skeleton: seen.then_some(&self.skeleton),
                hand,
            };
        }
        Ok(Ok(Gathered {
            input,
            requests_lost,
            residual_late,
        }))
    }

    /// Every camera's new repulsion results into the accumulator (those
    /// published after `cut` held back), then fused at `now` [ns].
    fn gather_repulsion(
        &mut self,
        ch: &InputChannels,
        gate: &InputGate,
        now: u64,
        cut: u64,
    ) -> Result<(), IpcError> {
        let (held, repulsion) = (&mut self.held_results, &mut self.repulsion);
        // refused results are counted by the accumulator (perception then turns stale)
        held.release(cut, |camera, r| {
            let _ = repulsion.push_camera(camera, r);
        });
        for (camera, results) in ch.results.iter().enumerate() {
            results.drain_from(|pid, r| {
                if gate.repulsion(pid, r, now) {
                    held.offer(camera, r, cut, |camera, r| {
                        let _ = repulsion.push_camera(camera, r);
                    });
                }
            })?;
        }
        repulsion.fuse(now);
        Ok(())
    }
}

/// Takes at most [`MAX_REQUESTS`] requests into `pending`, those the gate
/// admits first: (admitted, taken).
fn take_requests(
    requests: &Subscriber<HriRequest>,
    gate: &InputGate,
    pending: &mut [HriRequest],
    mono: u64,
) -> Result<(usize, usize), IpcError> {
    let (mut k, mut taken) = (0, 0);
    while taken < MAX_REQUESTS {
        let Some((pid, mut r)) = requests.receive_from()? else {
            break;
        };
        taken += 1;
        if gate.request(pid, &mut r, mono) {
            pending[k] = r;
            k += 1;
        }
    }
    Ok((k, taken))
}

/// The cameras' skeletons merged into `skeleton` (whether one is seen) and
/// the best of their hands, each as of `cut`.
fn collab_views<'a>(
    (skeletons, hands): (
        &mut [LatestReader<Skeleton>],
        &mut [LatestReader<HandObservation>],
    ),
    gate: &InputGate,
    now: u64,
    cut: u64,
    spread_ns: u64,
    (cut_skeletons, cut_hands): (
        &mut [CutLatest<Skeleton>; MAX_CAMERAS],
        &'a mut [CutLatest<HandObservation>; MAX_CAMERAS],
    ),
    skeleton: &mut Skeleton,
) -> Result<(bool, Option<&'a HandObservation>), IpcError> {
    let mut views = [None; MAX_CAMERAS];
    for ((v, r), c) in views
        .iter_mut()
        .zip(skeletons.iter_mut())
        .zip(cut_skeletons.iter_mut())
    {
        r.update_from(|pid, s| gate.skeleton(pid, s, now))?;
        *v = c.take(r.get(), cut);
    }
    let seen = phri_ipc::merge_newest(&views, spread_ns, skeleton);
    let mut seen_hands = [None; MAX_CAMERAS];
    for ((v, r), c) in seen_hands
        .iter_mut()
        .zip(hands.iter_mut())
        .zip(cut_hands.iter_mut())
    {
        r.update_from(|pid, h| gate.hand(pid, h, now))?;
        *v = c.take(r.get(), cut);
    }
    Ok((seen, phri_ipc::best_hand(&seen_hands, spread_ns)))
}
