//! franka-sim for the adapter's tests: installed by the project's script,
//! started on 127.0.0.1 by the test itself, stopped when dropped.

#![allow(dead_code)]

use std::io::{BufRead, BufReader};
use std::path::{Path, PathBuf};
use std::process::{Child, Command, Stdio};

pub fn deploy() -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR")).join("../../deploy")
}

/// A port of this test process's own (`k` < 10: which of its servers).
pub fn port(k: u16) -> u16 {
    assert!(k < 10);
    20_000 + (std::process::id() % 4_000) as u16 * 10 + k
}

/// franka-sim's FCI server on 127.0.0.1:`port`, killed when dropped.
pub struct Server(Child);

impl Drop for Server {
    fn drop(&mut self) {
        let _ = self.0.kill();
        let _ = self.0.wait();
    }
}

pub fn serve(port: u16) -> Server {
    serve_with(port, None)
}

/// franka-sim at `port`, taking the simulated person's contact forces on
/// udp 127.0.0.1:`forces` (`sim.forces_to`) when given.
pub fn serve_with(port: u16, forces: Option<u16>) -> Server {
    let out = Command::new(deploy().join("franka-sim/install"))
        .stderr(Stdio::inherit())
        .output()
        .expect("deploy/franka-sim/install runs");
    assert!(out.status.success(), "deploy/franka-sim/install failed");
    let dir = PathBuf::from(String::from_utf8_lossy(&out.stdout).trim());
    let mut child = Command::new(dir.join("venv/bin/python"))
        .arg(deploy().join("franka-sim/serve.py"))
        .arg("--port")
        .arg(port.to_string())
        .args(forces.map(|f| format!("--forces-port={f}")))
        .env("FR3_MJCF", dir.join("fr3.xml"))
        .stdout(Stdio::piped())
        .stderr(Stdio::inherit())
        .spawn()
        .expect("franka-sim starts");
    // its first line says it listens
    let mut line = String::new();
    let stdout = child.stdout.take().expect("stdout");
    BufReader::new(stdout).read_line(&mut line).expect("a line");
    assert!(line.contains("FCI server"), "franka-sim said: {line}");
    Server(child)
}
