//! Markov chain Monte Carlo integrators over primary sample space: the path-sampler targets
//! (PSSMLT over BDPT, MMLT) run through mcmc-core's generic render loop.

pub mod direct;
pub mod dr;
pub mod mala;
mod path_sampler;
pub mod pathmlt;
mod run;
mod stage_map;
mod strata;

pub use path_sampler::{
    mmlt_depth_normalization, MmltTarget, PathPayload, PssmltTarget, PATH_STREAMS,
};
pub use run::{
    render_mlt, render_mlt_normalized, render_mlt_per_chain, render_mlt_with_estimator,
    render_mlt_with_states, render_mlt_with_states_rounds, LargeStepMode, MakeKernel, MltBudget,
    MltEstimator, MltOutput, MltSettings, PerChain,
};
pub use stage_map::StagedSplats;
pub use strata::MmltStrata;
