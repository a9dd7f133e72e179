//! Kernels compared on a toy target with a known density: chains from exact starts, their
//! acceptance per stage, the integrated autocorrelation time of the first coordinate, and
//! trace and histogram panels (the delayed-rejection paper's Fig. 3 is one such study).

use mcmc_core::seed::chain_seed;
use mcmc_core::stats::{integrated_autocorrelation_time, AcceptanceStats};
use mcmc_core::toy::ToyTarget;
use mcmc_core::{Chain, Kernel, NoAdaptation};
use rand::SeedableRng;
use rand_pcg::Pcg64;
use render::image::Image;

use crate::table::Table;
use crate::ExperimentError;

/// Steps of chain 0 drawn in the trace panel.
const TRACE_STEPS: usize = 2_000;
/// States of chain 0 in the histogram panel.
const HISTOGRAM_STATES: usize = 5_000;
/// Panel size in pixels.
const PANEL_W: usize = 600;
const PANEL_H: usize = 160;
/// One colour per kernel, cycled.
const COLOURS: [[f32; 3]; 5] = [
    [0.8, 0.1, 0.1],
    [0.1, 0.3, 0.9],
    [0.1, 0.6, 0.1],
    [0.8, 0.5, 0.0],
    [0.5, 0.1, 0.6],
];
const COLOUR_NAMES: [&str; 5] = ["red", "blue", "green", "orange", "purple"];
const GREY: [f32; 3] = [0.6, 0.6, 0.6];

/// One kernel's chains: chain 0's first coordinate over its first steps, the IAT of the first
/// coordinate per chain, and the acceptance counts pooled over chains.
#[derive(Clone, Debug, PartialEq)]
pub struct ToyRun {
    /// The kernel's name.
    pub name: String,
    /// Chain 0's first coordinate over its first 5000 steps (the trace panel draws 2000).
    pub trace: Vec<f64>,
    /// The integrated autocorrelation time of the first coordinate, per chain.
    pub iat: Vec<f64>,
    /// Acceptance counts pooled over the chains.
    pub stats: AcceptanceStats,
}

impl ToyRun {
    /// The mean IAT over chains and its standard error.
    #[must_use]
    pub fn iat_mean_se(&self) -> (f64, f64) {
        let n = self.iat.len() as f64;
        let mean = self.iat.iter().sum::<f64>() / n;
        let var = self.iat.iter().map(|t| (t - mean).powi(2)).sum::<f64>() / (n - 1.0);
        (mean, (var / n).sqrt())
    }

    /// Target evaluations per step: candidates tried at any stage over steps.
    #[must_use]
    pub fn evaluations_per_step(&self) -> f64 {
        let tried: u64 = self.stats.stage_tried.iter().sum();
        tried as f64 / self.stats.steps.max(1) as f64
    }
}

/// A study of several kernels on one toy target: every kernel runs `chains` chains of
/// `steps` steps, each started from an exact draw of the target (so there is no burn-in) and
/// seeded from (the kernel's seed, the chain's index).
///
/// # Example
/// ```
/// use experiments::ToyStudy;
/// use mcmc_core::toy::UniformMixture;
/// use mcmc_core::{GaussianRandomWalk, Mh};
///
/// let walk = |s| Mh::new(GaussianRandomWalk::new(s).unwrap());
/// let study = ToyStudy::new(UniformMixture::rioux_lavoie2020(), 2, 1_000)
///     .kernel("MH, sigma 1", &walk(1.0), 1)?
///     .kernel("MH, sigma 0.1", &walk(0.1), 2)?;
/// let small = &study.runs()[1];
/// assert!(small.stats.acceptance_rate() > study.runs()[0].stats.acceptance_rate());
/// assert_eq!(study.table().rows().len(), 2);
/// assert_eq!(study.trace_image().height, 2 * 160);
/// # Ok::<(), experiments::ExperimentError>(())
/// ```
#[derive(Clone, Debug)]
pub struct ToyStudy<T> {
    target: T,
    chains: u64,
    steps: usize,
    runs: Vec<ToyRun>,
}

impl<T: ToyTarget> ToyStudy<T> {
    /// A study of `chains` chains of `steps` steps per kernel on `target`.
    #[must_use]
    pub fn new(target: T, chains: u64, steps: usize) -> Self {
        Self {
            target,
            chains,
            steps,
            runs: Vec::new(),
        }
    }

