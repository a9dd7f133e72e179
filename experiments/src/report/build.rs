//! Builds `report.html`: metrics over seeds, error maps, convergence SVG and the template.

use std::path::{Path, PathBuf};

use base64::Engine as _;
use render::image::Image;
use render::image_io::{self, ErrorScale};
use render::metrics;
use serde::Serialize;

use super::manifest::{resolve, RunManifest};
use super::ReportError;
use crate::plot::{self, Axes, Curve};

/// The page template (HTML, CSS and script; no external resources).
const TEMPLATE: &str = include_str!("report.html.j2");

/// Error-map scale: relative error from 1e-3 (bottom colour) to 1 (yellow), as `compare`.
const ERROR_SCALE: ErrorScale = ErrorScale::Log10 {
    min: 1e-3,
    max: 1.0,
};

/// One metric summarised over seeds.
#[derive(Serialize)]
struct Summary {
    median: String,
    min: String,
    max: String,
    best: bool,
}

/// A method as the template sees it (`error_map` is a data URI built here: base64 only, so
/// the template marks it safe).
#[derive(Serialize)]
struct MethodView {
    name: String,
    colour: String,
    seeds: usize,
    shown_seed: u64,
    metrics: Vec<Summary>,
    parameters: Vec<(String, String)>,
    error_map: String,
}

/// Everything the template renders.
#[derive(Serialize)]
struct PageView {
    title: String,
    commit: String,
    width: usize,
    height: usize,
    parameters: Vec<(String, String)>,
    metric_names: Vec<&'static str>,
    methods: Vec<MethodView>,
    colour_bar: String,
    convergence_svg: Option<String>,
    data_json: String,
    generated_by: String,
}

/// Float pixel data handed to the page's script.
#[derive(Serialize)]
struct PixelData {
    width: usize,
    height: usize,
    reference: String,
    methods: Vec<NamedPixels>,
}

#[derive(Serialize)]
struct NamedPixels {
    name: String,
    pixels: String,
}

/// Reads the images of `manifest` (paths relative to `run_dir`), computes everything and writes
/// the report to `output`. Returns `output`.
///
/// For each method the viewer and the error map show the seed whose relMSE is the median over
/// seeds (the lower median for an even count); the table shows the median and the range of
/// each metric over seeds.
///
/// # Errors
/// [`ReportError`] naming the file or method at fault: unreadable images, a size mismatch with
/// the reference, an invalid manifest, an unwritable output.
pub fn write_report(
    manifest: &RunManifest,
    run_dir: impl AsRef<Path>,
    output: impl AsRef<Path>,
) -> Result<PathBuf, ReportError> {
    let html = render_html(manifest, run_dir.as_ref())?;
    let output = output.as_ref();
    if let Some(parent) = output.parent().filter(|p| !p.as_os_str().is_empty()) {
        std::fs::create_dir_all(parent).map_err(|source| ReportError::Io {
            path: parent.to_path_buf(),
            source,
        })?;
    }
    render::files::write_bytes_atomic(output, html).map_err(|source| ReportError::Io {
        path: output.to_path_buf(),
        source,
    })?;
    Ok(output.to_path_buf())
}

