//! Markov chain Monte Carlo integrators over primary sample space: the path-sampler targets
//! (PSSMLT over BDPT, MMLT) run through mcmc-core's generic render loop.

pub mod dr;
mod path_sampler;
mod run;
mod stage_map;

pub use path_sampler::{MmltTarget, PathPayload, PssmltTarget, PATH_STREAMS};
pub use run::{render_mlt, LargeStepMode, MltBudget, MltOutput, MltSettings};
pub use stage_map::StagedSplats;
