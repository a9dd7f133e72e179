//! Test adaptors, read-set toy targets and negative controls for PSS kernels (feature `testing`).
//!
//! What a renderer author needs to run the `mcmc-core` correctness harness
//! ([`mcmc_core::testing`]) on primary-sample-space kernels:
//!
//! - **Adaptors.** [`OnPss`] evaluates a fixed-dimension toy target of
//!   [`mcmc_core::toy`] on the first `d` primary samples of a [`PssState`](crate::PssState);
//!   [`Eager`] wraps a PSS proposal so that its candidate is fully materialised in `propose`
//!   (what the pairwise checks need, and the reference of lazy-versus-eager tests).
//! - **Targets whose read set depends on the state** ([`Stripes`], [`RoulettePath`],
//!   [`LobeChoice`], which also has discrete numbers whose set depends on the state): the
//!   case of path tracers with Russian roulette, varying path length and MMLT strategies,
//!   where lazy mutation has to be careful (a coordinate the current state has not read for a
//!   while must not be re-drawn at every proposal). Each has an exact sampler of fully
//!   materialised states and exact bins ([`ExactPssTarget`]), so the stationarity test from
//!   exact starts ([`pss_stationarity_test`]) and the splat-weight check
//!   ([`pss_splat_weight_test`]) apply directly.
//! - **Negative controls** ([`RegionalGaussian`] with its Hastings term is correct; wrapped in
//!   [`mcmc_core::testing::TreatedAsSymmetric`] it is not; [`ClampedKelemen`] never crosses
//!   the torus seam): PSS proposals that must *fail* the harness, so tests show they can.
//!
//! # Example
//! ```
//! use mcmc_core::testing::StationarityParams;
//! use mcmc_core::Mh;
//! use pss::testing::{pss_stationarity_test, Stripes};
//! use pss::{KelemenParams, SmallMutation, SmallStep};
//!
//! let target = Stripes::default();
//! let small = SmallMutation::kelemen(KelemenParams::kelemen2002()).unwrap();
//! let kernel = Mh::new(SmallStep::new(small));
//! let report = pss_stationarity_test(&target, &kernel, &StationarityParams::new(2000, 10, 1));
//! assert!(report.p_value.is_finite());
//! ```

mod broken;
mod eager;
mod exact;
mod lobes;
mod on_pss;
mod roulette;
mod stripes;

pub use broken::{BlindPssCoordinates, Blindness, ClampedKelemen, RegionalGaussian};
pub use eager::Eager;
pub use exact::{
    exact_sampler_test, pss_splat_weight_test, pss_stationarity_test, ExactPssTarget, PssBins,
};
pub use lobes::LobeChoice;
pub use on_pss::{OnPss, MAX_FIXED_DIM};
pub use roulette::RoulettePath;
pub use stripes::Stripes;
