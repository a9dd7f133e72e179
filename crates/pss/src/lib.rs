//! Primary sample space (PSS) for Metropolis light transport.
//!
//! A path generator (path tracer, BDPT) is a deterministic function of the uniform random
//! numbers it consumes; Kelemen et al. 2002 run the Markov chain on those numbers instead of
//! on paths. This crate provides the PSS state ([`PssState`]: lazily grown, with separate
//! streams and cheap copies), the mutations as `mcmc_core` proposals with exact densities
//! ([`SmallStep`] with Kelemen's exponential or a Gaussian kernel, [`LargeStep`], and their
//! mixture [`PssmltProposal`] whose large-step probability a controller may tune; optionally
//! with [`RasterStep`]s, an image-plane mutation after LuxCore's, [`RasterParams`]).
//!
//! [`FreshPss`] supplies independent points to `mcmc_core::render_loop`, so a renderer that
//! implements one `mcmc_core::Target` over [`PssState`] gets PSSMLT with bootstrap, chain
//! starts, deterministic multi-chain jobs, expected-value splatting and adaptive control; and
//! with the kernels of [`dr`] it gets delayed-rejection MLT (on a [`PairLayout`] of what it
//! reads), and of [`mala`], if it also implements `mcmc_core::DifferentiableTarget`, Langevin
//! MLT.
//!
//! Lazy mutation is exact, rejections included: see [`PssState`] ("Why lazy equals eager").
//!
//! # Example
//!
//! The whole outside-user program (`examples/pss_custom_target.rs`; run it with
//! `cargo run --release -p pss --example pss_custom_target`): an analytic integrand rendered to
//! a small image with PSSMLT and automatic large-step control, with DR orbital and with MALA.
//! (Compiled here; its convergence tests run with the workspace tests.)
//!
#![doc = concat!("```rust,no_run\n", include_str!("../examples/pss_custom_target.rs"), "\n```")]

pub mod dr;
mod error;
mod fresh;
pub mod langevin;
pub mod lazy_pairs;
pub mod mala;
mod mutation;
pub mod noise;
mod on_layout;
pub mod orbital;
mod pairwise;
mod per_coordinate;
mod proposal;
mod raster;
mod state;
#[cfg(feature = "testing")]
pub mod testing;

pub use error::PssError;
pub use fresh::FreshPss;
pub use lazy_pairs::{LazyOrbital, LazyPairParams, LazyPairwise, PairDraws};
pub use mcmc_core::delayed_rejection::{WrappedCauchy, RIOUX_LAVOIE2020_RHO};
pub use mutation::{standard_normal_quantile, wrap, KelemenParams, SmallMutation};
pub use on_layout::{LayoutGhost, LogQPair, OnLayout, PairwiseMltProposal};
pub use orbital::Orbital;
pub use pairwise::{
    torus_displacement, Group, PairLayout, PairwiseKelemen, PairwiseKelemenParams,
    DRMLT2020_RADIUS_SCALE,
};
pub use proposal::{LargeStep, PssmltProposal, SmallStep, ALL_STREAMS};
pub use raster::{RasterParams, RasterStep, RASTER_DEFAULT_PROBABILITY};
pub use state::{Pending, PssState, MAX_STREAMS, TAGGED_READS};
