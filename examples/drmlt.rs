//! Delayed-rejection MLT (Rioux-Lavoie, Litalien et al. 2020): equal-time renderer comparison
//! and the 1-D toy of Fig. 3.
//!
//! Scenes (default glossy-highlight, caustic-pool, cornell-glass): at `--size` x `--size`,
//! each method gets `--time` seconds per render (bootstrap included) and runs with `--seeds`
//! seeds; methods are interleaved seed by seed so that a change in machine load hits all of
//! them alike. Methods:
//! - PSSMLT/K: PSSMLT with Kelemen's small step (s1 = 1/1024, s2 = 1/64);
//! - PSSMLT/G: PSSMLT with a Gaussian small step whose sigma is found by bisection (in log
//!   sigma, on a fixed mutation budget) so that its overall acceptance equals DR-orbital's
//!   (on PSSMLT) on that scene;
//! - MMLT/K: MMLT with Kelemen's small step (the baseline of DR on MMLT, as in the paper's
//!   Fig. 11);
//! - DR (Tierney-Mira, Green-Mira, orbital) on PSSMLT and on MMLT.
//!
//! Every method uses large steps with probability 0.3. Errors are relMSE and MAD against the
//! scene's BDPT reference (`scenes/references/<scene>.exr`, box-downsampled to the render
//! size), median over the seeds with the min-max range. Also reported: mutations per second,
//! overall acceptance, and the cost of one step relative to a PSSMLT/K step (the ratio of
//! mutations per second). Writes `results.md`, `results.csv` and the seed-0 images (EXR and
//! PNG) of every method to `--out` (default `target/drmlt`), and per scene a run directory
//! (`<out>/<scene>/`: every seed's EXR, `run.json`) with a self-contained `report.html`
//! (`experiments::report`; equal time, so each seed contributes one error-vs-time sample).
//!
//! The toy: the mixture of uniforms of eq. 8 (alpha = 1/10, beta = 1), MH with sigma 1 and
//! 0.1 and Tierney-Mira DR (sigma 1 then 0.1): acceptance, integrated autocorrelation time
//! (16 chains of 5x10^4 steps), and `toy_trace.png` / `toy_hist.png`. The per-pixel DR stage map
//! (paper Fig. 1, 9) is not produced (not implemented).
//!
//! `cargo run --release --example drmlt -- [--time 4] [--seeds 5] [--size 64] [--out DIR]
//! [--no-toy] [--no-scenes] [--stats-only] [scene ...]` (`--stats-only`: the sigma matching
//! and the per-stage tables without the timed renders).

use std::fmt::Write as _;
use std::path::{Path, PathBuf};
use std::sync::atomic::AtomicBool;
use std::time::Duration;

use experiments::report::{
    current_commit, write_report, ConvergencePoint, ConvergenceSeries, MethodRun, RunManifest,
    SeedImage,
};
use mcmc_core::delayed_rejection::IndependentSecondStage;
use mcmc_core::render_loop::ChainSlot;
use mcmc_core::seed::chain_seed;
use mcmc_core::stats::{integrated_autocorrelation_time, AcceptanceStats};
use mcmc_core::toy::{ToyTarget, UniformMixture};
use mcmc_core::{Chain, DelayedRejection, GaussianRandomWalk, Kernel, Mh, NoAdaptation};
use pss::SmallMutation;
use rand::SeedableRng;
use rand_pcg::Pcg64;
use render::bdpt::BdptParams;
use render::image::Image;
use render::methods::{DrmltSettings, MethodSettings, MmltSettings, PssmltSettings};
use render::mlt::dr::{self, DrBase, DrVariant};
use render::mlt::{
    LargeStepMode, MltBudget, MltDriver, MltSettings, MmltTarget, PerChain, PssmltTarget,
    PATH_STREAMS,
};
use render::scene::Scene;
use render::session::{render, Budget, NoProgress, RenderSettings};

