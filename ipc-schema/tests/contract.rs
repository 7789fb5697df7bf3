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
    // 8 bytes larger: the violations of the standard's own S_p
    check::<SsmStatus>("phri::SsmStatus", 96);
    check::<BarrierStatus>("phri::BarrierStatus", 80);
    check::<ControlBehaviour>("phri::ControlBehaviour", 8232);
    // 40 bytes larger: the commands refused per slot (a stranger's, malformed)
    check::<CommanderStats>("phri::CommanderStats", 144);
    check::<BridgeRequests>("phri::BridgeRequests", 56);
    check::<CameraStatus>("phri::CameraStatus", 72);
    check::<MicStatus>("phri::MicStatus", 40);
}

/// phri opens its channels' services without naming their types to iceoryx2
/// (one compiled instance of iceoryx2's ports serves every channel), yet it
/// records each channel's types exactly as a typed port would: an outside
/// client that opens a channel by its types (as `iox2` and the Python
/// binding do) finds the service and talks with phri both ways, for a
/// message channel and for depth frames. A mismatch makes iceoryx2 refuse
/// the outside client's open.
#[test]
fn a_typed_outside_client_opens_phri_s_channels_and_talks_both_ways() {
    use iceoryx2::prelude::*;
    let prefix = format!("ctr{}_", std::process::id());
    let node = phri_ipc::node("contract", &prefix).unwrap();
    let name = |c: &str| -> ServiceName { c.try_into().unwrap() };

    // a message channel, created by phri
    let ours = ROBOT_STATE.publisher(&node).unwrap();
    let our_reader = ROBOT_STATE.subscriber(&node, Queue::Drain).unwrap();
    let theirs = node
        .service_builder(&name(ROBOT_STATE.name))
        .publish_subscribe::<JointState>()
        .open()
        .expect("robot/state opens with phri::JointState");
    let their_reader = theirs.subscriber_builder().create().unwrap();
    let mut js = <JointState as Zeroed>::zeroed();
    js.seq = 7;
    js.dof = 7;
    js.q[3] = 1.25;
    js.tau[6] = -2.5;
    ours.publish(&js).unwrap();
    let got = their_reader.receive().unwrap().expect("phri's state");
    assert_eq!((got.seq, got.dof, got.q[3], got.tau[6]), (7, 7, 1.25, -2.5));
    assert_eq!(our_reader.receive().unwrap().map(|s| s.seq), Some(7));
    // the other way (robot/state takes one publisher: phri's goes first)
    drop(ours);
    let their_writer = theirs.publisher_builder().create().unwrap();
    js.seq = 8;
    their_writer.send_copy(js).unwrap();
    let (pid, got) = our_reader.receive_from().unwrap().expect("their state");
    assert_eq!((got.seq, got.q[3]), (8, 1.25));
    assert_eq!(pid, std::process::id() as i32);

    // depth frames: a slice of u16 with a FrameHeader
    let ours = CAMERA_DEPTH.frame_publisher(&node, 640 * 480).unwrap();
    let our_reader = CAMERA_DEPTH.frame_subscriber(&node, Queue::Drain).unwrap();
    let theirs = node
        .service_builder(&name(CAMERA_DEPTH.name))
        .publish_subscribe::<[u16]>()
        .user_header::<FrameHeader>()
        .open()
        .expect("camera/depth opens with [u16] and phri::FrameHeader");
    let their_reader = theirs.subscriber_builder().create().unwrap();
    let mut frame = ours.loan(640 * 480).unwrap();
    assert!(frame.payload().iter().all(|&d| d == 0));
    frame.user_header_mut().seq = 11;
    frame.user_header_mut().width = 640;
    frame.payload_mut()[1234] = 1500;
    ours.send(frame).unwrap();
    let got = their_reader.receive().unwrap().expect("phri's frame");
    assert_eq!((got.user_header().seq, got.user_header().width), (11, 640));
    assert_eq!(got.payload().len(), 640 * 480);
    assert_eq!(got.payload()[1234], 1500);
    let mine = our_reader.receive().unwrap().expect("phri's own frame");
    assert_eq!((mine.user_header().seq, mine.payload()[1234]), (11, 1500));
    drop(ours);
    let their_writer = theirs
        .publisher_builder()
        .initial_max_slice_len(100)
        .create()
        .unwrap();
    let mut s = their_writer.loan_slice(100).unwrap();
    s.user_header_mut().seq = 12;
    s.payload_mut()[99] = 4321;
    s.send().unwrap();
    let got = our_reader.receive().unwrap().expect("their frame");
    assert_eq!(got.user_header().seq, 12);
    assert_eq!(got.payload().len(), 100);
    assert_eq!(got.payload()[99], 4321);

    drop((our_reader, their_reader, got, mine, theirs));
    drop(node);
    let _ = remove_leftovers(&prefix);
}
