//! Regional adaptive path-space MLT (Otsu et al. 2018): equal-time comparison of FIXED,
//! GLOBAL, RA-GRID and RA-QUADTREE for the lens and the multi-chain perturbation.
//!
//! Scenes (default cornell, glossy-diffuse, ajar-door: a diffuse interior, a glossy and diffuse
//! mix, difficult visibility) at `--size` x `--size` (default 64), maximum depth 5. Each of the
//! 8 configurations (`--integrator pathmlt --perturbation lens|multichain --adapt
//! fixed|global|grid|quadtree`, 256 chains, 100 000 bootstrap samples) gets `--time` seconds
//! per render (default 5, bootstrap included) on `--threads` render threads (default 1), with
//! `--seeds` seeds (default 5). Runs are interleaved (for seed: for scene: for configuration)
//! so that a change in machine load hits every configuration alike; `/proc/loadavg` is recorded
//! before every run.
//!
//! Under a time budget the renderer uses the paper's `M_refine = 10^7` (too many for short
//! renders on one thread: the quadtree would never refine). Here RA-QUADTREE gets the paper's
//! parameters scaled to the budget (`RegionalAdaptParams::otsu2018_for_budget`, about 100
//! refinement passes) for the mutation count FIXED reached with the same perturbation, scene,
//! seed and time, which runs just before it (`--m-split N` sets `M_split` instead).
//!
//! Measured: rRMSE (the paper's metric) and relMSE against the scene's BDPT reference
//! (`scenes/references/<scene>.exr`, box-downsampled), median over the seeds with the min-max
//! range, mutations per second, acceptance, the median learned sigma over the pixels. Then,
//! for `--ladder-scene` (default glossy-diffuse), an rRMSE-vs-time ladder (`--ladder`, default
//! 1,4,15,60 s, `--ladder-seeds` seeds, default 3; interleaved for seed: for time: for
//! configuration) drawn as a log-log SVG (the paper's Fig. 10).
//!
//! Writes to `--out` (default `target/regional_adaptive`): `results.md`, `results.csv`,
//! `ladder.csv`, `convergence.svg`; per scene `<scene>/`: the reference, the seed-0 image (EXR,
//! PNG), per-pixel relative-error map (`*_error.png`, viridis, log scale 1e-3..1, 3x
//! upscaled) of every configuration, the learned-sigma heat map of every adaptive one
//! (`*_sigma.png`, viridis, log scale 1e-3..1 rad, 3x upscaled), every seed's EXR, `run.json`
//! and a self-contained `report.html`. docs/methods/regional-adaptive.md reports a run.
//!
//! `cargo run --release --example regional_adaptive -- [--time 5 | --spp N] [--seeds 5]
//! [--size 64] [--threads 1] [--m-split N] [--ladder 1,4,15,60] [--ladder-seeds 3]
//! [--ladder-scene glossy-diffuse] [--out DIR] [--quick] [scene ...]`; `--quick` is a smoke run (0.5 s, 2
//! seeds, 32 x 32, ladder 0.25,0.5 s with 1 seed; later flags override it); `--spp`: equal
//! mutations per pixel instead of equal time, to separate a configuration's cost per mutation
//! from its efficiency per mutation (no ladder; `--ladder-seeds 0` skips it under `--time`).

use std::fmt::Write as _;
use std::path::{Path, PathBuf};
use std::sync::atomic::AtomicBool;
use std::time::{Duration, Instant};

use experiments::report::{
    current_commit, ConvergencePoint, ConvergenceSeries, MethodRun, RunManifest, SeedImage,
};
use pathspace::regional::RegionalAdaptParams;
use pathspace::PerturbationKind;
use plotters::prelude::*;
use render::image::Image;
use render::image_io::{write_false_color, ErrorScale};
use render::methods::PathMltSettings;
use render::metrics::median_min_max;
use render::mlt::pathmlt::{self, PathAdapt};
use render::mlt::{LargeStepMode, MltBudget, MltSettings};
use render::scene::Scene;
use render::session::NoProgress;

