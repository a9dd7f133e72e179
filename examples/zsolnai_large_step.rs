//! Automatic large-step control (Zsolnai & Szirmay-Kalos 2013) on the bundled scenes.
//!
//! For each scene: run PSSMLT with automatic control and print the measured `eta_s`, `eta_l`,
//! `eta_0` and the chosen `p_l`; then sweep fixed `p_l` in {0.1, ..., 1.0} at the same mutation
//! count and print the relMSE of each against the scene's BDPT reference
//! (`scenes/references/<scene>.exr`, box-downsampled to the render size), marking where the
//! automatic choice falls. relMSE is the median over `--runs` seeds (MCMC errors are heavy
//! tailed; the DRMLT paper reports medians too).
//!
//! `cargo run --release --example zsolnai_large_step -- [--size 64] [--mpp 64] [--runs 3] [scene ...]`

use std::path::{Path, PathBuf};
use std::sync::atomic::AtomicBool;

use render::mlt::LargeStepMode;
use render::scene::Scene;
use render::session::{render, Budget, IntegratorKind, McmcSettings, NoProgress, RenderSettings};

fn median(mut v: Vec<f64>) -> f64 {
    v.sort_by(f64::total_cmp);
    v[v.len() / 2]
}

fn main() {
    let mut size = 64u32;
    let mut mpp = 64u32;
    let mut runs = 3u64;
    let mut names = Vec::new();
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
        let Some(reference) = render::image_io::read_exr(&reference_path)
            .ok()
            .and_then(|r| r.box_downsample(size as usize, size as usize))
        else {
            eprintln!(
                "{name}: no usable reference at {} (run scripts/make_references.sh); skipped",
                reference_path.display()
            );
            continue;
        };
        let scene = match Scene::load(&path) {
            Ok(s) => s,
            Err(e) => {
                eprintln!("{name}: {e}");
                continue;
            }
        };
        let run = |large_step: LargeStepMode, seed: u64| {
            let settings = RenderSettings {
                width: size,
                height: size,
                integrator: IntegratorKind::Pssmlt,
                budget: Budget::SamplesPerPixel(mpp),
                threads: std::thread::available_parallelism().map_or(1, |n| n.get()),
                seed,
                max_depth: 5,
                mcmc: McmcSettings {
                    large_step,
                    bootstrap_samples: 20_000,
                    ..McmcSettings::default()
                },
                strategy_images: false,
            };
            render(&scene, &settings, &NoProgress, &AtomicBool::new(false)).expect("render")
        };
        // Automatic control: statistics from the estimation phase (logged in the notes).
        let mut autos = Vec::new();
        let mut etas = (0.0, 0.0, 0.0, 0.0);
        for r in 0..runs {
            let out = run(
                LargeStepMode::Auto {
                    initial: 0.5,
                    estimation_steps: 1_000,
                },
                100 + r,
            );
            autos.push(render::metrics::relmse(&out.image, &reference).unwrap_or(f64::NAN));
            if r == 0 {
                if let Some(note) = out.notes.iter().find(|n| n.starts_with("automatic")) {
                    let grab = |key: &str| -> f64 {
                        note.split(key)
                            .nth(1)
                            .and_then(|t| t.trim_start_matches([' ', '=']).split([',', ' ']).next())
                            .and_then(|v| v.parse().ok())
                            .unwrap_or(f64::NAN)
                    };
                    etas = (grab("eta_s"), grab("eta_l"), grab("eta_0"), grab("p_large"));
                }
            }
        }
        let auto = median(autos);
        let errs: Vec<f64> = sweep
            .iter()
            .map(|&p| {
                median(
                    (0..runs)
                        .map(|r| {
                            render::metrics::relmse(
                                &run(LargeStepMode::Fixed(p), 100 + r).image,
                                &reference,
                            )
                            .unwrap_or(f64::NAN)
                        })
                        .collect(),
                )
            })
            .collect();
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
    }
    println!("`*` marks the sweep value nearest the automatic p_l; rank 1 = the automatic run beat every fixed p_l.");
}
