//! The differentiable path evaluator of Langevin MLT (Luan et al. 2020, section 6; the design
//! is described in `docs/methods/mala.md`): the contribution of ONE multiplexed-MLT strategy
//! `(s, t)` of a fixed depth as a function of the primary samples, written once over [`Real`]
//! so that it runs in `f64` (its reference value) and in forward-mode dual numbers ([`Dual`],
//! one lane per primary sample the path reads) for the gradient of MALA.
//!
//! # How it relates to the f32 renderer
//! It restates `bdpt::sample_strategy` (camera subpath, light subpath, connection, MIS weight)
//! with the same branches, and **replays the discrete decisions** through the renderer's own
//! f32 queries on the rounded values: which triangle a ray hits (the BVH stays f32), mutual
//! visibility, which light and which point-selection branch, which dielectric lobe, the
//! texture values (constants: texture lookups carry no derivative). Everything continuous is
//! recomputed in `T`: the camera ray from raster, lens and time (motion blur moves the camera
//! pose with time), re-intersection of the known triangle (positions and interpolated shading
//! normals carry derivatives), BSDF sampling warps and eval/pdf, the light point and emission
//! direction, the connection, and every density of the MIS weight. A visibility change is a
//! discontinuity the gradient ignores; MALA stays exact whatever the gradient's accuracy, as
//! long as forward and reverse moves use the same gradient function of the state.
//!
//! # Coverage
//! Area lights, Lambertian, GGX and smooth conductors, smooth dielectrics, base-colour
//! textures (bilinear, differentiated through the UVs), pinhole and thin-lens cameras with
//! motion, paths of depth <= 4 — every bundled scene. Environment and punctual lights,
//! emissive, metallic-roughness and normal-map textures and rough dielectrics are not
//! restated (vertex colours enter as constants):
//! [`Evaluation::Unsupported`], and the caller falls back to finite differences
//! (`mlt::mala::DifferentiableMmlt`).
//!
//! # Example
//! ```
//! use render::bdpt::diff::{evaluate_strategy, scene_supported, Evaluation};
//! use render::bdpt::MisHeuristic;
//! use render::glam::Vec2;
//! use render::Scene;
//!
//! let scene = Scene::cornell_box(16, 16);
//! assert!(scene_supported(&scene));
//! // Primary samples of a depth-1 path, three streams interleaved (camera, light, connection).
//! let values: Vec<f64> = (0..64).map(|i| ((i as f64) * 0.618_034).fract()).collect();
//! let e = evaluate_strategy::<f64>(
//!     &scene, 1, Vec2::new(16.0, 16.0), MisHeuristic::Power, &values, 3, [0; 3], |v, _| v,
//! );
//! assert!(!matches!(e, Evaluation::Unsupported));
//! ```

mod bsdf;
mod connect;
mod geometry;
mod path;
mod subpath;
mod texture;
mod vertex;

use glam::Vec2;

use crate::autodiff::{Real, V3};
use crate::bdpt::MisHeuristic;
use crate::scene::Scene;

pub use crate::autodiff::Dual;

/// What [`evaluate_strategy`] found.
#[derive(Clone, Copy, Debug)]
pub enum Evaluation<T> {
    /// The strategy's MIS-weighted RGB contribution times the number of strategies (as
    /// `bdpt::sample_strategy`), with its strategy and the numbers read per stream.
    Contribution {
        /// RGB contribution.
        rgb: V3<T>,
        /// Light-subpath vertices.
        s: usize,
        /// Camera-subpath vertices.
        t: usize,
        /// Numbers read per stream (camera, light, connection).
        reads: [usize; 3],
        /// A hash of the discrete decisions replayed (triangles hit, lights chosen, lobes):
        /// equal hashes mean the same path structure.
        decisions: u64,
    },
    /// No light (a subpath ended early, an occluded connection...), with the numbers read.
    Zero {
        /// Numbers read per stream.
        reads: [usize; 3],
    },
    /// The path meets something the evaluator does not restate, or needs more numbers than
    /// were given.
    Unsupported,
}

impl<T: Real> Evaluation<T> {
    /// The Rec. 709 luminance of the contribution (0 for [`Evaluation::Zero`]).
    #[must_use]
    pub fn luminance(&self) -> Option<T> {
        match self {
            Evaluation::Contribution { rgb, .. } => {
                Some(rgb.x * 0.2126 + rgb.y * 0.7152 + rgb.z * 0.0722)
            }
            Evaluation::Zero { .. } => Some(T::cst(0.0)),
            Evaluation::Unsupported => None,
        }
    }
}

/// True if every light, material and camera of `scene` is restated by the evaluator (area
/// lights only, no normal maps; rough dielectrics are detected per path).
#[must_use]
pub fn scene_supported(scene: &Scene) -> bool {
    let lights = scene.lights();
    lights.punctual().is_empty()
        && lights.environment_index().is_none()
        && !lights.lights().iter().any(|l| l.textured)
        && !scene
            .materials()
            .iter()
            .any(|m| m.normal_texture.is_some() || m.metallic_roughness_texture.is_some())
}

