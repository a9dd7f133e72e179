//! Markov chain Monte Carlo integrators over primary sample space: the path-sampler targets
//! (PSSMLT over BDPT or the path tracer, MMLT) run through mcmc-core's generic render loop.

pub mod direct;
pub mod dr;
mod driver;
mod estimation;
pub mod mala;
mod path_sampler;
pub mod pathmlt;
mod pt_target;
mod run;
mod stage_map;
mod strata;

pub use driver::{GivenStates, MltDriver, PrimarySamples};
pub use estimation::{
    ESTIMATION_SHARE_DIVISOR, TIME_BUDGET_ESTIMATION_STEPS, TIME_BUDGET_WARM_UP_STEPS,
};
pub use path_sampler::{
    mmlt_depth_normalization, mmlt_depth_normalization_until, DepthNormalization, MmltTarget,
    PathPayload, PssmltTarget, PATH_STREAMS,
};
pub use pt_target::PtTarget;
pub use run::{
    LargeStepMode, MakeKernel, MltBudget, MltEstimator, MltOutput, MltSettings, PerChain,
};
pub use stage_map::StagedSplats;
pub use strata::MmltStrata;
