//! Independent paths from every bidirectional strategy (one-sample MIS with the balance
//! heuristic): light subpath, eye subpath, a connection, and the exact combined density.

use rand::{Rng, RngExt};

use crate::error::PathspaceError;
use crate::lightside::{extend_light_walk, log_light_scatter_density};
use crate::path::{Path, Vertex};
use crate::sampler::{camera_vertex, extend_walk, log_scatter_density, IndependentSampler};
use crate::scene::PathScene;

/// Longest path [`BidirectionalSampler`] handles (edges): the density's per-strategy terms
/// live on the stack.
const MAX_SEGMENTS: usize = 64;

/// Parameters of [`BidirectionalSampler`].
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct BidirectionalSamplerParams {
    /// Paths have `1..=max_segments` edges, each length equally likely.
    pub max_segments: usize,
}

impl Default for BidirectionalSamplerParams {
    /// Up to 5 edges.
    fn default() -> Self {
        Self { max_segments: 5 }
    }
}

impl BidirectionalSamplerParams {
    /// Checks the parameters.
    ///
    /// # Errors
    /// [`PathspaceError::InvalidParameter`] for `max_segments` outside `1..=64`.
    pub fn validate(&self) -> Result<(), PathspaceError> {
        PathspaceError::check_range(
            "max_segments",
            self.max_segments as f64,
            1.0,
            MAX_SEGMENTS as f64,
        )
    }
}

/// A bidirectional path sampler (Veach 1997, chapter 10, as a one-sample estimator,
/// section 9.2.4) with an exact density: it reaches every path a bidirectional path tracer
/// reaches, and `f / p` is the balance-heuristic combination of all its strategies.
///
/// # Sampling
/// Choose the number of edges `n` uniformly in `1..=max_segments` (`k = n + 1` vertices), then
/// the strategy `t` uniformly in `1..=k` (`t` eye vertices, `s = k - t` light vertices):
/// trace an eye random walk of `t` vertices (camera ray, BSDF sampling; as
/// [`crate::UnidirectionalSampler`]), a light random walk of `s` vertices (an emitter point by
/// [`crate::Emitters::sample_emitter`], an emission direction by
/// [`crate::Emitters::sample_emission_direction`], then BSDF sampling with the light-side
/// direction as `wo`), and join them: `s = 0` needs the eye walk to end on an emitter; else
/// the two ends (both non-specular; the camera counts as non-specular) must see each other
/// (`t = 1` is light tracing: the end of the light walk joined to the pinhole, landing
/// wherever it lands on the image).
///
/// # Density
/// `p(x) = (1 / N) (1 / k) sum_{t=1}^{k} p_t(x)`, with `p_t = 0` if strategy `t` would join
/// through a specular vertex, else `p_t(x) = prod_{i<t-1} q_i^E(x)  prod_{j>=t} q_j^L(x)`: the
/// eye walk's densities ([`crate::UnidirectionalSampler`]'s `q_i`), the emitter's area
/// density, and the light walk's densities converted into [`Path`]'s measure (at a specular
/// vertex of the light walk, the Jacobian `J(x_j -> x_{j-1}) / J(x_j -> x_{j+1})
/// dω_{j+1} / dω_{j-1}` between the two walks' measures, [`crate::Bsdfs::specular_jacobian`]).
/// [`BidirectionalSampler::log_strategy_density`] is one `p_t`.
///
/// # Example
/// ```
/// use pathspace::analytic::AnalyticScene;
/// use pathspace::{BidirectionalSampler, BidirectionalSamplerParams, IndependentSampler, Path};
/// use rand::SeedableRng;
///
/// // In the furnace box every path of n <= 3 edges carries L_e rho^(n-1): E[f/p] = 1.75.
/// let scene = AnalyticScene::furnace_box(0.5, 1.0).unwrap();
/// let params = BidirectionalSamplerParams { max_segments: 3 };
/// let sampler = BidirectionalSampler::new(&scene, params).unwrap();
/// let mut rng = rand_pcg::Pcg64::seed_from_u64(1);
/// let mut path = Path::new();
/// let n = 20_000;
/// let mut sum = 0.0;
/// for _ in 0..n {
///     if sampler.sample(&mut rng, &mut path) {
///         sum += path.contribution(&scene).luminance() / sampler.log_density(&path).exp();
///     }
/// }
/// assert!((sum / n as f64 - 1.75).abs() < 0.05);
/// ```
#[derive(Debug)]
pub struct BidirectionalSampler<'a, S: ?Sized> {
    scene: &'a S,
    params: BidirectionalSamplerParams,
}

impl<S: ?Sized> Clone for BidirectionalSampler<'_, S> {
    fn clone(&self) -> Self {
        *self
    }
}

impl<S: ?Sized> Copy for BidirectionalSampler<'_, S> {}

impl<'a, S: PathScene + ?Sized> BidirectionalSampler<'a, S> {
    /// A sampler over `scene`.
    ///
    /// # Errors
    /// If the parameters are out of range (see [`BidirectionalSamplerParams::validate`]).
    pub fn new(scene: &'a S, params: BidirectionalSamplerParams) -> Result<Self, PathspaceError> {
        params.validate()?;
        Ok(Self { scene, params })
    }

