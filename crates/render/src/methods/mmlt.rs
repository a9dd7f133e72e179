//! `mmlt`: multiplexed MLT (Hachisuka et al. 2014): one BDPT strategy per sample, the path
//! depth chosen per chain, the strategy by a primary sample number.

use std::time::Instant;

use super::direct_pass::{self, DirectSettings};
use super::pssmlt::push_estimator_notes;
use super::{
    bdpt_params, depth_note, emitter_notes, mcmc_output, remaining, ChainSettings, IntegratorKind,
    Method, PssKernel, RenderOutput, RenderSettings, Run,
};
use crate::bdpt::{BdptParams, Roulette};
use crate::budget::Budget;
use crate::error::RenderError;
use crate::mlt::{self, MltDriver, MltEstimator, MmltTarget, PATH_STREAMS};
use crate::scene::Scene;
use mcmc_core::render_loop::ChainAllocation;
use pss::RasterParams;

/// `mmlt`'s settings.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct MmltSettings {
    /// Chains, bootstrap, large and small steps.
    pub chain: ChainSettings,
    /// Combine the large steps with the Metropolis estimator by MIS (Kelemen et al. 2002,
    /// section 4). Default off (docs/methods/large-step-mis.md).
    pub large_step_mis: bool,
    /// Raster (image-plane) mutation ([`pss::RasterStep`]). Default off.
    pub raster: RasterParams,
    /// How chains are spread over path depths ([`MltEstimator::chain_allocation`]).
    /// Default: joint resampling (pbrt-v3's scheme).
    pub chain_allocation: ChainAllocation,
    /// Stratify the bootstrap over strategies ([`MltEstimator::strategy_strata`]; Hachisuka
    /// et al. 2014, section 4). Default off.
    pub strategy_strata: bool,
    /// Estimate each depth's integral `b_d` from this many all-strategy BDPT samples
    /// ([`mlt::mmlt_depth_normalization`]) instead of from the bootstrap; 0 (default): the
    /// bootstrap's.
    pub bdpt_normalization: u64,
    /// Russian roulette of the all-strategy samples of `bdpt_normalization` (the chains'
    /// paths have a fixed length and never use it). Default from 3 bounces on.
    pub roulette: Roulette,
    /// A separate direct-lighting pass ([`crate::mlt::direct`], shared with `pssmlt`): BDPT
    /// renders depths `0..=direct.depth`, the chains only the deeper ones. Default off (the
    /// paper's MMLT has none).
    pub direct: DirectSettings,
}

impl Default for MmltSettings {
    fn default() -> Self {
        Self::hachisuka2014()
    }
}

impl MmltSettings {
    /// Hachisuka et al. 2014 as pbrt-v3 runs it (section 4: a depth per chain, the strategy
    /// as one more primary sample number, the bootstrap's `b_d` per depth; Kelemen's small
    /// steps with s1 = 1/1024, s2 = 1/64 and large steps with probability 0.3).
    #[must_use]
    pub const fn hachisuka2014() -> Self {
        Self {
            chain: ChainSettings::kelemen2002(),
            large_step_mis: false,
            raster: RasterParams::off(),
            chain_allocation: ChainAllocation::Joint,
            strategy_strata: false,
            bdpt_normalization: 0,
            roulette: Roulette { start: Some(3) },
            direct: DirectSettings::OFF,
        }
    }
}

/// Largest accepted `bdpt_normalization`.
pub const MAX_BDPT_NORMALIZATION: u64 = 100_000_000;

/// Under a time budget, the share of it the `bdpt_normalization` samples may take (the
/// bootstrap's share, `mcmc_core::render_loop::LoopSettings::bootstrap_time_share`); they
/// stop early, with a note, when it is spent.
pub const NORMALIZATION_TIME_SHARE: f64 = 0.25;

impl Method for MmltSettings {
    fn kind(&self) -> IntegratorKind {
        IntegratorKind::Mmlt
    }

    fn validate(&self, _common: &RenderSettings) -> Result<(), RenderError> {
        if self.bdpt_normalization > MAX_BDPT_NORMALIZATION {
            return Err(RenderError::setting(
                "bdpt-normalization",
                self.bdpt_normalization,
                "0..=100000000",
            ));
        }
        self.chain.validate()
    }

