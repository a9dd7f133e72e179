//! chainlight's reference renderer: glTF scenes, an obvhs BVH, materials, cameras, lights,
//! independent samplers and path tracing, a deterministic film, and EXR/PNG output.
//!
//! Every integrator draws its random numbers through [`sampler::Sampler`], so the same path
//! construction code runs under an independent sampler (PT, BDPT) and under primary-sample-space
//! Markov chains (PSSMLT, MMLT, DRMLT, MALA).

pub mod bdpt;
pub mod budget;
pub mod bvh;
pub mod camera;
pub mod error;
pub mod film;
pub mod frame;
pub mod image;
pub mod image_io;
pub mod integrator;
pub mod light;
pub mod material;
pub mod mesh;
pub mod metrics;
pub mod mlt;
pub mod sampler;
pub mod scene;
pub mod session;
pub mod warp;
