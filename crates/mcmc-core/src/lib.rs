//! State-space-agnostic Markov chain Monte Carlo for light transport.
//!
//! The crate separates *what is sampled* ([`Target`]), *how to move* ([`Proposal`]), *how to
//! decide* ([`Kernel`]: [`Mh`], delayed rejection, MALA) and *how to learn*
//! ([`Controller`]: global or regional scale adaptation, automatic large-step control). A
//! [`Chain`] drives one kernel with its own RNG and reports every evaluated candidate, with
//! its expected-value weight, to an [`Observer`].
//!
//! # Example
//! ```
//! use mcmc_core::{Chain, GaussianRandomWalk, Mh, NoAdaptation, Target};
//! use rand::SeedableRng;
//!
//! /// A standard normal in one dimension.
//! struct Normal;
//! impl Target for Normal {
//!     type State = Vec<f64>;
//!     type Payload = ();
//!     fn evaluate(&self, x: &mut Vec<f64>, _: &mut ()) -> f64 {
//!         -0.5 * x[0] * x[0]
//!     }
//! }
//!
//! let kernel = Mh::new(GaussianRandomWalk::new(1.0).unwrap());
//! let rng = rand_pcg::Pcg64::seed_from_u64(7);
//! let mut chain = Chain::new(&Normal, kernel, NoAdaptation, rng, vec![0.0]).unwrap();
//! chain.run(1000, &mut ()).unwrap();
//! assert!(chain.stats().acceptance_rate() > 0.3);
//! ```
//!
//! # Layers
//!
//! The modules form layers, lowest first. A module uses only its own layer and the layers
//! below it (`tests/layering.rs` checks every `use crate::...` against this table), so each
//! layer can be read, tested and reused without the ones above it.
//!
//! | layer | modules | what it holds |
//! |---|---|---|
//! | foundations | `error`, [`torus`], [`special`], [`seed`], `progress`, [`partition`] | the error type, the unit torus (wrapping, minimal displacements, the wrapped normal), special functions, per-chain seeds, progress reporting, partitions of a state space |
//! | target | `target` | *what is sampled*: [`Target`], [`DifferentiableTarget`], [`Point`] |
//! | tunable | [`tunable`] | the interfaces through which controllers tune kernels: [`tunable::ScaleTunable`], [`tunable::RegionalTunable`], [`tunable::LargeStepTunable`], [`tunable::SharedRegionalScales`] |
//! | proposal | [`proposal`] | *how to move*: [`Proposal`], [`Mixture`], [`GaussianRandomWalk`], scaled and regional proposals, conditional (second-stage) proposals |
//! | kernel | `kernel`, `mh`, [`stats`] | *how to decide*: [`Kernel`], [`Observer`], [`Mh`]; acceptance statistics |
//! | controller | [`controller`] | *how to learn*: [`Controller`], [`controller::SharedController`], global and regional scale adaptation, automatic large-step control |
//! | kernel families | [`delayed_rejection`], [`langevin`] | two-stage delayed rejection and its stages; MALA with its adaptations, gradient cache and cache-sharing controller |
//! | chain | `chain` | [`Chain`]: one kernel, one controller, one RNG |
//! | render loop | `render_loop` (feature `parallel`) | many chains in fixed jobs, bootstrap, rounds with shared statistics, splatting |
//! | test support | `testing`, `toy` (feature `testing`) | the correctness harness and the toy targets with exact densities |
//!
//! # Features
//!
//! None is on by default: targets, proposals, Metropolis-Hastings, delayed rejection, diagonal
//! MALA, the controllers and [`Chain`] need neither rayon nor nalgebra.
//!
//! | feature | what it adds | pulls in |
//! |---|---|---|
//! | `parallel` | the multi-chain render loop (`render_loop`) | rayon |
//! | `nalgebra` | full-covariance MALA (`langevin::FullOnline`, `ProposalGaussian::set_full`) | nalgebra |
//! | `testing` | the correctness harness (`testing`) and the toy targets (`toy`); implies `parallel` and `nalgebra` | proptest |

mod chain;
pub mod controller;
pub mod delayed_rejection;
mod error;
mod kernel;
pub mod langevin;
mod mh;
pub mod partition;
mod progress;
pub mod proposal;
#[cfg(feature = "parallel")]
pub mod render_loop;
pub mod seed;
pub mod special;
pub mod stats;
mod target;
#[cfg(feature = "testing")]
pub mod testing;
pub mod torus;
#[cfg(feature = "testing")]
pub mod toy;
pub mod tunable;

pub use chain::Chain;

/// The `rand` crate mcmc-core is built against, re-exported so users need not pin a version.
pub use rand;

/// The random number generator of every chain a render loop (`render_loop::RenderLoop`, feature
/// `parallel`) runs (PCG64, seeded from (seed, chain index)); re-exported so users need not
/// depend on `rand_pcg`.
pub type ChainRng = rand_pcg::Pcg64;
pub use controller::{Controller, NoAdaptation};
pub use delayed_rejection::{DelayedRejection, DrRule, Euclidean, NoGhost, StateArithmetic, Torus};
pub use error::McmcError;
pub use kernel::{
    accept_prob_from_log_ratio, mh_accept_prob, mh_log_accept_prob, Kernel, Observer, StepInfo,
    MAX_STAGES,
};
pub use mh::Mh;
pub use partition::Partition;
pub use progress::{NoProgress, Progress};
pub use proposal::{GaussianRandomWalk, Mixture, Proposal, Proposed};
pub use target::{
    finite_difference_gradient, DifferentiableTarget, FiniteDifference, Point, Sample, SampleOf,
    Target,
};
