//! `chainlight render`: flags to `RenderSettings`, progress bar, Ctrl-C, EXR + PNG output, summary.

use std::path::{Path, PathBuf};
use std::sync::atomic::{AtomicBool, Ordering};
use std::time::Duration;

use clap::Args;
use render::image_io;
use render::light::EnvironmentLight;
use render::scene::{LoadOptions, Scene};
use render::session::{self, Budget, RenderOutput, RenderSettings};
use render::{IntegratorKind, MethodSettings, INTEGRATORS};

use super::integrator::IntegratorChoice;
use super::method_flags::MethodFlags;
use super::outputs::{self, Named};
use super::progress::BarProgress;
use super::{parse, shard_cmd, CliResult};

/// The largest `--width` / `--height`.
const MAX_SIDE: u32 = 16_384;

/// Set by the Ctrl-C handler; the session polls it and returns the partial image.
static CANCEL: AtomicBool = AtomicBool::new(false);

/// Arguments of `chainlight render`.
#[derive(Debug, Args)]
#[command(
    after_help = "Ctrl-C (or SIGTERM) stops the render early and still writes the image rendered \
                  so far; a second one aborts without writing (files are replaced atomically: \
                  an aborted write leaves the old file)."
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
    /// Render only shard K of N (0 <= K < N, 2 <= N <= 4096) of the fixed work list and write its
    /// accumulators to `--output` (a .clpart file); `chainlight merge` adds the N parts up to
    /// the image one process would render (bit-identical under --spp). docs/cluster.md.
    #[arg(long, allow_negative_numbers = true, value_name = "K/N", value_parser = shard_cmd::parse_shard)]
    shard: Option<render::shard::Shard>,
    /// MCMC integrators with a separate direct-lighting pass: also write the pass's image and
    /// the chains' part as `<stem>_direct.exr` and `<stem>_chains.exr` (the image is their
    /// sum), e.g. to compare methods that share the pass without its noise.
    #[arg(long)]
    write_parts: bool,
}

/// The default `--spp`.
const DEFAULT_SPP: u32 = 16;

/// The stem of the output file names (`out` of `out.exr`).
fn stem(output: &Path) -> String {
    output
        .file_stem()
        .map_or_else(|| "chainlight".into(), |x| x.to_string_lossy().into_owned())
}

/// The MIS-weighted image of BDPT strategy `(s, t)`: `<stem>_s<S>_t<T>.exr` next to `output`.
fn strategy_path(output: &Path, (s, t): (u8, u8)) -> PathBuf {
    output.with_file_name(format!("{}_s{s}_t{t}.exr", stem(output)))
}

/// A part of an image with a direct-lighting pass: `<stem>_<part>.exr` next to `output`.
fn part_path(output: &Path, part: &str) -> PathBuf {
    output.with_file_name(format!("{}_{part}.exr", stem(output)))
}

/// The delayed-rejection stage map: `<stem>_stage2.exr` next to `output` (and its `.png`).
fn stage_map_path(output: &Path) -> PathBuf {
    output.with_file_name(format!("{}_stage2.exr", stem(output)))
}

/// Every file a render of `settings` writes besides the EXR and its PNG preview: the strategy
/// images of `bdpt --strategy-images`, the stage map of `drmlt`.
fn side_files(output: &Path, settings: &RenderSettings) -> Vec<Named> {
    let mut files = Vec::new();
    if matches!(settings.method, MethodSettings::Bdpt(b) if b.strategy_images) {
        for strategy in render::bdpt::strategy_list(settings.max_depth) {
            files.push(Named::new(
                "the strategy image",
                strategy_path(output, strategy),
            ));
        }
    }
    if settings.integrator() == IntegratorKind::Drmlt {
        let map = stage_map_path(output);
        files.push(Named::new(
            "the DR stage map preview",
            map.with_extension("png"),
        ));
        files.push(Named::new("the DR stage map", map));
    }
    files
}