/// Command-line options.
struct Options {
    time: f64,
    seeds: u64,
    size: u32,
    out: PathBuf,
    toy: bool,
    scenes: bool,
    stats_only: bool,
    names: Vec<String>,
}

fn parse_options() -> Options {
    let mut o = Options {
        time: 4.0,
        seeds: 5,
        size: 64,
        out: PathBuf::from("target/drmlt"),
        toy: true,
        scenes: true,
        stats_only: false,
        names: Vec::new(),
    };
    let mut args = std::env::args().skip(1);
    while let Some(a) = args.next() {
        let mut value = |what: &str| -> String {
            args.next().unwrap_or_else(|| {
                eprintln!("{what} needs a value");
                std::process::exit(2)
            })
        };
        let bad = |what: &str| -> ! {
            eprintln!("{what} needs a positive number");
            std::process::exit(2)
        };
        match a.as_str() {
            "--time" => {
                o.time = value("--time")
                    .parse()
                    .ok()
                    .filter(|t: &f64| *t > 0.0)
                    .unwrap_or_else(|| bad("--time"));
            }
            "--seeds" => {
                o.seeds = value("--seeds")
                    .parse()
                    .ok()
                    .filter(|&n| n > 0)
                    .unwrap_or_else(|| bad("--seeds"));
            }
            "--size" => {
                o.size = value("--size")
                    .parse()
                    .ok()
                    .filter(|&n| n > 0)
                    .unwrap_or_else(|| bad("--size"));
            }
            "--out" => o.out = PathBuf::from(value("--out")),
            "--no-toy" => o.toy = false,
            "--no-scenes" => o.scenes = false,
            "--stats-only" => o.stats_only = true,
            _ => o.names.push(a),
        }
    }
    if o.names.is_empty() {
        o.names = ["glossy-highlight", "caustic-pool", "cornell-glass"]
            .map(String::from)
            .to_vec();
    }
    o
}

/// Median, min and max of `v` (`render::metrics::median_min_max`; NaN for no values).
fn summary(v: &[f64]) -> (f64, f64, f64) {
    render::metrics::median_min_max(v).unwrap_or((f64::NAN, f64::NAN, f64::NAN))
}

/// One compared configuration.
#[derive(Clone, Copy, Debug)]
enum Method {
    /// PSSMLT with Kelemen's small step.
    Kelemen,
    /// PSSMLT with a Gaussian small step of this sigma.
    Gaussian(f64),
    /// MMLT with Kelemen's small step (the baseline of DR on MMLT).
    MmltKelemen,
    /// Delayed rejection.
    Dr(DrVariant, DrBase),
}

impl Method {
    fn label(self) -> String {
        match self {
            Method::Kelemen => "PSSMLT/K".to_owned(),
            Method::Gaussian(s) => format!("PSSMLT/G (sigma {s:.4})"),
            Method::MmltKelemen => "MMLT/K".to_owned(),
            Method::Dr(v, b) => format!(
                "DR {} on {}",
                v.name(),
                match b {
                    DrBase::Pssmlt => "PSSMLT",
                    DrBase::Mmlt => "MMLT",
                }
            ),
        }
    }

    fn file_stem(self) -> String {
        match self {
            Method::Kelemen => "pssmlt-k".to_owned(),
            Method::Gaussian(_) => "pssmlt-g".to_owned(),
            Method::MmltKelemen => "mmlt-k".to_owned(),
            Method::Dr(v, b) => format!(
                "dr-{}-{}",
                v.name(),
                match b {
                    DrBase::Pssmlt => "pssmlt",
                    DrBase::Mmlt => "mmlt",
                }
            ),
        }
    }

