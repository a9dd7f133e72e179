//! `cargo run --release --example custom_target` from the workspace root: the program is
//! `crates/pss/examples/pss_custom_target.rs` (also the crate-level example of `pss`).

#[path = "../crates/pss/examples/pss_custom_target.rs"]
mod pss_custom_target;

fn main() -> std::io::Result<()> {
    pss_custom_target::main()
}
