//! Automatic large-step control (Zsolnai & Szirmay-Kalos 2013) on the bundled scenes.
//!
//! For each scene: run PSSMLT with automatic control and print the measured `eta_s`, `eta_l`,
//! `eta_0` and the chosen `p_l`; then sweep fixed `p_l` in {0.1, ..., 1.0} at the same mutation
//! count and print the relMSE of each against the scene's BDPT reference
//! (`scenes/references/<scene>.exr`, box-downsampled to the render size), marking where the
//! automatic choice falls. relMSE is the median over `--runs` seeds (MCMC errors are heavy
//! tailed; the DRMLT paper reports medians too).
//!
//! Each scene also gets a run directory, `<out>/<scene>/` (default `--out
//! out/zsolnai_large_step`): the downsampled reference, every method's final image per seed
//! (EXR), error-vs-time samples from extra runs at 1/8, 1/4 and 1/2 of the budget, `run.json`
//! and a self-contained `report.html` (`chainlight::report`; open it in a browser, or rebuild it
//! with `chainlight report <out>/<scene>`). `--no-report` skips the run directory and the extra
//! runs.
//!
//! `cargo run --release --example zsolnai_large_step -- [--size 64] [--mpp 64] [--runs 3] [--out DIR] [--no-report] [scene ...]`

use std::path::{Path, PathBuf};
use std::sync::atomic::AtomicBool;

use chainlight::report::{
    current_commit, write_report, ConvergencePoint, ConvergenceSeries, MethodRun, RunManifest,
    SeedImage,
};
use render::image::Image;
use render::methods::{ChainSettings, PssmltSettings};
use render::mlt::LargeStepMode;
use render::session::{render, Budget, NoProgress, RenderSettings};

fn median(mut v: Vec<f64>) -> f64 {
    v.sort_by(f64::total_cmp);
    v[v.len() / 2]
}

/// A method's name, large-step mode and final (seed, image, render seconds) per seed.
type MethodFinals = (String, LargeStepMode, Vec<(u64, Image, f64)>);

/// Writes `dir`: the reference, every method's images, convergence samples (extra runs at
/// 1/8, 1/4 and 1/2 of `mpp`, plus the final run), `run.json` and `report.html`.
fn write_run(
    dir: &Path,
    scene: &str,
    params: &[(&str, String)],
    reference: &Image,
    finals: &[MethodFinals],
    run: &dyn Fn(LargeStepMode, u64, u32) -> (Image, f64),
    mpp: u32,
) -> Result<PathBuf, Box<dyn std::error::Error>> {
    std::fs::create_dir_all(dir).map_err(|e| format!("{}: {e}", dir.display()))?;
    render::image_io::write_exr(dir.join("reference.exr"), reference)?;
    let mut methods = Vec::new();
    for (name, mode, images) in finals {
        let slug: String = name
            .chars()
            .map(|c| if c.is_ascii_alphanumeric() { c } else { '_' })
            .collect();
        let mut seed_images = Vec::new();
        let mut convergence = Vec::new();
        for (seed, image, secs) in images {
            let file = format!("{slug}_seed{seed}.exr");
            render::image_io::write_exr(dir.join(&file), image)?;
            seed_images.push(SeedImage {
                seed: *seed,
                path: file.into(),
            });
            let mut points = Vec::new();
            for div in [8, 4, 2] {
                if mpp / div == 0 {
                    continue;
                }
                let (img, t) = run(*mode, *seed, mpp / div);
                points.push(ConvergencePoint {
                    time_s: t,
                    relmse: render::metrics::relmse(&img, reference)?,
                });
            }
            points.push(ConvergencePoint {
                time_s: *secs,
                relmse: render::metrics::relmse(image, reference)?,
            });
            convergence.push(ConvergenceSeries {
                seed: *seed,
                points,
            });
        }
        let mode_text = match mode {
            LargeStepMode::Fixed(p) => format!("fixed p_large = {p}"),
            other => format!("{other:?}"),
        };
        methods.push(MethodRun {
            name: name.clone(),
            parameters: [("large step".to_string(), mode_text)].into(),
            images: seed_images,
            convergence,
        });
    }
    let manifest = RunManifest {
        title: format!("zsolnai_large_step: {scene}"),
        commit: current_commit("."),
        parameters: params
            .iter()
            .map(|(k, v)| ((*k).to_string(), v.clone()))
            .collect(),
        reference: "reference.exr".into(),
        methods,
    };
    manifest.save(dir)?;
    Ok(write_report(&manifest, dir, dir.join("report.html"))?)
}

