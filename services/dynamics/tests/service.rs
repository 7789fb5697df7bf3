//! The `phri-dynamics` process behind its channels: joint states published on
//! `robot/state` are answered on `dynamics/residual` (valid after the
//! warm-up, naming the state they answer, near zero for an arm at rest under
//! its gravity torque); a bad configuration is one line and exit 2.

use std::process::{Child, Command, Stdio};
use std::time::{Duration, Instant};

use phri_config::Config;
use phri_ipc::{node, residual_flags, JointState, Queue, Zeroed, DYNAMICS_RESIDUAL, ROBOT_STATE};
use phri_model::{Data, Model};

fn deploy() -> String {
    format!("{}/../../deploy/phri.toml", env!("CARGO_MANIFEST_DIR"))
}

fn service(prefix: &str, extra: &[&str]) -> Command {
    let mut c = Command::new(env!("CARGO_BIN_EXE_phri-dynamics"));
    c.args([
        "--config",
        &deploy(),
        "--prefix",
        prefix,
        "--name",
        "dynamics",
    ])
    .args(extra)
    .stdin(Stdio::null());
    c
}

struct Killed(Child);

impl Drop for Killed {
    fn drop(&mut self) {
        let _ = self.0.kill();
        let _ = self.0.wait();
    }
}

#[test]
fn states_in_residuals_out() {
    let prefix = format!("dyntest{}_", std::process::id());
    let child = Killed(service(&prefix, &[]).stderr(Stdio::null()).spawn().unwrap());
    let node = node("dynamics-test", &prefix).unwrap();
    let states = ROBOT_STATE.publisher(&node).unwrap();
    let residuals = DYNAMICS_RESIDUAL.subscriber(&node, Queue::Drain).unwrap();
    // the arm at rest at its initial posture, holding it with the gravity torque
    let cfg = Config::defaults();
    let model = Model::from_urdf_file(&cfg.robot.urdf).unwrap();
    let n = model.nv();
    let q0 = &cfg.sim.q0;
    let g = phri_model::gravity(&model, &mut Data::new(&model), q0)
        .unwrap()
        .clone();
    let mut s = JointState::zeroed();
    s.dof = n as u32;
    s.q[..n].copy_from_slice(q0);
    s.tau[..n].copy_from_slice(g.as_slice());
    let t0 = Instant::now();
    let mut last = None;
    let mut seq = 0u64;
    // 1 kHz for up to 3 s (the service may take a moment to start)
    while t0.elapsed() < Duration::from_secs(3) {
        seq += 1;
        s.seq = seq;
        s.stamp_ns = seq * 1_000_000;
        s.published_ns = seq * 1_000_000;
        states.publish(&s).unwrap();
        std::thread::sleep(Duration::from_millis(1));
        residuals
            .drain(|r| {
                last = Some(*r);
            })
            .unwrap();
        if last.is_some_and(|r| r.flags & residual_flags::VALID != 0 && seq > 300) {
            break;
        }
    }
    drop(child);
    drop((states, residuals, node));
    let _ = phri_ipc::remove_leftovers(&prefix);
    let r = last.expect("phri-dynamics never answered on dynamics/residual");
    assert_ne!(r.flags & residual_flags::VALID, 0, "never valid: {r:?}");
    assert_eq!(r.dof as usize, n);
    assert!(
        r.state_seq > 0 && r.state_seq <= seq,
        "answers state {}",
        r.state_seq
    );
    assert_eq!(r.state_stamp_ns, r.state_seq * 1_000_000);
    assert_eq!(r.flags & residual_flags::COLLISION, 0);
    assert!(r.norm < 0.5, "at rest under gravity: ‖r‖ = {}", r.norm);
}

#[test]
fn a_bad_configuration_is_one_line_and_exit_2() {
    let prefix = format!("dynbad{}_", std::process::id());
    for (set, key) in [
        ("dynamics.gain=[1, 2]", "dynamics.gain"),
        (
            "dynamics.velocity_cutoff_hz=-1",
            "dynamics.velocity_cutoff_hz",
        ),
        ("dynamics.gian=1", "dynamics.gian"),
    ] {
        let out = service(&prefix, &["--set", set]).output().unwrap();
        let err = String::from_utf8_lossy(&out.stderr);
        assert_eq!(out.status.code(), Some(2), "{set}: {err}");
        assert_eq!(err.trim_end().lines().count(), 1, "{set}: {err}");
        assert!(err.contains(key), "{set}: {err}");
    }
    let _ = phri_ipc::remove_leftovers(&prefix);
}
