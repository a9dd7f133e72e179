//! Primary sample space (PSS) for Metropolis light transport.
//!
//! A path generator (path tracer, BDPT) is a deterministic function of the uniform random
//! numbers it consumes; Kelemen et al. 2002 run the Markov chain on those numbers instead of
//! on paths. This crate provides the PSS state ([`PssState`]: lazily grown, with separate
//! streams and cheap copies), the mutations as `mcmc_core` proposals with exact densities
//! ([`SmallStep`] with Kelemen's exponential or a Gaussian kernel, [`LargeStep`], and their
//! mixture [`PssmltProposal`] whose large-step probability a controller may tune).
//!
//! # Example
//! ```
//! use mcmc_core::{Chain, Mh, NoAdaptation, Target};
//! use pss::{KelemenParams, PssState, PssmltProposal, SmallMutation, SmallStep};
//! use rand::SeedableRng;
//!
//! /// A toy "path": the first two primary samples, density 1 + 8 u0 u1.
//! struct Toy;
//! impl Target for Toy {
//!     type State = PssState;
//!     type Payload = ();
//!     fn evaluate(&self, x: &mut PssState, _: &mut ()) -> f64 {
//!         x.begin();
//!         let (a, b) = (x.next_sample(), x.next_sample());
//!         (1.0 + 8.0 * a * b).ln()
//!     }
//! }
//!
//! let small = SmallStep::new(SmallMutation::kelemen(KelemenParams::kelemen2002()).unwrap());
//! let kernel = Mh::new(PssmltProposal::new(small, 0.3).unwrap());
//! let rng = rand_pcg::Pcg64::seed_from_u64(1);
//! let mut chain = Chain::new(&Toy, kernel, NoAdaptation, rng, PssState::new(1, 7)).unwrap();
//! chain.run(1000, &mut ()).unwrap();
//! ```

mod error;
mod fresh;
mod mutation;
pub mod noise;
mod proposal;
mod state;
#[cfg(feature = "testing")]
pub mod testing;

pub use error::PssError;
pub use fresh::FreshPss;
pub use mutation::{standard_normal_quantile, wrap, KelemenParams, SmallMutation};
pub use proposal::{LargeStep, PssmltProposal, SmallStep, ALL_STREAMS};
pub use state::{Pending, PssState, MAX_STREAMS};
