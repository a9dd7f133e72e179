//! The `chainlight` command-line tool: render a scene to EXR + PNG, compare two EXR images, or
//! write an HTML comparison report.

mod cli;

fn main() -> std::process::ExitCode {
    cli::main()
}
