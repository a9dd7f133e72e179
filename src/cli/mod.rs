//! Command-line parsing and dispatch for the `chainlight` binary.

mod compare_cmd;
mod integrator;
mod method_flags;
mod parse;
mod progress;
mod render_cmd;
mod report_cmd;
mod sweep_cmd;

use std::error::Error;
use std::process::ExitCode;

use clap::{Parser, Subcommand};

/// Errors reaching `main`: every message names the file or flag at fault.
pub(crate) type CliResult<T> = Result<T, Box<dyn Error + Send + Sync>>;

/// Composable MCMC light transport: render scenes and compare images.
#[derive(Debug, Parser)]
#[command(name = "chainlight", version, about, propagate_version = true)]
struct Cli {
    #[command(subcommand)]
    command: Command,
}

// Parsed once per process: boxing the large `render` arguments would gain nothing.
#[allow(clippy::large_enum_variant)]
#[derive(Debug, Subcommand)]
enum Command {
    /// Render a glTF scene (or the built-in Cornell box) to an EXR and a PNG preview.
    Render(render_cmd::RenderArgs),
    /// Compare an EXR image with a reference EXR: print error metrics, write an error map.
    Compare(compare_cmd::CompareArgs),
    /// Write a self-contained HTML report comparing result images with a reference.
    Report(report_cmd::ReportArgs),
    /// Run a sweep's job list here, run one job of it on a cluster node, show its progress.
    Sweep(sweep_cmd::SweepArgs),
}

/// Parses the command line, runs the command and turns errors into a message and exit code 1
/// (clap's own usage errors exit with code 2).
pub(crate) fn main() -> ExitCode {
    let cli = Cli::parse();
    let result = match cli.command {
        Command::Render(args) => render_cmd::run(args),
        Command::Compare(args) => compare_cmd::run(args),
        Command::Report(args) => report_cmd::run(args),
        Command::Sweep(args) => sweep_cmd::run(args),
    };
    match result {
        Ok(()) => ExitCode::SUCCESS,
        Err(error) => {
            eprintln!("error: {}", chain(error.as_ref()));
            ExitCode::FAILURE
        }
    }
}

/// `error: cause: cause ...`, skipping causes whose text the outer message already contains.
fn chain(error: &(dyn Error + 'static)) -> String {
    let mut message = error.to_string();
    let mut source = error.source();
    while let Some(cause) = source {
        let text = cause.to_string();
        if !message.contains(&text) {
            message.push_str(": ");
            message.push_str(&text);
        }
        source = cause.source();
    }
    message
}
