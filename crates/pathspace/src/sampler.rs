//! Independent path sampling with an exact density: the scene trait for a whole new path
//! and a generic unidirectional implementation (camera random walk, ending by BSDF sampling
//! or by a connection to a sampled emitter point).

use rand::{Rng, RngExt};

use crate::error::PathspaceError;
use crate::path::{direction, solid_angle_to_area, Path, Vertex};
use crate::scene::{PathScene, SurfacePoint};

/// A source of independent paths with their exact density (with respect to [`Path`]'s
/// measure): what the independence mutation draws from. A renderer may implement it with its
/// bidirectional path tracer (the combined density of all its strategies);
/// [`UnidirectionalSampler`] implements it for any [`PathScene`].
pub trait IndependentSampler {
    /// Draws a path into `path` (overwriting it). Returns false if the sample failed
    /// (absorbed, missed the scene, blocked connection): the density below is a
    /// sub-probability density and failures carry the missing mass.
    fn sample<R: Rng + ?Sized>(&self, rng: &mut R, path: &mut Path) -> bool;

    /// `ln p(x)`: the density with which [`IndependentSampler::sample`] produces `path`
    /// (`NEG_INFINITY` if it cannot).
    fn log_density(&self, path: &Path) -> f64;
}

/// Parameters of [`UnidirectionalSampler`].
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct UnidirectionalParams {
    /// Paths have `1..=max_segments` edges, each length equally likely.
    pub max_segments: usize,
    /// Probability of ending a path of two or more edges with a connection to a sampled
    /// emitter point (next-event estimation) rather than by BSDF sampling.
    pub connect_probability: f64,
}

impl Default for UnidirectionalParams {
    /// Up to 5 edges, connection probability 1/2.
    fn default() -> Self {
        Self {
            max_segments: 5,
            connect_probability: 0.5,
        }
    }
}

impl UnidirectionalParams {
    /// Checks the parameters.
    ///
    /// # Errors
    /// [`PathspaceError::InvalidParameter`] for `max_segments` outside `1..=64` or a
    /// connection probability outside `[0, 1]`.
    pub fn validate(&self) -> Result<(), PathspaceError> {
        PathspaceError::check_range("max_segments", self.max_segments as f64, 1.0, 64.0)?;
        PathspaceError::check_range("connect_probability", self.connect_probability, 0.0, 1.0)
    }
}

/// A length-first unidirectional path sampler with an exact, cheap density.
///
/// To draw a path: choose the number of edges `n` uniformly in `1..=max_segments`; choose the
/// technique: with probability `c = connect_probability` (only for `n >= 2`) *connect*, else
/// *hit*. Trace a camera random walk (raster uniform, then BSDF sampling; specular lobes chosen
/// with their probability) for `n` edges (hit: the last vertex must lie on an emitter) or for
/// `n - 1` edges and connect to an emitter point sampled by area (connect: the last walk vertex
/// must be non-specular, the connection unoccluded).
///
/// Its density is the sum over the two techniques that can produce `x`:
///
/// `p(x) = (1 / N) [ (1 - c_n) p_hit(x) + c_n p_connect(x) ]`, with `c_1 = 0`, `c_n = c`,
///
/// `p_hit(x) = p_cam(w_1) J_2 prod_{i=2}^{k-1} q_i`, where `J_j = |cos θ_j| / r^2` converts
/// solid angle at `x_{j-1}` to area at `x_j` and `q_i` is `p_bsdf(w_i) J_{i+1}` at a
/// non-specular vertex or the lobe probability at a specular one;
/// `p_connect(x) = p_cam(w_1) J_2 prod_{i=2}^{k-2} q_i  p_light(x_k)` (zero if `x_{k-1}` is
/// specular, or if BSDF sampling at `x_{k-1}` could not produce the connection: zero pdf or
/// zero cosine at `x_k`; such connections fail). Both are densities with respect to
/// [`Path`]'s measure.
///
/// # Example
/// ```
/// use pathspace::analytic::AnalyticScene;
/// use pathspace::{IndependentSampler, Path, UnidirectionalParams, UnidirectionalSampler};
/// use rand::SeedableRng;
///
/// // In the furnace box every path of n <= 3 edges carries L_e rho^(n-1): E[f/p] = 1.75.
/// let scene = AnalyticScene::furnace_box(0.5, 1.0).unwrap();
/// let params = UnidirectionalParams { max_segments: 3, connect_probability: 0.5 };
/// let sampler = UnidirectionalSampler::new(&scene, params).unwrap();
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
pub struct UnidirectionalSampler<'a, S: ?Sized> {
    scene: &'a S,
    params: UnidirectionalParams,
}

