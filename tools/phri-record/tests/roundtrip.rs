//! Record a real cell for 3 s, read the MCAP back with the `mcap` crate, plot it.
//! The recording holds the 3-D scene in Foxglove's schemas, as phri-viz serves it.

use std::collections::BTreeMap;
use std::path::{Path, PathBuf};
use std::process::{Child, Command, Stdio};
use std::time::{Duration, Instant};

/// Stops the supervisor (SIGINT: ordered shutdown) if the test fails early.
struct Cell(Option<Child>);

impl Drop for Cell {
    fn drop(&mut self) {
        if let Some(c) = &mut self.0 {
            if matches!(c.try_wait(), Ok(None)) {
                let _ = Command::new("kill")
                    .arg("-INT")
                    .arg(c.id().to_string())
                    .status();
                let _ = c.wait();
            }
        }
    }
}

fn dir() -> PathBuf {
    PathBuf::from(env!("CARGO_MANIFEST_DIR"))
}

#[test]
fn record_read_back_and_plot() {
    // the cell's binaries sit beside this package's (same target directory)
    let sup = Path::new(env!("CARGO_BIN_EXE_phri-record")).with_file_name("phri-supervisor");
    assert!(
        sup.exists(),
        "{} is not built: run the workspace's tests (cargo test --workspace --release) or cargo build --release --bins first",
        sup.display()
    );
    let pid = std::process::id();
    let prefix = format!("rec{pid}_");
    let tmp = std::env::temp_dir().join(format!("phri-record-test-{pid}"));
    let _ = std::fs::remove_dir_all(&tmp);
    std::fs::create_dir_all(&tmp).unwrap();
    let run_dir = tmp.join("run");
    std::fs::create_dir_all(&run_dir).unwrap();
    let mut cell = Cell(Some(
        Command::new(&sup)
            .current_dir(dir())
            .args([
                "--config",
                "../../deploy/phri.toml",
                "--scenario",
                "coexistence",
            ])
            .args(["--duration", "12", "--prefix", &prefix, "--run-dir"])
            .arg(&run_dir)
            .stdout(Stdio::null())
            .stderr(Stdio::inherit())
            .spawn()
            .expect("start the supervisor"),
    ));
    std::thread::sleep(Duration::from_secs(3));

    // record
    let file = tmp.join("cell.mcap");
    let t = Instant::now();
    let st = Command::new(env!("CARGO_BIN_EXE_phri-record"))
        .args([
            "--prefix",
            &prefix,
            "--seconds",
            "3",
            "--config",
            "../../deploy/phri.toml",
        ])
        .arg("--out")
        .arg(&file)
        .current_dir(dir())
        .status()
        .unwrap();
    assert!(st.success(), "phri-record failed: {st}");
    let took = t.elapsed().as_secs_f64();
    assert!(took < 10.0, "recording 3 s took {took:.1} s");

    // read back
    let buf = std::fs::read(&file).unwrap();
    let summary = mcap::Summary::read(&buf)
        .expect("summary readable")
        .expect("the file has a summary section");
    assert!(!summary.chunk_indexes.is_empty(), "no chunk indexes");
    // zstd chunks by default
    assert!(summary
        .chunk_indexes
        .iter()
        .all(|c| c.compression == "zstd"));
    let stats = summary.stats.as_ref().expect("statistics record");
    let topics: Vec<&str> = summary
        .channels
        .values()
        .map(|c| c.topic.as_str())
        .collect();
    for c in phri_ipc::ALL {
        assert!(topics.contains(c), "no MCAP channel for {c}");
    }
    for c in [phri_ipc::CAMERA_DEPTH.name, phri_ipc::PERCEPTION_DEPTH.name] {
        let image = phri_record::foxglove::image_topic(c);
        assert!(topics.contains(&image.as_str()), "no MCAP channel {image}");
    }
    assert!(
        summary
            .metadata_indexes
            .iter()
            .any(|m| m.name == "phri-record"),
        "no phri-record metadata"
    );
    let mut counts: BTreeMap<String, u64> = BTreeMap::new();
    let mut frames_ok = 0;
    // camera/depth frames by sequence number, to compare with their image view
    let mut frame_pixels: BTreeMap<u32, String> = BTreeMap::new();
    let mut images: BTreeMap<u32, String> = BTreeMap::new();
    let mut last_state_t = 0u64;
    // robot/state's sequence numbers as recorded
    let mut state_seqs: Vec<u64> = Vec::new();
    // robot/stats' robot cycles as recorded
    let mut stats_cycles: Vec<u64> = Vec::new();
    // the scene's topics: schema name, schema encoding, message encoding; a message of each
    let mut scene: BTreeMap<String, (String, String, String)> = BTreeMap::new();
    let mut scene_last: BTreeMap<String, Vec<u8>> = BTreeMap::new();
    for m in mcap::MessageStream::new(&buf).expect("message stream") {
        let m = m.expect("message");
        if m.channel.topic.starts_with("/viz/") {
            let schema = m.channel.schema.as_ref().expect("schema");
            scene.insert(
                m.channel.topic.clone(),
                (
                    schema.name.clone(),
                    schema.encoding.clone(),
                    m.channel.message_encoding.clone(),
                ),
            );
            scene_last.insert(m.channel.topic.clone(), m.data.to_vec());
            *counts.entry(m.channel.topic.clone()).or_default() += 1;
            continue;
        }
        assert_eq!(m.channel.message_encoding, "json");
        let schema = m.channel.schema.as_ref().expect("schema");
        assert_eq!(schema.encoding, "jsonschema");
        let v: serde_json::Value = serde_json::from_slice(&m.data).expect("JSON message");
        assert!(v.is_object());
        let topic = m.channel.topic.clone();
        if phri_record::is_frame_channel(&topic) && topic == phri_ipc::CAMERA_DEPTH.name {
            let data = v["data"].as_array().expect("frame data");
            assert_eq!(data.len(), 160 * 120, "downsampled frame size");
            assert!(
                data.iter().any(|x| x.as_u64().unwrap() > 0),
                "empty depth frame"
            );
            frames_ok += 1;
            let mut bytes = Vec::new();
            for x in data {
                bytes.extend_from_slice(&(x.as_u64().unwrap() as u16).to_le_bytes());
            }
            frame_pixels.insert(m.sequence, phri_record::foxglove::base64(&bytes));
        }
        if topic == phri_record::foxglove::image_topic(phri_ipc::CAMERA_DEPTH.name) {
            assert_eq!(schema.name, "foxglove.RawImage");
            assert_eq!(
                (&v["encoding"], &v["width"], &v["height"], &v["step"]),
                (&"16UC1".into(), &160.into(), &120.into(), &320.into()),
                "{}",
                &v["encoding"]
            );
            assert!(
                v["timestamp"]["sec"].as_u64().is_some()
                    && v["timestamp"]["nsec"].as_u64() < Some(1_000_000_000)
            );
            images.insert(
                m.sequence,
                v["data"].as_str().expect("base64 data").to_string(),
            );
        }
        if topic == phri_ipc::ROBOT_STATS.name {
            stats_cycles.push(v["cycles"].as_u64().expect("robot/stats cycles"));
        }
        if topic == phri_ipc::ROBOT_STATE.name {
            state_seqs.push(v["seq"].as_u64().expect("robot/state seq"));
            assert_eq!(m.log_time, v["published_ns"].as_u64().unwrap());
            assert!(m.log_time >= last_state_t, "robot/state log times go back");
            last_state_t = m.log_time;
        }
        *counts.entry(topic).or_default() += 1;
    }
    eprintln!(
        "recorded {:.1} MB, {} messages: {counts:?}",
        buf.len() as f64 / 1e6,
        stats.message_count
    );
    assert_eq!(stats.message_count, counts.values().sum::<u64>());
    // fault/depth carries messages only while phri-fault injects
    for c in phri_ipc::ALL
        .iter()
        .filter(|c| !phri_ipc::ON_DEMAND.contains(c))
    {
        let n = counts.get(*c).copied().unwrap_or(0);
        assert!(n > 0, "no messages on {c}");
    }
    // nothing lost: every state the robot published between the first and
    // the last recorded, in order; at most 1 kHz for 3 s (a loaded machine's
    // robot loop may fall behind: its pace is the cell's report's matter)
    let state = counts["robot/state"];
    let (first, last) = (state_seqs[0], state_seqs[state_seqs.len() - 1]);
    assert!(
        state_seqs.windows(2).all(|w| w[1] == w[0] + 1),
        "robot/state: {state} messages in 3 s, seq {first}..={last}, not one after another"
    );
    assert!(
        (1500..=3100).contains(&state),
        "robot/state: {state} messages in 3 s"
    );
    // the 1 kHz chain answers every state (a few in flight at the ends)
    for c in [
        "sim/truth",
        "dynamics/residual",
        "control/status",
        "robot/command",
    ] {
        let n = counts[c];
        assert!(
            n + 60 >= state && n <= state + 60,
            "{c}: {n} messages in 3 s beside robot/state's {state}"
        );
    }
    assert!(
        frames_ok >= 5,
        "camera/depth: {frames_ok} downsampled frames"
    );
    // every frame has its Foxglove image, with the same pixels
    assert_eq!(images.len(), frame_pixels.len());
    for (seq, pixels) in &frame_pixels {
        assert_eq!(
            images.get(seq),
            Some(pixels),
            "camera/depth/image of frame {seq}"
        );
    }
    assert!(counts["perception/depth"] >= 5);
    // the robot's statistics every 100 of its periods (`STATS_EVERY`), by
    // its own clock, none lost: as many inside the states' span (state n is
    // the robot's cycle n) as it holds, one at either end in flight; the
    // recorder may also hold one from before the first state it recorded
    // (its subscriptions open one after another)
    let inside = stats_cycles
        .iter()
        .filter(|&&c| c >= first && c <= last)
        .count() as u64;
    assert!(
        stats_cycles.windows(2).all(|w| w[1] == w[0] + 100),
        "robot/stats: cycles {stats_cycles:?}"
    );
    assert!(
        inside + 1 >= (last - first) / 100 && inside <= (last - first) / 100 + 1,
        "robot/stats: {inside} of {} messages inside robot/state's seq {first}..={last}: {stats_cycles:?}",
        stats_cycles.len()
    );
    assert!(counts["supervisor/health"] >= 20);

    // the 3-D scene, in Foxglove's schemas, on phri-viz's topics
    let pb = |name: &str| {
        (
            name.to_string(),
            "protobuf".to_string(),
            "protobuf".to_string(),
        )
    };
    for topic in phri_viz::topics::SCENE {
        assert_eq!(
            scene.get(*topic),
            Some(&pb("foxglove.SceneUpdate")),
            "{topic}"
        );
    }
    assert_eq!(scene.get("/viz/tf"), Some(&pb("foxglove.FrameTransforms")));
    assert_eq!(scene.get("/viz/joints"), Some(&pb("foxglove.JointStates")));
    assert_eq!(
        scene.get("/viz/depth/points"),
        Some(&pb("foxglove.PointCloud"))
    );
    assert_eq!(
        scene.get("/viz/depth/image"),
        Some(&pb("foxglove.RawImage"))
    );
    assert_eq!(
        scene.get("/viz/status"),
        Some(&(
            "phri.viz.Status".to_string(),
            "jsonschema".to_string(),
            "json".to_string()
        ))
    );
    assert_eq!(scene.len(), phri_viz::TOPICS.len(), "{scene:?}");
    // rates: the scene at 30 Hz, joint states at 250 Hz, a cloud per
    // recorded filtered frame; a loaded virtual machine's wall clock (a
    // robot loop 24 % short in one CI run) may see half of them, never more
    let robot = counts["/viz/robot"];
    assert!((30..=100).contains(&robot), "/viz/robot: {robot} in 3 s");
    let joints = counts["/viz/joints"];
    assert!(
        (300..=800).contains(&joints),
        "/viz/joints: {joints} in 3 s"
    );
    assert_eq!(counts["/viz/depth/points"], counts["perception/depth"]);
    // and they decode: a capsule per link, seven joints, the camera's image
    use phri_viz::foxglove::messages::{JointStates, RawImage, SceneUpdate};
    use phri_viz::foxglove::Decode;
    let robot = SceneUpdate::decode(&scene_last["/viz/robot"][..]).expect("SceneUpdate");
    assert!(robot.entities.len() >= 7, "{}", robot.entities.len());
    assert!(robot.entities.iter().all(|e| e.spheres.len() >= 2));
    let person = SceneUpdate::decode(&scene_last["/viz/person"][..]).expect("SceneUpdate");
    assert!(
        !person.entities.is_empty(),
        "the coexistence scenario's person"
    );
    let j = JointStates::decode(&scene_last["/viz/joints"][..]).expect("JointStates");
    assert_eq!(j.joints.len(), 7);
    let im = RawImage::decode(&scene_last["/viz/depth/image"][..]).expect("RawImage");
    assert_eq!(
        (im.width, im.height, im.encoding.as_str()),
        (160, 120, "16UC1")
    );
    let status: serde_json::Value =
        serde_json::from_slice(&scene_last["/viz/status"]).expect("JSON status");
    assert_eq!(
        status["residual"].as_array().map(Vec::len),
        Some(7),
        "{status}"
    );

    // plot
    let out = tmp.join("plots");
    let st = Command::new(env!("CARGO_BIN_EXE_phri-plot"))
        .arg("--file")
        .arg(&file)
        .arg("--out")
        .arg(&out)
        .status()
        .unwrap();
    assert!(st.success(), "phri-plot failed: {st}");
    for name in ["ee_trajectory.png", "residual.png", "min_distance.png"] {
        check_png(&out.join(name));
    }
    // with a second recording's path underneath (here the same file)
    let out2 = tmp.join("plots2");
    let st = Command::new(env!("CARGO_BIN_EXE_phri-plot"))
        .arg("--file")
        .arg(&file)
        .arg("--without")
        .arg(&file)
        .arg("--out")
        .arg(&out2)
        .status()
        .unwrap();
    assert!(st.success(), "phri-plot --without failed: {st}");
    check_png(&out2.join("ee_trajectory.png"));

    // a bad file: one-line error, exit 2
    let o = Command::new(env!("CARGO_BIN_EXE_phri-plot"))
        .args(["--file", "/nonexistent.mcap", "--out"])
        .arg(&out)
        .output()
        .unwrap();
    assert_eq!(o.status.code(), Some(2));
    assert_eq!(String::from_utf8_lossy(&o.stderr).lines().count(), 1);

    // replay into a prefix of its own: every replayable channel of the file
    let o = Command::new(env!("CARGO_BIN_EXE_phri-replay"))
        .args(["--prefix", &format!("rp{pid}_"), "--speed", "4", "--file"])
        .arg(&file)
        .output()
        .unwrap();
    let err = String::from_utf8_lossy(&o.stderr);
    assert!(o.status.success(), "phri-replay failed: {err}");
    for c in [
        "robot/state",
        "sim/world",
        "perception/repulsion",
        "control/status",
    ] {
        assert!(err.contains(&format!("{c}=")), "{c} not replayed: {err}");
    }
    // recorded obstacles are never replayed into a commanded robot's cell
    let o = Command::new(env!("CARGO_BIN_EXE_phri-replay"))
        .args([
            "--prefix",
            &prefix,
            "--channels",
            "perception/repulsion",
            "--file",
        ])
        .arg(&file)
        .output()
        .unwrap();
    let err = String::from_utf8_lossy(&o.stderr);
    assert_eq!(o.status.code(), Some(2), "{err}");
    assert!(err.contains("robot/command"), "{err}");

    // lz4 chunks, every frame at half resolution, on request, read back; an
    // unknown compression is refused
    let lz4 = tmp.join("lz4.mcap");
    let st = Command::new(env!("CARGO_BIN_EXE_phri-record"))
        .args([
            "--prefix",
            &prefix,
            "--seconds",
            "1",
            "--compression",
            "lz4",
        ])
        .args(["--frame-every", "1", "--frame-downsample", "2"])
        .arg("--out")
        .arg(&lz4)
        .status()
        .unwrap();
    assert!(st.success(), "phri-record --compression lz4 failed: {st}");
    let buf = std::fs::read(&lz4).unwrap();
    let summary = mcap::Summary::read(&buf).unwrap().expect("summary");
    assert!(summary.chunk_indexes.iter().all(|c| c.compression == "lz4"));
    let (mut n, mut frames) = (0, 0);
    let mut seqs = Vec::new();
    for m in mcap::MessageStream::new(&buf).unwrap() {
        let m = m.expect("lz4 message");
        if m.channel.topic == phri_ipc::ROBOT_STATE.name {
            n += 1;
            let v: serde_json::Value = serde_json::from_slice(&m.data).unwrap();
            seqs.push(v["seq"].as_u64().expect("robot/state seq"));
        } else if m.channel.topic == phri_ipc::CAMERA_DEPTH.name {
            let v: serde_json::Value = serde_json::from_slice(&m.data).unwrap();
            assert_eq!(v["data"].as_array().map(Vec::len), Some(320 * 240));
            assert_eq!(
                (&v["data_width"], &v["downsample"]),
                (&320.into(), &2.into())
            );
            frames += 1;
        }
    }
    // about a second of states (fewer when this machine is loaded: the
    // rate is the benchmark's), none lost on the way
    assert!(
        (300..=1200).contains(&n),
        "robot/state: {n} messages in 1 s"
    );
    seqs.sort_unstable();
    assert!(
        seqs.windows(2).all(|w| w[1] == w[0] + 1),
        "robot/state: a gap in the recorded sequence"
    );
    assert!(
        (10..=40).contains(&frames),
        "camera/depth: {frames} frames in 1 s"
    );
    let o = Command::new(env!("CARGO_BIN_EXE_phri-record"))
        .args(["--prefix", &prefix, "--compression", "gzip", "--out"])
        .arg(tmp.join("never.mcap"))
        .output()
        .unwrap();
    let err = String::from_utf8_lossy(&o.stderr);
    assert_eq!(o.status.code(), Some(2), "{err}");
    assert_eq!(err.lines().count(), 1, "{err}");
    assert!(err.contains("--compression 'gzip'"), "{err}");
    // the command line: one line naming the flag, exit 2; completions
    for (args, needle) in [
        (vec!["--seconds", "0"], "--seconds"),
        (vec!["--frame-every", "0"], "--frame-every"),
        (vec!["--seconds", "soon"], "--seconds"),
        (vec!["--sconds", "3"], "--seconds"),
    ] {
        let o = Command::new(env!("CARGO_BIN_EXE_phri-record"))
            .args(["--prefix", &prefix, "--out"])
            .arg(tmp.join("never.mcap"))
            .args(&args)
            .output()
            .unwrap();
        let err = String::from_utf8_lossy(&o.stderr);
        assert_eq!(o.status.code(), Some(2), "{args:?}: {err}");
        assert_eq!(err.lines().count(), 1, "{args:?}: {err}");
        assert!(err.contains(needle), "{args:?}: {err}");
    }
    let o = Command::new(env!("CARGO_BIN_EXE_phri-record"))
        .args(["--prefix", &prefix])
        .output()
        .unwrap();
    let err = String::from_utf8_lossy(&o.stderr);
    assert_eq!(o.status.code(), Some(2), "{err}");
    assert!(err.contains("--out"), "{err}");
    let o = Command::new(env!("CARGO_BIN_EXE_phri-record"))
        .args(["completions", "bash"])
        .output()
        .unwrap();
    assert!(o.status.success());
    assert!(String::from_utf8_lossy(&o.stdout).contains("--frame-downsample"));

    // the cell finishes its run on its own, successfully
    let mut child = cell.0.take().unwrap();
    let deadline = Instant::now() + Duration::from_secs(30);
    let status = loop {
        if let Some(s) = child.try_wait().unwrap() {
            break s;
        }
        if Instant::now() > deadline {
            cell.0 = Some(child);
            panic!("supervisor did not exit");
        }
        std::thread::sleep(Duration::from_millis(100));
    };
    assert!(status.success(), "supervisor: {status}");
    let _ = std::fs::remove_dir_all(&tmp);
}

fn check_png(path: &Path) {
    let f = std::fs::File::open(path).unwrap_or_else(|e| panic!("{}: {e}", path.display()));
    let dec = png::Decoder::new(std::io::BufReader::new(f));
    let mut r = dec.read_info().expect("PNG header");
    let mut img = vec![0; r.output_buffer_size().expect("buffer size")];
    let info = r.next_frame(&mut img).expect("PNG data");
    assert_eq!(info.color_type, png::ColorType::Rgb);
    let px = &img[..info.buffer_size()];
    let bg = [px[0], px[1], px[2]];
    let other = px.chunks(3).filter(|p| *p != bg).count();
    // the curve itself, not just the frame: blue pixels
    let blue = px.chunks(3).filter(|p| p[2] > 150 && p[0] < 100).count();
    assert!(other > 1000, "{}: almost blank", path.display());
    assert!(blue > 50, "{}: no curve", path.display());
}
