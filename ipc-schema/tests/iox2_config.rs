//! `config/iceoryx2.toml` is the cell's own iceoryx2 configuration for the
//! default prefix `phri_`: iceoryx2's tools (`iox2 service list`) and its
//! Python binding read `config/iceoryx2.toml` from the working directory, so
//! run from the repository root they see the cell. The file must stay what
//! the cell's nodes use; `PHRI_WRITE_IOX2_CONFIG=1` writes it anew.

use std::path::Path;

#[test]
fn the_shipped_iceoryx2_config_is_the_cells() {
    let path = Path::new(env!("CARGO_MANIFEST_DIR")).join("../config/iceoryx2.toml");
    let ours = phri_ipc::node_config("phri_").unwrap();
    if std::env::var_os("PHRI_WRITE_IOX2_CONFIG").is_some() {
        let text = format!(
            "# iceoryx2's configuration for the phri cell's default namespace (prefix phri_):\n# iox2 and the Python binding read config/iceoryx2.toml from the working\n# directory. Generated from the cell's own (ipc-schema/tests/iox2_config.rs).\n{}",
            toml::to_string(&ours).unwrap()
        );
        std::fs::write(&path, text).unwrap();
    }
    let text = std::fs::read_to_string(&path).expect("config/iceoryx2.toml");
    let shipped: iceoryx2::config::Config = toml::from_str(&text).expect("a valid iceoryx2 config");
    assert_eq!(
        shipped, ours,
        "config/iceoryx2.toml differs from the cell's configuration"
    );
    assert_eq!(shipped.global.prefix.to_string(), "phri_");
}