/// Maximum path depth (bounces), as the references.
const MAX_DEPTH: u32 = 5;
/// Upscaling of the error and sigma PNGs (nearest neighbour).
const PNG_SCALE: usize = 3;

/// Command-line options.
struct Options {
    time: f64,
    /// Equal-sample mode: mutations per pixel instead of `time` (no ladder).
    spp: Option<u32>,
    /// RA-QUADTREE's `M_split` instead of the budget-scaled one.
    m_split: Option<u64>,
    seeds: u64,
    size: u32,
    threads: usize,
    ladder: Vec<f64>,
    ladder_seeds: u64,
    ladder_scene: String,
    out: PathBuf,
    scenes: Vec<String>,
}

impl Options {
    /// The table's budget per render.
    fn budget(&self) -> MltBudget {
        match self.spp {
            Some(n) => MltBudget::MutationsPerPixel(f64::from(n)),
            None => MltBudget::Time(Duration::from_secs_f64(self.time)),
        }
    }

    /// The table's budget in words.
    fn budget_text(&self) -> String {
        match self.spp {
            Some(n) => format!("equal samples: {n} mutations per pixel"),
            None => format!(
                "equal time: {} s per render (bootstrap included)",
                self.time
            ),
        }
    }
}

fn usage(msg: &str) -> ! {
    eprintln!(
        "{msg}\nusage: regional_adaptive [--time SECONDS | --spp N] [--seeds N] [--size PIXELS] [--threads N] [--m-split N] \
         [--ladder T1,T2,..] [--ladder-seeds N] [--ladder-scene NAME] [--out DIR] [--quick] [scene ...]"
    );
    std::process::exit(2)
}

