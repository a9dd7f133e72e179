//! Langevin MCMC rendering (Luan et al. 2020): equal-time comparison on bundled scenes.
//!
//! Scenes (default caustic-pool, motion-blur, glossy-highlight): at `--size` x `--size`, each
//! method gets `--time` seconds per render (bootstrap included) and runs with `--seeds` seeds;
//! methods are interleaved seed by seed so that a change in machine load hits all of them
//! alike. Methods (all with large steps of probability 0.3, maximum depth 5):
//! - PSSMLT/K: PSSMLT with Kelemen's small step (s1 = 1/1024, s2 = 1/64);
//! - MMLT/K: multiplexed MLT with Kelemen's small step (the base MALA runs on);
//! - MALA, MALA-online, MALA-cache, MALA-hybrid: `--integrator mala*` (MALA on MMLT depths
//!   <= 3, Kelemen beyond; the paper's parameters, `--mala-preset paper`);
//! - DR cheap-then-expensive: `--integrator drmlt --dr-variant cheap-then-expensive`;
//! - MALA-online and MALA-hybrid with the authors' code's values (`--mala-preset code`:
//!   epsilon 0.005, K 5, H 3000, preconditioner clamped to [0.01, 100], shrink prior 0.005).
//!
//! Errors are MSE (the paper's metric) and relMSE against the scene's BDPT reference
//! (`scenes/references/<scene>.exr`, box-downsampled to the render size), median over the
//! seeds with the min-max range; also mutations per second and acceptance. Writes
//! `results.md`, `results.csv` and the seed-0 images (EXR and PNG) of every method to `--out`
//! (default `target/langevin`), and per scene a run directory (`<out>/<scene>/`: every seed's
//! EXR, `run.json`) with a self-contained `report.html` (`experiments::report`; each seed is one
//! error-vs-time sample). docs/methods/mala.md reports a run.
//!
//! `cargo run --release --example langevin -- [--time 3 | --spp N] [--seeds 5] [--size 64]
//! [--out DIR] [scene ...]` (`--spp`: equal mutations per pixel instead of equal time, to
//! separate a method's cost per mutation from its efficiency per mutation).

use std::fmt::Write as _;
use std::path::PathBuf;
use std::sync::atomic::AtomicBool;
use std::time::Duration;

use experiments::report::{
    current_commit, ConvergencePoint, ConvergenceSeries, MethodRun, RunManifest, SeedImage,
};
use render::image::Image;
use render::methods::{DrmltSettings, MalaSettings, MethodSettings, MmltSettings, PssmltSettings};
use render::metrics::median_min_max;
use render::mlt::dr::{DrBase, DrVariant};
use render::mlt::mala::{MalaConfig, MalaVariant};
use render::scene::Scene;
use render::session::{render, Budget, IntegratorKind, NoProgress, RenderSettings};

/// Command-line options.
struct Options {
    time: f64,
    /// Equal-sample mode: mutations per pixel instead of `time`.
    spp: Option<u32>,
    seeds: u64,
    size: u32,
    out: PathBuf,
    scenes: Vec<String>,
}

fn usage(msg: &str) -> ! {
    eprintln!(
        "{msg}\nusage: langevin [--time SECONDS | --spp N] [--seeds N] [--size PIXELS] [--out DIR] [scene ...]"
    );
    std::process::exit(2)
}

fn parse_options() -> Options {
    let mut o = Options {
        time: 3.0,
        spp: None,
        seeds: 5,
        size: 64,
        out: PathBuf::from("target/langevin"),
        scenes: Vec::new(),
    };
    let mut args = std::env::args().skip(1);
    while let Some(a) = args.next() {
        let mut value = |what: &str| {
            args.next()
                .unwrap_or_else(|| usage(&format!("{what} needs a value")))
        };
        match a.as_str() {
            "--time" => {
                o.time = value("--time")
                    .parse()
                    .ok()
                    .filter(|t: &f64| *t > 0.0 && *t <= 3600.0)
                    .unwrap_or_else(|| usage("--time needs seconds in (0, 3600]"))
            }
            "--seeds" => {
                o.seeds = value("--seeds")
                    .parse()
                    .ok()
                    .filter(|n| (1..=100).contains(n))
                    .unwrap_or_else(|| usage("--seeds needs a number in 1..=100"))
            }
            "--size" => {
                o.size = value("--size")
                    .parse()
                    .ok()
                    .filter(|n| (8..=1024).contains(n))
                    .unwrap_or_else(|| usage("--size needs a number in 8..=1024"))
            }
            "--spp" => {
                o.spp = Some(
                    value("--spp")
                        .parse()
                        .ok()
                        .filter(|n| (1..=1_000_000).contains(n))
                        .unwrap_or_else(|| usage("--spp needs mutations per pixel in 1..=1000000")),
                )
            }
            "--out" => o.out = PathBuf::from(value("--out")),
            s if s.starts_with('-') => usage(&format!("unknown option {s}")),
            s => o.scenes.push(s.to_owned()),
        }
    }
    if o.scenes.is_empty() {
        o.scenes = ["caustic-pool", "motion-blur", "glossy-highlight"]
            .map(String::from)
            .to_vec();
    }
    o
}

