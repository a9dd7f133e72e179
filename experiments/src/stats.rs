//! Per-run statistics of the MCMC methods (normalisation, acceptance, the large-step estimate)
//! and [`run_stats`], which takes them from a render's typed statistics.

use mcmc_core::stats::AcceptanceStats;
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
    /// The acceptance counts pooled over chains, per mixture component and per
    /// delayed-rejection stage (`render::McmcStats::acceptance`): what the per-component and
    /// per-stage [`crate::Measure`]s read. `None` without chains or mutations.
    pub acceptance_counts: Option<AcceptanceStats>,
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

/// The statistics of one render, from its typed run statistics
/// ([`RenderOutput::mcmc`], `render::McmcStats`); all `None` for the methods without chains.
///
/// # Example
/// ```
/// use std::sync::atomic::AtomicBool;
///
/// use experiments::run_stats;
/// use render::methods::PssmltSettings;
/// use render::session::{render, Budget, NoProgress, RenderSettings};
/// use render::Scene;
///
/// let settings = RenderSettings {
///     width: 8,
///     height: 8,
///     method: PssmltSettings::kelemen2002().into(),
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
    let Some(m) = &output.mcmc else {
        return RunStats::default();
    };
    let finite = |v: f64| v.is_finite().then_some(v);
    RunStats {
        b: (!m.found_nothing).then_some(m.b).and_then(finite),
        b_standard_error: (!m.found_nothing)
            .then_some(m.b_standard_error)
            .and_then(finite),
        acceptance: (m.mutations > 0)
            .then(|| m.acceptance_rate())
            .and_then(finite),
        mutations: Some(m.mutations),
        large_step: m.large_step.map(|e| LargeStepStats {
            eta_s: e.eta_s,
            eta_l: e.eta_l,
            eta_0: e.eta_0,
            p_large: e.large_step_probability,
        }),
        acceptance_counts: (m.mutations > 0).then_some(m.acceptance),
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use render::McmcStats;

    fn output(mcmc: Option<McmcStats>) -> RenderOutput {
        RenderOutput {
            mcmc,
            notes: vec!["acceptance rate 0.9 over 1 mutations".to_owned()],
            ..RenderOutput::new(render::Image::new(1, 1), std::time::Duration::ZERO)
        }
    }

    #[test]
    fn reads_the_typed_statistics_not_the_notes() {
        let mut accepted = [0; mcmc_core::proposal::MAX_COMPONENTS];
        accepted[0] = 1;
        let acceptance = mcmc_core::stats::AcceptanceStats {
            steps: 4,
            accepted,
            ..Default::default()
        };
        let m = McmcStats {
            b: 0.123456,
            b_standard_error: 1.5e-3,
            mutations: 4,
            acceptance,
            large_step: Some(mcmc_core::controller::LargeStepEstimate {
                eta_s: 0.9,
                eta_l: 0.271,
                eta_0: 0.985,
                small_steps: 10,
                large_steps: 10,
                large_step_probability: 0.71,
            }),
            ..McmcStats::default()
        };
        let s = run_stats(&output(Some(m)));
        assert_eq!(s.b, Some(0.123456));
        assert_eq!(s.b_standard_error, Some(1.5e-3));
        assert_eq!(s.acceptance, Some(0.25));
        assert_eq!(s.mutations, Some(4));
        assert_eq!(s.acceptance_counts, Some(acceptance));
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
        // The note says 0.9; without typed statistics nothing is reported (negative control
        // of reading notes).
        assert_eq!(run_stats(&output(None)), RunStats::default());
    }

    #[test]
    fn a_run_without_mutations_has_no_acceptance_counts() {
        let m = McmcStats {
            b: 0.5,
            ..McmcStats::default()
        };
        let s = run_stats(&output(Some(m)));
        assert_eq!((s.mutations, s.acceptance_counts), (Some(0), None));
    }
}