    /// Runs `kernel` (cloned per chain) under `name` with chain seeds from `seed`.
    ///
    /// # Errors
    /// [`ExperimentError::Invalid`] naming the kernel if a chain cannot start or step (an
    /// exact start of zero density, a kernel error).
    pub fn kernel<K: Kernel<T> + Clone>(
        mut self,
        name: impl Into<String>,
        kernel: &K,
        seed: u64,
    ) -> Result<Self, ExperimentError> {
        let name = name.into();
        let fail = |e: mcmc_core::McmcError| ExperimentError::Invalid(format!("{name}: {e}"));
        let mut run = ToyRun {
            name: name.clone(),
            trace: Vec::new(),
            iat: Vec::new(),
            stats: AcceptanceStats::default(),
        };
        for i in 0..self.chains {
            let mut rng = Pcg64::seed_from_u64(chain_seed(seed, i));
            let x0 = self.target.sample_exact(&mut rng);
            let mut chain =
                Chain::new(&self.target, kernel.clone(), NoAdaptation, rng, x0).map_err(fail)?;
            let mut xs = Vec::with_capacity(self.steps);
            for _ in 0..self.steps {
                chain.step(&mut ()).map_err(fail)?;
                xs.push(chain.state()[0]);
            }
            run.iat.push(integrated_autocorrelation_time(&xs));
            if i == 0 {
                xs.truncate(HISTOGRAM_STATES);
                run.trace = xs;
            }
            run.stats.merge(chain.stats());
        }
        self.runs.push(run);
        Ok(self)
    }

    /// The runs, in the order the kernels were added.
    #[must_use]
    pub fn runs(&self) -> &[ToyRun] {
        &self.runs
    }

    /// One row per kernel: acceptance, the stage-2 share of accepted moves, the IAT of the
    /// first coordinate (mean +- standard error over chains) and target evaluations per step.
    #[must_use]
    pub fn table(&self) -> Table {
        let mut t = Table::new([
            "kernel",
            "acceptance",
            "stage-2 share of accepted moves",
            "IAT(x) mean +- se",
            "target evaluations per step",
        ]);
        for r in &self.runs {
            let (mean, se) = r.iat_mean_se();
            t.push_row([
                r.name.clone(),
                format!("{:.3}", r.stats.acceptance_rate()),
                format!("{:.3}", r.stats.second_stage_share()),
                format!("{mean:.1} +- {se:.1}"),
                format!("{:.2}", r.evaluations_per_step()),
            ]);
        }
        t
    }

    /// Writes the panels as `<dir>/<prefix>_trace.png` and `<dir>/<prefix>_hist.png` (the
    /// histogram with `bins` bins) and returns the study's markdown: a `## title` heading,
    /// [`ToyStudy::table`] and a caption naming each kernel's colour and the files.
    ///
    /// # Errors
    /// [`ExperimentError::Image`] naming a file that cannot be written.
    pub fn write(
        &self,
        dir: &std::path::Path,
        prefix: &str,
        title: &str,
        bins: usize,
    ) -> Result<String, ExperimentError> {
        let (trace, hist) = (format!("{prefix}_trace.png"), format!("{prefix}_hist.png"));
        render::image_io::write_png(dir.join(&trace), &self.trace_image(), 0.0)?;
        render::image_io::write_png(dir.join(&hist), &self.histogram_image(bins), 0.0)?;
        let kernels: Vec<String> = (self.runs.iter().enumerate())
            .map(|(i, r)| format!("{} ({})", r.name, COLOUR_NAMES[i % COLOUR_NAMES.len()]))
            .collect();
        let (lo, hi) = self.range();
        let (chains, steps) = (self.chains, self.steps);
        let states = steps.min(HISTOGRAM_STATES);
        Ok(format!(
            "\n## {title}\n\n{} chains x {steps} steps per kernel, from exact starts.\n\n{}\nPanels top to bottom: {}. `{trace}`: x (the first coordinate) over the first {} steps of chain 0 (grey: x = 0). `{hist}`: histogram of the first {states} states of chain 0 on [{lo}, {hi}]{}.\n",
            chains,
            self.table().to_markdown(),
            kernels.join(", "),
            steps.min(TRACE_STEPS),
            if self.target.dim() == 1 { " with the exact density in grey" } else { "" },
        ))
    }

    /// The range of the first coordinate the panels show: the target's bounding box.
    fn range(&self) -> (f64, f64) {
        let (lo, hi) = self.target.bounding_box();
        (lo[0], hi[0])
    }

