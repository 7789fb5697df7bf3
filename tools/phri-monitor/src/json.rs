//! The JSON views live in `phri-ipc-json`, shared with `phri-record`.

pub use phri_ipc_json::*;
