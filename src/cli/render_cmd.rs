//! `chainlight render`: flags to `RenderSettings`, progress bar, Ctrl-C, EXR + PNG output, summary.

use std::path::{Path, PathBuf};
use std::sync::atomic::{AtomicBool, Ordering};
use std::time::Duration;

use clap::Args;
use render::image_io;
use render::light::EnvironmentLight;
use render::scene::{LoadOptions, Scene};
use render::session::{self, Budget, RenderOutput, RenderSettings};
use render::{IntegratorKind, INTEGRATORS};

use super::integrator::IntegratorChoice;
use super::method_flags::MethodFlags;
use super::progress::BarProgress;
use super::{parse, CliResult};

/// The largest `--width` / `--height`.
const MAX_SIDE: u32 = 16_384;

/// Set by the Ctrl-C handler; the session polls it and returns the partial image.
static CANCEL: AtomicBool = AtomicBool::new(false);

/// Arguments of `chainlight render`.
#[derive(Debug, Args)]
#[command(
    after_help = "Ctrl-C stops the render early and still writes the image rendered so far; \
                        a second Ctrl-C aborts without writing."
)]
pub(crate) struct RenderArgs {
    /// A glTF 2.0 scene (.gltf or .glb) [default: the built-in Cornell box].
    #[arg(value_name = "SCENE")]
    scene: Option<PathBuf>,
    /// Let the scene's buffer and image URIs name files outside the scene file's folder
    /// (absolute paths, `..`, `file://` URIs, symbolic links leading out). Without it such
    /// URIs are an error. Only regular files are read either way.
    #[arg(long)]
    allow_external_files: bool,
    /// The light-transport algorithm.
    #[arg(long, value_enum, default_value = INTEGRATORS[0].name)]
    integrator: IntegratorChoice,
    /// Samples per pixel (for MCMC integrators: mutations per pixel) [default: 16].
    #[arg(long, visible_alias = "mutations-per-pixel", allow_negative_numbers = true, value_name = "N", conflicts_with = "time",
          value_parser = clap::value_parser!(u32).range(1..=1_000_000))]
    spp: Option<u32>,
    /// Render for this many seconds instead of a fixed sample count (not bit-reproducible).
    #[arg(long, allow_negative_numbers = true, value_name = "SECONDS", value_parser = parse::seconds)]
    time: Option<Duration>,
    /// Worker threads, 1..=1024 [default: the available parallelism]. The image does not depend on it.
    #[arg(long, allow_negative_numbers = true, value_name = "T", value_parser = clap::value_parser!(u16).range(1..=1024))]
    threads: Option<u16>,
    /// Master seed; the same seed gives a bit-identical image under --spp.
    #[arg(
        long,
        allow_negative_numbers = true,
        value_name = "K",
        default_value_t = 0
    )]
    seed: u64,
    /// Image width in pixels, 1..=16384.
    #[arg(long, allow_negative_numbers = true, value_name = "W", default_value_t = 256,
          value_parser = clap::value_parser!(u32).range(1..=i64::from(MAX_SIDE)))]
    width: u32,
    /// Image height in pixels, 1..=16384.
    #[arg(long, allow_negative_numbers = true, value_name = "H", default_value_t = 256,
          value_parser = clap::value_parser!(u32).range(1..=i64::from(MAX_SIDE)))]
    height: u32,
    /// Maximum path depth (bounces), 0..=1024; 0 shows only directly visible emitters.
    #[arg(long, allow_negative_numbers = true, value_name = "D", default_value_t = 5,
          value_parser = clap::value_parser!(u32).range(0..=1024))]
    max_depth: u32,
    /// Output OpenEXR file; a tonemapped PNG preview is written next to it (same stem, .png).
    #[arg(short, long, value_name = "OUT.exr", default_value = "chainlight.exr")]
    output: PathBuf,
    /// The method's own flags.
    #[command(flatten)]
    method: MethodFlags,
    /// Exposure of the PNG preview in stops, -64..=64 (the EXR is never scaled).
    #[arg(long, allow_negative_numbers = true, value_name = "STOPS", default_value = "0", value_parser = parse::stops)]
    exposure: f32,
    /// Environment light: `none`, a radiance `R,G,B` or grey `V` (each in 0..=1e6), or an
    /// equirectangular map (.exr, .hdr, .pfm; +Y up, image centre towards -Z) [default: the
    /// scene's lights; a scene without any light gets a uniform environment of radiance 1].
    #[arg(long, allow_negative_numbers = true, value_name = "none|R,G,B|FILE", value_parser = parse::environment)]
    env: Option<parse::EnvArg>,
    /// Rotation of the environment about +Y in degrees, -360..=360.
    #[arg(long, allow_negative_numbers = true, value_name = "DEG", default_value = "0", requires = "env", value_parser = parse::env_rotation)]
    env_rotate: f32,
    /// Multiplier of the environment's radiance, 0..=1e6.
    #[arg(long, allow_negative_numbers = true, value_name = "S", default_value = "1", requires = "env", value_parser = parse::env_strength)]
    env_strength: f32,
}