fn main() {
    let mut size = 64u32;
    let mut mpp = 64u32;
    let mut runs = 3u64;
    let mut names = Vec::new();
    let mut out_dir = PathBuf::from("out/zsolnai_large_step");
    let mut report = true;
    let mut args = std::env::args().skip(1);
    while let Some(a) = args.next() {
        let mut num = |what: &str| -> u32 {
            args.next().and_then(|v| v.parse().ok()).unwrap_or_else(|| {
                eprintln!("{what} needs a positive integer");
                std::process::exit(2)
            })
        };
        match a.as_str() {
            "--size" => size = num("--size").max(1),
            "--mpp" => mpp = num("--mpp").max(1),
            "--runs" => runs = u64::from(num("--runs").max(1)),
            "--no-report" => report = false,
            "--out" => {
                out_dir = args.next().map(PathBuf::from).unwrap_or_else(|| {
                    eprintln!("--out needs a directory");
                    std::process::exit(2)
                })
            }
            _ => names.push(a),
        }
    }
    let mut scenes: Vec<PathBuf> = std::fs::read_dir("scenes")
        .map(|d| {
            d.filter_map(|e| e.ok().map(|e| e.path()))
                .filter(|p| p.extension().is_some_and(|e| e == "gltf"))
                .collect()
        })
        .unwrap_or_default();
    scenes.sort();
    if !names.is_empty() {
        scenes.retain(|p| {
            names
                .iter()
                .any(|n| p.file_stem().is_some_and(|s| s == n.as_str()))
        });
    }
    let sweep: Vec<f64> = (1..=10).map(|i| f64::from(i) / 10.0).collect();
    println!("PSSMLT over BDPT, {size}x{size}, {mpp} mutations per pixel, 256 chains, max depth 5, median relMSE of {runs} runs");
    print!("| scene | eta_s | eta_l | eta_0 | eta_l/eta_0 | auto p_l |");
    for p in &sweep {
        print!(" p={p:.1} |");
    }
    println!(" auto relMSE | best sweep p | auto rank |");
    print!("|---|---|---|---|---|---|");
    for _ in &sweep {
        print!("---|");
    }
    println!("---|---|---|");
    for path in scenes {
        let name = path
            .file_stem()
            .unwrap_or_default()
            .to_string_lossy()
            .into_owned();
        let reference_path = Path::new("scenes/references").join(format!("{name}.exr"));
        let (scene, reference) = match render::bundled::scene_and_reference(&path, size) {
            Ok(pair) => pair,
            Err(e) => {
                eprintln!("{e}; skipped");
                continue;
            }
        };
        let run_for = |large_step: LargeStepMode, seed: u64, mpp: u32| {
            let settings = RenderSettings {
                width: size,
                height: size,
                budget: Budget::SamplesPerPixel(mpp.max(1)),
                threads: std::thread::available_parallelism().map_or(1, |n| n.get()),
                seed,
                max_depth: 5,
                // Kelemen et al. 2002's PSSMLT (the expected-value estimator, no raster steps,
                // no direct pass), with the large-step probability under test.
                method: PssmltSettings {
                    chain: ChainSettings {
                        large_step,
                        bootstrap_samples: 20_000,
                        ..ChainSettings::kelemen2002()
                    },
                    ..PssmltSettings::kelemen2002()
                }
                .into(),
            };
            let start = std::time::Instant::now();
            let out =
                render(&scene, &settings, &NoProgress, &AtomicBool::new(false)).expect("render");
            (out, start.elapsed().as_secs_f64())
        };
        let run = |large_step: LargeStepMode, seed: u64| run_for(large_step, seed, mpp);
        // Every method of the report: its name, mode, and final (seed, image, seconds).
        let mut finals: Vec<MethodFinals> = Vec::new();
        // Automatic control: statistics from the estimation phase (logged in the notes).
        let mut autos = Vec::new();
        let mut auto_images = Vec::new();
        let mut etas = (0.0, 0.0, 0.0, 0.0);
        let auto_mode = LargeStepMode::Auto {
            initial: 0.5,
            estimation_steps: 1_000,
        };
        for r in 0..runs {
            let (out, secs) = run(auto_mode, 100 + r);
            autos.push(render::metrics::relmse(&out.image, &reference).unwrap_or(f64::NAN));
            if r == 0 {
                if let Some(e) = out.mcmc.as_ref().and_then(|m| m.large_step) {
                    etas = (e.eta_s, e.eta_l, e.eta_0, e.large_step_probability);
                }
            }
            auto_images.push((100 + r, out.image, secs));
        }
        finals.push(("auto".into(), auto_mode, auto_images));
        let auto = median(autos);
        let mut errs = Vec::new();
        for &p in &sweep {
            let mut values = Vec::new();
            let mut images = Vec::new();
            for r in 0..runs {
                let (out, secs) = run(LargeStepMode::Fixed(p), 100 + r);
                values.push(render::metrics::relmse(&out.image, &reference).unwrap_or(f64::NAN));
                images.push((100 + r, out.image, secs));
            }
            errs.push(median(values));
            finals.push((format!("p_l={p:.1}"), LargeStepMode::Fixed(p), images));
        }
        let best = errs
            .iter()
            .enumerate()
            .min_by(|a, b| a.1.total_cmp(b.1))
            .map_or(0, |(i, _)| i);
        let rank = errs.iter().filter(|&&e| e < auto).count() + 1;
        print!(
            "| {name} | {:.3} | {:.3} | {:.3} | {:.3} | **{:.2}** |",
            etas.0,
            etas.1,
            etas.2,
            etas.1 / etas.2,
            etas.3
        );
        for (i, e) in errs.iter().enumerate() {
            let mark = if (sweep[i] - etas.3).abs() <= 0.05 {
                "*"
            } else {
                ""
            };
            print!(" {e:.4}{mark} |");
        }
        println!(" {auto:.4} | {:.1} | {rank} of 11 |", sweep[best]);
        if report {
            let dir = out_dir.join(&name);
            let params = [
                ("scene", name.clone()),
                ("size", format!("{size}x{size}")),
                ("mutations per pixel", mpp.to_string()),
                ("runs (seeds)", runs.to_string()),
                ("chains", "256".into()),
                ("max depth", "5".into()),
                ("bootstrap samples", "20000".into()),
                ("integrator", "pssmlt over BDPT".into()),
                (
                    "auto: measured eta_s, eta_l, eta_0",
                    format!("{:.3}, {:.3}, {:.3}", etas.0, etas.1, etas.2),
                ),
                ("auto: chosen p_l (seed 100)", format!("{:.3}", etas.3)),
                (
                    "reference",
                    format!("{} box-downsampled", reference_path.display()),
                ),
                (
                    "convergence",
                    "independent runs at 1/8, 1/4, 1/2 and all of the budget".into(),
                ),
            ];
            match write_run(
                &dir,
                &name,
                &params,
                &reference,
                &finals,
                &|mode, seed, m| {
                    let (out, secs) = run_for(mode, seed, m);
                    (out.image, secs)
                },
                mpp,
            ) {
                Ok(html) => eprintln!("{name}: report {}", html.display()),
                Err(e) => eprintln!("{name}: no report: {e}"),
            }
        }
    }
    println!("`*` marks the sweep value nearest the automatic p_l; rank 1 = the automatic run beat every fixed p_l.");
}
