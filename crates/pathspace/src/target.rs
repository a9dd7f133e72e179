//! The path-space MLT target: `pi(x) = luminance(f(x))` over [`Path`] states.

use mcmc_core::Target;

use crate::path::Path;
use crate::scene::PathScene;
use crate::vec3::Rgb;

/// What evaluating a path produces besides its density: where and what it splats.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct PathContribution {
    /// Raster position in `[0, 1)^2` (meaningful only if the density is nonzero).
    pub raster: [f64; 2],
    /// The measurement contribution `f(x)` (RGB).
    pub rgb: Rgb,
}

/// The target of path-space MLT (regional-adaptive paper, section 3.2): the scalar
/// contribution `pi(x) = l(f(x))` with `l` the Rec. 709 luminance, with respect to [`Path`]'s
/// measure. The payload carries the raster position and the RGB `f(x)`; an MLT estimate of a
/// pixel is `b / N sum_i h_j(x_i) f(x_i) / pi(x_i)` with `b = int pi dmu`.
///
/// # Example
/// ```
/// use mcmc_core::Sample;
/// use pathspace::analytic::AnalyticScene;
/// use pathspace::{IndependentSampler, Path, PathTarget, UnidirectionalParams, UnidirectionalSampler};
/// use rand::SeedableRng;
///
/// let scene = AnalyticScene::furnace_box(0.5, 2.0).unwrap();
/// let sampler = UnidirectionalSampler::new(&scene, UnidirectionalParams::default()).unwrap();
/// let mut rng = rand_pcg::Pcg64::seed_from_u64(4);
/// let mut x = Path::new();
/// while !sampler.sample(&mut rng, &mut x) {}
/// let sample = Sample::evaluate(&PathTarget::new(&scene), x);
/// assert!(sample.log_density.is_finite());
/// assert!((0.0..1.0).contains(&sample.payload.raster[0]));
/// ```
#[derive(Debug)]
pub struct PathTarget<'a, S: ?Sized> {
    scene: &'a S,
}

impl<S: ?Sized> Clone for PathTarget<'_, S> {
    fn clone(&self) -> Self {
        *self
    }
}

impl<S: ?Sized> Copy for PathTarget<'_, S> {}

impl<'a, S: PathScene + ?Sized> PathTarget<'a, S> {
    /// The target over `scene`.
    pub fn new(scene: &'a S) -> Self {
        Self { scene }
    }

    /// The scene.
    #[must_use]
    pub fn scene(&self) -> &'a S {
        self.scene
    }
}

impl<S: PathScene + ?Sized> Target for PathTarget<'_, S> {
    type State = Path;
    type Payload = PathContribution;

    fn evaluate(&self, x: &mut Path, payload: &mut PathContribution) -> f64 {
        let Some(raster) = x.raster(self.scene) else {
            *payload = PathContribution::default();
            return f64::NEG_INFINITY;
        };
        let rgb = x.contribution(self.scene);
        *payload = PathContribution { raster, rgb };
        let y = rgb.luminance();
        if y > 0.0 {
            y.ln()
        } else {
            f64::NEG_INFINITY
        }
    }
}