/// Checks the paths before rendering, so a long render never ends in an unwritable output and
/// never overwrites its own inputs: the scene and the environment map are regular files, and
/// every output (the EXR, its PNG preview and the side files; with `--shard`, the part file
/// alone) can be written and is not an input. Returns the PNG preview's path.
fn check_paths(args: &RenderArgs, settings: &RenderSettings) -> CliResult<PathBuf> {
    let is_ext = |p: &Path, ext: &str| {
        p.extension()
            .is_some_and(|e| e.to_string_lossy().eq_ignore_ascii_case(ext))
    };
    let mut inputs = Vec::new();
    if let Some(scene) = &args.scene {
        if !(is_ext(scene, "gltf") || is_ext(scene, "glb")) {
            return Err(format!(
                "SCENE must be a .gltf or .glb file, got '{}'",
                scene.display()
            )
            .into());
        }
        render::files::regular_file_metadata(scene).map_err(|e| match e.kind() {
            std::io::ErrorKind::NotFound => format!("SCENE '{}': no such file", scene.display()),
            _ => format!("SCENE '{}': {e}", scene.display()),
        })?;
        inputs.push(Named::new("SCENE", scene));
    }
    if let Some(parse::EnvArg::File(map)) = &args.env {
        inputs.push(Named::new("--env", map));
    }
    if args.shard.is_some() {
        // A shard writes only its part file (no preview, no side files).
        shard_cmd::check_part_path(&args.output, &inputs)?;
        return Ok(args.output.with_extension("png"));
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
    let mut outputs = vec![
        Named::new("--output", &args.output),
        Named::new("the PNG preview", &png),
    ];
    outputs.extend(side_files(&args.output, settings));
    if args.write_parts {
        for part in ["direct", "chains"] {
            outputs.push(Named::new(
                format!("the {part} part"),
                part_path(&args.output, part),
            ));
        }
    }
    outputs::check(&outputs, &inputs)?;
    Ok(png)
}

/// Builds the session settings from validated flags; `given` says which flags were typed.
fn settings(args: &RenderArgs, given: &dyn Fn(&str) -> bool) -> CliResult<RenderSettings> {
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
        method: args.method.settings(args.integrator.info.kind, given)?,
    })
}

