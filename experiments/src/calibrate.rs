//! Matching a parameter to a target value by bisection, e.g. a proposal's scale to the
//! acceptance rate another kernel reaches, and the acceptance of a render on a fixed budget.
//!
//! The delayed-rejection paper compares its kernels with a Gaussian random walk "of the same
//! acceptance"; [`Bisection`] finds that step size for any monotone measurement, and
//! [`acceptance`] is the measurement for a render (on a sample budget, so it does not depend
//! on the machine's load).

use std::sync::atomic::AtomicBool;

use render::methods::MethodSettings;
use render::session::{render, NoProgress, RenderSettings};
use render::Scene;

use crate::scene::SceneCase;
use crate::stats::run_stats;
use crate::table::Table;
use crate::ExperimentError;

/// Bisection of a monotone measurement `f(parameter)` on `[lo, hi]`, in the parameter or in
/// its logarithm.
///
/// Each of the `steps` measurements halves the bracket; the answer is the measured point
/// closest to the target (not the last midpoint), so a noisy measurement cannot make it
/// worse than one already seen. A target beyond the range ends at the nearer end.
///
/// # Example
/// The step size whose "acceptance" `1 / (1 + s)` is 0.25:
/// ```
/// use experiments::Bisection;
///
/// let fit = Bisection::log(1e-3, 100.0, 30).solve(0.25, |s| Ok::<_, ()>(1.0 / (1.0 + s)))?;
/// assert!((fit.value - 3.0).abs() < 1e-6 && (fit.achieved - 0.25).abs() < 1e-6);
/// assert_eq!(fit.measurements, 30);
/// # Ok::<(), ()>(())
/// ```
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Bisection {
    /// The lower end of the range.
    pub lo: f64,
    /// The upper end of the range.
    pub hi: f64,
    /// Measurements to make (each halves the bracket).
    pub steps: u32,
    /// Bisect the logarithm of the parameter (for scales spanning decades; `lo > 0`).
    pub log: bool,
    /// The measurement decreases as the parameter grows (acceptance against step size);
    /// `false` for an increasing one.
    pub decreasing: bool,
}

/// What a [`Bisection`] found.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Calibrated {
    /// The parameter.
    pub value: f64,
    /// The measurement at `value`.
    pub achieved: f64,
    /// The value sought.
    pub target: f64,
    /// Measurements made.
    pub measurements: u32,
}

impl Bisection {
    /// `steps` bisections of `log(parameter)` on `[lo, hi]` for a measurement decreasing in
    /// the parameter (an acceptance rate against a step size).
    #[must_use]
    pub const fn log(lo: f64, hi: f64, steps: u32) -> Self {
        Self {
            lo,
            hi,
            steps,
            log: true,
            decreasing: true,
        }
    }

    /// `steps` bisections of the parameter on `[lo, hi]` for a measurement increasing in it.
    #[must_use]
    pub const fn linear(lo: f64, hi: f64, steps: u32) -> Self {
        Self {
            lo,
            hi,
            steps,
            log: false,
            decreasing: false,
        }
    }

    /// The parameter whose measurement `f` comes closest to `target`.
    ///
    /// A range with `lo >= hi`, a non-finite end, a non-positive `lo` in log mode, or zero
    /// steps measures nothing: `value` is NaN and `measurements` 0.
    ///
    /// # Errors
    /// The first error of `f`.
    pub fn solve<E>(
        &self,
        target: f64,
        mut f: impl FnMut(f64) -> Result<f64, E>,
    ) -> Result<Calibrated, E> {
        let mut found = Calibrated {
            value: f64::NAN,
            achieved: f64::NAN,
            target,
            measurements: 0,
        };
        let valid = self.lo < self.hi
            && self.lo.is_finite()
            && self.hi.is_finite()
            && (!self.log || self.lo > 0.0);
        if !valid {
            return Ok(found);
        }
        let log = self.log;
        let from = |t: f64| if log { t.exp() } else { t };
        let (mut lo, mut hi) = if log {
            (self.lo.ln(), self.hi.ln())
        } else {
            (self.lo, self.hi)
        };
        for _ in 0..self.steps {
            let mid = 0.5 * (lo + hi);
            let value = from(mid);
            let achieved = f(value)?;
            found.measurements += 1;
            if found.value.is_nan() || (achieved - target).abs() < (found.achieved - target).abs() {
                (found.value, found.achieved) = (value, achieved);
            }
            // Too high a measurement: move towards the parameters that lower it.
            if (achieved > target) == self.decreasing {
                lo = mid;
            } else {
                hi = mid;
            }
        }
        Ok(found)
    }
}