    fn render(
        &self,
        scene: &Scene,
        common: &RenderSettings,
        run: &Run<'_>,
    ) -> Result<RenderOutput, RenderError> {
        let params: BdptParams = bdpt_params(common, self.roulette);
        let (w, h) = (common.width, common.height);
        let mut notes = emitter_notes(scene);
        notes.extend(depth_note(common));
        let kernel = PssKernel::new(self.chain.small_step, &self.raster, w, h);
        let (direct, direct_spent, min_depth) =
            self.direct.run(scene, &params, common, run, &mut notes);
        let mut mlt_settings = self
            .chain
            .mlt_settings(common, PATH_STREAMS, false, run.shard);
        if let Some(spent) = direct_spent {
            mlt_settings.budget = remaining(mlt_settings.budget, spent);
        }
        let estimator = MltEstimator {
            large_step_mis: self.large_step_mis,
            chain_allocation: self.chain_allocation,
            strategy_strata: self.strategy_strata,
        };
        push_estimator_notes(&mut notes, self.large_step_mis, &kernel, &self.raster);
        let normalization = (self.bdpt_normalization > 0)
            .then(|| {
                let t0 = Instant::now();
                // Under a time budget the normalisation gets the bootstrap's share of it.
                let deadline = match common.budget {
                    Budget::Time(t) => Some(run.start + t.mul_f64(NORMALIZATION_TIME_SHARE)),
                    Budget::SamplesPerPixel(_) => None,
                };
                let nb = mlt::mmlt_depth_normalization_until(
                    scene,
                    params,
                    w,
                    h,
                    self.bdpt_normalization,
                    common.seed,
                    deadline,
                    run.cancel,
                )?;
                let stopped = if nb.samples < self.bdpt_normalization {
                    format!(
                        " of {} (stopped at {:.0} % of the time budget)",
                        self.bdpt_normalization,
                        NORMALIZATION_TIME_SHARE * 100.0
                    )
                } else {
                    String::new()
                };
                notes.push(format!(
                    "MMLT depth normalisation from {}{stopped} all-strategy BDPT samples ({:.2} s): b = {:.6}",
                    nb.samples,
                    t0.elapsed().as_secs_f64(),
                    nb.b.iter().sum::<f64>()
                ));
                // The chains' targets are the depths beyond the direct pass.
                let b = nb.b.get(min_depth as usize..).unwrap_or_default().to_vec();
                Some((b, t0.elapsed()))
            })
            .flatten();
        if self.bdpt_normalization > 0 && normalization.is_none() {
            notes.push(
                "cancelled during the MMLT depth normalisation: the chains use the bootstrap's b"
                    .to_owned(),
            );
        }
        let targets = MmltTarget::depths_from(scene, params, w, h, min_depth);
        let make_kernel = |p: f64| kernel.with_large_step(p);
        let driver = MltDriver::new(&targets, &mlt_settings)
            .estimator(estimator)
            .first_depth(min_depth);
        let (out, spent) = match &normalization {
            Some((nb, spent)) => {
                let budgeted = mlt::MltSettings {
                    budget: remaining(mlt_settings.budget, *spent),
                    ..mlt_settings
                };
                let out = MltDriver::new(&targets, &budgeted)
                    .estimator(estimator)
                    .first_depth(min_depth)
                    .normalized(nb)
                    .run(make_kernel, run.progress, run.cancel);
                (out, *spent)
            }
            None => (
                driver.run(make_kernel, run.progress, run.cancel),
                std::time::Duration::ZERO,
            ),
        };
        let chains_ran = out.mutations > 0;
        let mut output = mcmc_output(out, notes, run.start.elapsed());
        if let Some(stats) = output.mcmc.as_mut() {
            stats.times.normalization = spent;
        }
        if let Some(d) = direct {
            direct_pass::merge_into(d, &mut output, common, run, chains_ran);
        }
        output.elapsed = run.start.elapsed();
        Ok(output)
    }
}