/// Renders, writes the EXR, the PNG preview and the side files (or, with `--shard`, the
/// part file), prints a summary. `given` says which flags were typed on the command line.
pub(crate) fn run(args: RenderArgs, given: &dyn Fn(&str) -> bool) -> CliResult<()> {
    let settings = settings(&args, given)?;
    if args.shard.is_some() && args.method.strategy_images {
        return Err("--strategy-images cannot be combined with --shard (a part holds only the image's accumulators)".into());
    }
    let png_path = check_paths(&args, &settings)?;

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
            parse::EnvArg::File(path) => {
                let env = EnvironmentLight::from_file(path, args.env_strength, args.env_rotate)
                    .map_err(|e| format!("--env: {e}"))?;
                let dropped = env.dropped_texels();
                if !dropped.is_empty() {
                    scene.warnings.push(format!(
                        "--env '{}': {} texels with a NaN or infinite channel and {} with a \
                         negative channel; those channels count as 0",
                        path.display(),
                        dropped.non_finite,
                        dropped.negative
                    ));
                }
                Some(env)
            }
        };
        scene.set_environment(environment);
    }
    for warning in &scene.warnings {
        eprintln!("warning: {warning}");
    }

    let progress = BarProgress::new("samples");
    let bar = progress.handle();
    // Ctrl-C, SIGTERM and SIGHUP (the `termination` feature of `ctrlc`) all stop the render
    // and write what it has; a second one aborts, leaving every output file as it was.
    if let Err(e) = ctrlc::set_handler(move || {
        if CANCEL.swap(true, Ordering::SeqCst) {
            render::files::remove_temporaries();
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
    let shard = args.shard.unwrap_or(render::shard::Shard::WHOLE);
    let output = session::render_shard(&scene, &settings, shard, &progress, &CANCEL);
    progress.finish();
    let output = output?;
    for note in &output.notes {
        eprintln!("note: {note}");
    }
    if let Some(shard) = args.shard {
        let environment = format!(
            "{:?} rotate {} strength {}",
            args.env, args.env_rotate, args.env_strength
        );
        let identity = shard_cmd::scene_identity(args.scene.as_deref(), &environment)?;
        shard_cmd::write_render_part(
            &args.output,
            &settings,
            args.integrator.info.name,
            identity,
            shard,
            &output,
        )?;
        println!(
            "wrote       {} (shard {}/{}; merge the parts with `chainlight merge`)",
            args.output.display(),
            shard.index,
            shard.count
        );
        return Ok(());
    }
    if output.cancelled {
        eprintln!(
            "interrupted: writing the partial image ({} samples, {:.2} per pixel)",
            output.samples,
            per_pixel(&output, &settings)
        );
    }
    // The image first: a side file that cannot be written loses nothing else. Every write is
    // attempted; the failures are reported together at the end.
    let mut failed = Vec::new();
    let mut written = Vec::new();
    let mut write = |path: &Path, what: &str, result: Result<(), image_io::ImageError>| match result
    {
        Ok(()) => written.push(format!("{}{what}", path.display())),
        Err(e) => failed.push(e.to_string()),
    };
    write(
        &args.output,
        "",
        image_io::write_exr(&args.output, &output.image),
    );
    write(
        &png_path,
        "",
        image_io::write_png(&png_path, &output.image, args.exposure),
    );
    for (strategy, img) in &output.strategy_images {
        let path = strategy_path(&args.output, *strategy);
        write(&path, "", image_io::write_exr(&path, img));
    }
    if args.write_parts {
        match &output.direct_parts {
            Some(parts) => {
                for (part, img) in [("direct", &parts.direct), ("chains", &parts.chains)] {
                    let path = part_path(&args.output, part);
                    write(&path, "", image_io::write_exr(&path, img));
                }
            }
            None => eprintln!(
                "note: --write-parts: this render ran no separate direct-lighting pass, so there are no parts to write"
            ),
        }
    }
    if let Some(map) = &output.stage_map {
        // The delayed-rejection stage map (share of each pixel's estimate from second-stage
        // moves, 0..=1) and a PNG preview.
        let path = stage_map_path(&args.output);
        write(&path, " (DR stage map)", image_io::write_exr(&path, map));
        let png = path.with_extension("png");
        write(&png, "", image_io::write_png(&png, map, 0.0));
    }
    print_summary(&args, &settings, &output, &written);
    if failed.is_empty() {
        Ok(())
    } else {
        Err(format!(
            "{} of {} files could not be written (the others were): {}",
            failed.len(),
            failed.len() + written.len(),
            failed.join("; ")
        )
        .into())
    }
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

/// The normalisation of a Markov chain render and the error of the brightness it causes,
/// with a note when that error exceeds [`render::methods::BRIGHTNESS_TARGET`].
fn print_brightness(m: &render::methods::McmcStats, mean: f64) {
    if m.normalization_given {
        println!("brightness  mean luminance {mean:.6}, b = {:.6} given", m.b);
        return;
    }
    let error = m.brightness_standard_error;
    println!(
        "brightness  mean luminance {mean:.6}, standard error {:.2} % (b = {:.6} +- {:.2e} from {} bootstrap samples and {} large steps)",
        100.0 * error,
        m.b,
        m.b_standard_error,
        m.bootstrap_samples,
        m.large_step_samples
    );
    let target = render::methods::BRIGHTNESS_TARGET;
    if error > target {
        println!(
            "note        the brightness standard error {:.2} % exceeds {:.0} %: more --bootstrap-samples, a larger budget (large steps refine b), or --normalization with a reference",
            100.0 * error,
            100.0 * target
        );
    }
}

fn print_summary(
    args: &RenderArgs,
    settings: &RenderSettings,
    output: &RenderOutput,
    written: &[String],
) {
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
    if let Some(m) = output.mcmc.as_ref().filter(|m| !m.found_nothing) {
        print_brightness(m, output.image.mean_luminance());
    }
    println!("rate        {rate:.0} samples/s");
    println!("non-finite  {} samples dropped", output.dropped_nonfinite);
    println!("elapsed     {secs:.2} s");
    for file in written {
        println!("wrote       {file}");
    }
}