/// The overall acceptance rate of one render of `scene` with `settings` (use a sample budget
/// for a load-independent measurement); NaN for a method without chains.
///
/// # Errors
/// [`ExperimentError::Render`] naming the scene (`scene_name`) and the method's integrator.
pub fn acceptance(
    scene_name: &str,
    scene: &Scene,
    settings: &RenderSettings,
) -> Result<f64, ExperimentError> {
    let out = render(scene, settings, &NoProgress, &AtomicBool::new(false)).map_err(|source| {
        ExperimentError::Render {
            scene: scene_name.to_owned(),
            method: settings.integrator().name().to_owned(),
            seed: settings.seed,
            source,
        }
    })?;
    Ok(run_stats(&out).acceptance.unwrap_or(f64::NAN))
}

/// Per-scene results of [`match_acceptance`], in the order of the scenes.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct Calibrations(pub Vec<(String, Calibrated)>);

impl Calibrations {
    /// The parameter found for `scene` (NaN for a scene not calibrated).
    #[must_use]
    pub fn value(&self, scene: &str) -> f64 {
        self.0
            .iter()
            .find(|(s, _)| s == scene)
            .map_or(f64::NAN, |(_, c)| c.value)
    }

    /// One row per scene: the target acceptance, the `parameter` found and the acceptance it
    /// reached.
    #[must_use]
    pub fn table(&self, parameter: &str) -> Table {
        let mut t = Table::new([
            "scene".to_owned(),
            "target acceptance".to_owned(),
            parameter.to_owned(),
            "its acceptance".to_owned(),
        ]);
        for (scene, c) in &self.0 {
            t.push_row([
                scene.clone(),
                format!("{:.3}", c.target),
                format!("{:.5}", c.value),
                format!("{:.3}", c.achieved),
            ]);
        }
        t
    }
}

/// Per scene, the parameter of `family` whose acceptance matches `reference`'s: both
/// rendered with `probe` (its budget, seed, threads and depth; the size is the scene's, the
/// method replaced), the parameter found by `bisection`; [`Calibrated::target`] is the
/// reference's acceptance.
///
/// # Errors
/// [`ExperimentError::Render`] naming the scene of a failed render.
pub fn match_acceptance(
    cases: &[SceneCase],
    probe: &RenderSettings,
    reference: MethodSettings,
    family: impl Fn(f64) -> MethodSettings,
    bisection: Bisection,
) -> Result<Calibrations, ExperimentError> {
    let fits = cases
        .iter()
        .map(|case| {
            let rate = |method: MethodSettings| {
                let settings = RenderSettings {
                    width: case.reference.width as u32,
                    height: case.reference.height as u32,
                    method,
                    ..probe.clone()
                };
                acceptance(&case.name, &case.scene, &settings)
            };
            let target = rate(reference)?;
            let fit = bisection.solve(target, |p| rate(family(p)))?;
            Ok((case.name.clone(), fit))
        })
        .collect::<Result<_, ExperimentError>>()?;
    Ok(Calibrations(fits))
}

/// A small PSSMLT for the calibration tests: Kelemen's small step (`sigma = 0`) or a
/// Gaussian of `sigma`, with `chains` chains and `bootstrap` bootstrap samples.
#[cfg(test)]
pub(crate) fn small_pssmlt(sigma: f64, chains: usize, bootstrap: usize) -> MethodSettings {
    let mut s = render::methods::PssmltSettings::kelemen2002();
    s.chain.chains = chains;
    s.chain.bootstrap_samples = bootstrap;
    if sigma > 0.0 {
        s.chain.small_step = pss::SmallMutation::Gaussian { sigma };
    }
    MethodSettings::from(s)
}

#[cfg(test)]
mod tests {
    use render::methods::{MethodSettings, PssmltSettings};
    use render::session::{Budget, IntegratorKind};

    use super::*;