/// The default `--spp`.
const DEFAULT_SPP: u32 = 16;

/// Checks the paths before rendering, so a long render never ends in an unwritable output.
fn check_paths(args: &RenderArgs) -> CliResult<PathBuf> {
    let is_ext = |p: &Path, ext: &str| {
        p.extension()
            .is_some_and(|e| e.to_string_lossy().eq_ignore_ascii_case(ext))
    };
    if let Some(scene) = &args.scene {
        if !(is_ext(scene, "gltf") || is_ext(scene, "glb")) {
            return Err(format!(
                "SCENE must be a .gltf or .glb file, got '{}'",
                scene.display()
            )
            .into());
        }
        if !scene.is_file() {
            return Err(format!("SCENE '{}': no such file", scene.display()).into());
        }
    }
    if !is_ext(&args.output, "exr") {
        return Err(format!(
            "--output must name an .exr file, got '{}'",
            args.output.display()
        )
        .into());
    }
    let dir = match args.output.parent() {
        Some(d) if !d.as_os_str().is_empty() => d,
        _ => Path::new("."),
    };
    if !dir.is_dir() {
        return Err(format!(
            "--output '{}': directory '{}' does not exist",
            args.output.display(),
            dir.display()
        )
        .into());
    }
    let png = args.output.with_extension("png");
    probe_writable(&args.output, "--output")?;
    probe_writable(&png, "the PNG preview")?;
    Ok(png)
}

/// Fails unless `path` can be written, without changing anything: an existing regular file is
/// opened for writing without truncation; a missing one is created and removed again. So a
/// read-only directory, an output path that is a directory or an unwritable file is reported
/// before rendering, not after.
fn probe_writable(path: &Path, what: &str) -> CliResult<()> {
    let fail = |why: &dyn std::fmt::Display| -> Box<dyn std::error::Error + Send + Sync> {
        format!("{what} '{}' cannot be written: {why}", path.display()).into()
    };
    match std::fs::metadata(path) {
        Ok(meta) if meta.is_dir() => Err(fail(&"it is a directory")),
        Ok(meta) if !meta.is_file() => Err(fail(&"it is not a regular file")),
        Ok(_) => {
            std::fs::OpenOptions::new()
                .write(true)
                .open(path)
                .map_err(|e| fail(&e))?;
            Ok(())
        }
        Err(e) if e.kind() == std::io::ErrorKind::NotFound => {
            std::fs::OpenOptions::new()
                .write(true)
                .create_new(true)
                .open(path)
                .map_err(|e| fail(&e))?;
            std::fs::remove_file(path).map_err(|e| fail(&e))
        }
        Err(e) => Err(fail(&e)),
    }
}

/// Builds the session settings from validated flags.
fn settings(args: &RenderArgs) -> CliResult<RenderSettings> {
    let budget = match args.time {
        Some(time) => Budget::Time(time),
        None => Budget::SamplesPerPixel(args.spp.unwrap_or(DEFAULT_SPP)),
    };
    let threads = args.threads.map_or_else(
        || std::thread::available_parallelism().map_or(1, |n| n.get()),
        usize::from,
    );
    Ok(RenderSettings {
        width: args.width,
        height: args.height,
        budget,
        threads,
        seed: args.seed,
        max_depth: args.max_depth,
        method: args.method.settings(args.integrator.info.kind)?,
    })
}