fn parse_options() -> Options {
    let mut o = Options {
        time: 5.0,
        spp: None,
        m_split: None,
        seeds: 5,
        size: 64,
        threads: 1,
        ladder: vec![1.0, 4.0, 15.0, 60.0],
        ladder_seeds: 3,
        ladder_scene: "glossy-diffuse".into(),
        out: PathBuf::from("target/regional_adaptive"),
        scenes: Vec::new(),
    };
    let mut args = std::env::args().skip(1);
    while let Some(a) = args.next() {
        let mut value = |what: &str| {
            args.next()
                .unwrap_or_else(|| usage(&format!("{what} needs a value")))
        };
        let seconds = |v: &str| v.parse().ok().filter(|t: &f64| *t > 0.0 && *t <= 3600.0);
        match a.as_str() {
            "--quick" => {
                (o.time, o.seeds, o.size) = (0.5, 2, 32);
                (o.ladder, o.ladder_seeds) = (vec![0.25, 0.5], 1);
            }
            "--time" => {
                o.time = seconds(&value("--time"))
                    .unwrap_or_else(|| usage("--time needs seconds in (0, 3600]"))
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
            "--m-split" => {
                o.m_split = Some(
                    value("--m-split")
                        .parse()
                        .ok()
                        .filter(|n| *n >= 1)
                        .unwrap_or_else(|| usage("--m-split needs visits >= 1")),
                )
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
            "--threads" => {
                o.threads = value("--threads")
                    .parse()
                    .ok()
                    .filter(|n| (1..=256).contains(n))
                    .unwrap_or_else(|| usage("--threads needs a number in 1..=256"))
            }
            "--ladder" => {
                let v = value("--ladder");
                o.ladder = v
                    .split(',')
                    .map(|t| seconds(t.trim()))
                    .collect::<Option<Vec<f64>>>()
                    .filter(|l| !l.is_empty())
                    .unwrap_or_else(|| {
                        usage("--ladder needs seconds in (0, 3600], comma-separated")
                    })
            }
            "--ladder-seeds" => {
                o.ladder_seeds = value("--ladder-seeds")
                    .parse()
                    .ok()
                    .filter(|n| *n <= 100)
                    .unwrap_or_else(|| {
                        usage("--ladder-seeds needs a number in 0..=100 (0: no ladder)")
                    })
            }
            "--ladder-scene" => o.ladder_scene = value("--ladder-scene"),
            "--out" => o.out = PathBuf::from(value("--out")),
            s if s.starts_with('-') => usage(&format!("unknown option {s}")),
            s => o.scenes.push(s.to_owned()),
        }
    }
    if o.scenes.is_empty() {
        o.scenes = ["cornell", "glossy-diffuse", "ajar-door"]
            .map(String::from)
            .to_vec();
    }
    o
}

/// The compared configurations, FIXED first within each perturbation (RA-QUADTREE's budget
/// comes from FIXED's mutation count).
const CONFIGS: [(PerturbationKind, PathAdapt); 8] = [
    (PerturbationKind::Lens, PathAdapt::Fixed),
    (PerturbationKind::Lens, PathAdapt::Global),
    (PerturbationKind::Lens, PathAdapt::Grid),
    (PerturbationKind::Lens, PathAdapt::Quadtree),
    (PerturbationKind::MultiChain, PathAdapt::Fixed),
    (PerturbationKind::MultiChain, PathAdapt::Global),
    (PerturbationKind::MultiChain, PathAdapt::Grid),
    (PerturbationKind::MultiChain, PathAdapt::Quadtree),
];

fn perturbation_name(kind: PerturbationKind) -> &'static str {
    match kind {
        PerturbationKind::Lens => "lens",
        PerturbationKind::MultiChain => "multichain",
    }
}

fn label(c: usize) -> String {
    let (kind, adapt) = CONFIGS[c];
    let a = match adapt {
        PathAdapt::Fixed => "FIXED",
        PathAdapt::Global => "GLOBAL",
        PathAdapt::Grid => "RA-GRID",
        PathAdapt::Quadtree => "RA-QUADTREE",
    };
    format!("{} {a}", perturbation_name(kind))
}

fn stem(c: usize) -> String {
    let (kind, adapt) = CONFIGS[c];
    format!("{}-{}", perturbation_name(kind), adapt.name())
}

/// The 1-minute load average (`/proc/loadavg`), NaN where unavailable.
fn load_average() -> f64 {
    std::fs::read_to_string("/proc/loadavg")
        .ok()
        .and_then(|s| s.split_whitespace().next().and_then(|v| v.parse().ok()))
        .unwrap_or(f64::NAN)
}

/// One render's measurements.
struct Run {
    rrmse: f64,
    relmse: f64,
    mutations: u64,
    seconds: f64,
    acceptance: f64,
    /// Median of the learned `sigma_1` over the pixels (NaN for FIXED).
    sigma_median: f64,
    load: f64,
}

/// A run's image, learned sigma map and the adaptation note.
struct RunOutput {
    run: Run,
    image: Image,
    sigma_map: Option<Vec<f64>>,
    note: Option<String>,
}

/// RA-QUADTREE's refinement parameters for one run.
#[derive(Clone, Copy, Debug)]
struct Refinement {
    /// FIXED's mutation count for the same perturbation, scene, seed and budget: `M_refine`,
    /// `M_split` are scaled to it.
    fixed_mutations: Option<u64>,
    /// `--m-split`: `M_split` instead of the scaled one.
    m_split: Option<u64>,
}

/// Renders configuration `c` with `budget`; RA-QUADTREE refines as `refinement` says.
fn run_once(
    pool: &rayon::ThreadPool,
    scene: &Scene,
    reference: &Image,
    c: usize,
    budget: MltBudget,
    seed: u64,
    refinement: Refinement,
) -> RunOutput {
    let (kind, adapt) = CONFIGS[c];
    let method = PathMltSettings::otsu2018(kind, adapt);
    let settings = MltSettings {
        width: reference.width,
        height: reference.height,
        chains: method.chains,
        bootstrap_samples: method.bootstrap_samples,
        budget,
        large_step: LargeStepMode::Fixed(0.0),
        seed,
        streams: 1,
        stage_map: false,
    };
    let mut params = pathmlt::adapt_params(adapt, &settings);
    if adapt == PathAdapt::Quadtree {
        let scaled =
            RegionalAdaptParams::otsu2018_for_budget(refinement.fixed_mutations.unwrap_or(1));
        params.split_after_visits = refinement.m_split.or(scaled.split_after_visits);
        params.refine_every = scaled.refine_every;
    }
    let load = load_average();
    let start = Instant::now();
    let (out, sigma_map) = pool
        .install(|| {
            pathmlt::render_adaptive_with_params(
                scene,
                kind,
                adapt,
                MAX_DEPTH,
                &settings,
                &params,
                &NoProgress,
                &AtomicBool::new(false),
            )
        })
        .unwrap_or_else(|e| panic!("{}: {e}", label(c)));
    let seconds = start.elapsed().as_secs_f64();
    let sigma_median = sigma_map
        .as_deref()
        .and_then(median_min_max)
        .map_or(f64::NAN, |s| s.0);
    let run = Run {
        rrmse: render::metrics::rrmse(&out.image, reference).unwrap_or(f64::NAN),
        relmse: render::metrics::relmse(&out.image, reference).unwrap_or(f64::NAN),
        mutations: out.mutations,
        seconds,
        acceptance: out.stats.acceptance_rate(),
        sigma_median,
        load,
    };
    let note = out.notes.iter().find(|n| n.starts_with("--adapt")).cloned();
    RunOutput {
        run,
        image: out.image,
        sigma_map,
        note,
    }
}

/// `values` (`width x height`, row-major) repeated `PNG_SCALE` times along both axes.
fn upscale(values: &[f32], width: usize, height: usize) -> Vec<f32> {
    let mut out = Vec::with_capacity(values.len() * PNG_SCALE * PNG_SCALE);
    for y in 0..height * PNG_SCALE {
        let row = &values[(y / PNG_SCALE) * width..][..width];
        out.extend(row.iter().flat_map(|&v| std::iter::repeat_n(v, PNG_SCALE)));
    }
    out
}

/// Writes a false-colour PNG of per-pixel values, log scale `[lo, hi]`, upscaled.
fn write_map(path: &Path, values: &[f32], width: usize, height: usize, lo: f32, hi: f32) {
    let scale = ErrorScale::Log10 { min: lo, max: hi };
    let big = upscale(values, width, height);
    if let Err(e) = write_false_color(path, &big, width * PNG_SCALE, height * PNG_SCALE, scale) {
        eprintln!("cannot write {}: {e}", path.display());
    }
}

fn summary(v: &[f64]) -> (f64, f64, f64) {
    median_min_max(v).unwrap_or((f64::NAN, f64::NAN, f64::NAN))
}

/// A loaded scene with its reference and measurements.
struct SceneRuns {
    name: String,
    scene: Scene,
    reference: Image,
    runs: Vec<Vec<Run>>,
    notes: Vec<Option<String>>,
    methods: Vec<MethodRun>,
}

fn load_scene(name: &str, size: u32) -> Option<(Scene, Image)> {
    match render::bundled::bundled(name, size) {
        Ok((mut scene, reference)) => {
            scene.set_resolution(size, size);
            Some((scene, reference))
        }
        Err(e) => {
            eprintln!("{e}; skipped");
            None
        }
    }
}

/// The equal-time table: every seed, scene and configuration, interleaved.
fn run_table(o: &Options, pool: &rayon::ThreadPool) -> Vec<SceneRuns> {
    let mut scenes: Vec<SceneRuns> = o
        .scenes
        .iter()
        .filter_map(|name| {
            let (scene, reference) = load_scene(name, o.size)?;
            let dir = o.out.join(name);
            let _ = std::fs::create_dir_all(&dir);
            let _ = render::image_io::write_png(dir.join("reference.png"), &reference, 0.0);
            Some(SceneRuns {
                name: name.clone(),
                scene,
                reference,
                runs: CONFIGS.iter().map(|_| Vec::new()).collect(),
                notes: vec![None; CONFIGS.len()],
                methods: (0..CONFIGS.len())
                    .map(|c| MethodRun {
                        name: label(c),
                        ..MethodRun::default()
                    })
                    .collect(),
            })
        })
        .collect();
    for seed in 0..o.seeds {
        for s in &mut scenes {
            let dir = o.out.join(&s.name);
            let mut fixed_mutations = None;
            for (c, &(_, adapt)) in CONFIGS.iter().enumerate() {
                if adapt == PathAdapt::Fixed {
                    fixed_mutations = None;
                }
                let r = run_once(
                    pool,
                    &s.scene,
                    &s.reference,
                    c,
                    o.budget(),
                    seed,
                    Refinement {
                        fixed_mutations,
                        m_split: o.m_split,
                    },
                );
                if adapt == PathAdapt::Fixed {
                    fixed_mutations = Some(r.run.mutations);
                }
                eprintln!(
                    "{} seed {seed} {}: rRMSE {:.4}, {:.2} Mmut/s, acceptance {:.3}, sigma median {:.3e}, load {:.2}",
                    s.name,
                    label(c),
                    r.run.rrmse,
                    r.run.mutations as f64 / r.run.seconds / 1e6,
                    r.run.acceptance,
                    r.run.sigma_median,
                    r.run.load
                );
                let file = format!("{}_seed{seed}.exr", stem(c));
                if render::image_io::write_exr(dir.join(&file), &r.image).is_ok() {
                    s.methods[c].images.push(SeedImage {
                        seed,
                        path: file.into(),
                    });
                    s.methods[c].convergence.push(ConvergenceSeries {
                        seed,
                        points: vec![ConvergencePoint {
                            time_s: r.run.seconds,
                            relmse: r.run.relmse,
                        }],
                    });
                }
                if seed == 0 {
                    write_seed0_images(&dir, c, &r, &s.reference);
                    s.notes[c] = r.note;
                }
                s.runs[c].push(r.run);
            }
        }
    }
    scenes
}

/// The seed-0 image (EXR, PNG), its relative-error map and its sigma heat map.
fn write_seed0_images(dir: &Path, c: usize, r: &RunOutput, reference: &Image) {
    let path = dir.join(stem(c));
    let _ = render::image_io::write_exr(path.with_extension("exr"), &r.image);
    let _ = render::image_io::write_png(path.with_extension("png"), &r.image, 0.0);
    let (w, h) = (reference.width, reference.height);
    if let Ok(map) = render::metrics::relative_error_map(&r.image, reference) {
        write_map(
            &dir.join(format!("{}_error.png", stem(c))),
            &map,
            w,
            h,
            1e-3,
            1.0,
        );
    }
    if let Some(sigma) = &r.sigma_map {
        let map: Vec<f32> = sigma.iter().map(|&v| v as f32).collect();
        write_map(
            &dir.join(format!("{}_sigma.png", stem(c))),
            &map,
            w,
            h,
            1e-3,
            1.0,
        );
    }
}

/// Writes a scene's run directory (`run.json`, `report.html`).
fn write_report(o: &Options, s: &SceneRuns) {
    let dir = o.out.join(&s.name);
    let manifest = RunManifest {
        title: format!("regional_adaptive: {}", s.name),
        commit: current_commit("."),
        parameters: [
            ("scene", s.name.clone()),
            ("size", format!("{0}x{0}", o.size)),
            ("budget", o.budget_text()),
            ("seeds", o.seeds.to_string()),
            ("render threads", o.threads.to_string()),
            ("max depth", MAX_DEPTH.to_string()),
        ]
        .into_iter()
        .map(|(k, v)| (k.to_string(), v))
        .collect(),
        reference: "reference.exr".into(),
        methods: s
            .methods
            .iter()
            .filter(|m| !m.images.is_empty())
            .cloned()
            .collect(),
    };
    let report = render::image_io::write_exr(dir.join("reference.exr"), &s.reference)
        .map_err(|e| e.to_string())
        .and_then(|()| manifest.save_with_report(&dir).map_err(|e| e.to_string()));
    match report {
        Ok(html) => eprintln!("{}: report {}", s.name, html.display()),
        Err(e) => eprintln!("{}: no report: {e}", s.name),
    }
}

/// Per scene: the table, the orderings the paper reports, and the adaptation notes.
fn table_markdown(o: &Options, s: &SceneRuns, md: &mut String, csv: &mut String) {
    let _ = writeln!(md, "\n### {}\n", s.name);
    let _ = writeln!(
        md,
        "| configuration | rRMSE median [min, max] | relMSE median | rRMSE / FIXED | Mmut/s | acceptance | learned sigma, pixel median (rad) |"
    );
    let _ = writeln!(md, "|---|---|---|---|---|---|---|");
    let col = |c: usize, f: fn(&Run) -> f64| summary(&s.runs[c].iter().map(f).collect::<Vec<_>>());
    for (c, &(kind, adapt)) in CONFIGS.iter().enumerate() {
        let fixed = c - c % 4;
        let (e, e0, e1) = col(c, |r| r.rrmse);
        let q = col(c, |r| r.relmse).0;
        let rate = col(c, |r| r.mutations as f64 / r.seconds).0;
        let acc = col(c, |r| r.acceptance).0;
        let sigma = col(c, |r| r.sigma_median).0;
        let sigma = if sigma.is_nan() {
            format!("{} (fixed)", pathmlt::PATHMLT_SIGMA)
        } else {
            format!("{sigma:.3e}")
        };
        let _ = writeln!(
            md,
            "| {} | {e:.4} [{e0:.4}, {e1:.4}] | {q:.4} | {:.3} | {:.2} | {acc:.3} | {sigma} |",
            label(c),
            e / col(fixed, |r| r.rrmse).0,
            rate / 1e6
        );
        for (seed, r) in s.runs[c].iter().enumerate() {
            let _ = writeln!(
                csv,
                "{},{},{},{seed},{},{},{},{},{},{},{},{}",
                s.name,
                perturbation_name(kind),
                adapt.name(),
                o.spp
                    .map_or_else(|| format!("{}s", o.time), |n| format!("{n}mpp")),
                r.rrmse,
                r.relmse,
                r.mutations,
                r.seconds,
                r.acceptance,
                r.sigma_median,
                r.load
            );
        }
    }
    let _ = writeln!(md);
    for base in [0, 4] {
        let kind = perturbation_name(CONFIGS[base].0);
        let order = |better: usize, worse: usize| {
            let (b, w) = (col(better, |r| r.rrmse).0, col(worse, |r| r.rrmse).0);
            let wins = s.runs[better]
                .iter()
                .zip(&s.runs[worse])
                .filter(|(x, y)| x.rrmse <= y.rrmse)
                .count();
            format!(
                "{} ({b:.4} vs {w:.4}; {wins}/{} seeds)",
                if b <= w { "holds" } else { "does not hold" },
                s.runs[better].len()
            )
        };
        let _ = writeln!(
            md,
            "- {kind}: RA-QUADTREE <= RA-GRID {}; GLOBAL <= FIXED {}",
            order(base + 3, base + 2),
            order(base + 1, base)
        );
    }
    let _ = writeln!(md, "\nAdaptation notes (seed 0):\n");
    for (c, n) in s.notes.iter().enumerate() {
        if let Some(n) = n {
            let _ = writeln!(md, "- {}: {n}", label(c));
        }
    }
}

/// The rRMSE-vs-time ladder on one scene; returns per configuration the median (time, rRMSE)
/// per rung, and appends to the markdown and CSV.
fn run_ladder(o: &Options, pool: &rayon::ThreadPool, md: &mut String) -> Vec<Vec<(f64, f64)>> {
    let Some((scene, reference)) = load_scene(&o.ladder_scene, o.size) else {
        return Vec::new();
    };
    let mut runs: Vec<Vec<Vec<Run>>> = (0..CONFIGS.len())
        .map(|_| o.ladder.iter().map(|_| Vec::new()).collect())
        .collect();
    let mut csv =
        String::from("scene,perturbation,adapt,budget,seed,rrmse,relmse,mutations,seconds,acceptance,sigma_median,load1\n");
    for seed in 0..o.ladder_seeds {
        for (t, &time) in o.ladder.iter().enumerate() {
            let mut fixed_mutations = None;
            for c in 0..CONFIGS.len() {
                let r = run_once(
                    pool,
                    &scene,
                    &reference,
                    c,
                    MltBudget::Time(Duration::from_secs_f64(time)),
                    1000 + seed,
                    Refinement {
                        fixed_mutations,
                        m_split: o.m_split,
                    },
                );
                if CONFIGS[c].1 == PathAdapt::Fixed {
                    fixed_mutations = Some(r.run.mutations);
                }
                eprintln!(
                    "ladder {} {time} s seed {seed} {}: rRMSE {:.4}, load {:.2}",
                    o.ladder_scene,
                    label(c),
                    r.run.rrmse,
                    r.run.load
                );
                let x = &r.run;
                let _ = writeln!(
                    csv,
                    "{},{},{},{time}s,{},{},{},{},{},{},{},{}",
                    o.ladder_scene,
                    perturbation_name(CONFIGS[c].0),
                    CONFIGS[c].1.name(),
                    1000 + seed,
                    x.rrmse,
                    x.relmse,
                    x.mutations,
                    x.seconds,
                    x.acceptance,
                    x.sigma_median,
                    x.load
                );
                runs[c][t].push(r.run);
            }
        }
    }
    let _ = std::fs::write(o.out.join("ladder.csv"), &csv);
    let _ = writeln!(
        md,
        "\n## rRMSE vs time: {} ({} seeds per point, seeds 1000..)\n",
        o.ladder_scene, o.ladder_seeds
    );
    let head: String = o.ladder.iter().map(|t| format!(" {t} s |")).collect();
    let _ = writeln!(md, "| configuration |{head}");
    let _ = writeln!(md, "|---|{}", "---|".repeat(o.ladder.len()));
    let mut curves = Vec::new();
    for (c, per_time) in runs.iter().enumerate() {
        let mut line = format!("| {} |", label(c));
        let mut curve = Vec::new();
        for rs in per_time {
            let (e, e0, e1) = summary(&rs.iter().map(|r| r.rrmse).collect::<Vec<_>>());
            let t = summary(&rs.iter().map(|r| r.seconds).collect::<Vec<_>>()).0;
            let _ = write!(line, " {e:.4} [{e0:.4}, {e1:.4}] |");
            curve.push((t, e));
        }
        let _ = writeln!(md, "{line}");
        curves.push(curve);
    }
    curves
}

/// The log-log rRMSE-vs-time plot of the ladder's medians.
fn plot_ladder(path: &Path, scene: &str, curves: &[Vec<(f64, f64)>]) -> Result<(), String> {
    let points = curves
        .iter()
        .flatten()
        .filter(|(t, e)| *t > 0.0 && *e > 0.0);
    let (mut t0, mut t1, mut e0, mut e1) = (f64::MAX, f64::MIN, f64::MAX, f64::MIN);
    for &(t, e) in points {
        (t0, t1, e0, e1) = (t0.min(t), t1.max(t), e0.min(e), e1.max(e));
    }
    if t0 > t1 {
        return Err("no positive sample".into());
    }
    let err = |e: &dyn std::fmt::Display| format!("convergence plot: {e}");
    let root = SVGBackend::new(path, (760, 480)).into_drawing_area();
    root.fill(&WHITE).map_err(|e| err(&e))?;
    let mut chart = ChartBuilder::on(&root)
        .margin(12)
        .x_label_area_size(40)
        .y_label_area_size(70)
        .caption(
            format!("rRMSE vs render time, {scene} (median over seeds, log-log)"),
            ("sans-serif", 18),
        )
        .build_cartesian_2d(
            (t0 / 1.3..t1 * 1.3).log_scale(),
            (e0 / 1.3..e1 * 1.3).log_scale(),
        )
        .map_err(|e| err(&e))?;
    chart
        .configure_mesh()
        .x_labels(12)
        .y_labels(12)
        .x_desc("time [s]")
        .y_desc("rRMSE")
        .x_label_formatter(&|v| format!("{v:.3}"))
        .y_label_formatter(&|v| format!("{v:.3}"))
        .draw()
        .map_err(|e| err(&e))?;
    // One colour per --adapt mode; lens thick, multichain thin.
    let colours = [
        RGBColor(120, 120, 120),
        RGBColor(0, 114, 178),
        RGBColor(0, 158, 115),
        RGBColor(213, 94, 0),
    ];
    for (c, curve) in curves.iter().enumerate() {
        let colour = colours[c % 4];
        let width = if c < 4 { 3 } else { 1 };
        let line: Vec<(f64, f64)> = curve
            .iter()
            .copied()
            .filter(|(t, e)| *t > 0.0 && *e > 0.0)
            .collect();
        chart
            .draw_series(LineSeries::new(line, colour.stroke_width(width)).point_size(3))
            .map_err(|e| err(&e))?
            .label(label(c))
            .legend(move |(x, y)| {
                PathElement::new(vec![(x, y), (x + 18, y)], colour.stroke_width(width))
            });
    }
    chart
        .configure_series_labels()
        .position(SeriesLabelPosition::UpperRight)
        .background_style(WHITE.mix(0.85))
        .border_style(BLACK)
        .draw()
        .map_err(|e| err(&e))?;
    root.present().map_err(|e| err(&e))
}

fn main() {
    let o = parse_options();
    if let Err(e) = std::fs::create_dir_all(&o.out) {
        usage(&format!("cannot create {}: {e}", o.out.display()));
    }
    let pool = rayon::ThreadPoolBuilder::new()
        .num_threads(o.threads)
        .build()
        .unwrap_or_else(|e| usage(&format!("cannot start {} threads: {e}", o.threads)));
    let started = Instant::now();
    let load_start = load_average();
    let mut md = format!(
        "# Regional adaptive MLT\n\n{}, {} seeds, {}x{} pixels, max depth {MAX_DEPTH}, \
         256 chains, 100 000 bootstrap samples, {} render thread(s), runs interleaved (for seed: for scene: for configuration). \
         RA-QUADTREE: M_refine, M_split scaled to FIXED's mutation count of the same slot (otsu2018_for_budget){}. \
         rRMSE / FIXED: against FIXED of the same perturbation (medians). Commit {}.\n",
        o.budget_text(),
        o.seeds,
        o.size,
        o.size,
        o.threads,
        o.m_split
            .map_or_else(String::new, |m| format!(", M_split set to {m}")),
        current_commit(".")
    );
    let mut csv = String::from(
        "scene,perturbation,adapt,budget,seed,rrmse,relmse,mutations,seconds,acceptance,sigma_median,load1\n",
    );
    let scenes = run_table(&o, &pool);
    for s in &scenes {
        table_markdown(&o, s, &mut md, &mut csv);
        write_report(&o, s);
    }
    let table_loads: Vec<f64> = scenes
        .iter()
        .flat_map(|s| s.runs.iter().flatten().map(|r| r.load))
        .collect();
    let table_seconds = started.elapsed().as_secs_f64();
    if o.ladder_seeds > 0 && o.spp.is_none() {
        let curves = run_ladder(&o, &pool, &mut md);
        if !curves.is_empty() {
            match plot_ladder(&o.out.join("convergence.svg"), &o.ladder_scene, &curves) {
                Ok(()) => eprintln!("wrote {}", o.out.join("convergence.svg").display()),
                Err(e) => eprintln!("{e}"),
            }
        }
    }
    let (l, l0, l1) = summary(&table_loads);
    let _ = writeln!(
        md,
        "\nMachine load (1-minute /proc/loadavg before each run of the table): median {l:.2} [min {l0:.2}, max {l1:.2}]; \
         at start {load_start:.2}, at the end {:.2}. Wall time: table {table_seconds:.0} s, total {:.0} s.",
        load_average(),
        started.elapsed().as_secs_f64()
    );
    let _ = std::fs::write(o.out.join("results.md"), &md);
    let _ = std::fs::write(o.out.join("results.csv"), &csv);
    println!("{md}");
    println!("wrote {}", o.out.display());
}