/// The compared configurations: label, file stem, integrator, DR variant, the authors' code
/// preset (`--mala-preset code`) instead of the paper's.
const METHODS: [(&str, &str, IntegratorKind, Option<DrVariant>, bool); 9] = [
    ("PSSMLT/K", "pssmlt-k", IntegratorKind::Pssmlt, None, false),
    ("MMLT/K", "mmlt-k", IntegratorKind::Mmlt, None, false),
    ("MALA", "mala", IntegratorKind::Mala, None, false),
    (
        "MALA-online",
        "mala-online",
        IntegratorKind::MalaOnline,
        None,
        false,
    ),
    (
        "MALA-cache",
        "mala-cache",
        IntegratorKind::MalaCache,
        None,
        false,
    ),
    (
        "MALA-hybrid",
        "mala-hybrid",
        IntegratorKind::MalaHybrid,
        None,
        false,
    ),
    (
        "DR cheap-then-expensive",
        "dr-cte",
        IntegratorKind::Drmlt,
        Some(DrVariant::CheapThenExpensive),
        false,
    ),
    (
        "MALA-online (code preset)",
        "mala-online-code",
        IntegratorKind::MalaOnline,
        None,
        true,
    ),
    (
        "MALA-hybrid (code preset)",
        "mala-hybrid-code",
        IntegratorKind::MalaHybrid,
        None,
        true,
    ),
];

fn settings(method: usize, size: u32, budget: Budget, seed: u64) -> RenderSettings {
    let (_, _, integrator, dr, code_preset) = METHODS[method];
    let mala = if code_preset {
        MalaSettings::luan2020_code()
    } else {
        MalaSettings::luan2020()
    };
    let method: MethodSettings = match (integrator, dr) {
        // Kelemen's PSSMLT with large-step MIS, no raster steps, no direct pass.
        (IntegratorKind::Pssmlt, _) => PssmltSettings::kelemen2002_mis().into(),
        (IntegratorKind::Mmlt, _) => MmltSettings::hachisuka2014().into(),
        (_, Some(variant)) => DrmltSettings {
            mala: mala.config,
            ..DrmltSettings::rioux_lavoie2020_with(variant, DrBase::Mmlt)
        }
        .into(),
        (kind, None) => MalaSettings {
            config: MalaConfig {
                variant: kind.mala_variant().unwrap_or(MalaVariant::Hybrid),
                ..mala.config
            },
            ..mala
        }
        .into(),
    };
    RenderSettings {
        width: size,
        height: size,
        budget,
        threads: std::thread::available_parallelism().map_or(1, |n| n.get()),
        seed,
        max_depth: 5,
        method,
    }
}

/// One render's measurements.
struct Run {
    mse: f64,
    relmse: f64,
    mutations_per_second: f64,
    acceptance: f64,
    seconds: f64,
}

fn run_once(scene: &Scene, reference: &Image, s: &RenderSettings) -> (Run, Image) {
    let out = render(scene, s, &NoProgress, &AtomicBool::new(false)).expect("render");
    let run = Run {
        mse: render::metrics::mse(&out.image, reference).unwrap_or(f64::NAN),
        relmse: render::metrics::relmse(&out.image, reference).unwrap_or(f64::NAN),
        mutations_per_second: out.samples as f64 / out.elapsed.as_secs_f64(),
        acceptance: out.mcmc.as_ref().map_or(f64::NAN, |m| m.acceptance_rate()),
        seconds: out.elapsed.as_secs_f64(),
    };
    (run, out.image)
}

fn summary(v: &[f64]) -> (f64, f64, f64) {
    median_min_max(v).unwrap_or((f64::NAN, f64::NAN, f64::NAN))
}

