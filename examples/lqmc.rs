//! Local quasi-Monte Carlo exploration (Tessari, Hanika & Dachsbacher): the 2-D toy of
//! Fig. 2 and an equal-time renderer comparison with temporal stability.
//!
//! The toy: the unit torus explored by `N = 128` points, by the rank-1 lattice with
//! `g = (1, 12)` and by a Markov chain of uniform steps in `[-1/sqrt(N), 1/sqrt(N)]` per
//! coordinate, on the full domain and locally (a 1/4 x 1/4 tile around a seed: the lattice
//! Cranley-Patterson-shifted onto the seed, the chain's steps scaled to the tile). Writes
//! `toy_full.png` and `toy_local.png` (lattice left, chain right) and the number of cells of
//! an 8 x 8 grid (of the domain, of the tile) each point set hits.
//!
//! The renders (default scenes dof, caustic-pool, ajar-door): at `--size` x `--size`, each
//! method gets `--time` seconds per render and runs with seeds `0..--seeds` (methods
//! interleaved seed by seed so that load changes hit all alike). Methods: Halton QMC path
//! tracing (`qmc`, the paper's "Halton points"), PSSMLT/K (`pssmlt` with Kelemen's small step
//! and large steps 0.3: the paper's KMLT) and LQMC (`lqmc`, the paper's parameters). Errors:
//! relMSE and MAD against the BDPT reference (`scenes/references/<scene>.exr`,
//! box-downsampled), median [min, max] over the seeds. Temporal stability: the per-pixel
//! variance of the luminance across the seeds' renders (the frames of a still "animation"
//! with a new seed per frame), averaged over the pixels, next to the mean MSE (for an unbiased
//! method the variance is the noise part of the MSE), and how blotchy that variance is (the
//! variance of 8 x 8-block means times 64 over the per-pixel variance: 1 for uncorrelated
//! pixels, more for clumps). Writes `results.md`, `results.csv`,
//! the seed-0 images of every method (EXR and PNG) and the reference PNG to `--out`
//! (default `target/lqmc`), and per scene a run directory (`<out>/<scene>/`: every seed's EXR,
//! `run.json`) with a self-contained `report.html` (`experiments::report`; each seed is one
//! error-vs-time sample).
//!
//! `cargo run --release --example lqmc -- [--time 2] [--seeds 10] [--size 64] [--out DIR]
//! [--no-toy] [--no-scenes] [scene ...]`

use std::fmt::Write as _;
use std::path::{Path, PathBuf};
use std::sync::atomic::AtomicBool;
use std::time::Duration;

use experiments::report::{
    current_commit, ConvergencePoint, ConvergenceSeries, MethodRun, RunManifest, SeedImage,
};
use lqmc::{torus_difference, Rank1Lattice, ShiftedLattice};
use mcmc_core::seed::mix64;
use render::image::Image;
use render::methods::{LqmcSettings, PssmltSettings, QmcSettings};
use render::session::{render, Budget, NoProgress, RenderSettings};

/// Command-line options.
struct Options {
    time: f64,
    seeds: u64,
    size: u32,
    out: PathBuf,
    toy: bool,
    scenes: bool,
    names: Vec<String>,
}

fn parse_options() -> Options {
    let mut o = Options {
        time: 2.0,
        seeds: 10,
        size: 64,
        out: PathBuf::from("target/lqmc"),
        toy: true,
        scenes: true,
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
        let bad = |what: &str, range: &str| -> ! {
            eprintln!("{what} needs a number in {range}");
            std::process::exit(2)
        };
        match a.as_str() {
            "--time" => {
                o.time = value("--time")
                    .parse()
                    .ok()
                    .filter(|t: &f64| *t > 0.0 && t.is_finite())
                    .unwrap_or_else(|| bad("--time", "(0, inf) seconds"));
            }
            "--seeds" => {
                o.seeds = value("--seeds")
                    .parse()
                    .ok()
                    .filter(|&n| n >= 2)
                    .unwrap_or_else(|| bad("--seeds", "2.. (variance needs two)"));
            }
            "--size" => {
                o.size = value("--size")
                    .parse()
                    .ok()
                    .filter(|&n| (1..=4096).contains(&n))
                    .unwrap_or_else(|| bad("--size", "1..=4096"));
            }
            "--out" => o.out = PathBuf::from(value("--out")),
            "--no-toy" => o.toy = false,
            "--no-scenes" => o.scenes = false,
            _ => o.names.push(a),
        }
    }
    if o.names.is_empty() {
        o.names = ["dof", "caustic-pool", "ajar-door"]
            .map(String::from)
            .to_vec();
    }
    o
}

