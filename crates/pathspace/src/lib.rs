//! Path-space Metropolis light transport: the path model, the scene traits it needs, and the
//! mutations of Veach and Guibas (1997) as used by the regional-adaptive MLT paper (Otsu et
//! al. 2018, sections 3-4 and 8.1).
//!
//! - [`Path`] / [`Vertex`]: `x_1` on the camera, `x_k` on an emitter; specular flags that say
//!   reflection or refraction; the measure (area, with the vertex after a specular one
//!   determined) and the measurement contribution [`Path::contribution`].
//! - Scene traits ([`RayTracer`], [`Bsdfs`], [`Emitters`], [`Camera`], together
//!   [`PathScene`]; [`IndependentSampler`] for a whole new path with its density), which a
//!   renderer implements; [`analytic::AnalyticScene`] implements them in f64 for tests.
//! - [`PathTarget`]: the MLT target `pi = luminance(f)` for mcmc-core's kernels.
//! - Mutations, each an mcmc-core [`mcmc_core::Proposal`] with its exact transition density:
//!   [`IndependenceMutation`] (regenerate the path, e.g. from a [`BidirectionalSampler`] that
//!   reaches every path a bidirectional path tracer reaches), [`BidirectionalMutation`]
//!   (delete a subpath and regenerate it from the eye side, the light side or both),
//!   [`Perturbation`] (lens and multi-chain, with a state-dependent angular scale from a
//!   [`ScaleSource`]), [`perturb::CausticPerturbation`], and their combination
//!   [`ra_mixture`] (section 8.1; [`PerturbOrGlobalPair`] splits the global move in two).
//!
//! The method page is `docs/methods/pathspace-mlt.md`.
//!
//! # Example
//! Path-space MLT on the white furnace box, with the lens perturbation and the independence
//! mutation mixed as in the paper:
//! ```
//! use mcmc_core::{Chain, Mh, NoAdaptation};
//! use pathspace::analytic::AnalyticScene;
//! use pathspace::{
//!     ra_mixture, FixedScale, IndependenceMutation, IndependentSampler, Path, PathTarget,
//!     Perturbation, PerturbationKind, UnidirectionalParams, UnidirectionalSampler,
//! };
//! use rand::SeedableRng;
//!
//! let scene = AnalyticScene::furnace_box(0.5, 1.0).unwrap();
//! let sampler = UnidirectionalSampler::new(&scene, UnidirectionalParams::default()).unwrap();
//! let mutation = ra_mixture(
//!     PerturbationKind::Lens,
//!     Perturbation::lens(&scene, FixedScale::uniform(0.1)),
//!     IndependenceMutation::new(sampler),
//! )
//! .unwrap();
//! let target = PathTarget::new(&scene);
//! let mut rng = rand_pcg::Pcg64::seed_from_u64(1);
//! let mut start = Path::new();
//! while !sampler.sample(&mut rng, &mut start) {}
//! let mut chain = Chain::new(&target, Mh::new(mutation), NoAdaptation, rng, start).unwrap();
//! chain.run(1000, &mut ()).unwrap();
//! assert!(chain.stats().acceptance_rate() > 0.2);
//! ```

pub mod analytic;
mod bidir_sampler;
mod bidirectional;
mod combine;
mod error;
mod independence;
mod lightside;
mod path;
pub mod perturb;
pub mod regional;
mod sampler;
mod scene;
mod target;
mod vec3;

pub use bidir_sampler::{BidirectionalSampler, BidirectionalSamplerParams};
pub use bidirectional::{BidirectionalMutation, BidirectionalParams};
pub use combine::{ra_mixture, PathMutation, PerturbOrGlobal, PerturbOrGlobalPair};
pub use error::PathspaceError;
pub use independence::IndependenceMutation;
pub use path::{direction, geometry_term, solid_angle_to_area, Path, Vertex};
pub use perturb::{
    eye_subpath_end, FixedScale, Perturbation, PerturbationKind, ScaleSource,
    TruncatedNormalDirection,
};
pub use sampler::{IndependentSampler, UnidirectionalParams, UnidirectionalSampler};
pub use scene::{
    BsdfSample, Bsdfs, Camera, Emitters, PathScene, RayTracer, SpecularLobe, SurfacePoint,
};
pub use target::{PathContribution, PathTarget};
pub use vec3::{Rgb, Vec3};