/// The report as a string.
pub(crate) fn render_html(manifest: &RunManifest, run_dir: &Path) -> Result<String, ReportError> {
    manifest.validate()?;
    let reference_path = resolve(run_dir, &manifest.reference);
    let reference = image_io::read_image(&reference_path)?;
    let (width, height) = (reference.width, reference.height);

    let metric_names = vec!["MSE", "relMSE", "rRMSE", "MAD"];
    let mut methods = Vec::new();
    let mut pixels = Vec::new();
    let mut medians: Vec<Vec<f64>> = Vec::new();
    for (index, method) in manifest.methods.iter().enumerate() {
        let mut per_seed = Vec::new();
        for seed_image in &method.images {
            let path = resolve(run_dir, &seed_image.path);
            let image = image_io::read_image(&path)?;
            let m = metrics::compare(&image, &reference).map_err(|source| ReportError::Metric {
                path: path.clone(),
                source,
            })?;
            per_seed.push((seed_image.seed, image, [m.mse, m.relmse, m.rrmse, m.mad]));
        }
        // The seed with the median relMSE represents the method in the viewer.
        let mut order: Vec<usize> = (0..per_seed.len()).collect();
        order.sort_by(|&a, &b| per_seed[a].2[1].total_cmp(&per_seed[b].2[1]));
        let shown = order[(order.len() - 1) / 2];
        let (shown_seed, shown_image) = (per_seed[shown].0, &per_seed[shown].1);
        let map = metrics::relative_error_map(shown_image, &reference).map_err(|source| {
            ReportError::Metric {
                path: resolve(run_dir, &method.images[shown].path),
                source,
            }
        })?;
        let error_map = png_data_uri(
            &image_io::false_color_rgb8(&map, ERROR_SCALE),
            width,
            height,
        )?;
        let mut summaries = Vec::new();
        let mut method_medians = Vec::new();
        for k in 0..metric_names.len() {
            let values: Vec<f64> = per_seed.iter().map(|s| s.2[k]).collect();
            let (median, min, max) = metrics::median_min_max(&values).unwrap_or_default();
            method_medians.push(median);
            summaries.push(Summary {
                median: format!("{median:.4e}"),
                min: format!("{min:.3e}"),
                max: format!("{max:.3e}"),
                best: false,
            });
        }
        medians.push(method_medians);
        pixels.push(NamedPixels {
            name: method.name.clone(),
            pixels: float_base64(shown_image),
        });
        methods.push(MethodView {
            name: method.name.clone(),
            colour: plot::css_colour(index),
            seeds: per_seed.len(),
            shown_seed,
            metrics: summaries,
            parameters: method
                .parameters
                .iter()
                .map(|(k, v)| (k.clone(), v.clone()))
                .collect(),
            error_map,
        });
    }
    // Mark the lowest median of each metric.
    for k in 0..metric_names.len() {
        let best = medians
            .iter()
            .enumerate()
            .min_by(|a, b| a.1[k].total_cmp(&b.1[k]))
            .map(|(i, _)| i);
        if let Some(best) = best {
            methods[best].metrics[k].best = true;
        }
    }

    let curves: Vec<Curve> = manifest
        .methods
        .iter()
        .map(|m| Curve {
            name: m.name.clone(),
            series: m
                .convergence
                .iter()
                .map(|s| s.points.iter().map(|p| (p.time_s, p.relmse)).collect())
                .collect(),
        })
        .collect();
    let convergence_svg =
        plot::log_log_svg(Axes::RELMSE_VS_TIME, &curves).map_err(ReportError::Output)?;

    let data = PixelData {
        width,
        height,
        reference: float_base64(&reference),
        methods: pixels,
    };
    let data_json = serde_json::to_string(&data)
        .map_err(|e| ReportError::Output(format!("pixel data: {e}")))?
        // `<` only occurs inside JSON strings: escaping it keeps `</script>` or `<!--` in a
        // method name from ending or confusing the data block.
        .replace('<', "\\u003c");
    let bar: Vec<f32> = (0..256)
        .map(|i| 10f32.powf(-3.0 + 3.0 * i as f32 / 255.0))
        .collect();
    let colour_bar = png_data_uri(&image_io::false_color_rgb8(&bar, ERROR_SCALE), 256, 1)?;

    let page = PageView {
        title: manifest.title.clone(),
        commit: manifest.commit.clone(),
        width,
        height,
        parameters: manifest
            .parameters
            .iter()
            .map(|(k, v)| (k.clone(), v.clone()))
            .collect(),
        metric_names,
        methods,
        colour_bar,
        convergence_svg,
        data_json,
        generated_by: format!("chainlight {}", env!("CARGO_PKG_VERSION")),
    };
    let mut env = minijinja::Environment::new();
    env.add_template("report.html", TEMPLATE)
        .map_err(|e| ReportError::Output(format!("template: {e}")))?;
    env.get_template("report.html")
        .and_then(|t| t.render(&page))
        .map_err(|e| ReportError::Output(format!("template: {e}")))
}

/// Linear RGB as little-endian `f32` triples, base64: what the page's script decodes.
fn float_base64(image: &Image) -> String {
    let mut bytes = Vec::with_capacity(image.pixels.len() * 12);
    for p in &image.pixels {
        for c in p {
            bytes.extend_from_slice(&c.to_le_bytes());
        }
    }
    base64::engine::general_purpose::STANDARD.encode(bytes)
}

/// `data:image/png;base64,...` of an RGB8 buffer.
fn png_data_uri(rgb: &[u8], width: usize, height: usize) -> Result<String, ReportError> {
    use image::ImageEncoder as _;
    let mut png = Vec::new();
    let (w, h) = (
        u32::try_from(width).map_err(|_| ReportError::Output("image too wide".into()))?,
        u32::try_from(height).map_err(|_| ReportError::Output("image too tall".into()))?,
    );
    image::codecs::png::PngEncoder::new(&mut png)
        .write_image(rgb, w, h, image::ExtendedColorType::Rgb8)
        .map_err(|e| ReportError::Output(format!("PNG encoding: {e}")))?;
    Ok(format!(
        "data:image/png;base64,{}",
        base64::engine::general_purpose::STANDARD.encode(png)
    ))
}