/// Renders, writes the EXR and the PNG preview, prints a summary.
pub(crate) fn run(args: RenderArgs) -> CliResult<()> {
    let png_path = check_paths(&args)?;
    let settings = settings(&args)?;

    let mut scene = match &args.scene {
        None => Scene::cornell_box(settings.width, settings.height),
        Some(path) => Scene::load_with(
            path,
            &LoadOptions {
                allow_external_files: args.allow_external_files,
            },
        )?,
    };
    if let Some(env) = &args.env {
        let environment = match env {
            parse::EnvArg::None => None,
            parse::EnvArg::Rgb(rgb) => Some(
                EnvironmentLight::constant(render::glam::Vec3::from(*rgb) * args.env_strength)
                    .rotated(args.env_rotate),
            ),
            parse::EnvArg::File(path) => Some(
                EnvironmentLight::from_file(path, args.env_strength, args.env_rotate)
                    .map_err(|e| format!("--env: {e}"))?,
            ),
        };
        scene.set_environment(environment);
    }
    for warning in &scene.warnings {
        eprintln!("warning: {warning}");
    }

    let progress = BarProgress::new("samples");
    let bar = progress.handle();
    if let Err(e) = ctrlc::set_handler(move || {
        if CANCEL.swap(true, Ordering::SeqCst) {
            eprintln!("\ninterrupted twice: aborting without writing an image");
            std::process::exit(130);
        }
        bar.println(
            "Ctrl-C: stopping; the image rendered so far will be written (Ctrl-C again to abort)",
        );
    }) {
        eprintln!(
            "warning: cannot install the Ctrl-C handler ({e}); Ctrl-C will abort without writing"
        );
    }

    let budget = match settings.budget {
        Budget::SamplesPerPixel(spp) => format!("{spp} spp"),
        Budget::Time(t) => format!("{:.1} s", t.as_secs_f64()),
    };
    eprintln!(
        "rendering {} at {}x{} with {}, {budget}, {} threads (Ctrl-C writes the partial image)",
        scene_name(&args),
        settings.width,
        settings.height,
        args.integrator.info.name,
        settings.threads
    );
    let output = session::render(&scene, &settings, &progress, &CANCEL);
    progress.finish();
    let output = output?;
    for note in &output.notes {
        eprintln!("note: {note}");
    }
    if args.method.strategy_images && settings.integrator() != IntegratorKind::Bdpt {
        eprintln!("warning: --strategy-images applies to --integrator bdpt only; ignored");
    }
    for ((s, t), img) in &output.strategy_images {
        let stem = args
            .output
            .file_stem()
            .map_or_else(|| "chainlight".into(), |x| x.to_string_lossy().into_owned());
        let path = args.output.with_file_name(format!("{stem}_s{s}_t{t}.exr"));
        image_io::write_exr(&path, img)?;
        println!("wrote       {}", path.display());
    }
    if let Some(map) = &output.stage_map {
        // The delayed-rejection stage map (share of each pixel's estimate from second-stage
        // moves, 0..=1) as `<stem>_stage2.exr` and a PNG preview.
        let stem = args
            .output
            .file_stem()
            .map_or_else(|| "chainlight".into(), |x| x.to_string_lossy().into_owned());
        let path = args.output.with_file_name(format!("{stem}_stage2.exr"));
        image_io::write_exr(&path, map)?;
        image_io::write_png(path.with_extension("png"), map, 0.0)?;
        println!("wrote       {} (DR stage map)", path.display());
    }
    if output.cancelled {
        eprintln!(
            "interrupted: writing the partial image ({} samples, {:.2} per pixel)",
            output.samples,
            per_pixel(&output, &settings)
        );
    }
    image_io::write_exr(&args.output, &output.image)?;
    image_io::write_png(&png_path, &output.image, args.exposure)?;
    print_summary(&args, &settings, &output, &png_path);
    Ok(())
}

fn scene_name(args: &RenderArgs) -> String {
    args.scene.as_ref().map_or_else(
        || "the built-in Cornell box".to_string(),
        |p| p.display().to_string(),
    )
}

fn per_pixel(output: &RenderOutput, settings: &RenderSettings) -> f64 {
    output.samples as f64 / (f64::from(settings.width) * f64::from(settings.height))
}

fn print_summary(args: &RenderArgs, settings: &RenderSettings, output: &RenderOutput, png: &Path) {
    let secs = output.elapsed.as_secs_f64();
    let rate = if secs > 0.0 {
        output.samples as f64 / secs
    } else {
        0.0
    };
    println!("scene       {}", scene_name(args));
    println!(
        "integrator  {} ({}x{}, max depth {}, seed {}, {} threads)",
        args.integrator.info.name,
        settings.width,
        settings.height,
        settings.max_depth,
        settings.seed,
        settings.threads
    );
    println!(
        "samples     {} ({:.2} per pixel){}",
        output.samples,
        per_pixel(output, settings),
        if output.cancelled { ", cancelled" } else { "" }
    );
    if output.unsampled_pixels > 0 {
        println!(
            "unsampled   {} pixels ({:.1} %): the image is incomplete",
            output.unsampled_pixels,
            100.0 * output.unsampled_pixels as f64
                / (f64::from(settings.width) * f64::from(settings.height))
        );
    }
    println!("rate        {rate:.0} samples/s");
    println!("non-finite  {} samples dropped", output.dropped_nonfinite);
    println!("elapsed     {secs:.2} s");
    println!("wrote       {}", args.output.display());
    println!("wrote       {}", png.display());
}
