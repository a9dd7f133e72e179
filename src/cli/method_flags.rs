//! The methods' own flags of `chainlight render` and how they become a method's settings:
//! the chosen row's defaults ([`render::IntegratorKind::settings`]) with each flag that
//! applies to the method set on them. A flag given on the command line that has no effect on
//! the chosen method is an error naming the integrators it applies to
//! ([`super::flag_rules`]).

use clap::Args;
use pss::{RasterParams, SmallMutation};
use render::methods::direct_pass::DirectSettings;
use render::methods::{ChainSettings, MalaSettings, MethodSettings, AUTO_LARGE_STEP_ESTIMATION};
use render::mlt::direct::DirectPass;
use render::mlt::dr::{DrBase, DrVariant};
use render::mlt::LargeStepMode;
use render::IntegratorKind;

use super::flag_rules::check_applicable;
use super::parse;

/// `--large-step` when not given: Kelemen et al. 2002's probability (pbrt-v3's value).
const DEFAULT_LARGE_STEP: LargeStepMode = LargeStepMode::Fixed(0.3);

/// The flags of `chainlight render` that belong to one method or a family of methods.
#[derive(Debug, Args)]
pub(crate) struct MethodFlags {
    /// MCMC integrators: the large-step probability, `auto` (Zsolnai & Szirmay-Kalos 2013:
    /// estimated from the first mutations of every chain), a number in 0..=1, or `P1,P2`
    /// (P1 for the first tenth of every chain's mutations, then P2) [default: 0.3; with
    /// `--mala-preset code`: 0.05,0.2, the authors' schedule].
    #[arg(long, value_name = "auto|P|P1,P2", value_parser = parse::large_step)]
    pub(crate) large_step: Option<LargeStepMode>,
    /// pssmlt, mmlt: `on` combines the large-step samples with the Metropolis estimator by
    /// multiple importance sampling (Kelemen et al. 2002, section 4; LuxCore's METROPOLIS
    /// sampler), `off` uses the plain expected-value estimator [default: on for pssmlt, off
    /// for mmlt].
    #[arg(long, value_name = "on|off", value_parser = parse::on_off,
          action = clap::ArgAction::Set)]
    pub(crate) large_step_mis: Option<bool>,
    /// pssmlt, mmlt: raster (image-plane) mutation after LuxCore's: with probability P a small
    /// step moves only the two raster numbers, by 1 pixel to 10% of the image (Kelemen-style,
    /// log-uniform per axis); `on` is P = 0.5 [default: on for pssmlt, off for mmlt].
    #[arg(long, value_name = "off|on|P", value_parser = parse::raster_mutation)]
    pub(crate) raster_mutation: Option<f64>,
    /// mmlt: how chains are spread over path depths, `joint` (pbrt's resampling over all
    /// depths) or `per-depth` (a fixed count per depth, proportional to its bootstrap
    /// estimate, splats scaled by b_d / n_d).
    #[arg(long, value_name = "joint|per-depth", default_value = "joint", value_parser = parse::chain_allocation)]
    pub(crate) chain_allocation: mcmc_core::render_loop::ChainAllocation,
    /// mmlt: `on` stratifies the bootstrap over strategies (every primary point evaluated
    /// under all strategies of its depth).
    #[arg(long, value_name = "on|off", default_value = "off", value_parser = parse::on_off,
          action = clap::ArgAction::Set)]
    pub(crate) strategy_strata: bool,
    /// mmlt: estimate each depth's normalisation from N all-strategy BDPT samples instead of
    /// the bootstrap (0: the bootstrap's), 0..=100000000.
    #[arg(long, value_name = "N", default_value_t = 0,
          value_parser = clap::value_parser!(u64).range(0..=100_000_000))]
    pub(crate) bdpt_normalization: u64,
    /// pssmlt, mmlt, mala*: a separate direct-lighting pass (Mitsuba 0.6's `directSamples`):
    /// BDPT renders path depths 0..=K (--direct-depth) at N samples per pixel first (under
    /// --time at most a quarter of the time), the chains only deeper paths; 0..=65536, 0 = off
    /// [default: --direct-share auto for pssmlt and mala*, off for mmlt].
    #[arg(long, value_name = "N", conflicts_with = "direct_share",
          value_parser = clap::value_parser!(u32).range(0..=65_536))]
    pub(crate) direct_samples: Option<u32>,
    /// pssmlt, mmlt, mala*: the direct pass's share of the budget: `auto` picks it per scene from a pilot
    /// of 16384 BDPT samples (how much of the light the pass's depths carry; about 25 % of the
    /// time on cornell-glass, 10 % on ajar-door), or a share in 0.01..=0.9 of --time (under
    /// --spp the samples per mutation that cost as much) [default: auto].
    #[arg(long, value_name = "auto|S", value_parser = parse::direct_share)]
    pub(crate) direct_share: Option<render::mlt::direct::DirectPass>,
    /// pssmlt, mmlt, mala*: the direct pass's depth K, 1..=64: BDPT renders paths of up to K
    /// bounces, the chains the deeper ones (1: direct light only; no pass if K >=
    /// --max-depth) [default: 2 for pssmlt, 1 for mmlt and mala*].
    #[arg(long, value_name = "K", value_parser = clap::value_parser!(u32).range(1..=64))]
    pub(crate) direct_depth: Option<u32>,
    /// MCMC integrators: the small-step kernel, `kelemen` (s1 = 1/1024, s2 = 1/64; Kelemen et
    /// al. 2002), `kelemen=S1,S2` (0 < S1 < S2 <= 0.5), `gaussian=SIGMA` with SIGMA in
    /// (0, 10] (pbrt-v3 uses gaussian=0.01) or `uniform=A`, a box of half-width A in
    /// (0, 0.5] (corona-13's KMLT uses uniform=0.01).
    #[arg(long, value_name = "kelemen|kelemen=S1,S2|gaussian=SIGMA|uniform=A", default_value = "kelemen", value_parser = parse::small_step)]
    pub(crate) small_step: SmallMutation,
    /// MCMC integrators: number of Markov chains, 1..=1000000.
    #[arg(long, value_name = "N", default_value_t = 256,
          value_parser = clap::value_parser!(u32).range(1..=1_000_000))]
    pub(crate) chains: u32,
    /// MCMC integrators: independent samples in the bootstrap that estimates the
    /// normalisation and seeds the chains, 1..=100000000.
    #[arg(long, value_name = "N", default_value_t = 100_000,
          value_parser = clap::value_parser!(u32).range(1..=100_000_000))]
    pub(crate) bootstrap_samples: u32,
    /// MCMC integrators: the image's normalisation `b`: `pooled` (the bootstrap's samples with
    /// every large-step candidate of the chains, so the brightness error falls with the
    /// budget), `bootstrap` (pbrt's: the bootstrap's alone), a number `b > 0`, or an image
    /// file (e.g. a reference .exr) whose mean luminance the image gets: comparisons on one
    /// footing [default: pooled].
    #[arg(long, allow_negative_numbers = true, value_name = "pooled|bootstrap|B|FILE",
          value_parser = parse::normalization)]
    pub(crate) normalization: Option<mcmc_core::render_loop::NormalizationMode>,
    /// pt (and qmc), bdpt, pssmlt (and drmlt over it): Russian roulette, `off`, or `N` (from N
    /// bounces on, 0..=1024; pt: continue with probability min(1, max beta) after every bounce
    /// beyond the N-th; bdpt: min(0.95, f cos / pdf of the last bounce)) [default: 5 for pt,
    /// 3 otherwise]. MMLT-based paths have a fixed length and no roulette (mmlt: only its
    /// --bdpt-normalization pass).
    #[arg(long, value_name = "off|N", value_parser = parse::roulette)]
    pub(crate) roulette: Option<render::bdpt::Roulette>,
    /// pt and bdpt: the per-pixel sampler, `independent` or `sobol` (Owen-scrambled Sobol
    /// points, stratified per pixel); pssmlt: its direct-lighting pass's [default: sobol].
    /// Other integrators own their numbers.
    #[arg(long, value_name = "independent|sobol")]
    pub(crate) sampler: Option<render::sampler::SamplerKind>,
    /// BDPT only: also write the MIS-weighted image of every strategy (s, t) next to the
    /// output, as `<stem>_s<S>_t<T>.exr`.
    #[arg(long)]
    pub(crate) strategy_images: bool,
    /// drmlt: the second-stage rule, `tierney-mira`, `green-mira` (the authors' stages: 1-D
    /// Kelemen then Gaussian 0.1/64), `orbital` (the paper's recommendation),
    /// `tierney-mira-pairwise`, `green-mira-pairwise` (pairwise Kelemen stages) or
    /// `cheap-then-expensive` (Gaussian first stage, MALA second stage, Green-Mira; on MMLT).
    #[arg(long, value_name = "RULE", default_value = "orbital", value_parser = parse::dr_variant)]
    pub(crate) dr_variant: DrVariant,
    /// drmlt: the path sampler, `pssmlt` (over BDPT), `pssmlt-pt` (over the path tracer) or
    /// `mmlt` (second stage on the camera subpath only).
    #[arg(long, value_name = "pssmlt|pssmlt-pt|mmlt", default_value = "pssmlt", value_parser = parse::dr_on)]
    pub(crate) dr_on: DrBase,
    /// drmlt with `--dr-on mmlt` and the orbital rule: keep MMLT's strategy along the chain
    /// in both stages (the paper's chain; large steps still draw it afresh).
    #[arg(long)]
    pub(crate) dr_fixed_strategy: bool,
    /// pathmlt: the perturbation mixed with the bidirectional mutation (0.5 each, RA paper
    /// section 8.1), `lens` or `multichain`.
    #[arg(long, value_name = "lens|multichain", default_value = "lens", value_parser = parse::perturbation)]
    pub(crate) perturbation: pathspace::PerturbationKind,
    /// pathmlt: how the perturbation's angular scale is adapted (Otsu et al. 2018): `fixed`
    /// (at --sigma), `global` (one adapted scale), `grid` (per cell of a 20 x 20 screen grid;
    /// multichain: x a 50 x 50 direction grid per cell) or `quadtree` (a refined screen
    /// quadtree; multichain: a direction quadtree per cell of the 20 x 20 screen grid).
    #[arg(long, value_name = "fixed|global|grid|quadtree", default_value = "fixed", value_parser = parse::adapt)]
    pub(crate) adapt: render::mlt::pathmlt::PathAdapt,
    /// pathmlt: FIXED's angular scale and the adaptive variants' start: `paper` (lambda = 1,
    /// sigma = e^0.5 = 1.6487 rad, Otsu et al. 2018 section 8.1), `tuned` (0.02 rad) or a
    /// value in (0, pi] radians [default: tuned].
    #[arg(long, value_name = "paper|tuned|RAD", value_parser = parse::pathmlt_sigma)]
    pub(crate) sigma: Option<f64>,
    /// pathmlt: the adaptive variants' target acceptance, in (0, 1) (the paper's 0.5; 0.8 for
    /// its glossy Necklace scene).
    #[arg(long, value_name = "ALPHA", default_value_t = 0.5)]
    pub(crate) target_acceptance: f64,
    /// mala*: parameter preset, `paper` (Luan et al. 2020's text, section 7: epsilon 0.01 as
    /// the variance of eq. 7, K 30, H 10000), `paper-values` (those values with the authors'
    /// code's semantics: covariance epsilon^2 (M + 1), M in [0.01, 100], drift clamp 5, radius
    /// 0.01 sqrt(d), first-visit Adam start, fallback step 0.1) or `code` (the authors' code:
    /// epsilon 0.005, shrink prior 0.005, K 5, H 3000, otherwise as `paper-values`).
    #[arg(long, value_name = "paper|paper-values|code", default_value = "paper", value_parser = parse::mala_preset)]
    pub(crate) mala_preset: render::mlt::mala::MalaParams,
    /// mala*: chains of MMLT depth up to D run MALA, deeper ones the Kelemen small step,
    /// 0..=1024.
    #[arg(long, allow_negative_numbers = true, value_name = "D", default_value_t = 3,
          value_parser = clap::value_parser!(u32).range(0..=1024))]
    pub(crate) mala_max_depth: u32,
    /// mala*: the kernel of the Langevin chains, `mala` (the variant's MALA) or
    /// `cheap-then-expensive` (the DR paper's section 5.2: an isotropic Gaussian of sigma 1/64,
    /// then plain MALA), with the same direct pass, chains and large steps.
    #[arg(long, value_name = "mala|cheap-then-expensive", default_value = "mala", value_parser = parse::mala_kernel)]
    pub(crate) mala_kernel: parse::CheapThenExpensive,
    /// mala*: gradient of the log contribution, `dual` (forward-mode dual numbers through the
    /// differentiable path evaluator; finite differences where it does not apply),
    /// `dual-constant-mis` (the same with the MIS weight held constant) or `fd` (central
    /// finite differences of the f32 renderer).
    #[arg(long, value_name = "dual|dual-constant-mis|fd", default_value = "dual", value_parser = parse::mala_gradient)]
    pub(crate) mala_gradient: render::mlt::mala::GradientMethod,
    /// lqmc: parameter preset, `paper` (Tessari et al. 2020: NEE paths that are neither
    /// caustic nor out of focus splatted unexplored) or `code` (the authors' code: those NEE
    /// paths explored with lattices of 7 points) [default: paper].
    #[arg(long, value_name = "paper|code", value_parser = parse::lqmc_preset)]
    pub(crate) lqmc_preset: Option<render::methods::LqmcSettings>,
}

