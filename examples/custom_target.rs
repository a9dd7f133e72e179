//! `cargo run --release --example custom_target` from the workspace root: the program is
//! `crates/pss/examples/custom_target.rs` (also the crate-level example of `pss`).

#[path = "../crates/pss/examples/custom_target.rs"]
mod custom_target;

fn main() -> std::io::Result<()> {
    custom_target::main()
}