impl<S: ?Sized> Clone for UnidirectionalSampler<'_, S> {
    fn clone(&self) -> Self {
        *self
    }
}

impl<S: ?Sized> Copy for UnidirectionalSampler<'_, S> {}

impl<'a, S: PathScene + ?Sized> UnidirectionalSampler<'a, S> {
    /// A sampler over `scene`.
    ///
    /// # Errors
    /// If the parameters are out of range (see [`UnidirectionalParams::validate`]).
    pub fn new(scene: &'a S, params: UnidirectionalParams) -> Result<Self, PathspaceError> {
        params.validate()?;
        Ok(Self { scene, params })
    }

    /// The parameters.
    #[must_use]
    pub fn params(&self) -> &UnidirectionalParams {
        &self.params
    }

    fn connect_probability(&self, segments: usize) -> f64 {
        if segments >= 2 {
            self.params.connect_probability
        } else {
            0.0
        }
    }

    /// Log density of the walk prefix: camera ray and the scattering at vertices
    /// `1..last`, producing vertices `1..=last`.
    fn log_walk_density(&self, path: &Path, last: usize) -> f64 {
        (0..last)
            .map(|i| log_scatter_density(self.scene, &path.vertices, i))
            .sum()
    }
}

/// `ln` of the density with which a camera random walk at vertex `i` produces `v[i + 1]`
/// (w.r.t. [`Path`]'s measure): the camera's direction pdf times `J` at `i = 0`; at a
/// specular vertex the probability of its lobe; else the BSDF pdf (given the direction to
/// `v[i - 1]`) times `J = |cos θ_{i+1}| / r^2`.
pub(crate) fn log_scatter_density<S: PathScene + ?Sized>(scene: &S, v: &[Vertex], i: usize) -> f64 {
    let p = &v[i].point;
    let q = if i == 0 {
        scene.direction_pdf(direction(p.position, v[1].position()))
            * solid_angle_to_area(p.position, &v[1].point)
    } else {
        let wo = direction(p.position, v[i - 1].position());
        match v[i].specular {
            Some(lobe) => scene.specular_pdf(p, wo, lobe),
            None => {
                let wi = direction(p.position, v[i + 1].position());
                scene.pdf(p, wo, wi) * solid_angle_to_area(p.position, &v[i + 1].point)
            }
        }
    };
    q.ln()
}

/// Extends a camera random walk at vertex `i` (the camera if `i == 0`): samples a direction
/// (setting the vertex's specular flag to the chosen lobe) and pushes the hit. Returns false
/// on failure (absorbed, missed the scene, outside the image).
pub(crate) fn extend_walk<S: PathScene + ?Sized, R: Rng + ?Sized>(
    scene: &S,
    rng: &mut R,
    path: &mut Path,
    i: usize,
) -> bool {
    let v = path.vertices[i];
    let dir = if i == 0 {
        scene.direction([rng.random(), rng.random()])
    } else {
        let wo = direction(v.position(), path.vertices[i - 1].position());
        let u = [rng.random(), rng.random(), rng.random()];
        let Some(s) = scene.sample(&v.point, wo, u) else {
            return false;
        };
        if s.pdf.is_nan() || s.pdf <= 0.0 {
            return false;
        }
        path.vertices[i].specular = s.lobe;
        s.wi
    };
    let Some(hit) = scene.intersect(v.position(), dir) else {
        return false;
    };
    path.vertices.push(Vertex {
        point: hit,
        specular: None,
    });
    true
}

