//! Per-run statistics of the MCMC methods (normalisation, acceptance, the large-step estimate)
//! and [`run_stats`], the one function that extracts them from a render's output.

use render::session::RenderOutput;

/// What one MCMC render reports about itself; every field is `None` where the method does not
/// report it (PT, BDPT, QMC have none).
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct RunStats {
    /// The normalisation `b` (mean image luminance) from the bootstrap.
    pub b: Option<f64>,
    /// The standard error of `b`.
    pub b_standard_error: Option<f64>,
    /// The overall acceptance rate of the chains' mutations.
    pub acceptance: Option<f64>,
    /// Mutations the chains made.
    pub mutations: Option<u64>,
    /// Automatic large-step control's estimate (Zsolnai & Szirmay-Kalos 2013), when it ran.
    pub large_step: Option<LargeStepStats>,
}

/// The estimate of automatic large-step control (Zsolnai & Szirmay-Kalos 2013, eq. 4-6).
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct LargeStepStats {
    /// Acceptance rate of small steps.
    pub eta_s: f64,
    /// Acceptance rate of large steps.
    pub eta_l: f64,
    /// Acceptance rate of large steps from the chains' stationary states, `eta_0`.
    pub eta_0: f64,
    /// The large-step probability the control chose, `p_l`.
    pub p_large: f64,
}

/// The statistics of one render.
///
/// **This is the one place that knows how a render reports its statistics.** It reads them
/// from [`RenderOutput::notes`], the human-readable lines the MCMC integrators write
/// (`bootstrap: b = ... (standard error ...)`, `acceptance rate ... over ... mutations`,
/// `automatic large-step control: eta_s = ..., eta_l = ..., eta_0 = ... -> p_large = ...`),
/// as the paper examples used to. When `RenderOutput` carries typed run statistics, switch
/// this function's body to them; the harness, the tables and the CSV files only see
/// [`RunStats`].
///
/// # Example
/// ```
/// use std::sync::atomic::AtomicBool;
///
/// use experiments::run_stats;
/// use render::session::{render, Budget, IntegratorKind, NoProgress, RenderSettings};
/// use render::Scene;
///
/// let settings = RenderSettings {
///     width: 8,
///     height: 8,
///     integrator: IntegratorKind::Pssmlt,
///     budget: Budget::SamplesPerPixel(2),
///     ..RenderSettings::default()
/// };
/// let out = render(&Scene::cornell_box(8, 8), &settings, &NoProgress, &AtomicBool::new(false))?;
/// let stats = run_stats(&out);
/// assert!(stats.b.is_some_and(|b| b > 0.0));
/// assert!(stats.acceptance.is_some_and(|a| (0.0..=1.0).contains(&a)));
/// # Ok::<(), render::RenderError>(())
/// ```
#[must_use]
pub fn run_stats(output: &RenderOutput) -> RunStats {
    let mut stats = RunStats::default();
    for note in &output.notes {
        if let Some(rest) = note.strip_prefix("bootstrap:") {
            stats.b = number_after(rest, "b =");
            stats.b_standard_error = number_after(rest, "standard error");
        } else if let Some(rest) = note.strip_prefix("acceptance rate") {
            stats.acceptance = number_after(rest, "");
            stats.mutations = number_after(rest, "over").map(|m| m as u64);
        } else if let Some(rest) = note.strip_prefix("automatic large-step control:") {
            let eta = |key| number_after(rest, key);
            if let (Some(eta_s), Some(eta_l), Some(eta_0), Some(p_large)) =
                (eta("eta_s"), eta("eta_l"), eta("eta_0"), eta("p_large"))
            {
                stats.large_step = Some(LargeStepStats {
                    eta_s,
                    eta_l,
                    eta_0,
                    p_large,
                });
            }
        }
    }
    stats
}

/// The number right after the first `key` in `text` (skipping spaces and `=`), e.g.
/// `number_after("eta_s = 0.9, eta_l = 0.2", "eta_l") == Some(0.2)`.
fn number_after(text: &str, key: &str) -> Option<f64> {
    let rest = &text[text.find(key)? + key.len()..];
    let rest = rest.trim_start_matches([' ', '=']);
    let end = rest
        .find(|c: char| !(c.is_ascii_digit() || matches!(c, '.' | '-' | '+' | 'e' | 'E')))
        .unwrap_or(rest.len());
    rest[..end].parse().ok().filter(|v: &f64| v.is_finite())
}

#[cfg(test)]
mod tests {
    use super::*;

    fn output(notes: &[&str]) -> RenderOutput {
        RenderOutput {
            image: render::Image::new(1, 1),
            samples: 0,
            dropped_nonfinite: 0,
            cancelled: false,
            elapsed: std::time::Duration::ZERO,
            notes: notes.iter().map(|n| (*n).to_owned()).collect(),
            strategy_images: Vec::new(),
            stage_map: None,
        }
    }

    #[test]
    fn reads_the_mcmc_notes() {
        let out = output(&[
            "bootstrap: b = 0.123456 (standard error 1.50e-3) from 20000 samples",
            "acceptance rate 0.642 over 262144 mutations",
            "automatic large-step control: eta_s = 0.9000, eta_l = 0.2710, eta_0 = 0.9850 (25600 small, 25600 large steps) -> p_large = 0.7100",
        ]);
        let s = run_stats(&out);
        assert_eq!(s.b, Some(0.123456));
        assert_eq!(s.b_standard_error, Some(1.5e-3));
        assert_eq!(s.acceptance, Some(0.642));
        assert_eq!(s.mutations, Some(262_144));
        assert_eq!(
            s.large_step,
            Some(LargeStepStats {
                eta_s: 0.9,
                eta_l: 0.271,
                eta_0: 0.985,
                p_large: 0.71
            })
        );
    }

    #[test]
    fn methods_without_statistics_give_none() {
        let s = run_stats(&output(&["the scene has no light (and no environment)"]));
        assert_eq!(s, RunStats::default());
        assert_eq!(number_after("x = nan", "x"), None);
        assert_eq!(
            number_after("eta_s = 0.5, eta_l = 0.25", "eta_l"),
            Some(0.25)
        );
    }
}
