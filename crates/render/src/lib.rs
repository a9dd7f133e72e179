//! chainlight's reference renderer: glTF scenes, an obvhs BVH, materials, cameras, lights,
//! independent samplers, path tracing and BDPT, the MCMC integrators (PSSMLT, MMLT) over
//! mcmc-core's render loop, a deterministic film, and EXR/PNG output.
//!
//! Every integrator draws its random numbers through [`Sampler`], so the same path
//! construction code runs under an independent sampler (PT, BDPT) and under primary-sample-space
//! Markov chains (PSSMLT, MMLT, DRMLT, MALA). The integrators are listed once, in
//! [`INTEGRATORS`]; the command line and its tests are built from that table.
//!
//! Layers (a module imports only from layers below it):
//!
//! | layer | modules |
//! |---|---|
//! | entry point | [`session`]: common settings, validation, the method's render function |
//! | methods | [`methods`]: one module per integrator family (settings, paper presets, render function), the integrator table |
//! | drivers | [`integrator::pt_driver`], [`bdpt::render_bdpt`], [`mlt`] |
//! | integrators | [`integrator::pt`], [`bdpt`] (subpaths, connections, MIS) |
//! | scene | [`scene`], [`camera`], [`light`], [`material`], [`bvh`], [`mesh`] |
//! | foundations | [`autodiff`], [`sampler`], [`film`], [`image`], [`image_io`], [`files`], [`metrics`], [`budget`], [`frame`], [`warp`], [`error`] |
//!
//! # Example
//! ```
//! use std::sync::atomic::AtomicBool;
//!
//! use render::methods::BdptSettings;
//! use render::{render, Budget, NoProgress, RenderSettings, Scene};
//!
//! let settings = RenderSettings {
//!     width: 16,
//!     height: 16,
//!     method: BdptSettings::default().into(),
//!     budget: Budget::SamplesPerPixel(2),
//!     ..RenderSettings::default()
//! };
//! let scene = Scene::cornell_box(16, 16);
//! let cancel = AtomicBool::new(false); // set it (e.g. from a Ctrl-C handler) to stop early
//! let out = render(&scene, &settings, &NoProgress, &cancel).unwrap();
//! assert!(!out.cancelled && out.image.mean_luminance() > 0.0);
//! ```

pub mod autodiff;
pub mod bdpt;
pub mod budget;
pub mod bundled;
pub mod bvh;
pub mod camera;
pub mod error;
pub mod files;
pub mod film;
pub mod frame;
pub mod image;
pub mod image_io;
pub mod integrator;
pub mod light;
pub mod material;
pub mod mesh;
pub mod methods;
pub mod metrics;
pub mod mlt;
pub mod pathspace_scene;
pub mod sampler;
pub mod scene;
pub mod session;
pub mod shard;
#[cfg(test)]
mod test_util;
pub mod warp;

pub use bdpt::{render_bdpt, BdptOutput, BdptParams};
pub use budget::Budget;
pub use camera::Camera;
pub use error::RenderError;
pub use film::{Film, FilmTile, Filter};
/// The vector maths crate of the public API (positions, colours), re-exported.
pub use glam;
pub use image::Image;
pub use integrator::pt_driver::{render_pt, PtDriverSettings, PtOutput};
pub use material::{Bsdf, TransportMode};
pub use mesh::Mesh;
pub use methods::{
    IntegratorInfo, IntegratorKind, McmcStats, Method, MethodSettings, RenderOutput,
    RenderSettings, INTEGRATORS,
};
pub use sampler::{IndependentSampler, Sampler, Stream};
pub use scene::{CameraSpec, Material, Scene};
pub use session::{render, render_cornell_box, NoProgress, Progress};
