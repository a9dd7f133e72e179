//! Command-line parsing and dispatch for the `chainlight` binary.

mod compare_cmd;
mod flag_rules;
mod integrator;
mod method_flags;
mod outputs;
mod parse;
mod progress;
mod render_cmd;
mod report_cmd;
mod shard_cmd;
mod sweep_cmd;

use std::error::Error;
use std::process::ExitCode;

use clap::{CommandFactory, FromArgMatches, Parser, Subcommand};

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
    /// Add up the parts of a render split with `render --shard K/N` into its EXR.
    Merge(shard_cmd::MergeArgs),
    /// Run a sweep's job list here, run one job of it on a cluster node, show its progress.
    Sweep(sweep_cmd::SweepArgs),
}

/// Parses the command line, runs the command and turns errors into a message and exit code 1
/// (clap's own usage errors exit with code 2).
pub(crate) fn main() -> ExitCode {
    let matches = Cli::command().get_matches();
    let cli = Cli::from_arg_matches(&matches).unwrap_or_else(|e| e.exit());
    let result = match cli.command {
        Command::Render(args) => {
            // Which flags were typed (not defaulted): a typed flag that has no effect on the
            // chosen integrator is an error.
            let render = matches.subcommand_matches("render");
            let given = |id: &str| {
                render.and_then(|m| m.value_source(id))
                    == Some(clap::parser::ValueSource::CommandLine)
            };
            render_cmd::run(args, &given)
        }
        Command::Compare(args) => compare_cmd::run(args),
        Command::Report(args) => report_cmd::run(args),
        Command::Merge(args) => shard_cmd::run(args),
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
