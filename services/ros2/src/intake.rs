//! `/phri/request` into `hri/request`, once per loop: every sample DDS holds
//! (at most [`MAX_REQUESTS_PER_LOOP`]) is taken, passed through the
//! [`Bridge`] (stops first, every other request within its peer's rate) and
//! published; each refusal is counted by the bridge and logged at most once
//! a second ([`RefusalLog`]), each text cut and escaped ([`shown`]).

use phri_ipc::HriRequest;

use crate::gate::{shown, RefusalLog};
use crate::{Bridge, RefusalKind, RequestSample};

/// `/phri/request` samples taken per loop at most (the rest wait for the next).
pub const MAX_REQUESTS_PER_LOOP: usize = 256;

/// The samples of one loop and the refusals not yet logged.
#[derive(Debug, Default)]
pub struct Intake {
    batch: Vec<RequestSample>,
    refusals: RefusalLog,
}

impl Intake {
    /// Take the samples waiting, at `now_ns` [ns, CLOCK_MONOTONIC]: `next`
    /// gives the next one (`Ok(None)`: none left; `Err`: DDS's error for a
    /// sample it could not make a `std_msgs/String` of, counted on `bridge`
    /// as malformed and logged). At most [`MAX_REQUESTS_PER_LOOP`] calls.
    pub fn take(
        &mut self,
        bridge: &mut Bridge,
        now_ns: u64,
        mut next: impl FnMut() -> Result<Option<RequestSample>, String>,
    ) {
        self.batch.clear();
        for _ in 0..MAX_REQUESTS_PER_LOOP {
            match next() {
                Ok(Some(sample)) => self.batch.push(sample),
                Ok(None) => break,
                Err(e) => {
                    bridge.malformed_request();
                    let why = format!("malformed sample ({})", shown(&e));
                    if let Some(line) = self.refusals.note(RefusalKind::Malformed, "", &why, now_ns)
                    {
                        tracing::warn!("{line}");
                    }
                }
            }
        }
    }

    /// The samples taken, in arrival order.
    pub fn batch(&self) -> &[RequestSample] {
        &self.batch
    }

    /// Pass the samples taken at `now_ns` [ns, CLOCK_MONOTONIC] through
    /// `bridge`: each request it lets through goes to `publish`
    /// (`hri/request`) in [`Bridge::requests`]' order, stops first; each
    /// refusal is noted, the refusal line due is logged. A publishing error
    /// ends the pass.
    pub fn pass<E>(
        &mut self,
        bridge: &mut Bridge,
        now_ns: u64,
        mut publish: impl FnMut(&HriRequest) -> Result<(), E>,
    ) -> Result<(), E> {
        for (i, result) in bridge.requests(&self.batch, now_ns) {
            let text = &self.batch[i].text;
            match result {
                Ok(r) => {
                    publish(&r)?;
                    tracing::info!("/phri/request '{}': on hri/request", shown(text.trim()));
                }
                Err(e) => {
                    if let Some(line) = self.refusals.note(e.kind(), text, &e.to_string(), now_ns) {
                        tracing::warn!("{line}");
                    }
                }
            }
        }
        if let Some(line) = self.refusals.flush(now_ns) {
            tracing::warn!("{line}");
        }
        Ok(())
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use phri_config::Config;
    use phri_ipc::RequestKind;

    fn accepting() -> Bridge {
        let model = phri_model::Model::from_urdf_file(concat!(
            env!("CARGO_MANIFEST_DIR"),
            "/../../deploy/robots/kuka_lwr4.urdf"
        ))
        .unwrap();
        let mut c = Config::defaults();
        c.ros2.accept_requests = true;
        Bridge::new(&c, model).unwrap()
    }

    fn sample(peer: u8, text: &str) -> RequestSample {
        RequestSample {
            peer: [peer; 16],
            text: text.to_string(),
        }
    }

    #[test]
    fn a_loop_takes_a_bounded_batch_and_counts_the_malformed() {
        let mut b = accepting();
        let mut intake = Intake::default();
        // a flood: more samples than one loop takes
        let mut left = 1000;
        intake.take(&mut b, 1, || {
            left -= 1;
            Ok(Some(sample(1, "begin")))
        });
        assert_eq!(intake.batch().len(), MAX_REQUESTS_PER_LOOP);
        assert_eq!(left, 1000 - MAX_REQUESTS_PER_LOOP as i32, "the rest wait");
        // a malformed sample is counted and skipped; the next loop starts afresh
        let mut queue = vec![
            Ok(None),
            Ok(Some(sample(2, "stop"))),
            Err("bad CDR".to_string()),
            Ok(Some(sample(1, "begin"))),
        ];
        intake.take(&mut b, 2, || queue.pop().unwrap());
        let texts: Vec<&str> = intake.batch().iter().map(|s| s.text.as_str()).collect();
        assert_eq!(texts, ["begin", "stop"]);
        assert_eq!(b.counts.requests_malformed, 1);
    }

    #[test]
    fn the_pass_publishes_stops_first_and_stops_at_an_error() {
        let mut b = accepting();
        let mut intake = Intake::default();
        let mut queue = vec![
            Ok(None),
            Ok(Some(sample(2, "stop"))),
            Ok(Some(sample(1, "dance"))),
            Ok(Some(sample(1, "begin"))),
        ];
        intake.take(&mut b, 1_000_000_000, || queue.pop().unwrap());
        let mut published = Vec::new();
        let r: Result<(), ()> = intake.pass(&mut b, 1_000_000_000, |q| {
            published.push(q.kind);
            Ok(())
        });
        assert!(r.is_ok());
        assert_eq!(
            published,
            [RequestKind::Stop as u32, RequestKind::Begin as u32]
        );
        assert_eq!((b.counts.requests, b.counts.requests_refused), (2, 1));
        // a publisher that fails: the error comes back, nothing after it is published
        let mut queue = vec![
            Ok(None),
            Ok(Some(sample(1, "end"))),
            Ok(Some(sample(3, "stop"))),
        ];
        intake.take(&mut b, 2_000_000_000, || queue.pop().unwrap());
        let mut tried = 0;
        let r = intake.pass(&mut b, 2_000_000_000, |_| {
            tried += 1;
            Err("full")
        });
        assert_eq!((r, tried), (Err("full"), 1));
    }
}
