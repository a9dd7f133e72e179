//! `chainlight report`: a self-contained HTML comparison report from a run directory or from a
//! reference EXR and result EXRs.

use std::path::{Path, PathBuf};

use clap::Args;
use experiments::report::{self, RunManifest, MANIFEST_FILE};

use super::outputs::{self, Named};
use super::CliResult;

/// Arguments of `chainlight report`.
#[derive(Debug, Args)]
pub(crate) struct ReportArgs {
    /// A run directory holding `run.json` (written by the examples), or, with --reference, the
    /// result images to compare (.exr, .pfm or .hdr), one method each, named after the file.
    #[arg(value_name = "RUN_DIR | IMAGE", required = true)]
    inputs: Vec<PathBuf>,
    /// The reference image; makes the inputs result images instead of a run directory.
    #[arg(long, value_name = "EXR")]
    reference: Option<PathBuf>,
    /// Where to write the report [default: RUN_DIR/report.html, or report.html next to the
    /// first image].
    #[arg(short, long, value_name = "HTML")]
    output: Option<PathBuf>,
    /// Report title (with --reference; a run directory's title comes from its run.json).
    #[arg(long, value_name = "TEXT")]
    title: Option<String>,
}

/// Builds the manifest, writes the report and prints its path.
pub(crate) fn run(args: ReportArgs) -> CliResult<()> {
    let (manifest, run_dir, default_output) = match &args.reference {
        Some(reference) => {
            let mut manifest = RunManifest::from_images(
                reference.clone(),
                &args.inputs,
                report::BUILD_COMMIT.to_string(),
            );
            if let Some(title) = &args.title {
                manifest.title.clone_from(title);
            }
            let out = args.inputs[0].with_file_name("report.html");
            (manifest, PathBuf::new(), out)
        }
        None => {
            if args.inputs.len() != 1 {
                return Err(format!(
                    "expected one run directory, got {} paths (to compare images, pass --reference)",
                    args.inputs.len()
                )
                .into());
            }
            let dir = args.inputs[0].clone();
            let manifest_file = dir.join(MANIFEST_FILE);
            match render::files::regular_file_metadata(&manifest_file) {
                Ok(_) => {}
                Err(e) if e.kind() == std::io::ErrorKind::NotFound => {
                    return Err(format!(
                        "{}: no {MANIFEST_FILE} here (to compare images, pass --reference REF.exr)",
                        dir.display()
                    )
                    .into())
                }
                Err(e) => return Err(format!("{}: {e}", manifest_file.display()).into()),
            }
            let mut manifest = RunManifest::load(&dir)?;
            if let Some(title) = &args.title {
                manifest.title.clone_from(title);
            }
            let out = dir.join("report.html");
            (manifest, dir, out)
        }
    };
    let output = args.output.clone().unwrap_or(default_output);
    outputs::refuse_inputs(
        &[Named::new("the report", &output)],
        &inputs(&manifest, &run_dir),
    )?;
    let written = report::write_report(&manifest, &run_dir, &output)?;
    println!("report     {}", written.display());
    Ok(())
}

/// The files a report of `manifest` reads: `run.json` (of a run directory), the reference and
/// every method's images.
fn inputs(manifest: &RunManifest, run_dir: &Path) -> Vec<Named> {
    let mut files: Vec<Named> = manifest
        .image_files(run_dir)
        .into_iter()
        .map(|(what, path)| Named::new(what, path))
        .collect();
    if !run_dir.as_os_str().is_empty() {
        files.push(Named::new("the run manifest", run_dir.join(MANIFEST_FILE)));
    }
    files
}
