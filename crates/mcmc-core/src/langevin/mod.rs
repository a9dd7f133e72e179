//! Langevin Monte Carlo: the Metropolis-adjusted Langevin algorithm (MALA) with online,
//! cache-driven and hybrid adaptation (Luan et al. 2020, "Langevin Monte Carlo Rendering with
//! Gradient-based Adaptation", sections 4-7, Alg. 1-4), and the
//! "cheap-then-expensive" delayed-rejection kernel with a MALA second stage (DR paper,
//! section 5.2).
//!
//! The parts follow the crate's separation: [`LangevinParams`] (configuration with the
//! paper's and the authors' code's presets), [`Adaptation`] (how to learn: [`Plain`],
//! [`Online`], `FullOnline` (feature `nalgebra`), [`CacheDriven`], [`Hybrid`]; the adaptation state and the
//! Gaussian it implies at a point), [`LangevinSpace`] (the coordinates moved, Euclidean or
//! torus), and the kernels [`Langevin`] and [`CheapThenExpensive`] (how to decide). A
//! [`GradientCache`] (a k-d tree with a bounded K-nearest-within-radius query) backs the
//! cache-driven adaptations; [`CacheSharing`] shares it among a render loop's chains.
//! docs/methods/mala.md derives the reverse density and lists the departures from the paper.
//!
//! # Example
//! ```
//! use mcmc_core::langevin::{Hybrid, Langevin, LangevinParams};
//! use mcmc_core::toy::Ridge;
//! use mcmc_core::{Chain, Euclidean, NoAdaptation};
//! use rand::SeedableRng;
//!
//! let target = Ridge::thin();
//! let params = LangevinParams { epsilon: 0.05, cache_size: 500, ..LangevinParams::luan2020() };
//! let kernel = Langevin::new(params, Hybrid::new(&params), Euclidean).unwrap();
//! let mut chain = Chain::new(&target, kernel, NoAdaptation, rand_pcg::Pcg64::seed_from_u64(2), vec![0.0, 0.0]).unwrap();
//! chain.run(3000, &mut ()).unwrap();
//! // The hybrid switched to its frozen cache after 500 distinct states.
//! assert!(!chain.kernel().adaptation.is_online());
//! ```

mod adaptation;
pub mod cache;
mod cache_view;
mod cheap_then_expensive;
#[cfg(feature = "nalgebra")]
mod full_online;
mod gaussian;
mod kernel;
mod params;
mod sharing;
mod space;

pub use adaptation::{Adaptation, AnyAdaptation, CacheDriven, Hybrid, Online, PerDimension, Plain};
pub use cache::{GradientCache, Neighbour, Neighbours};
pub use cache_view::{CacheView, PooledCache};
pub use cheap_then_expensive::CheapThenExpensive;
#[cfg(feature = "nalgebra")]
pub use full_online::FullOnline;
pub use gaussian::ProposalGaussian;
pub use kernel::{
    HasGradientCache, Langevin, NoMove, FALLBACK_COMPONENT, LARGE_STEP_COMPONENT, MALA_COMPONENT,
};
pub use params::{AdamStart, Covariance, LangevinParams};
pub use sharing::CacheSharing;
pub use space::LangevinSpace;
