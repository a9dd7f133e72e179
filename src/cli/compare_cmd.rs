//! `chainlight compare`: error metrics of an EXR against a reference EXR and a false-colour map.

use std::path::{Path, PathBuf};

use clap::Args;
use render::image_io::{self, ErrorScale};
use render::metrics;

use super::outputs::{self, Named};
use super::{parse, CliResult};

/// Arguments of `chainlight compare`.
#[derive(Debug, Args)]
pub(crate) struct CompareArgs {
    /// The image to measure (OpenEXR .exr or Portable Float Map .pfm).
    #[arg(value_name = "IMAGE")]
    image: PathBuf,
    /// The reference image (.exr or .pfm, same size).
    #[arg(value_name = "REFERENCE")]
    reference: PathBuf,
    /// Where to write the false-colour error map [default: <IMAGE stem>_error.png next to IMAGE].
    #[arg(long, value_name = "PNG")]
    error_map: Option<PathBuf>,
    /// Relative error drawn with the bottom colour of the log scale (ignored with --linear).
    #[arg(long, allow_negative_numbers = true, value_name = "E", default_value = "0.001", value_parser = parse::positive)]
    error_min: f32,
    /// Relative error drawn with the top colour (yellow).
    #[arg(long, allow_negative_numbers = true, value_name = "E", default_value = "1", value_parser = parse::positive)]
    error_max: f32,
    /// Use a linear error scale from 0 to --error-max instead of a logarithmic one.
    #[arg(long)]
    linear: bool,
}

/// `<stem>_error.png` in the directory of `image`.
fn default_error_map(image: &Path) -> PathBuf {
    let stem = image
        .file_stem()
        .map_or_else(|| "image".into(), |s| s.to_string_lossy());
    image.with_file_name(format!("{stem}_error.png"))
}

/// Checks that the error map can be written and is neither input, reads both images, prints
/// the metrics and writes the error map.
pub(crate) fn run(args: CompareArgs) -> CliResult<()> {
    let scale = if args.linear {
        ErrorScale::Linear {
            max: args.error_max,
        }
    } else {
        ErrorScale::Log10 {
            min: args.error_min,
            max: args.error_max,
        }
    };
    scale
        .validate()
        .map_err(|e| format!("--error-min/--error-max: {e}"))?;
    let map_path = args
        .error_map
        .clone()
        .unwrap_or_else(|| default_error_map(&args.image));
    outputs::check(
        &[Named::new("the error map", &map_path)],
        &[
            Named::new("IMAGE", &args.image),
            Named::new("REFERENCE", &args.reference),
        ],
    )?;
    let image = image_io::read_image(&args.image)?;
    let reference = image_io::read_image(&args.reference)?;
    let context = |e: metrics::MetricError| {
        format!(
            "cannot compare {} with reference {}: {e}",
            args.image.display(),
            args.reference.display()
        )
    };
    let m = metrics::compare(&image, &reference).map_err(context)?;
    let map = metrics::relative_error_map(&image, &reference).map_err(context)?;
    image_io::write_false_color(&map_path, &map, image.width, image.height, scale)?;

    println!("image      {}", args.image.display());
    println!("reference  {}", args.reference.display());
    println!("size       {}x{}", image.width, image.height);
    println!("MSE        {:.6e}", m.mse);
    println!("RMSE       {:.6e}", m.rmse);
    println!("relMSE     {:.6e}", m.relmse);
    println!("rRMSE      {:.6e}", m.rrmse);
    println!("MAD        {:.6e}", m.mad);
    let scale_text = match scale {
        ErrorScale::Linear { max } => format!("linear 0..{max}"),
        ErrorScale::Log10 { min, max } => format!("log10 {min}..{max}"),
    };
    println!(
        "error map  {} (per-pixel relative error, viridis, {scale_text})",
        map_path.display()
    );
    Ok(())
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn default_map_path_sits_next_to_the_image() {
        assert_eq!(
            default_error_map(Path::new("out/a.b.exr")),
            Path::new("out/a.b_error.png")
        );
        assert_eq!(
            default_error_map(Path::new("x.exr")),
            Path::new("x_error.png")
        );
    }
}