fn run_scene(o: &Options, name: &str, md: &mut String, csv: &mut String) {
    let size = o.size;
    let (scene, reference) = match render::bundled::bundled(name, size) {
        Ok(pair) => pair,
        Err(e) => {
            eprintln!("{e}; skipped");
            return;
        }
    };
    let dir = o.out.join(name);
    let _ = std::fs::create_dir_all(&dir);
    let budget = match o.spp {
        Some(n) => Budget::SamplesPerPixel(n),
        None => Budget::Time(Duration::from_secs_f64(o.time)),
    };
    let mut runs: Vec<Vec<Run>> = METHODS.iter().map(|_| Vec::new()).collect();
    let mut report_methods: Vec<MethodRun> = METHODS
        .iter()
        .map(|(label, ..)| MethodRun {
            name: (*label).to_string(),
            ..MethodRun::default()
        })
        .collect();
    for seed in 0..o.seeds {
        for (m, (label, stem, ..)) in METHODS.iter().enumerate() {
            let (run, image) = run_once(&scene, &reference, &settings(m, size, budget, seed));
            eprintln!(
                "{name} seed {seed} {label}: MSE {:.3e}, relMSE {:.4}, {:.0} mut/s, acceptance {:.3}",
                run.mse, run.relmse, run.mutations_per_second, run.acceptance
            );
            let file = format!("{stem}_seed{seed}.exr");
            if render::image_io::write_exr(dir.join(&file), &image).is_ok() {
                report_methods[m].images.push(SeedImage {
                    seed,
                    path: file.into(),
                });
                report_methods[m].convergence.push(ConvergenceSeries {
                    seed,
                    points: vec![ConvergencePoint {
                        time_s: run.seconds,
                        relmse: run.relmse,
                    }],
                });
            }
            if seed == 0 {
                let path = dir.join(stem);
                let _ = render::image_io::write_exr(path.with_extension("exr"), &image);
                let _ = render::image_io::write_png(path.with_extension("png"), &image, 0.0);
            }
            runs[m].push(run);
        }
    }
    let _ = render::image_io::write_png(dir.join("reference.png"), &reference, 0.0);
    let manifest = RunManifest {
        title: format!("langevin: {name}"),
        commit: current_commit("."),
        parameters: [
            ("scene", name.to_string()),
            ("size", format!("{size}x{size}")),
            (
                "budget",
                o.spp.map_or_else(
                    || format!("{} s per render", o.time),
                    |n| format!("{n} mutations per pixel"),
                ),
            ),
            ("seeds", o.seeds.to_string()),
            ("large-step probability", "0.3".into()),
            ("max depth", "5".into()),
        ]
        .into_iter()
        .map(|(k, v)| (k.to_string(), v))
        .collect(),
        reference: "reference.exr".into(),
        methods: report_methods
            .into_iter()
            .filter(|m| !m.images.is_empty())
            .collect(),
    };
    let report = render::image_io::write_exr(dir.join("reference.exr"), &reference)
        .map_err(|e| e.to_string())
        .and_then(|()| manifest.save_with_report(&dir).map_err(|e| e.to_string()));
    match report {
        Ok(html) => eprintln!("{name}: report {}", html.display()),
        Err(e) => eprintln!("{name}: no report: {e}"),
    }
    let _ = writeln!(md, "\n### {name}\n");
    let _ = writeln!(
        md,
        "| method | MSE median [min, max] | relMSE median [min, max] | kmut/s | acceptance | MSE / MMLT/K |"
    );
    let _ = writeln!(md, "|---|---|---|---|---|---|");
    let mmlt_mse = summary(&runs[1].iter().map(|r| r.mse).collect::<Vec<_>>()).0;
    for ((label, ..), rs) in METHODS.iter().zip(&runs) {
        let col = |f: fn(&Run) -> f64| summary(&rs.iter().map(f).collect::<Vec<_>>());
        let (e, e0, e1) = col(|r| r.mse);
        let (q, q0, q1) = col(|r| r.relmse);
        let rate = col(|r| r.mutations_per_second).0;
        let acc = col(|r| r.acceptance).0;
        let _ = writeln!(
            md,
            "| {label} | {e:.3e} [{e0:.3e}, {e1:.3e}] | {q:.4} [{q0:.4}, {q1:.4}] | {:.1} | {acc:.3} | {:.2} |",
            rate / 1e3,
            e / mmlt_mse
        );
        for (seed, r) in rs.iter().enumerate() {
            let _ = writeln!(
                csv,
                "{name},{label},{seed},{},{},{},{}",
                r.mse, r.relmse, r.mutations_per_second, r.acceptance
            );
        }
    }
}

fn main() {
    let o = parse_options();
    if let Err(e) = std::fs::create_dir_all(&o.out) {
        usage(&format!("cannot create {}: {e}", o.out.display()));
    }
    let budget = match o.spp {
        Some(n) => format!("equal samples: {n} mutations per pixel"),
        None => format!("equal time: {} s per render (bootstrap included)", o.time),
    };
    let mut md = format!(
        "# Langevin MLT\n\n{budget}, {} seeds, {}x{} pixels, max depth 5, large-step probability 0.3, {} threads.\n",
        o.seeds,
        o.size,
        o.size,
        std::thread::available_parallelism().map_or(1, |n| n.get())
    );
    let mut csv = String::from("scene,method,seed,mse,relmse,mutations_per_second,acceptance\n");
    for name in &o.scenes {
        run_scene(&o, name, &mut md, &mut csv);
    }
    let _ = std::fs::write(o.out.join("results.md"), &md);
    let _ = std::fs::write(o.out.join("results.csv"), &csv);
    println!("{md}");
    println!("wrote {}", o.out.display());
}
