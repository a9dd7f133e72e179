//! `mala`, `mala-online`, `mala-cache`, `mala-hybrid`: Langevin MLT (Luan et al. 2020) over
//! MMLT: MALA small steps on shallow depths with plain, online, cache-driven or hybrid
//! adaptation of the preconditioner, Kelemen steps beyond ([`crate::mlt::mala`]).

use mcmc_core::langevin::{
    LangevinParams, FALLBACK_COMPONENT, LARGE_STEP_COMPONENT, MALA_COMPONENT,
};
use mcmc_core::stats::AcceptanceStats;

use super::direct_pass::{self, DirectSettings};
use super::{
    bdpt_params, depth_note, emitter_notes, mcmc_output, remaining, ChainSettings, IntegratorKind,
    Method, RenderOutput, RenderSettings, Run,
};
use crate::bdpt::BdptParams;
use crate::error::RenderError;
use crate::mlt::direct::DirectPass;
use crate::mlt::mala::{self, GradientMethod, MalaConfig, MalaVariant};
use crate::mlt::{LargeStepMode, PATH_STREAMS};
use crate::scene::Scene;

/// Langevin MLT's settings; the variant ([`MalaConfig::variant`]) picks the row.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct MalaSettings {
    /// Chains, bootstrap, large steps, and the Kelemen small step of chains deeper than
    /// [`MalaConfig::max_depth`].
    pub chain: ChainSettings,
    /// The variant, MALA's parameters, the depth rule and the gradient.
    pub config: MalaConfig,
    /// The separate direct-lighting pass: BDPT renders depths `0..=direct.depth`, the
    /// Langevin chains only the deeper paths (the authors' code renders paths of at most
    /// two segments, our depths 0 and 1, by a separate 256-spp pass; the paper's text does
    /// not say).
    pub direct: DirectSettings,
    /// Run the cheap-then-expensive delayed-rejection kernel (DR paper section 5.2: an
    /// isotropic Gaussian of `config.cheap_sigma`, then plain MALA) in place of the
    /// variant's MALA, with the same direct pass, chains and large steps as the `mala*`
    /// rows (for comparisons; the command line's is `drmlt --dr-variant
    /// cheap-then-expensive`). Default false.
    pub cheap_then_expensive: bool,
}

impl Default for MalaSettings {
    /// [`MalaSettings::luan2020`] (hybrid adaptation).
    fn default() -> Self {
        Self::luan2020()
    }
}

impl MalaSettings {
    /// The paper's method as its text reads (Luan et al. 2020): hybrid adaptation (Alg. 4,
    /// the paper's main algorithm) with section 7's parameters, epsilon 0.01 as the variance
    /// of eq. 7 (`Sigma = epsilon M`), K = 30 neighbours within radius 0.01, cache size
    /// H = 10 000, Adam accumulators from zero ([`LangevinParams::luan2020`]); MALA on MMLT
    /// depths up to 3, Kelemen steps beyond; gradients by forward-mode dual numbers.
    #[must_use]
    pub const fn luan2020() -> Self {
        Self::luan2020_variant(MalaVariant::Hybrid)
    }

    /// The paper's values read with the authors' code's semantics
    /// ([`LangevinParams::luan2020_values`]: epsilon 0.01 as a standard deviation with a
    /// floor, covariance `epsilon^2 (M + 1)`, `M` in `[0.01, 100]`, drift clamped to `+-5`,
    /// K = 30 within `0.01 sqrt(d)`, H = 10 000, first-visit Adam start), plus the code's
    /// fallback step (probability 0.1, sigma 0.01 on every coordinate).
    #[must_use]
    pub const fn luan2020_values() -> Self {
        let mut s = Self::luan2020();
        let p = pss::mala::MalaParams::luan2020_values();
        s.config.params = p.langevin;
        s.config.fallback = p.fallback;
        s
    }