impl MethodFlags {
    /// The Markov chain settings of the flags.
    fn chain(&self) -> ChainSettings {
        ChainSettings {
            chains: self.chains as usize,
            bootstrap_samples: self.bootstrap_samples as usize,
            large_step: match self.large_step.unwrap_or(DEFAULT_LARGE_STEP) {
                LargeStepMode::Auto { initial, .. } => LargeStepMode::Auto {
                    initial,
                    estimation_steps: AUTO_LARGE_STEP_ESTIMATION,
                },
                other => other,
            },
            small_step: self.small_step,
            normalization: self.normalization.unwrap_or_default(),
        }
    }

    /// The raster mutation of `--raster-mutation`, or `default`.
    fn raster(&self, default: RasterParams) -> RasterParams {
        self.raster_mutation
            .map_or(default, RasterParams::with_probability)
    }

    /// The settings of `integrator` with these flags: its row's defaults, every flag that
    /// applies to it set. `given` says which flags (by clap id, the field name) were on the
    /// command line.
    ///
    /// # Errors
    /// A flag given on the command line that has no effect on the resulting settings
    /// ([`check_applicable`]).
    pub(crate) fn settings(
        &self,
        integrator: IntegratorKind,
        given: &dyn Fn(&str) -> bool,
    ) -> Result<MethodSettings, String> {
        let method = self.apply(integrator.settings());
        check_applicable(&method, given)?;
        Ok(method)
    }

