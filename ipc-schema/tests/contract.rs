//! The contract with outside clients (iceoryx2's `iox2`, its Python
//! binding): they match a channel's payload by type name, size and
//! alignment. These are the values they rely on; a change here breaks them.

use iceoryx2::prelude::ZeroCopySend;
use phri_ipc::*;

fn check<T: ZeroCopySend>(name: &str, size: usize) {
    // SAFETY: type_name only reads the type's static name
    let type_name = unsafe { <T as ZeroCopySend>::type_name() };
    assert_eq!(type_name, name);
    assert_eq!(std::mem::size_of::<T>(), size, "{name}: size");
    assert_eq!(std::mem::align_of::<T>(), 8, "{name}: alignment");
}

#[test]
fn type_names_sizes_and_alignments_are_the_published_ones() {
    check::<JointState>("phri::JointState", 288);
    check::<TorqueCommand>("phri::TorqueCommand", 136);
    check::<Residual>("phri::Residual", 256);
    // 8 bytes larger than before issue 9: `model_errors` (failed model
    // evaluations, reported, never dropped)
    check::<ControlStatus>("phri::ControlStatus", 256);
    check::<Truth>("phri::Truth", 904);
    check::<RobotStats>("phri::RobotStats", 8064);
    check::<Health>("phri::Health", 920);
    check::<WorldState>("phri::WorldState", 1144);
    check::<FrameHeader>("phri::FrameHeader", 296);
    check::<RepulsionResult>("phri::RepulsionResult", 768);
    check::<DepthFault>("phri::DepthFault", 40);
    check::<ContactEvent>("phri::ContactEvent", 104);
    check::<Skeleton>("phri::Skeleton", 1992);
    check::<HriRequest>("phri::HriRequest", 120);
    check::<HandObservation>("phri::HandObservation", 96);
    check::<CollabState>("phri::CollabState", 240);
    check::<AudioChunk>("phri::AudioChunk", 672);
    check::<Utterance>("phri::Utterance", 128);
    check::<SsmStatus>("phri::SsmStatus", 88);
    check::<ControlBehaviour>("phri::ControlBehaviour", 8232);
    check::<CommanderStats>("phri::CommanderStats", 104);
}
