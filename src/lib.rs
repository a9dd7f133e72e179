//! chainlight: composable Markov chain Monte Carlo light transport. This facade re-exports the
//! workspace's crates, so one dependency gives all of them at matching versions.
//!
//! | crate | what it holds |
//! |---|---|
//! | [`mcmc_core`] | targets, proposals, kernels, controllers, chain statistics, the generic MCMC render loop, toy targets, the `testing` harness |
//! | [`pss`] | primary sample space: the lazy PSS state and the Kelemen / Gaussian / large-step mutations |
//! | [`pathspace`] | path-space perturbations and partitions |
//! | [`lqmc`] | rank-1 lattices and local quasi-Monte Carlo |
//! | [`render`] | the reference renderer: scenes, BVH, materials, PT / BDPT, film, EXR/PNG, the MCMC integrators |
//!
//! The paper examples' harness and the HTML report of `chainlight report` live in the
//! workspace's `experiments` package (not published).
//!
//! # Example
//! ```
//! use std::sync::atomic::AtomicBool;
//!
//! use chainlight::render::methods::PssmltSettings;
//! use chainlight::render::{render, Budget, NoProgress, RenderSettings, Scene};
//!
//! // Kelemen et al. 2002's PSSMLT, a paper preset, with 16 chains.
//! let settings = RenderSettings {
//!     width: 8,
//!     height: 8,
//!     method: PssmltSettings::kelemen2002().into(),
//!     budget: Budget::SamplesPerPixel(4),
//!     ..RenderSettings::default()
//! };
//! let settings = RenderSettings {
//!     method: settings.method.with_chains(16, 10_000),
//!     ..settings
//! };
//! let out = render(&Scene::cornell_box(8, 8), &settings, &NoProgress, &AtomicBool::new(false))
//!     .unwrap();
//! assert!(out.image.mean_luminance() > 0.0);
//! ```

/// Local quasi-Monte Carlo: rank-1 lattices.
pub use lqmc;
/// State-space-agnostic MCMC and the generic render loop.
pub use mcmc_core;
/// Path-space perturbations and partitions.
pub use pathspace;
/// Primary sample space.
pub use pss;
/// The reference renderer.
pub use render;
