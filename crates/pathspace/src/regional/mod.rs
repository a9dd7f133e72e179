//! Regional adaptive path perturbations (Otsu et al. 2018, "Regional Adaptive Metropolis
//! Light Transport"): partitions of path space on canonical coordinates (sections 5.4, 6),
//! per-region angular scales (section 5.2) and their adaptation by Alg. 1 with statistics
//! shared by all chains at the render loop's synchronisation points (section 7).
//!
//! - [`PlanePartition`] / [`Quadtree`]: an `N x N` grid or a refinable quadtree over
//!   `[0, 1)^2` (section 6.1-6.2).
//! - [`ScreenPartition`] (2-D, lens: the raster position of the primary ray),
//!   [`DirectionPartition`] (4-D, multi-chain: an `N_top` screen grid whose cells each hold a
//!   plane partition of the cylindrical coordinates of the direction leaving the first
//!   non-specular vertex, section 6.3) and [`PathPartition`] (either, or one region), all
//!   mcmc-core [`mcmc_core::Partition`]s over [`crate::Path`].
//! - [`RegionalSigmas`] / [`SharedSigmas`]: `lambda_k = log sigma_k^2` per region as a
//!   [`crate::ScaleSource`] for [`crate::Perturbation`] (the reverse density uses the
//!   proposed state's region).
//! - [`SharedRegionalAdaptation`] / [`PooledRegionalStats`]: Alg. 1 pooled over chains in
//!   job order (bit-identical images for any thread count), quadtree refinement at the
//!   synchronisation points; [`RegionalAdaptParams::otsu2018`] holds the paper's values.
//!
//! The method page is `docs/methods/regional-adaptive.md`.
//!
//! # Example
//! Regional-adaptive lens perturbation on a screen quadtree, mixed with the independence
//! mutation (section 8.1), one chain synchronised by hand (mcmc-core's `RenderLoop` does this
//! for many chains):
//! ```
//! use mcmc_core::render_loop::SharedController;
//! use mcmc_core::{Chain, Mh};
//! use pathspace::analytic::AnalyticScene;
//! use pathspace::regional::{
//!     PathPartition, PlanePartition, PooledRegionalStats, RegionalAdaptParams, RegionalSigmas,
//!     ScreenPartition, SharedRegionalAdaptation, SharedSigmas,
//! };
//! use pathspace::{
//!     ra_mixture, IndependenceMutation, IndependentSampler, Path, PathTarget, Perturbation,
//!     PerturbationKind, UnidirectionalParams, UnidirectionalSampler,
//! };
//! use rand::SeedableRng;
//!
//! let scene = AnalyticScene::furnace_box(0.5, 1.0).unwrap();
//! let sampler = UnidirectionalSampler::new(&scene, UnidirectionalParams::default()).unwrap();
//! let partition = PathPartition::Screen(ScreenPartition::new(
//!     &scene,
//!     PlanePartition::quadtree(6).unwrap(),
//! ));
//! let params = RegionalAdaptParams {
//!     split_after_visits: Some(500),
//!     refine_every: 2000,
//!     ..RegionalAdaptParams::otsu2018()
//! };
//! let sigmas = SharedSigmas::new(RegionalSigmas::new(partition, params.adapt.lambda_initial, 1.0).unwrap());
//! let kernel = Mh::new(
//!     ra_mixture(
//!         PerturbationKind::Lens,
//!         Perturbation::lens(&scene, sigmas),
//!         IndependenceMutation::new(sampler),
//!     )
//!     .unwrap(),
//! );
//! let target = PathTarget::new(&scene);
//! let mut rng = rand_pcg::Pcg64::seed_from_u64(1);
//! let mut start = Path::new();
//! while !sampler.sample(&mut rng, &mut start) {}
//! let controller = SharedRegionalAdaptation::new(params).unwrap();
//! let mut chain = Chain::new(&target, kernel, controller, rng, start).unwrap();
//! let mut pooled = PooledRegionalStats::default();
//! for _round in 0..5 {
//!     chain.run(1000, &mut ()).unwrap();
//!     let (kernel, controller) = chain.kernel_and_controller_mut();
//!     controller.contribute(kernel, &mut pooled);
//!     pooled.end_round();
//!     controller.receive(kernel, &pooled);
//! }
//! assert_eq!(pooled.mutations(), 5000);
//! assert!(pooled.refinements() >= 2 && pooled.num_regions() > 1);
//! // Adaptation moved the scales away from the paper's (deliberately large) lambda_0 = 1.
//! assert!(pooled.sigmas().unwrap().get().lambdas().iter().any(|&l| l < -1.0));
//! ```

mod controller;
mod partition;
mod plane;
mod sigmas;

pub use controller::{
    PooledRegionalStats, RegionalAdaptParams, RegionalUpdateRule, SharedRegionalAdaptation,
    MAX_VISITS_PER_ROUND,
};
pub use partition::{
    canonical_4d, cylindrical, first_nonspecular_direction, screen_coordinates, DirectionPartition,
    PathPartition, ScreenPartition,
};
pub use plane::{PlanePartition, Quadtree, MAX_GRID_CELLS, MAX_QUADTREE_DEPTH};
pub use sigmas::{HasSharedSigmas, RegionalSigmas, SharedSigmas};