    /// The authors' code ([`LangevinParams::luan2020_code`]: epsilon 0.005 as a standard
    /// deviation, shrink prior 0.005, `M` in `[0.01, 100]`, drift clamped to `+-5`, K = 5
    /// within `0.01 sqrt(d)`, H = 3000, first-visit Adam start), plus its fallback step
    /// (probability 0.1) and its large-step schedule ([`Self::CODE_LARGE_STEP`]).
    #[must_use]
    pub const fn luan2020_code() -> Self {
        let mut s = Self::luan2020();
        let p = pss::mala::MalaParams::luan2020_code();
        s.config.params = p.langevin;
        s.config.fallback = p.fallback;
        s.chain.large_step = Self::CODE_LARGE_STEP;
        s
    }

    /// The authors' code's large steps: probability 0.05 (`largestepprob`) for the first
    /// tenth of every chain's mutations (`LS_RATIO`), while the chain learns its
    /// preconditioner, then 0.05 x 4 = 0.2 (`largestepscale` 4, as both shipped `lmc.xml`
    /// scenes set it).
    pub const CODE_LARGE_STEP: LargeStepMode = LargeStepMode::Schedule {
        initial: 0.05,
        then: 0.2,
    };

    /// [`MalaSettings::luan2020`] with another adaptation variant (the paper's Fig. 7-9
    /// compare plain, online, cache-driven and hybrid adaptation).
    #[must_use]
    pub const fn luan2020_variant(variant: MalaVariant) -> Self {
        Self {
            chain: ChainSettings::kelemen2002(),
            config: MalaConfig {
                variant,
                params: LangevinParams::luan2020(),
                max_depth: 3,
                gradient: GradientMethod::Dual,
                fd_step: 1e-4,
                cheap_sigma: 1.0 / 64.0,
                fallback: 0.0,
                cache_round: mala::CACHE_ROUND_MUTATIONS,
            },
            direct: Self::AUTHORS_DIRECT,
            cheap_then_expensive: false,
        }
    }

    /// The authors' direct-lighting split: depths 0 and 1 by a separate pass of 256 samples
    /// per pixel (dpt's `directSpp`), the chains the deeper paths.
    pub const AUTHORS_DIRECT: DirectSettings = DirectSettings {
        pass: DirectPass::Fixed(256),
        depth: 1,
        sampler: crate::sampler::SamplerKind::Sobol,
    };

    /// The command line's defaults for `variant` (the `mala*` rows): the paper's method
    /// ([`MalaSettings::luan2020_variant`]) with its direct-lighting split budgeted as
    /// `pssmlt`'s pass is (balanced against the chains by a pilot,
    /// [`DirectSettings::balanced`]) instead of a fixed 256 samples per pixel, so short
    /// renders are not all direct pass.
    #[must_use]
    pub const fn with_variant(variant: MalaVariant) -> Self {
        let mut s = Self::luan2020_variant(variant);
        s.direct = DirectSettings::balanced(1);
        s
    }
}

/// One line on the Langevin settings for the render notes.
pub(super) fn mala_note(config: &MalaConfig) -> String {
    let gradients = match config.gradient {
        GradientMethod::Dual => format!(
            "gradients by forward-mode dual numbers (--mala-gradient dual; central finite \
             differences, h = {:e}, where they do not apply)",
            config.fd_step
        ),
        GradientMethod::DualConstantMis => format!(
            "gradients by forward-mode dual numbers with the MIS weight held constant \
             (--mala-gradient dual-constant-mis; central finite differences, h = {:e}, where \
             they do not apply)",
            config.fd_step
        ),
        GradientMethod::FiniteDifference => format!(
            "gradients by central finite differences (--mala-gradient fd, h = {:e})",
            config.fd_step
        ),
    };
    let covariance = match config.params.covariance {
        mcmc_core::langevin::Covariance::EpsilonM => "covariance epsilon M",
        mcmc_core::langevin::Covariance::EpsilonSquaredMPlusOne => "covariance epsilon^2 (M + 1)",
    };
    format!(
        "Langevin MLT: {} (epsilon {}, {covariance}, truncation {}, fallback {}), MALA on the continuous primary samples of MMLT depths <= {} and Kelemen beyond; {gradients}",
        config.variant.name(),
        config.params.epsilon,
        config.params.max_gradient,
        config.fallback,
        config.max_depth,
    )
}