    fn settings(self, size: u32, budget: Budget, seed: u64) -> RenderSettings {
        // Kelemen's PSSMLT (the expected-value estimator, no raster steps, no direct pass),
        // pbrt-v3's MMLT and the paper's DR kernels.
        let method: MethodSettings = match self {
            Method::Kelemen => PssmltSettings::kelemen2002().into(),
            Method::Gaussian(sigma) => {
                let mut s = PssmltSettings::kelemen2002();
                s.chain.small_step = SmallMutation::Gaussian { sigma };
                s.into()
            }
            Method::MmltKelemen => MmltSettings::hachisuka2014().into(),
            Method::Dr(v, b) => DrmltSettings::rioux_lavoie2020_with(v, b).into(),
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
}

/// One render's measurements.
struct Run {
    relmse: f64,
    mad: f64,
    mutations_per_second: f64,
    acceptance: f64,
}

/// The overall acceptance rate of a Markov chain render.
fn acceptance(out: &render::RenderOutput) -> f64 {
    out.mcmc.as_ref().map_or(f64::NAN, |m| m.acceptance_rate())
}

fn run_once(
    scene: &Scene,
    reference: &Image,
    method: Method,
    size: u32,
    budget: Budget,
    seed: u64,
) -> (Run, Image, Option<Image>) {
    let out = render(
        scene,
        &method.settings(size, budget, seed),
        &NoProgress,
        &AtomicBool::new(false),
    )
    .expect("render");
    let run = Run {
        relmse: render::metrics::relmse(&out.image, reference).unwrap_or(f64::NAN),
        mad: render::metrics::mad(&out.image, reference).unwrap_or(f64::NAN),
        mutations_per_second: out.samples as f64 / out.elapsed.as_secs_f64(),
        acceptance: acceptance(&out),
    };
    (run, out.image, out.stage_map)
}

/// Acceptance on a fixed mutation budget (16 per pixel, small bootstrap): load-independent.
fn calibration_acceptance(scene: &Scene, method: Method, size: u32) -> f64 {
    let mut s = method.settings(size, Budget::SamplesPerPixel(16), 7);
    if let Some(chain) = s.method.chain_mut() {
        chain.bootstrap_samples = 20_000;
    }
    let out = render(scene, &s, &NoProgress, &AtomicBool::new(false)).expect("render");
    acceptance(&out)
}

/// Bisection on log sigma in [1e-4, 0.5] (acceptance decreases with sigma): the Gaussian
/// sigma whose overall acceptance matches `target` (clamped to the range's ends).
fn match_sigma(scene: &Scene, size: u32, target: f64) -> (f64, f64) {
    let (mut lo, mut hi) = (1e-4f64.ln(), 0.5f64.ln());
    let mut best = (f64::NAN, f64::NAN);
    for _ in 0..9 {
        let mid = 0.5 * (lo + hi);
        let sigma = mid.exp();
        let a = calibration_acceptance(scene, Method::Gaussian(sigma), size);
        if best.0.is_nan() || (a - target).abs() < (best.1 - target).abs() {
            best = (sigma, a);
        }
        if a > target {
            lo = mid;
        } else {
            hi = mid;
        }
    }
    best
}

/// Per-stage statistics of DR on `scene` (at `size`, 16 mutations per pixel, seed 7): the
/// session's `render` reports only the overall acceptance, so this calls the MLT loop
/// directly with the same kernels (`render::mlt::dr`) to read the full `AcceptanceStats`.
fn stage_stats(scene: &Scene, size: u32, variant: DrVariant, base: DrBase) -> AcceptanceStats {
    let mut sized = scene.clone();
    sized.set_resolution(size, size);
    let params = BdptParams {
        max_depth: 5,
        ..BdptParams::default()
    };
    let settings = MltSettings {
        width: size as usize,
        height: size as usize,
        chains: 256,
        bootstrap_samples: 20_000,
        budget: MltBudget::MutationsPerPixel(16.0),
        large_step: LargeStepMode::Fixed(0.3),
        seed: 7,
        streams: PATH_STREAMS,
        stage_map: false,
    };
    let layout = dr::dr_layout(5);
    match base {
        DrBase::Pssmlt => stage_stats_on(
            &[PssmltTarget::new(&sized, params, size, size)],
            variant,
            base,
            layout,
            &settings,
        ),
        DrBase::Mmlt => stage_stats_on(
            &MmltTarget::all_depths(&sized, params, size, size),
            variant,
            base,
            layout,
            &settings,
        ),
    }
}

/// [`stage_stats`] on the path sampler's targets.
fn stage_stats_on<T>(
    targets: &[T],
    variant: DrVariant,
    base: DrBase,
    layout: pss::PairLayout,
    settings: &MltSettings,
) -> AcceptanceStats
where
    T: mcmc_core::Target<State = pss::PssState>,
    T::Payload: mcmc_core::render_loop::SplatPayload,
{
    let no = AtomicBool::new(false);
    match variant {
        DrVariant::Orbital => {
            MltDriver::new(targets, settings)
                .run(
                    PerChain(|slot: ChainSlot, p| {
                        dr::orbital_kernel(layout, base, p, slot.target as u32)
                    }),
                    &NoProgress,
                    &no,
                )
                .stats
        }
        DrVariant::TierneyMira => {
            MltDriver::new(targets, settings)
                .run(
                    PerChain(|slot: ChainSlot, p| {
                        dr::tierney_mira_kernel(layout, base, p, slot.target as u32)
                    }),
                    &NoProgress,
                    &no,
                )
                .stats
        }
        DrVariant::GreenMira => {
            MltDriver::new(targets, settings)
                .run(
                    PerChain(|slot: ChainSlot, p| {
                        dr::green_mira_kernel(layout, base, p, slot.target as u32)
                    }),
                    &NoProgress,
                    &no,
                )
                .stats
        }
        // Not among this example's configurations (it needs differentiable MMLT targets:
        // examples/langevin.rs measures it).
        DrVariant::CheapThenExpensive => AcceptanceStats::default(),
    }
}

/// Appends the per-stage table of the six DR configurations on `scene` to `md`.
fn stage_table(scene: &Scene, name: &str, size: u32, md: &mut String) {
    let _ = writeln!(
        md,
        "\n{name}, DR per stage (16 mutations per pixel, seed 7; stage 2 runs only after a rejected small step):\n\n| method | overall acceptance | stage 1 acceptance | stage 2 tried (% of steps) | stage 2 acceptance | stage-2 share of accepted moves | path evaluations per step (Green-Mira: at most; its ghost counted for every second stage) |\n|---|---|---|---|---|---|---|"
    );
    for base in [DrBase::Pssmlt, DrBase::Mmlt] {
        for v in [
            DrVariant::TierneyMira,
            DrVariant::GreenMira,
            DrVariant::Orbital,
        ] {
            let st = stage_stats(scene, size, v, base);
            let tried2 = st.stage_tried[1] as f64 / st.steps.max(1) as f64;
            // Green-Mira also evaluates the ghost y* (one more evaluation per second stage).
            let per_second = if v == DrVariant::GreenMira { 2.0 } else { 1.0 };
            let _ = writeln!(
                md,
                "| {} | {:.3} | {:.3} | {:.1} | {:.3} | {:.3} | {:.2} |",
                Method::Dr(v, base).label(),
                st.acceptance_rate(),
                st.stage_acceptance_rate(0),
                100.0 * tried2,
                st.stage_acceptance_rate(1),
                st.second_stage_share(),
                1.0 + per_second * tried2
            );
        }
    }
}

/// Runs every method on scene `name`; appends its table to `md` and its runs to `csv`.
fn run_scene(o: &Options, name: &str, md: &mut String, csv: &mut String) {
    let size = o.size;
    let (scene, reference) = match render::bundled::bundled(name, size) {
        Ok(pair) => pair,
        Err(e) => {
            eprintln!("{e}; skipped");
            return;
        }
    };
    let orbital = Method::Dr(DrVariant::Orbital, DrBase::Pssmlt);
    let target = calibration_acceptance(&scene, orbital, size);
    let (sigma, matched) = match_sigma(&scene, size, target);
    let note = format!(
        "{name}: DR orbital (PSSMLT) acceptance {target:.3}; PSSMLT/G sigma {sigma:.5} by 9 bisection steps on log sigma gives {matched:.3} (both on 16 mutations per pixel, seed 7)"
    );
    eprintln!("{note}");
    let _ = writeln!(md, "\n### {name}\n\n{note}.");
    stage_table(&scene, name, size, md);
    if o.stats_only {
        return;
    }
    let mut methods = vec![Method::Kelemen, Method::Gaussian(sigma)];
    for base in [DrBase::Pssmlt, DrBase::Mmlt] {
        if base == DrBase::Mmlt {
            methods.push(Method::MmltKelemen);
        }
        for v in [
            DrVariant::TierneyMira,
            DrVariant::GreenMira,
            DrVariant::Orbital,
        ] {
            methods.push(Method::Dr(v, base));
        }
    }
    let dir = o.out.join(name);
    let _ = std::fs::create_dir_all(&dir);
    let budget = Budget::Time(Duration::from_secs_f64(o.time));
    let mut runs: Vec<Vec<Run>> = methods.iter().map(|_| Vec::new()).collect();
    let mut report_methods: Vec<MethodRun> = methods
        .iter()
        .map(|m| MethodRun {
            name: m.label(),
            ..MethodRun::default()
        })
        .collect();
    for seed in 0..o.seeds {
        for (m, method) in methods.iter().enumerate() {
            let (run, image, stage_map) = run_once(&scene, &reference, *method, size, budget, seed);
            eprintln!(
                "{name} seed {seed} {}: relMSE {:.4}, MAD {:.4}, {:.0} mut/s, acceptance {:.3}",
                method.label(),
                run.relmse,
                run.mad,
                run.mutations_per_second,
                run.acceptance
            );
            let file = format!("{}_seed{seed}.exr", method.file_stem());
            if render::image_io::write_exr(dir.join(&file), &image).is_ok() {
                report_methods[m].images.push(SeedImage {
                    seed,
                    path: file.into(),
                });
                report_methods[m].convergence.push(ConvergenceSeries {
                    seed,
                    points: vec![ConvergencePoint {
                        time_s: o.time,
                        relmse: run.relmse,
                    }],
                });
            }
            if seed == 0 {
                let stem = dir.join(method.file_stem());
                let _ = render::image_io::write_exr(stem.with_extension("exr"), &image);
                let _ = render::image_io::write_png(stem.with_extension("png"), &image, 0.0);
                // DR methods: the stage map (share of each pixel from second-stage moves).
                if let Some(map) = &stage_map {
                    let name = format!("{}_stage2", method.file_stem());
                    let _ = render::image_io::write_exr(dir.join(&name).with_extension("exr"), map);
                    let _ =
                        render::image_io::write_png(dir.join(name).with_extension("png"), map, 0.0);
                }
            }
            runs[m].push(run);
        }
    }
    let _ = render::image_io::write_png(dir.join("reference.png"), &reference, 0.0);
    write_run_report(o, name, &dir, &reference, report_methods);
    let _ = writeln!(
        md,
        "\n| method | relMSE median [min, max] | MAD median [min, max] | Mmut/s | acceptance | step cost vs PSSMLT/K | relMSE / PSSMLT/K |"
    );
    let _ = writeln!(md, "|---|---|---|---|---|---|---|");
    let base_rate = summary(
        &runs[0]
            .iter()
            .map(|r| r.mutations_per_second)
            .collect::<Vec<_>>(),
    )
    .0;
    let base_err = summary(&runs[0].iter().map(|r| r.relmse).collect::<Vec<_>>()).0;
    for (method, rs) in methods.iter().zip(&runs) {
        let col = |f: fn(&Run) -> f64| summary(&rs.iter().map(f).collect::<Vec<_>>());
        let (e, e0, e1) = col(|r| r.relmse);
        let (d, d0, d1) = col(|r| r.mad);
        let rate = col(|r| r.mutations_per_second).0;
        let acc = col(|r| r.acceptance).0;
        let _ = writeln!(
            md,
            "| {} | {e:.4} [{e0:.4}, {e1:.4}] | {d:.4} [{d0:.4}, {d1:.4}] | {:.3} | {acc:.3} | {:.2} | {:.2} |",
            method.label(),
            rate / 1e6,
            base_rate / rate,
            e / base_err
        );
        for (seed, r) in rs.iter().enumerate() {
            let _ = writeln!(
                csv,
                "{name},{},{seed},{},{},{},{}",
                method.label(),
                r.relmse,
                r.mad,
                r.mutations_per_second,
                r.acceptance
            );
        }
    }
}

/// Writes `dir/run.json` and `dir/report.html` for one scene's equal-time runs.
fn write_run_report(
    o: &Options,
    name: &str,
    dir: &Path,
    reference: &Image,
    methods: Vec<MethodRun>,
) {
    let result = render::image_io::write_exr(dir.join("reference.exr"), reference)
        .map_err(|e| e.to_string())
        .and_then(|()| {
            let manifest = RunManifest {
                title: format!("drmlt: {name}"),
                commit: current_commit("."),
                parameters: [
                    ("scene", name.to_string()),
                    ("size", format!("{0}x{0}", o.size)),
                    ("time per render [s]", o.time.to_string()),
                    ("seeds", o.seeds.to_string()),
                    ("large-step probability", "0.3".into()),
                    ("max depth", "5".into()),
                    ("chains", "256".into()),
                ]
                .into_iter()
                .map(|(k, v)| (k.to_string(), v))
                .collect(),
                reference: "reference.exr".into(),
                methods: methods
                    .into_iter()
                    .filter(|m| !m.images.is_empty())
                    .collect(),
            };
            manifest.save(dir).map_err(|e| e.to_string())?;
            write_report(&manifest, dir, dir.join("report.html")).map_err(|e| e.to_string())
        });
    match result {
        Ok(html) => eprintln!("{name}: report {}", html.display()),
        Err(e) => eprintln!("{name}: no report: {e}"),
    }
}

// ---- the 1-D toy of Fig. 3 ----

/// Trace (2000 steps) and sample (5000 steps) of chain 0, IATs of `x` of every chain,
/// acceptance statistics.
struct ToyResult {
    trace: Vec<f64>,
    samples: Vec<f64>,
    iat: Vec<f64>,
    stats: AcceptanceStats,
}

fn toy_run<K: Kernel<UniformMixture> + Clone>(kernel: &K, seed: u64) -> ToyResult {
    let target = UniformMixture::rioux_lavoie2020();
    let (chains, steps) = (16u64, 50_000usize);
    let mut r = ToyResult {
        trace: Vec::new(),
        samples: Vec::new(),
        iat: Vec::new(),
        stats: AcceptanceStats::default(),
    };
    for i in 0..chains {
        let mut rng = Pcg64::seed_from_u64(chain_seed(seed, i));
        let x0 = target.sample_exact(&mut rng);
        let mut chain =
            Chain::new(&target, kernel.clone(), NoAdaptation, rng, x0).expect("exact start");
        let mut xs = Vec::with_capacity(steps);
        for _ in 0..steps {
            chain.step(&mut ()).expect("step");
            xs.push(chain.state()[0]);
        }
        r.iat.push(integrated_autocorrelation_time(&xs));
        if i == 0 {
            r.trace = xs[..2_000].to_vec();
            r.samples = xs[..5_000].to_vec();
        }
        r.stats.merge(chain.stats());
    }
    r
}

/// Fills the axis-aligned rectangle `[x0, x1) x [y0, y1)` (pixels, clipped).
fn fill(img: &mut Image, x0: i64, y0: i64, x1: i64, y1: i64, rgb: [f32; 3]) {
    let (w, h) = (img.width as i64, img.height as i64);
    for y in y0.max(0)..y1.min(h) {
        for x in x0.max(0)..x1.min(w) {
            img.set(x as usize, y as usize, rgb);
        }
    }
}

/// A line segment by dense sampling (one-pixel wide).
fn line(img: &mut Image, a: (f64, f64), b: (f64, f64), rgb: [f32; 3]) {
    let n = ((b.0 - a.0).abs().max((b.1 - a.1).abs()).ceil() as usize).max(1);
    for i in 0..=n {
        let t = i as f64 / n as f64;
        let (x, y) = (a.0 + t * (b.0 - a.0), a.1 + t * (b.1 - a.1));
        fill(img, x as i64, y as i64, x as i64 + 1, y as i64 + 1, rgb);
    }
}

const PANEL_W: usize = 600;
const PANEL_H: usize = 160;
const COLORS: [[f32; 3]; 3] = [[0.8, 0.1, 0.1], [0.1, 0.3, 0.9], [0.1, 0.6, 0.1]];
const GREY: [f32; 3] = [0.6, 0.6, 0.6];

/// Vertical pixel of `x` in [-0.1, 1] inside panel `p` (top to bottom).
fn x_to_row(x: f64, p: usize) -> f64 {
    let t = (x + 0.1) / 1.1;
    (p * PANEL_H) as f64 + 5.0 + (1.0 - t) * (PANEL_H - 10) as f64
}

/// Trace plots (one panel per kernel, x against step; grey line at x = 0).
fn trace_plot(results: &[ToyResult]) -> Image {
    let height = PANEL_H * results.len();
    let mut img = Image::new(PANEL_W, height);
    fill(&mut img, 0, 0, PANEL_W as i64, height as i64, [1.0; 3]);
    for (p, r) in results.iter().enumerate() {
        let zero = x_to_row(0.0, p);
        line(&mut img, (0.0, zero), (PANEL_W as f64, zero), GREY);
        let y0 = (p * PANEL_H) as i64;
        fill(&mut img, 0, y0, PANEL_W as i64, y0 + 1, [0.0; 3]);
        let sx = PANEL_W as f64 / r.trace.len() as f64;
        for (i, w) in r.trace.windows(2).enumerate() {
            line(
                &mut img,
                (i as f64 * sx, x_to_row(w[0], p)),
                ((i + 1) as f64 * sx, x_to_row(w[1], p)),
                COLORS[p],
            );
        }
    }
    img
}

/// Histograms of chain 0's first 5000 states (one panel per kernel, 110 bins on [-0.1, 1])
/// with the exact density in grey.
fn histogram_plot(results: &[ToyResult]) -> Image {
    let bins = 110usize;
    let bar = PANEL_W / bins;
    let (width, height) = (bar * bins, PANEL_H * results.len());
    let mut img = Image::new(width, height);
    fill(&mut img, 0, 0, width as i64, height as i64, [1.0; 3]);
    let peak = 5.0 * 1.25; // the spike's density 1/(2 alpha) = 5, with headroom
    for (p, r) in results.iter().enumerate() {
        let mut counts = vec![0usize; bins];
        for &x in &r.samples {
            let b = ((x + 0.1) / 1.1 * bins as f64).floor();
            if (0.0..bins as f64).contains(&b) {
                counts[b as usize] += 1;
            }
        }
        let base = ((p + 1) * PANEL_H) as f64 - 2.0;
        let to_px = |density: f64| base - density / peak * (PANEL_H - 8) as f64;
        let width = 1.1 / bins as f64;
        for (b, &c) in counts.iter().enumerate() {
            let density = c as f64 / (r.samples.len() as f64 * width);
            let x0 = (b * bar) as i64;
            fill(
                &mut img,
                x0,
                (to_px(density) as i64).max((p * PANEL_H) as i64 + 2),
                x0 + bar as i64 - 1,
                base as i64,
                COLORS[p],
            );
            let exact = if b < 10 { 5.0 } else { 0.5 };
            let y = to_px(exact) as i64;
            fill(&mut img, x0, y, x0 + bar as i64, y + 2, GREY);
        }
        let y0 = (p * PANEL_H) as i64;
        fill(&mut img, 0, y0, width as i64, y0 + 1, [0.0; 3]);
    }
    img
}

fn run_toy(out: &Path, md: &mut String) {
    let grw = |s: f64| GaussianRandomWalk::new(s).expect("sigma > 0");
    let dr = DelayedRejection::tierney_mira(grw(1.0), IndependentSecondStage(grw(0.1)))
        .with_symmetric_second_stage();
    let results = [
        toy_run(&Mh::new(grw(1.0)), 81),
        toy_run(&Mh::new(grw(0.1)), 82),
        toy_run(&dr, 83),
    ];
    let names = [
        "MH, sigma 1 (large)",
        "MH, sigma 0.1 (small)",
        "DR Tierney-Mira, 1 then 0.1",
    ];
    let _ = writeln!(
        md,
        "\n### 1-D toy of Fig. 3 (alpha = 1/10, beta = 1; 16 chains x 5x10^4 steps)\n\n| kernel | acceptance | stage-2 share of accepted moves | IAT(x) mean +- se | target evaluations per step |\n|---|---|---|---|---|"
    );
    for (name, r) in names.iter().zip(&results) {
        let n = r.iat.len() as f64;
        let mean = r.iat.iter().sum::<f64>() / n;
        let se = (r.iat.iter().map(|t| (t - mean).powi(2)).sum::<f64>() / (n - 1.0) / n).sqrt();
        let evals = 1.0 + r.stats.stage_tried[1] as f64 / r.stats.steps as f64;
        let _ = writeln!(
            md,
            "| {name} | {:.3} | {:.3} | {mean:.1} +- {se:.1} | {evals:.2} |",
            r.stats.acceptance_rate(),
            r.stats.second_stage_share()
        );
    }
    let _ = writeln!(
        md,
        "\nPanels top to bottom: MH sigma 1 (red), MH sigma 0.1 (blue), DR (green). `toy_trace.png`: x over the first 2000 steps of chain 0 (grey: x = 0, the spike is below it). `toy_hist.png`: histogram of the first 5000 states of chain 0 on [-0.1, 1] with the exact density in grey."
    );
    let _ = render::image_io::write_png(out.join("toy_trace.png"), &trace_plot(&results), 0.0);
    let _ = render::image_io::write_png(out.join("toy_hist.png"), &histogram_plot(&results), 0.0);
}

/// The 1-, 5- and 15-minute load averages (Linux), for the record.
fn load_average() -> String {
    std::fs::read_to_string("/proc/loadavg")
        .ok()
        .map(|l| l.split_whitespace().take(3).collect::<Vec<_>>().join(" "))
        .unwrap_or_else(|| "unknown".to_owned())
}

fn main() {
    let o = parse_options();
    let load_before = load_average();
    let _ = std::fs::create_dir_all(&o.out);
    let mut md = String::new();
    let mut csv = String::from("scene,method,seed,relmse,mad,mutations_per_second,acceptance\n");
    if o.toy {
        run_toy(&o.out, &mut md);
    }
    if o.scenes {
        let _ = writeln!(
            md,
            "\n## Equal time: {} s per render (bootstrap included), {}x{}, {} seeds, {} threads, max depth 5, 256 chains, large steps 0.3",
            o.time,
            o.size,
            o.size,
            o.seeds,
            std::thread::available_parallelism().map_or(1, |n| n.get())
        );
        let _ = writeln!(
            md,
            "\nrelMSE and MAD against the BDPT reference (box-downsampled from 256x256), median [min, max] over the seeds; Mmut/s and acceptance are medians; step cost = PSSMLT/K's mutations per second / the method's."
        );
        let names = o.names.clone();
        for name in &names {
            run_scene(&o, name, &mut md, &mut csv);
        }
    }
    if o.scenes {
        let _ = writeln!(
            md,
            "\nLoad average (1, 5, 15 min) before: {load_before}; after: {}.",
            load_average()
        );
    }
    println!("{md}");
    let _ = std::fs::write(o.out.join("results.md"), &md);
    if o.scenes {
        let _ = std::fs::write(o.out.join("results.csv"), &csv);
    }
    eprintln!("wrote {}", o.out.display());
}