/// A scene the evaluator supports ([`scene_supported`], checked once here, not per path), with
/// its camera restated over [`Real`].
#[derive(Clone, Copy)]
pub struct DiffScene<'s> {
    ctx: path::Ctx<'s>,
}

impl std::fmt::Debug for DiffScene<'_> {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.debug_struct("DiffScene").finish_non_exhaustive()
    }
}

impl<'s> DiffScene<'s> {
    /// `scene` if the evaluator supports it.
    #[must_use]
    pub fn new(scene: &'s Scene) -> Option<Self> {
        scene_supported(scene).then(|| Self {
            ctx: path::Ctx {
                scene,
                camera: geometry::Camera::new(scene.camera().params()),
                constant_mis: false,
            },
        })
    }

    /// The same scene with the MIS weight of a strategy computed from the vertices' values
    /// and entering as a constant (`on`), or differentiated like everything else: the
    /// gradient then covers the contribution only, at a fraction of the cost (the MIS
    /// weight's densities are most of the replay's arithmetic).
    #[must_use]
    pub fn with_constant_mis(mut self, on: bool) -> Self {
        self.ctx.constant_mis = on;
        self
    }

    /// Evaluates the multiplexed-MLT strategy of `depth` selected by the primary samples
    /// `values` (interleaved over `streams` streams as `pss::PssState::raw_values`: stream
    /// `s`'s `k`-th number at `s + streams k`) for an image of `image_size` pixels. Number `k`
    /// of stream `s` becomes `make(value, lanes[s] + k)`: `|v, _| v` for `f64`,
    /// [`Dual::variable`] for the gradient with respect to the numbers in read order
    /// (`lanes` = the prefix sums of the read counts).
    #[allow(clippy::too_many_arguments)]
    pub fn evaluate<T: Real>(
        &self,
        depth: u32,
        image_size: Vec2,
        heuristic: MisHeuristic,
        values: &[f64],
        streams: usize,
        lanes: [usize; 3],
        make: fn(f64, usize) -> T,
    ) -> Evaluation<T> {
        self.evaluate_continuous(
            depth, image_size, heuristic, values, streams, lanes, [0; 3], make,
        )
    }

    /// [`DiffScene::evaluate`] with lanes for the *continuous* numbers only: bit `k` of
    /// `discrete[s]` marks number `k` of stream `s` as discrete (`pss::PssState::discrete_mask`);
    /// it becomes the constant `T::cst(value)` and takes no lane, and the continuous numbers
    /// of stream `s` take lanes `lanes[s], lanes[s] + 1, ...` in read order
    /// (`pss::langevin::PssCoordinates` order when `lanes` are the prefix sums of the
    /// continuous read counts). The forward-mode gradient then carries only the coordinates a
    /// Langevin step moves.
    #[allow(clippy::too_many_arguments)]
    pub fn evaluate_continuous<T: Real>(
        &self,
        depth: u32,
        image_size: Vec2,
        heuristic: MisHeuristic,
        values: &[f64],
        streams: usize,
        lanes: [usize; 3],
        discrete: [u64; 3],
        make: fn(f64, usize) -> T,
    ) -> Evaluation<T> {
        if streams == 0 {
            return Evaluation::Unsupported;
        }
        let mut u = path::Replay {
            values,
            streams,
            lanes,
            discrete,
            make,
            stream: 0,
            cursor: [0; 3],
            overrun: false,
            decisions: 0,
        };
        let r = self
            .ctx
            .sample_strategy(&mut u, depth as usize, image_size, heuristic);
        if u.overrun {
            return Evaluation::Unsupported;
        }
        let reads = u.cursor;
        match r {
            Ok((rgb, s, t)) => Evaluation::Contribution {
                rgb,
                s,
                t,
                reads,
                decisions: u.decisions,
            },
            Err(path::Stop::Zero) => Evaluation::Zero { reads },
            Err(path::Stop::Unsupported) => Evaluation::Unsupported,
        }
    }
}

/// [`DiffScene::evaluate`] for a scene checked on every call (tests, one-off evaluations; a
/// sampler evaluating many paths keeps a [`DiffScene`]).
#[allow(clippy::too_many_arguments)]
pub fn evaluate_strategy<T: Real>(
    scene: &Scene,
    depth: u32,
    image_size: Vec2,
    heuristic: MisHeuristic,
    values: &[f64],
    streams: usize,
    lanes: [usize; 3],
    make: fn(f64, usize) -> T,
) -> Evaluation<T> {
    DiffScene::new(scene).map_or(Evaluation::Unsupported, |d| {
        d.evaluate(depth, image_size, heuristic, values, streams, lanes, make)
    })
}