/// Median, min and max of `v` (NaN-free input).
fn summary(v: &[f64]) -> (f64, f64, f64) {
    let mut s = v.to_vec();
    s.sort_by(f64::total_cmp);
    let n = s.len();
    let median = if n % 2 == 1 {
        s[n / 2]
    } else {
        0.5 * (s[n / 2 - 1] + s[n / 2])
    };
    (median, s[0], s[n - 1])
}

/// The 1-, 5- and 15-minute load averages (Linux), for the record.
fn load_average() -> String {
    std::fs::read_to_string("/proc/loadavg")
        .ok()
        .map(|l| l.split_whitespace().take(3).collect::<Vec<_>>().join(" "))
        .unwrap_or_else(|| "unknown".to_owned())
}

// ---- the 2-D toy of Fig. 2 ----

const PANEL: usize = 320;
const RED: [f32; 3] = [0.8, 0.1, 0.1];
const BLUE: [f32; 3] = [0.1, 0.3, 0.9];
const GREY: [f32; 3] = [0.6, 0.6, 0.6];

/// Fills the axis-aligned rectangle `[x0, x1) x [y0, y1)` (pixels, clipped).
fn fill(img: &mut Image, x0: i64, y0: i64, x1: i64, y1: i64, rgb: [f32; 3]) {
    let (w, h) = (img.width as i64, img.height as i64);
    for y in y0.max(0)..y1.min(h) {
        for x in x0.max(0)..x1.min(w) {
            img.set(x as usize, y as usize, rgb);
        }
    }
}

/// A uniform number in `[0, 1)` keyed by `(seed, i)`.
fn uniform(seed: u64, i: u64) -> f64 {
    (mix64(mix64(seed) ^ i) >> 11) as f64 / (1u64 << 53) as f64
}

/// `N` points of a Markov chain on the torus from `start`, uniform steps in `[-r, r]^2`.
fn chain(start: [f64; 2], r: f64, n: usize, seed: u64) -> Vec<[f64; 2]> {
    let mut x = start;
    let mut out = vec![x];
    for i in 1..n as u64 {
        for (d, c) in x.iter_mut().enumerate() {
            let step = (2.0 * uniform(seed, 2 * i + d as u64) - 1.0) * r;
            *c = (*c + step).rem_euclid(1.0);
        }
        out.push(x);
    }
    out
}

/// Draws `points` (unit-square coordinates mapped to the panel at `x_off`) as 3x3 dots; in
/// `tile` coordinates if given (`(origin, size)`: the tile is outlined, points inside it).
fn draw_panel(
    img: &mut Image,
    x_off: usize,
    points: &[[f64; 2]],
    rgb: [f32; 3],
    tile: Option<([f64; 2], f64)>,
) {
    let s = (PANEL - 20) as f64;
    let px = |u: f64| 10.0 + u * s;
    fill(
        img,
        x_off as i64 + 10,
        10,
        (x_off + PANEL - 10) as i64,
        11,
        GREY,
    );
    fill(
        img,
        x_off as i64 + 10,
        (PANEL - 11) as i64,
        (x_off + PANEL - 10) as i64,
        (PANEL - 10) as i64,
        GREY,
    );
    fill(
        img,
        x_off as i64 + 10,
        10,
        x_off as i64 + 11,
        (PANEL - 10) as i64,
        GREY,
    );
    fill(
        img,
        (x_off + PANEL - 11) as i64,
        10,
        (x_off + PANEL - 10) as i64,
        (PANEL - 10) as i64,
        GREY,
    );
    if let Some((o, size)) = tile {
        for (a, b) in [
            ([o[0], o[1]], [o[0] + size, o[1]]),
            ([o[0], o[1] + size], [o[0] + size, o[1] + size]),
        ] {
            fill(
                img,
                (x_off as f64 + px(a[0])) as i64,
                px(a[1]) as i64,
                (x_off as f64 + px(b[0])) as i64,
                px(a[1]) as i64 + 1,
                GREY,
            );
            let _ = b;
        }
        for xx in [o[0], o[0] + size] {
            fill(
                img,
                (x_off as f64 + px(xx)) as i64,
                px(o[1]) as i64,
                (x_off as f64 + px(xx)) as i64 + 1,
                px(o[1] + size) as i64,
                GREY,
            );
        }
    }
    for p in points {
        let (x, y) = (x_off as f64 + px(p[0]), px(p[1]));
        fill(
            img,
            x as i64 - 1,
            y as i64 - 1,
            x as i64 + 2,
            y as i64 + 2,
            rgb,
        );
    }
}