    /// Trace panels, one per kernel from top to bottom: chain 0's first coordinate over its
    /// first 2000 steps, with a grey line at 0 when 0 is inside the range.
    #[must_use]
    pub fn trace_image(&self) -> Image {
        let (lo, hi) = self.range();
        let mut img = blank(PANEL_W, PANEL_H * self.runs.len());
        for (p, r) in self.runs.iter().enumerate() {
            let row = |x: f64| {
                let t = (x - lo) / (hi - lo);
                (p * PANEL_H) as f64 + 5.0 + (1.0 - t) * (PANEL_H - 10) as f64
            };
            if lo < 0.0 && hi > 0.0 {
                line(&mut img, (0.0, row(0.0)), (PANEL_W as f64, row(0.0)), GREY);
            }
            let y0 = (p * PANEL_H) as i64;
            fill(&mut img, 0, y0, PANEL_W as i64, y0 + 1, [0.0; 3]);
            let trace = &r.trace[..r.trace.len().min(TRACE_STEPS)];
            let sx = PANEL_W as f64 / trace.len().max(1) as f64;
            for (i, w) in trace.windows(2).enumerate() {
                let (a, b) = ((i as f64 * sx, row(w[0])), ((i + 1) as f64 * sx, row(w[1])));
                line(&mut img, a, b, COLOURS[p % COLOURS.len()]);
            }
        }
        img
    }

    /// Histogram panels, one per kernel: chain 0's first 5000 states of the first coordinate
    /// in `bins` bins over the range, with the exact density in grey for a 1-D target.
    #[must_use]
    pub fn histogram_image(&self, bins: usize) -> Image {
        let (lo, hi) = self.range();
        let bins = bins.max(1);
        let bar = (PANEL_W / bins).max(1);
        let width = (hi - lo) / bins as f64;
        let exact: Vec<f64> = (0..bins)
            .map(|b| match self.target.dim() {
                1 => self
                    .target
                    .log_density(&[lo + (b as f64 + 0.5) * width])
                    .exp(),
                _ => f64::NAN,
            })
            .collect();
        let mut img = blank(bar * bins, PANEL_H * self.runs.len());
        for (p, r) in self.runs.iter().enumerate() {
            let mut density = vec![0.0; bins];
            for &x in &r.trace {
                let b = ((x - lo) / width).floor();
                if (0.0..bins as f64).contains(&b) {
                    density[b as usize] += 1.0 / (r.trace.len() as f64 * width);
                }
            }
            let top = exact.iter().chain(&density).fold(0.0f64, |m, &d| m.max(d));
            let base = ((p + 1) * PANEL_H) as f64 - 2.0;
            let to_px = |d: f64| base - d / (1.25 * top) * (PANEL_H - 8) as f64;
            for b in 0..bins {
                let x0 = (b * bar) as i64;
                let y = (to_px(density[b]) as i64).max((p * PANEL_H) as i64 + 2);
                let colour = COLOURS[p % COLOURS.len()];
                fill(&mut img, x0, y, x0 + bar as i64 - 1, base as i64, colour);
                if exact[b].is_finite() {
                    let y = to_px(exact[b]) as i64;
                    fill(&mut img, x0, y, x0 + bar as i64, y + 2, GREY);
                }
            }
            let y0 = (p * PANEL_H) as i64;
            fill(&mut img, 0, y0, (bar * bins) as i64, y0 + 1, [0.0; 3]);
        }
        img
    }
}

/// A white image.
fn blank(w: usize, h: usize) -> Image {
    let mut img = Image::new(w, h);
    fill(&mut img, 0, 0, w as i64, h as i64, [1.0; 3]);
    img
}

/// Fills the rectangle `[x0, x1) x [y0, y1)` (pixels, clipped).
fn fill(img: &mut Image, x0: i64, y0: i64, x1: i64, y1: i64, rgb: [f32; 3]) {
    let (w, h) = (img.width as i64, img.height as i64);
    for y in y0.max(0)..y1.min(h) {
        for x in x0.max(0)..x1.min(w) {
            img.set(x as usize, y as usize, rgb);
        }
    }
}

/// A one-pixel line from `a` to `b` by dense sampling.
fn line(img: &mut Image, a: (f64, f64), b: (f64, f64), rgb: [f32; 3]) {
    let n = ((b.0 - a.0).abs().max((b.1 - a.1).abs()).ceil() as usize).max(1);
    for i in 0..=n {
        let t = i as f64 / n as f64;
        let (x, y) = (a.0 + t * (b.0 - a.0), a.1 + t * (b.1 - a.1));
        fill(img, x as i64, y as i64, x as i64 + 1, y as i64 + 1, rgb);
    }
}

