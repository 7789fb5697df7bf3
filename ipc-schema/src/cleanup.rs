//! Cleaning up a run's shared memory.

use std::path::PathBuf;

use iceoryx2::prelude::*;

/// Nodes of `prefix` still alive; the resources of dead ones are removed on the way.
pub fn live_nodes(prefix: &str) -> usize {
    let mut config = Config::default();
    let Ok(p) = FileName::new(prefix.as_bytes()) else {
        return 0;
    };
    config.global.prefix = p;
    let mut alive = 0;
    let _ = Node::<ipc::Service>::list(&config, |state| {
        match state {
            NodeState::Alive(_) => alive += 1,
            NodeState::Dead(view) => {
                let _ = view.try_remove_stale_resources();
            }
            _ => {}
        }
        CallbackProgression::Continue
    });
    alive
}

/// Every iceoryx2 file of `prefix`: node, service and event files under
/// iceoryx2's root path, shared-memory objects in `/dev/shm`.
pub fn files_of(prefix: &str) -> Vec<PathBuf> {
    let mut found = Vec::new();
    let root = Config::default().global.root_path().to_string();
    for dir in [
        PathBuf::from(root.trim_end_matches('/')),
        PathBuf::from("/dev/shm"),
    ] {
        let Ok(rd) = std::fs::read_dir(&dir) else {
            continue;
        };
        let mut stack: Vec<PathBuf> = rd.filter_map(|e| e.ok().map(|e| e.path())).collect();
        while let Some(p) = stack.pop() {
            if p.is_dir() {
                if let Ok(rd) = std::fs::read_dir(&p) {
                    stack.extend(rd.filter_map(|e| e.ok().map(|e| e.path())));
                }
            } else if p
                .file_name()
                .is_some_and(|n| n.to_string_lossy().starts_with(prefix))
            {
                found.push(p);
            }
        }
    }
    found
}

/// Remove every iceoryx2 file of `prefix` ([`files_of`]) once no node of it
/// is alive (iceoryx2 keeps a management segment after its last node ends).
/// `Err(n)`: `n` nodes are still attached and nothing was removed. Call after
/// dropping your own node.
pub fn remove_leftovers(prefix: &str) -> Result<usize, usize> {
    let alive = live_nodes(prefix);
    if alive > 0 {
        return Err(alive);
    }
    Ok(files_of(prefix)
        .iter()
        .filter(|p| std::fs::remove_file(p).is_ok())
        .count())
}