    /// `direct` with the direct-pass flags that were given.
    fn direct(&self, direct: DirectSettings) -> DirectSettings {
        DirectSettings {
            pass: self
                .direct_samples
                .map(DirectPass::Fixed)
                .or(self.direct_share)
                .unwrap_or(direct.pass),
            depth: self.direct_depth.unwrap_or(direct.depth),
            sampler: self.sampler.unwrap_or(direct.sampler),
        }
    }

    /// `method` with every flag that applies to it set.
    pub(crate) fn apply(&self, mut method: MethodSettings) -> MethodSettings {
        match &mut method {
            MethodSettings::Pt(s) => {
                s.sampler = self.sampler.unwrap_or(s.sampler);
                s.roulette = self.roulette.map_or(s.roulette, |r| r.start);
            }
            MethodSettings::Qmc(s) => s.roulette = self.roulette.map_or(s.roulette, |r| r.start),
            MethodSettings::Bdpt(s) => {
                s.sampler = self.sampler.unwrap_or(s.sampler);
                s.roulette = self.roulette.unwrap_or(s.roulette);
                s.strategy_images = self.strategy_images;
            }
            MethodSettings::Pssmlt(s) => {
                s.chain = self.chain();
                s.large_step_mis = self.large_step_mis.unwrap_or(s.large_step_mis);
                s.raster = self.raster(s.raster);
                let d = self.direct(DirectSettings {
                    pass: s.direct,
                    depth: s.direct_depth,
                    sampler: s.sampler,
                });
                (s.direct, s.direct_depth, s.sampler) = (d.pass, d.depth, d.sampler);
                s.roulette = self.roulette.unwrap_or(s.roulette);
            }
            MethodSettings::Mmlt(s) => {
                s.chain = self.chain();
                s.large_step_mis = self.large_step_mis.unwrap_or(s.large_step_mis);
                s.raster = self.raster(s.raster);
                s.chain_allocation = self.chain_allocation;
                s.strategy_strata = self.strategy_strata;
                s.bdpt_normalization = self.bdpt_normalization;
                s.roulette = self.roulette.unwrap_or(s.roulette);
                s.direct = self.direct(s.direct);
            }
            MethodSettings::Drmlt(s) => {
                s.chain = self.chain();
                s.variant = self.dr_variant;
                s.on = self.dr_on;
                s.large_step_mis = self.large_step_mis.unwrap_or(s.large_step_mis);
                s.mala.params = self.mala_preset.langevin;
                s.mala.max_depth = self.mala_max_depth;
                s.mala.gradient = self.mala_gradient;
                s.roulette = self.roulette.unwrap_or(s.roulette);
                s.direct = self.direct(s.direct);
                s.fixed_strategy = self.dr_fixed_strategy;
            }
            MethodSettings::Mala(s) => {
                s.chain = self.chain();
                s.config.params = self.mala_preset.langevin;
                s.config.fallback = self.mala_preset.fallback;
                if self.large_step.is_none()
                    && self.mala_preset == render::mlt::mala::MalaParams::luan2020_code()
                {
                    s.chain.large_step = MalaSettings::CODE_LARGE_STEP;
                }
                s.cheap_then_expensive = self.mala_kernel.0;
                s.config.max_depth = self.mala_max_depth;
                s.config.gradient = self.mala_gradient;
                s.direct = self.direct(s.direct);
            }
            MethodSettings::PathMlt(s) => {
                s.chains = self.chains as usize;
                s.bootstrap_samples = self.bootstrap_samples as usize;
                s.perturbation = self.perturbation;
                s.adapt = self.adapt;
                s.sigma = self.sigma.unwrap_or(s.sigma);
                s.target_acceptance = self.target_acceptance;
                s.normalization = self.normalization.unwrap_or(s.normalization);
            }
            MethodSettings::Lqmc(s) => *s = self.lqmc_preset.unwrap_or(*s),
            _ => {}
        }
        method
    }
}