/// Cells of a `k x k` grid over `[o, o + size)^2` that contain at least one point.
fn cells_hit(points: &[[f64; 2]], o: [f64; 2], size: f64, k: usize) -> usize {
    let mut hit = vec![false; k * k];
    for p in points {
        let t: Vec<f64> = (0..2)
            .map(|d| (p[d] - o[d]).rem_euclid(1.0) / size)
            .collect();
        if t.iter().all(|c| (0.0..1.0).contains(c)) {
            hit[(t[1] * k as f64) as usize * k + (t[0] * k as f64) as usize] = true;
        }
    }
    hit.iter().filter(|&&h| h).count()
}

fn run_toy(out: &Path, md: &mut String) {
    let n = 128usize;
    let lattice = Rank1Lattice::new(n as u32, vec![1, 12]).expect("lattice");
    let r = 1.0 / (n as f64).sqrt();
    // Full domain: the lattice shifted by a random Cranley-Patterson vector; the chain from a
    // random start.
    let shift = [uniform(1, 0), uniform(1, 1)];
    let full_lattice: Vec<[f64; 2]> = (0..n as u32)
        .map(|j| {
            let p = lattice.point(j);
            [
                (p[0] + shift[0]).rem_euclid(1.0),
                (p[1] + shift[1]).rem_euclid(1.0),
            ]
        })
        .collect();
    let full_chain = chain([uniform(2, 0), uniform(2, 1)], r, n, 3);
    // Local: a seed, its 1/4 tile, the lattice shifted onto the seed inside the tile (Alg. 1
    // lines 3 and 7), the chain's steps scaled by the tile size.
    let (k, seed): (f64, [f64; 2]) = (4.0, [0.43, 0.61]);
    let o = [(seed[0] * k).floor() / k, (seed[1] * k).floor() / k];
    let t_seed: Vec<f64> = (0..2).map(|d| (seed[d] - o[d]) * k).collect();
    let shifted = ShiftedLattice::through(&lattice, &t_seed);
    let mut t = [0.0; 2];
    let local_lattice: Vec<[f64; 2]> = (0..n as u32)
        .map(|j| {
            shifted.member(&lattice, j, &mut t);
            [o[0] + t[0] / k, o[1] + t[1] / k]
        })
        .collect();
    let local_chain: Vec<[f64; 2]> = chain(t_seed.clone().try_into().expect("2-D"), r, n, 4)
        .into_iter()
        .map(|p| [o[0] + p[0] / k, o[1] + p[1] / k])
        .collect();
    let seed_member = shifted.seed_index();
    let err = torus_difference(local_lattice[seed_member as usize][0], seed[0]).abs();
    for (name, a, b, tile) in [
        ("toy_full.png", &full_lattice, &full_chain, None),
        (
            "toy_local.png",
            &local_lattice,
            &local_chain,
            Some((o, 1.0 / k)),
        ),
    ] {
        let mut img = Image::new(2 * PANEL, PANEL);
        fill(&mut img, 0, 0, 2 * PANEL as i64, PANEL as i64, [1.0; 3]);
        draw_panel(&mut img, 0, a, RED, tile);
        draw_panel(&mut img, PANEL, b, BLUE, tile);
        let _ = render::image_io::write_png(out.join(name), &img, 0.0);
    }
    let _ = writeln!(
        md,
        "## Toy (Fig. 2): N = {n}, rank-1 lattice g = (1, 12) vs a Markov chain with uniform steps in [-1/sqrt(N), 1/sqrt(N)]\n\n`toy_full.png` (unit torus) and `toy_local.png` (tile of side 1/4 around the seed ({}, {}); the lattice member {seed_member} is the seed, |error| {err:.1e}); lattice red (left), chain blue (right).\n",
        seed[0], seed[1]
    );
    let _ = writeln!(
        md,
        "| point set | cells of an 8x8 grid hit (of 64) |\n|---|---|"
    );
    for (label, pts, o2, size) in [
        ("lattice, full torus", &full_lattice, [0.0, 0.0], 1.0),
        ("chain, full torus", &full_chain, [0.0, 0.0], 1.0),
        ("lattice, local tile", &local_lattice, o, 1.0 / k),
        ("chain, local tile", &local_chain, o, 1.0 / k),
    ] {
        let _ = writeln!(md, "| {label} | {} |", cells_hit(pts, o2, size, 8));
    }
}

// ---- the equal-time renders ----

#[derive(Clone, Copy, Debug, PartialEq, Eq)]
enum Method {
    Qmc,
    PssmltK,
    Lqmc,
}

