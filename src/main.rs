//! The `chainlight` command-line tool: render a scene to EXR + PNG, or compare two EXR images.

mod cli;

fn main() -> std::process::ExitCode {
    cli::main()
}