#[cfg(test)]
mod tests {
    use mcmc_core::delayed_rejection::IndependentSecondStage;
    use mcmc_core::toy::UniformMixture;
    use mcmc_core::{DelayedRejection, GaussianRandomWalk, Mh};

    use super::*;

    fn grw(sigma: f64) -> GaussianRandomWalk {
        GaussianRandomWalk::new(sigma).unwrap()
    }

    fn study() -> ToyStudy<UniformMixture> {
        let dr = DelayedRejection::tierney_mira(grw(1.0), IndependentSecondStage(grw(0.1)))
            .with_symmetric_second_stage();
        ToyStudy::new(UniformMixture::rioux_lavoie2020(), 4, 4_000)
            .kernel("MH 1", &Mh::new(grw(1.0)), 81)
            .unwrap()
            .kernel("DR", &dr, 83)
            .unwrap()
    }

    #[test]
    fn delayed_rejection_tries_a_second_stage_and_mh_does_not() {
        let s = study();
        let (mh, dr) = (&s.runs()[0], &s.runs()[1]);
        assert_eq!(mh.stats.steps, 4 * 4_000);
        assert_eq!(
            mh.evaluations_per_step(),
            1.0,
            "negative control: one stage"
        );
        assert_eq!(mh.stats.second_stage_share(), 0.0);
        assert!(dr.evaluations_per_step() > 1.2 && dr.evaluations_per_step() < 2.0);
        assert!(dr.stats.second_stage_share() > 0.0);
        assert!(dr.stats.acceptance_rate() > mh.stats.acceptance_rate());
        assert_eq!(
            (mh.iat.len(), mh.trace.len()),
            (4, HISTOGRAM_STATES.min(4_000))
        );
        let (mean, se) = mh.iat_mean_se();
        assert!(mean >= 1.0 && se.is_finite());
        let table = s.table();
        assert_eq!(table.rows()[1][0], "DR");
        assert!(table.rows()[1][3].contains(" +- "));
    }

    #[test]
    fn seeded_runs_repeat_and_states_stay_in_the_support() {
        let (a, b) = (study(), study());
        assert_eq!(a.runs(), b.runs());
        assert!(a.runs()[0].trace.iter().all(|x| (-0.1..1.0).contains(x)));
        let other = ToyStudy::new(UniformMixture::rioux_lavoie2020(), 4, 4_000)
            .kernel("MH 1", &Mh::new(grw(1.0)), 82)
            .unwrap();
        assert_ne!(other.runs()[0].trace, a.runs()[0].trace, "another seed");
    }

    #[test]
    fn panels_have_one_band_per_kernel_and_draw_in_it() {
        let s = study();
        let trace = s.trace_image();
        assert_eq!((trace.width, trace.height), (PANEL_W, 2 * PANEL_H));
        let hist = s.histogram_image(110);
        assert_eq!((hist.width, hist.height), (550, 2 * PANEL_H));
        // The second band holds the second kernel's colour and the first does not.
        let has = |img: &Image, band: usize, rgb: [f32; 3]| {
            (band * PANEL_H..(band + 1) * PANEL_H)
                .any(|y| (0..img.width).any(|x| img.get(x, y) == rgb))
        };
        assert!(has(&trace, 1, COLOURS[1]) && !has(&trace, 0, COLOURS[1]));
        assert!(has(&hist, 0, GREY), "the exact density");
    }

    #[test]
    fn write_saves_both_panels_and_captions_them() {
        let dir = std::env::temp_dir().join(format!("experiments-toy-{}", std::process::id()));
        std::fs::create_dir_all(&dir).unwrap();
        let md = study().write(&dir, "toy", "Toy", 110).unwrap();
        assert!(dir.join("toy_trace.png").is_file() && dir.join("toy_hist.png").is_file());
        assert!(md.starts_with("\n## Toy\n\n4 chains x 4000 steps"), "{md}");
        assert!(
            md.contains("MH 1 (red), DR (blue)") && md.contains("on [-0.1, 1]"),
            "{md}"
        );
        assert!(md.contains("| DR |"), "{md}");
        // Negative control: an unwritable directory is an error naming the file.
        let e = study()
            .write(&dir.join("missing/deeper"), "toy", "Toy", 10)
            .unwrap_err();
        assert!(e.to_string().contains("toy_trace.png"), "{e}");
        std::fs::remove_dir_all(&dir).ok();
    }
}