    #[test]
    fn decreasing_and_increasing_measurements() {
        let down = |s: f64| Ok::<_, ()>(1.0 / (1.0 + s));
        let fit = Bisection::log(1e-4, 1e4, 40).solve(0.2, down).unwrap();
        assert!((fit.value - 4.0).abs() < 1e-6, "{fit:?}");
        let up = |x: f64| Ok::<_, ()>(x * x);
        let fit = Bisection::linear(0.0, 3.0, 40).solve(2.0, up).unwrap();
        assert!((fit.value - 2f64.sqrt()).abs() < 1e-9, "{fit:?}");
        // Negative control: the wrong direction walks away from the answer to an end.
        let wrong = Bisection {
            decreasing: true,
            ..Bisection::linear(0.0, 3.0, 40)
        };
        let fit = wrong.solve(2.0, up).unwrap();
        assert!((fit.achieved - 2.0).abs() > 0.2, "{fit:?}");
    }

    #[test]
    fn the_best_measured_point_wins_and_targets_beyond_the_range_clamp() {
        // The last midpoint is not the best one for a step function.
        let step = |s: f64| Ok::<_, ()>(if s < 1.0 { 0.9 } else { 0.1 });
        let fit = Bisection::log(0.01, 100.0, 6).solve(0.85, step).unwrap();
        assert_eq!(fit.achieved, 0.9);
        let fit = Bisection::log(1.0, 2.0, 20)
            .solve(1.5, |s: f64| Ok::<_, ()>(1.0 / s))
            .unwrap();
        assert!((fit.value - 1.0).abs() < 1e-5 && fit.measurements == 20);
    }

    #[test]
    fn degenerate_ranges_measure_nothing_and_errors_pass_through() {
        let count = std::cell::Cell::new(0);
        let f = |_| {
            count.set(count.get() + 1);
            Ok::<_, ()>(0.5)
        };
        for b in [
            Bisection::log(0.0, 1.0, 5),
            Bisection::log(2.0, 1.0, 5),
            Bisection::linear(0.0, f64::INFINITY, 5),
        ] {
            let fit = b.solve(0.5, f).unwrap();
            assert!(fit.value.is_nan() && fit.measurements == 0, "{b:?}");
        }
        assert_eq!(count.get(), 0);
        let e = Bisection::linear(0.0, 1.0, 5).solve(0.5, |_| Err::<f64, _>("boom"));
        assert_eq!(e, Err("boom"));
    }

    #[test]
    fn a_gaussian_step_matched_to_kelemens_acceptance() {
        let case = SceneCase::cornell_box(8, 4).unwrap();
        let probe = RenderSettings {
            budget: Budget::SamplesPerPixel(4),
            threads: 2,
            ..RenderSettings::default()
        };
        let pss = |sigma: f64| small_pssmlt(sigma, 16, 1000);
        let found =
            match_acceptance(&[case], &probe, pss(0.0), pss, Bisection::log(1e-4, 0.5, 8)).unwrap();
        let (scene, fit) = &found.0[0];
        assert_eq!(scene, "cornell-box");
        assert_eq!(found.value("cornell-box"), fit.value);
        assert!(found.value("elsewhere").is_nan());
        assert_eq!(fit.measurements, 8);
        assert!((fit.achieved - fit.target).abs() < 0.1, "{fit:?}");
        // Negative control: the range's ends are far from the target.
        let end = |sigma| {
            let case = SceneCase::cornell_box(8, 4).unwrap();
            let settings = RenderSettings {
                width: 8,
                height: 8,
                method: pss(sigma),
                ..probe.clone()
            };
            acceptance("c", &case.scene, &settings).unwrap()
        };
        assert!((end(0.5) - fit.target).abs() > 0.1);
        let t = found.table("sigma");
        assert_eq!(t.headers()[2], "sigma");
        assert_eq!(t.rows()[0][2], format!("{:.5}", fit.value));
    }

    #[test]
    fn acceptance_of_a_chain_render_and_of_a_method_without_chains() {
        let scene = Scene::cornell_box(8, 8);
        let settings = |method| RenderSettings {
            width: 8,
            height: 8,
            budget: Budget::SamplesPerPixel(4),
            method,
            ..RenderSettings::default()
        };
        let pss =
            settings(MethodSettings::from(PssmltSettings::kelemen2002()).with_chains(16, 1000));
        let a = acceptance("cornell", &scene, &pss).unwrap();
        assert!(a > 0.0 && a < 1.0, "{a}");
        assert_eq!(acceptance("cornell", &scene, &pss).unwrap(), a, "seeded");
        let pt = settings(IntegratorKind::Pt.settings());
        assert!(acceptance("cornell", &scene, &pt).unwrap().is_nan());
    }
}