    /// The parameters.
    #[must_use]
    pub fn params(&self) -> &BidirectionalSamplerParams {
        &self.params
    }

    /// True if strategy `t` (eye vertices) can produce `path` structurally: `t = k` (the eye
    /// walk hits the emitter), or both ends of the joining edge are non-specular.
    fn joinable(v: &[Vertex], t: usize) -> bool {
        t == v.len() || ((t == 1 || !v[t - 1].is_specular()) && !v[t].is_specular())
    }

    /// `ln p_t(path)`: the density of strategy `t` alone (`1 <= t <= k`: `t` eye vertices,
    /// `k - t` light vertices), w.r.t. [`Path`]'s measure, before the choice probabilities;
    /// `NEG_INFINITY` if it cannot produce the path (see the type's documentation).
    #[must_use]
    pub fn log_strategy_density(&self, path: &Path, t: usize) -> f64 {
        let v = &path.vertices;
        let k = v.len();
        if k < 2 || t == 0 || t > k || !Self::joinable(v, t) {
            return f64::NEG_INFINITY;
        }
        let eye: f64 = (0..t - 1)
            .map(|i| log_scatter_density(self.scene, v, i))
            .sum();
        if t == k {
            return eye;
        }
        let light: f64 = (t + 1..k)
            .map(|j| log_light_scatter_density(self.scene, v, j))
            .sum();
        eye + light + self.scene.emitter_pdf(&v[k - 1].point).ln()
    }

    /// Draws a path of `n` edges with strategy `t` (`1 <= t <= n + 1` eye vertices, the
    /// rest from the light) into `path`; false if the sample failed or the arguments are out
    /// of range. Its density is [`BidirectionalSampler::log_strategy_density`].
    pub fn sample_strategy<R: Rng + ?Sized>(
        &self,
        rng: &mut R,
        path: &mut Path,
        n: usize,
        t: usize,
    ) -> bool {
        let scene = self.scene;
        path.vertices.clear();
        let k = n + 1;
        if n == 0 || n > MAX_SEGMENTS || t == 0 || t > k {
            return false;
        }
        let s = k - t;
        path.vertices.push(camera_vertex(scene));
        for i in 0..t - 1 {
            if !extend_walk(scene, rng, path, i) {
                return false;
            }
        }
        if s == 0 {
            return scene.is_emitter(&path.vertices[k - 1].point) && path.raster(scene).is_some();
        }
        if t >= 2 && scene.is_specular(&path.vertices[t - 1].point) {
            return false;
        }
        let u = [rng.random(), rng.random(), rng.random()];
        let Some((light, pdf)) = scene.sample_emitter(u) else {
            return false;
        };
        if pdf.is_nan() || pdf <= 0.0 {
            return false;
        }
        path.vertices.push(Vertex {
            point: light,
            specular: None,
        });
        for _ in 1..s {
            if !extend_light_walk(scene, rng, path, t) {
                return false;
            }
        }
        if s >= 2 && scene.is_specular(&path.vertices[k - 1].point) {
            return false;
        }
        path.vertices[t..].reverse();
        let (a, b) = (path.vertices[t - 1].position(), path.vertices[t].position());
        scene.visible(a, b) && path.raster(scene).is_some()
    }
}

impl<S: PathScene + ?Sized> IndependentSampler for BidirectionalSampler<'_, S> {
    fn sample<R: Rng + ?Sized>(&self, rng: &mut R, path: &mut Path) -> bool {
        let n = rng.random_range(1..=self.params.max_segments);
        let t = rng.random_range(1..=n + 1);
        self.sample_strategy(rng, path, n, t)
    }

    fn log_density(&self, path: &Path) -> f64 {
        let v = &path.vertices;
        let k = v.len();
        let n = k.saturating_sub(1);
        if n == 0 || n > self.params.max_segments || path.raster(self.scene).is_none() {
            return f64::NEG_INFINITY;
        }
        // Prefix sums of the eye walk's log densities and suffix sums of the light walk's.
        let mut eye = [0.0f64; MAX_SEGMENTS + 2];
        for t in 1..k {
            eye[t + 1] = eye[t] + log_scatter_density(self.scene, v, t - 1);
        }
        let mut light = [0.0f64; MAX_SEGMENTS + 2];
        light[1] = self.scene.emitter_pdf(&v[k - 1].point).ln();
        for s in 1..k - 1 {
            light[s + 1] = light[s] + log_light_scatter_density(self.scene, v, k - s);
        }
        let (mut max, mut sum) = (f64::NEG_INFINITY, 0.0f64);
        for t in 1..=k {
            if !Self::joinable(v, t) {
                continue;
            }
            let term = eye[t] + light[k - t];
            if term.is_nan() || term == f64::NEG_INFINITY {
                continue;
            }
            if term > max {
                sum = sum * (max - term).exp() + 1.0;
                max = term;
            } else {
                sum += (term - max).exp();
            }
        }
        if max == f64::NEG_INFINITY {
            return max;
        }
        max + sum.ln() - (k as f64).ln() - (self.params.max_segments as f64).ln()
    }
}