/// One line on the acceptance per kind of step: the Langevin proposals (component
/// [`MALA_COMPONENT`]; with `--max-depth` above the MALA depth it also counts the Kelemen
/// small steps of the deeper chains), the large steps and the fallback steps.
pub(super) fn langevin_acceptance_note(
    stats: &AcceptanceStats,
    config: &MalaConfig,
    common: &RenderSettings,
) -> String {
    let part = |j: usize, what: &str| {
        format!(
            "{what} {:.3} of {}",
            stats.component_acceptance_rate(j),
            stats.proposed[j]
        )
    };
    let deeper = if common.max_depth > config.max_depth {
        " (with the Kelemen small steps of depths beyond the MALA depth)"
    } else {
        ""
    };
    format!(
        "acceptance by step: {}{deeper}, {}, {}",
        part(MALA_COMPONENT, "Langevin"),
        part(LARGE_STEP_COMPONENT, "large"),
        part(FALLBACK_COMPONENT, "fallback"),
    )
}

impl Method for MalaSettings {
    fn kind(&self) -> IntegratorKind {
        match self.config.variant {
            MalaVariant::Plain => IntegratorKind::Mala,
            MalaVariant::Online => IntegratorKind::MalaOnline,
            MalaVariant::Cache => IntegratorKind::MalaCache,
            MalaVariant::Hybrid => IntegratorKind::MalaHybrid,
        }
    }

    fn validate(&self, _common: &RenderSettings) -> Result<(), RenderError> {
        self.chain.validate()
    }

    fn render(
        &self,
        scene: &Scene,
        common: &RenderSettings,
        run: &Run<'_>,
    ) -> Result<RenderOutput, RenderError> {
        let params = bdpt_params(common, BdptParams::default().roulette);
        let mut notes = emitter_notes(scene);
        notes.extend(depth_note(common));
        let (direct, direct_spent, min_depth) =
            self.direct.run(scene, &params, common, run, &mut notes);
        let mut mlt_settings = self
            .chain
            .mlt_settings(common, PATH_STREAMS, false, run.shard);
        if let Some(spent) = direct_spent {
            mlt_settings.budget = remaining(mlt_settings.budget, spent);
        }
        direct_pass::given_normalization(&mut mlt_settings, direct.as_ref(), &mut notes)?;
        notes.push(mala_note(&self.config));
        let out = mala::render_from_depth(
            scene,
            params,
            &self.config,
            self.cheap_then_expensive,
            &mlt_settings,
            self.chain.small_step,
            min_depth,
            run.progress,
            run.cancel,
        );
        let chains_ran = out.mutations > 0;
        if chains_ran {
            notes.push(langevin_acceptance_note(&out.stats, &self.config, common));
        }
        let mut output = mcmc_output(out, notes, run.start.elapsed());
        if let Some(d) = direct {
            direct_pass::merge_into(d, &mut output, common, run, chains_ran);
        }
        output.elapsed = run.start.elapsed();
        Ok(output)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn the_note_names_the_gradient_in_use() {
        let mut config = MalaSettings::luan2020().config;
        config.gradient = GradientMethod::Dual;
        let dual = mala_note(&config);
        assert!(dual.contains("dual numbers"), "{dual}");
        config.gradient = GradientMethod::FiniteDifference;
        let fd = mala_note(&config);
        assert!(
            fd.contains("central finite differences") && !fd.contains("dual"),
            "{fd}"
        );
        assert_ne!(dual, fd);
    }
}