impl Method {
    const ALL: [Method; 3] = [Method::Qmc, Method::PssmltK, Method::Lqmc];

    fn label(self) -> &'static str {
        match self {
            Method::Qmc => "Halton QMC",
            Method::PssmltK => "PSSMLT/K (KMLT)",
            Method::Lqmc => "LQMC",
        }
    }

    fn file_stem(self) -> &'static str {
        match self {
            Method::Qmc => "qmc",
            Method::PssmltK => "pssmlt-k",
            Method::Lqmc => "lqmc",
        }
    }

    fn settings(self, size: u32, budget: Budget, seed: u64) -> RenderSettings {
        RenderSettings {
            width: size,
            height: size,
            budget,
            threads: std::thread::available_parallelism().map_or(1, |n| n.get()),
            seed,
            max_depth: 5,
            // The Halton baseline, Kelemen's PSSMLT (expected-value estimator, no raster
            // steps, no direct pass) and the paper's LQMC.
            method: match self {
                Method::Qmc => QmcSettings::default().into(),
                Method::PssmltK => PssmltSettings::kelemen2002().into(),
                Method::Lqmc => LqmcSettings::tessari2020().into(),
            },
        }
    }
}

/// One render's measurements.
struct Run {
    relmse: f64,
    mad: f64,
    mse: f64,
    samples_per_second: f64,
}

/// Mean over pixels of the variance (across `images`) of the pixel luminance.
fn temporal_variance(images: &[Image]) -> f64 {
    let (w, h) = (images[0].width, images[0].height);
    let n = images.len() as f64;
    let mut total = 0.0;
    for y in 0..h {
        for x in 0..w {
            let l: Vec<f64> = images
                .iter()
                .map(|im| f64::from(im.luminance(x, y)))
                .collect();
            let m = l.iter().sum::<f64>() / n;
            total += l.iter().map(|v| (v - m).powi(2)).sum::<f64>() / (n - 1.0);
        }
    }
    total / (w * h) as f64
}

/// Side of the blocks of [`block_variance_ratio`].
const BLOCK: usize = 8;

