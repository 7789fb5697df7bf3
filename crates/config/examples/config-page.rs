//! Prints the guide's configuration key reference, rendered from this
//! crate's definitions ([`phri_config::page::render`]). From the
//! workspace's root:
//! `cargo run --release -p phri-config --example config-page > docs/configuration-keys.md`

fn main() {
    print!("{}", phri_config::page::render());
}
