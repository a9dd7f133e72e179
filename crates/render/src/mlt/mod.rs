//! Markov chain Monte Carlo integrators over primary sample space: the shared driver
//! (bootstrap, chains, splatting) and the path-sampler targets (PSSMLT over BDPT, MMLT).

mod bootstrap;
mod driver;
mod splat;

pub use bootstrap::{bootstrap_key, Bootstrap};
pub use driver::{render_mlt, LargeStepMode, MltBudget, MltOutput, MltSettings};
mod path_sampler;
pub use path_sampler::{MmltTarget, PathPayload, PssmltTarget, PATH_STREAMS};
pub use splat::{luminance, Splat, SplatBuffer, SplatObserver, SplatPayload};