/// Clumping of the frame-to-frame error: the variance across `images` of the mean luminance
/// of `BLOCK x BLOCK` blocks, averaged over the blocks, times the pixels per block, divided
/// by [`temporal_variance`]. 1 if pixel errors are uncorrelated; above 1 if errors come in
/// blotches larger than a pixel (Markov chain clumping, or a lattice set splatting into its
/// image tile), the low-frequency flicker an animation shows.
fn block_variance_ratio(images: &[Image]) -> f64 {
    let (w, h) = (images[0].width / BLOCK, images[0].height / BLOCK);
    if w == 0 || h == 0 {
        return f64::NAN;
    }
    let n = images.len() as f64;
    let mut total = 0.0;
    for by in 0..h {
        for bx in 0..w {
            let means: Vec<f64> = images
                .iter()
                .map(|im| {
                    let mut s = 0.0;
                    for y in by * BLOCK..(by + 1) * BLOCK {
                        for x in bx * BLOCK..(bx + 1) * BLOCK {
                            s += f64::from(im.luminance(x, y));
                        }
                    }
                    s / (BLOCK * BLOCK) as f64
                })
                .collect();
            let m = means.iter().sum::<f64>() / n;
            total += means.iter().map(|v| (v - m).powi(2)).sum::<f64>() / (n - 1.0);
        }
    }
    total / (w * h) as f64 * (BLOCK * BLOCK) as f64 / temporal_variance(images)
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
    let budget = Budget::Time(Duration::from_secs_f64(o.time));
    let mut runs: Vec<Vec<Run>> = Method::ALL.iter().map(|_| Vec::new()).collect();
    let mut frames: Vec<Vec<Image>> = Method::ALL.iter().map(|_| Vec::new()).collect();
    let mut report_methods: Vec<MethodRun> = Method::ALL
        .iter()
        .map(|m| MethodRun {
            name: m.label().to_string(),
            ..MethodRun::default()
        })
        .collect();
    for seed in 0..o.seeds {
        for (m, method) in Method::ALL.iter().enumerate() {
            let out = render(
                &scene,
                &method.settings(size, budget, seed),
                &NoProgress,
                &AtomicBool::new(false),
            )
            .expect("render");
            let run = Run {
                relmse: render::metrics::relmse(&out.image, &reference).unwrap_or(f64::NAN),
                mad: render::metrics::mad(&out.image, &reference).unwrap_or(f64::NAN),
                mse: render::metrics::mse(&out.image, &reference).unwrap_or(f64::NAN),
                samples_per_second: out.samples as f64 / out.elapsed.as_secs_f64(),
            };
            eprintln!(
                "{name} seed {seed} {}: relMSE {:.4}, MAD {:.4}, {:.0} samples/s",
                method.label(),
                run.relmse,
                run.mad,
                run.samples_per_second
            );
            let file = format!("{}_seed{seed}.exr", method.file_stem());
            if render::image_io::write_exr(dir.join(&file), &out.image).is_ok() {
                report_methods[m].images.push(SeedImage {
                    seed,
                    path: file.into(),
                });
                report_methods[m].convergence.push(ConvergenceSeries {
                    seed,
                    points: vec![ConvergencePoint {
                        time_s: out.elapsed.as_secs_f64(),
                        relmse: run.relmse,
                    }],
                });
            }
            if seed == 0 {
                let stem = dir.join(method.file_stem());
                let _ = render::image_io::write_exr(stem.with_extension("exr"), &out.image);
                let _ = render::image_io::write_png(stem.with_extension("png"), &out.image, 0.0);
                if *method == Method::Lqmc {
                    if let Some(note) = out.notes.iter().find(|n| n.starts_with("lqmc:")) {
                        let _ = writeln!(md, "\n{name}, LQMC seed 0: {note}.");
                    }
                }
            }
            runs[m].push(run);
            frames[m].push(out.image);
        }
    }
    let _ = render::image_io::write_png(dir.join("reference.png"), &reference, 0.0);
    let manifest = RunManifest {
        title: format!("lqmc: {name}"),
        commit: current_commit("."),
        parameters: [
            ("scene", name.to_string()),
            ("size", format!("{size}x{size}")),
            ("time per render [s]", o.time.to_string()),
            ("seeds", o.seeds.to_string()),
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
        "| method | relMSE median [min, max] | MAD median [min, max] | mean MSE | temporal variance (mean per-pixel) | variance / mean MSE | 8x8-block variance ratio | samples/s (median) |"
    );
    let _ = writeln!(md, "|---|---|---|---|---|---|---|---|");
    for ((method, rs), fs) in Method::ALL.iter().zip(&runs).zip(&frames) {
        let col = |f: fn(&Run) -> f64| summary(&rs.iter().map(f).collect::<Vec<_>>());
        let (e, e0, e1) = col(|r| r.relmse);
        let (d, d0, d1) = col(|r| r.mad);
        let mse = rs.iter().map(|r| r.mse).sum::<f64>() / rs.len() as f64;
        let var = temporal_variance(fs);
        let clump = block_variance_ratio(fs);
        let rate = col(|r| r.samples_per_second).0;
        let _ = writeln!(
            md,
            "| {} | {e:.4} [{e0:.4}, {e1:.4}] | {d:.4} [{d0:.4}, {d1:.4}] | {mse:.3e} | {var:.3e} | {:.2} | {clump:.2} | {rate:.0} |",
            method.label(),
            var / mse
        );
        for (seed, r) in rs.iter().enumerate() {
            let _ = writeln!(
                csv,
                "{name},{},{seed},{},{},{},{}",
                method.label(),
                r.relmse,
                r.mad,
                r.mse,
                r.samples_per_second
            );
        }
    }
}

fn main() {
    let o = parse_options();
    let load_before = load_average();
    let _ = std::fs::create_dir_all(&o.out);
    let mut md = String::from("# LQMC example results\n\n");
    let mut csv = String::from("scene,method,seed,relmse,mad,mse,samples_per_second\n");
    if o.toy {
        run_toy(&o.out, &mut md);
    }
    if o.scenes {
        let _ = writeln!(
            md,
            "\n## Equal time: {} s per render, {}x{}, seeds 0..{}, {} threads, max depth 5\n\nHalton QMC (`qmc`), PSSMLT/K (`pssmlt`: Kelemen small step, large steps 0.3, 100 000 bootstrap samples inside the budget) and LQMC (`lqmc`, paper parameters). relMSE and MAD against the BDPT reference (box-downsampled from 256x256), median [min, max] over the seeds; temporal variance: per-pixel luminance variance across the seeds' renders, averaged over the pixels; 8x8-block variance ratio: the variance across seeds of 8x8-block means times 64, over the per-pixel variance (1 for uncorrelated pixel noise, larger for blotchy, low-frequency flicker); samples/s: pixel samples (seed paths for LQMC, mutations for PSSMLT) per second.",
            o.time,
            o.size,
            o.size,
            o.seeds,
            std::thread::available_parallelism().map_or(1, |n| n.get())
        );
        let names = o.names.clone();
        for name in &names {
            run_scene(&o, name, &mut md, &mut csv);
        }
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
