//! Renders split over processes: `chainlight render ... --shard K/N -o part.clpart` writes one
//! shard's accumulators; `chainlight merge PART... -o out.exr` checks that the parts belong
//! together and writes the image the single-process render would have written.

use std::path::{Path, PathBuf};

use clap::Args;
use render::image_io;
use render::session::{Budget, RenderOutput, RenderSettings};
use render::shard::{read_part, write_part, PartHeader, Partial, Shard, PART_EXTENSION};

use super::outputs::{self, Named};
use super::CliResult;

/// Parses `--shard K/N`: `0 <= K < N`, `2 <= N <= 4096` (one part is the plain render).
pub(crate) fn parse_shard(s: &str) -> Result<Shard, String> {
    let bad = || format!("'{s}' is not K/N with 0 <= K < N and 2 <= N <= 4096 (e.g. 0/4)");
    let (k, n) = s.split_once('/').ok_or_else(bad)?;
    let (index, count): (u32, u32) = (
        k.trim().parse().map_err(|_| bad())?,
        n.trim().parse().map_err(|_| bad())?,
    );
    if !(2..=4096).contains(&count) || index >= count {
        return Err(bad());
    }
    Ok(Shard { index, count })
}

/// Refuses an output path that is not a writable `.clpart` file or that is one of `inputs`
/// (the scene, the environment map).
pub(crate) fn check_part_path(output: &Path, inputs: &[Named]) -> CliResult<()> {
    let ok = output
        .extension()
        .is_some_and(|e| e.to_string_lossy().eq_ignore_ascii_case(PART_EXTENSION));
    if ok {
        outputs::check(&[Named::new("--output", output)], inputs)
    } else {
        Err(format!(
            "--output with --shard must name a .{PART_EXTENSION} file (a partial result for `chainlight merge`), got '{}'",
            output.display()
        )
        .into())
    }
}

/// What identifies the scene a part was rendered from: the scene file's bytes (or the
/// built-in Cornell box) and the environment options.
pub(crate) fn scene_identity(scene: Option<&Path>, environment: &str) -> CliResult<String> {
    let file = match scene {
        None => "built-in Cornell box".to_owned(),
        Some(path) => {
            let bytes = std::fs::read(path)
                .map_err(|e| format!("SCENE '{}': cannot read: {e}", path.display()))?;
            format!("scene file {}", render::shard::fingerprint(&bytes))
        }
    };
    Ok(format!("{file}; environment {environment}"))
}

/// Writes the part of a sharded render.
pub(crate) fn write_render_part(
    output: &Path,
    settings: &RenderSettings,
    integrator: &str,
    scene: String,
    shard: Shard,
    rendered: &RenderOutput,
) -> CliResult<()> {
    let partial = rendered
        .partial
        .as_ref()
        .ok_or("internal: the sharded render returned no accumulators")?;
    let mut fingerprint = settings.clone();
    fingerprint.threads = 0;
    let header = PartHeader {
        integrator: integrator.to_owned(),
        settings: format!("{fingerprint:?}"),
        scene,
        seed: settings.seed,
        budget: match settings.budget {
            Budget::SamplesPerPixel(n) => format!("--spp {n}"),
            Budget::Time(t) => format!("--time {}", t.as_secs_f64()),
        },
        shard,
    };
    write_part(output, &header, partial)?;
    Ok(())
}

/// Arguments of `chainlight merge`.
#[derive(Debug, Args)]
pub(crate) struct MergeArgs {
    /// The parts (`.clpart` files written by `render --shard K/N`), all N of one render, in
    /// any order.
    #[arg(value_name = "PART", required = true)]
    parts: Vec<PathBuf>,
    /// Output OpenEXR file; a tonemapped PNG preview is written next to it (same stem, .png).
    #[arg(short, long, value_name = "OUT.exr")]
    output: PathBuf,
    /// Exposure of the PNG preview in stops, -64..=64 (the EXR is never scaled).
    #[arg(long, allow_negative_numbers = true, value_name = "STOPS", default_value = "0", value_parser = super::parse::stops)]
    exposure: f32,
}

/// Reads, checks and adds the parts in shard order; writes the image.
pub(crate) fn run(args: MergeArgs) -> CliResult<()> {
    let is_exr = args
        .output
        .extension()
        .is_some_and(|e| e.to_string_lossy().eq_ignore_ascii_case("exr"));
    if !is_exr {
        return Err(format!(
            "--output must name an .exr file, got '{}'",
            args.output.display()
        )
        .into());
    }
    let png = args.output.with_extension("png");
    let inputs: Vec<Named> = args.parts.iter().map(|p| Named::new("PART", p)).collect();
    outputs::check(
        &[
            Named::new("--output", &args.output),
            Named::new("the PNG preview", &png),
        ],
        &inputs,
    )?;
    let mut parts: Vec<(PathBuf, PartHeader, Partial)> = Vec::new();
    for path in &args.parts {
        let (header, partial) = read_part(path)?;
        parts.push((path.clone(), header, partial));
    }
    let (first_path, first, _) = &parts[0];
    for (path, header, _) in &parts[1..] {
        if let Some((what, a, b)) = first.difference(header) {
            return Err(format!(
                "parts '{}' and '{}' are not of the same render: their {what} differs ('{a}' vs '{b}')",
                first_path.display(),
                path.display()
            )
            .into());
        }
    }
    let count = first.shard.count;
    let mut by_index: Vec<Option<usize>> = vec![None; count as usize];
    for (i, (path, header, _)) in parts.iter().enumerate() {
        let slot = &mut by_index[header.shard.index as usize];
        if let Some(j) = slot {
            return Err(format!(
                "shard {}/{count} is given twice: '{}' and '{}'",
                header.shard.index,
                parts[*j].0.display(),
                path.display()
            )
            .into());
        }
        *slot = Some(i);
    }
    let missing: Vec<String> = by_index
        .iter()
        .enumerate()
        .filter(|(_, s)| s.is_none())
        .map(|(k, _)| format!("{k}/{count}"))
        .collect();
    if !missing.is_empty() {
        return Err(format!(
            "missing shard(s) {} of the render ({} of {count} parts given)",
            missing.join(", "),
            parts.len()
        )
        .into());
    }
    let order: Vec<usize> = by_index.into_iter().flatten().collect();
    let mut merged = parts[order[0]].2.clone();
    for &i in &order[1..] {
        merged
            .add(&parts[i].2)
            .map_err(|e| format!("part '{}': {e}", parts[i].0.display()))?;
    }
    let (image, dropped) = merged.image();
    if dropped > 0 {
        eprintln!("note: {dropped} pixel(s) exceed the largest f32 value and were written black");
    }
    image_io::write_exr(&args.output, &image)?;
    image_io::write_png(&png, &image, args.exposure)?;
    println!(
        "merged      {count} parts of {} ({})",
        first.integrator, first.budget
    );
    println!("wrote       {}", args.output.display());
    println!("wrote       {}", png.display());
    Ok(())
}