/// True if a camera walk could have produced the last vertex from the one before it (nonzero
/// BSDF pdf and area Jacobian). The connect technique fails otherwise (e.g. a connection from
/// a black emitter, or within one plane), so that its support lies in the hit technique's and
/// every path it draws can also be reached by walks (what the mutations regenerate with).
fn connection_walkable<S: PathScene + ?Sized>(scene: &S, v: &[Vertex]) -> bool {
    let k = v.len();
    let (a, b) = (&v[k - 2].point, &v[k - 1].point);
    let j = solid_angle_to_area(a.position, b);
    let pdf = if k == 2 {
        scene.direction_pdf(direction(a.position, b.position))
    } else {
        let wo = direction(a.position, v[k - 3].position());
        scene.pdf(a, wo, direction(a.position, b.position))
    };
    j > 0.0 && pdf > 0.0
}

/// The camera vertex of a scene (normal along the view axis).
pub(crate) fn camera_vertex<S: PathScene + ?Sized>(scene: &S) -> Vertex {
    let forward = scene.direction([0.5, 0.5]);
    Vertex {
        point: SurfacePoint {
            position: scene.origin(),
            shading_normal: forward,
            geometric_normal: forward,
            material: u32::MAX,
        },
        specular: None,
    }
}

impl<S: PathScene + ?Sized> IndependentSampler for UnidirectionalSampler<'_, S> {
    fn sample<R: Rng + ?Sized>(&self, rng: &mut R, path: &mut Path) -> bool {
        let scene = self.scene;
        path.vertices.clear();
        let n = rng.random_range(1..=self.params.max_segments);
        let connect = rng.random::<f64>() < self.connect_probability(n);
        path.vertices.push(camera_vertex(scene));
        let walk_edges = if connect { n - 1 } else { n };
        for i in 0..walk_edges {
            if !extend_walk(scene, rng, path, i) {
                return false;
            }
        }
        if connect {
            let last = path.vertices[n - 1];
            if scene.is_specular(&last.point) {
                return false;
            }
            let u = [rng.random(), rng.random(), rng.random()];
            let Some((light, pdf)) = scene.sample_emitter(u) else {
                return false;
            };
            if pdf.is_nan() || pdf <= 0.0 || !scene.visible(last.position(), light.position) {
                return false;
            }
            path.vertices.push(Vertex {
                point: light,
                specular: None,
            });
            if !connection_walkable(scene, &path.vertices) {
                return false;
            }
        }
        let end = path.vertices[n].point;
        scene.is_emitter(&end) && path.raster(scene).is_some()
    }

    fn log_density(&self, path: &Path) -> f64 {
        let v = &path.vertices;
        let k = v.len();
        let n = k.saturating_sub(1);
        if n == 0 || n > self.params.max_segments || path.raster(self.scene).is_none() {
            return f64::NEG_INFINITY;
        }
        let c = self.connect_probability(n);
        let log_n = (self.params.max_segments as f64).ln();
        let hit = if c < 1.0 {
            (1.0 - c).ln() + self.log_walk_density(path, k - 1)
        } else {
            f64::NEG_INFINITY
        };
        let connect = if c > 0.0 && !v[k - 2].is_specular() && connection_walkable(self.scene, v) {
            c.ln()
                + self.log_walk_density(path, k - 2)
                + self.scene.emitter_pdf(&v[k - 1].point).ln()
        } else {
            f64::NEG_INFINITY
        };
        mcmc_core::proposal::log_sum_exp(&[hit, connect]) - log_n
    }
}
