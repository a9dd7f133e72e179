//! The path model: vertices, the measure conversions, and the measurement contribution f(x).

use crate::scene::{PathScene, SpecularLobe, SurfacePoint};
use crate::vec3::{Rgb, Vec3};

/// One path vertex: a surface point and the specular flag of the path *at* this vertex.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct Vertex {
    /// Where, and with which normals and material (the BSDF handle).
    pub point: SurfacePoint,
    /// `Some(lobe)` if the vertex is specular and the path uses `lobe` (reflection or
    /// refraction) there; `None` for non-specular vertices, the camera and the light vertex.
    pub specular: Option<SpecularLobe>,
}

impl Vertex {
    /// The position.
    #[must_use]
    pub fn position(&self) -> Vec3 {
        self.point.position
    }

    /// True if the vertex is specular.
    #[must_use]
    pub fn is_specular(&self) -> bool {
        self.specular.is_some()
    }
}

/// A light path `x_1 x_2 ... x_k` with `x_1` the camera vertex and `x_k` on an emitter (the
/// regional-adaptive paper's convention, section 3.1; Veach and Guibas 1997 number the other
/// way).
///
/// # The measure
/// `f` is a density with respect to the product measure
/// `mu = prod_{j=2..k} m_j`, where `m_j` is the area measure `dA(x_j)` if `x_{j-1}` is
/// non-specular (the camera counts as non-specular), and the counting measure if `x_{j-1}` is
/// specular: a specular vertex determines the next vertex from the previous one (the Dirac
/// BSDF integrated against `G dA`, Veach's thesis, section 8.2). The camera vertex is a pinhole
/// (a Dirac in area), so `x_1` carries no measure. Every density in this crate (independent
/// sampling, mutation transition densities) is with respect to this `mu`: "area measure" with
/// the specular deltas cancelled consistently.
///
/// The camera vertex has `material == u32::MAX` and is never passed to a scene's BSDF or
/// emitter methods.
///
/// # Example
/// ```
/// use pathspace::analytic::AnalyticScene;
/// use pathspace::{IndependentSampler, Path, UnidirectionalParams, UnidirectionalSampler};
/// use rand::SeedableRng;
///
/// let scene = AnalyticScene::test_box().unwrap();
/// let sampler = UnidirectionalSampler::new(&scene, UnidirectionalParams::default()).unwrap();
/// let mut rng = rand_pcg::Pcg64::seed_from_u64(3);
/// let mut path = Path::new();
/// while !sampler.sample(&mut rng, &mut path) {}
/// assert!(path.check_valid(&scene, 1e-9).is_ok());
/// // f(x) / p(x): one-sample estimate of the image's mean radiance.
/// let weight = path.contribution(&scene).luminance() / sampler.log_density(&path).exp();
/// assert!(weight.is_finite() && weight >= 0.0);
/// ```
///
/// # Invariants
/// Paths built by this crate's samplers and mutations are *valid*: every edge is unoccluded,
/// every specular vertex's successor is the first hit along its specular direction, `x_1` is
/// the camera origin and `x_k` lies on an emitter. [`Path::contribution`] trusts them (it casts
/// no rays); [`Path::check_valid`] verifies them for tests.
#[derive(Debug, Default, PartialEq)]
pub struct Path {
    /// The vertices, camera first.
    pub vertices: Vec<Vertex>,
}

impl Clone for Path {
    fn clone(&self) -> Self {
        Self {
            vertices: self.vertices.clone(),
        }
    }

    /// Copies `source` into `self`'s vertex storage: a proposal's `y.clone_from(x)` allocates
    /// nothing once `y` has held a path as long (a derived `clone_from` would build a new
    /// vector every step).
    fn clone_from(&mut self, source: &Self) {
        self.vertices.clone_from(&source.vertices);
    }
}

impl mcmc_core::Point for Path {}

/// `|cos|` between the geometric normal of `to` and the edge direction, over the squared
/// distance: the Jacobian `dω/dA(to)` converting solid angle at `from` into area at `to`.
#[must_use]
pub fn solid_angle_to_area(from: Vec3, to: &SurfacePoint) -> f64 {
    let d = to.position - from;
    let r2 = d.length_squared();
    if r2 == 0.0 {
        return 0.0;
    }
    to.geometric_normal.dot(d).abs() / (r2 * r2.sqrt())
}

/// The geometry term `G(a, b) = |cos θ_a| |cos θ_b| / |a - b|^2` (geometric normals;
/// visibility not included).
#[must_use]
pub fn geometry_term(a: &SurfacePoint, b: &SurfacePoint) -> f64 {
    let d = b.position - a.position;
    let r2 = d.length_squared();
    if r2 == 0.0 {
        return 0.0;
    }
    let r = r2.sqrt();
    (a.geometric_normal.dot(d) / r).abs() * (b.geometric_normal.dot(d) / r).abs() / r2
}

/// Unit direction from `a` to `b`.
#[must_use]
pub fn direction(a: Vec3, b: Vec3) -> Vec3 {
    (b - a).normalize()
}

impl Path {
    /// An empty path (fill it with a sampler).
    #[must_use]
    pub fn new() -> Self {
        Self::default()
    }

    /// Number of vertices `k`.
    #[must_use]
    pub fn len(&self) -> usize {
        self.vertices.len()
    }

    /// True if the path has no vertex.
    #[must_use]
    pub fn is_empty(&self) -> bool {
        self.vertices.is_empty()
    }

    /// Number of edges `k - 1`.
    #[must_use]
    pub fn segments(&self) -> usize {
        self.vertices.len().saturating_sub(1)
    }

    /// Unit direction of the primary ray `x_1 -> x_2`.
    #[must_use]
    pub fn primary_direction(&self) -> Vec3 {
        direction(self.vertices[0].position(), self.vertices[1].position())
    }

    /// The raster position of the path (where it splats), or `None` outside the image.
    pub fn raster<S: PathScene + ?Sized>(&self, scene: &S) -> Option<[f64; 2]> {
        if self.vertices.len() < 2 {
            return None;
        }
        scene.raster(self.primary_direction())
    }

    /// True if both paths have the same length and the same specular flags (lobes)
    /// vertex by vertex: what a perturbation must preserve.
    #[must_use]
    pub fn same_structure(&self, other: &Path) -> bool {
        self.vertices.len() == other.vertices.len()
            && self
                .vertices
                .iter()
                .zip(&other.vertices)
                .all(|(a, b)| a.specular == b.specular)
    }

    /// The measurement contribution `f(x)` with respect to [`Path`]'s measure
    /// (regional-adaptive paper, eq. 1; Veach 1997, eq. 8.7 and section 8.2 for specular
    /// vertices):
    ///
    /// `f = W_e cos θ_1 (|cos θ_2| / r_12^2) prod_{i=2}^{k-1} g_i  L_e(x_k -> x_{k-1})`, with
    /// `g_i = f_s(x_{i-1} <- x_i <- x_{i+1}) G(x_i, x_{i+1})` at a non-specular vertex and
    /// `g_i = ` the specular coefficient of its lobe (the Dirac integrated against `G dA`)
    /// at a specular vertex. Visibility is part of the path invariants, not re-checked here.
    /// Zero for paths with fewer than two vertices or outside the image.
    pub fn contribution<S: PathScene + ?Sized>(&self, scene: &S) -> Rgb {
        let v = &self.vertices;
        let k = v.len();
        if k < 2 {
            return Rgb::BLACK;
        }
        let w1 = self.primary_direction();
        let importance = scene.importance(w1);
        if importance <= 0.0 || !importance.is_finite() {
            return Rgb::BLACK;
        }
        let mut f = Rgb::gray(importance * solid_angle_to_area(v[0].position(), &v[1].point));
        for i in 1..k - 1 {
            let p = &v[i].point;
            let wo = direction(p.position, v[i - 1].position());
            f = match v[i].specular {
                Some(lobe) => f * scene.specular_weight(p, wo, lobe),
                None => {
                    let wi = direction(p.position, v[i + 1].position());
                    f * scene.eval(p, wo, wi) * geometry_term(p, &v[i + 1].point)
                }
            };
            if f.is_black() {
                return f;
            }
        }
        let last = &v[k - 1].point;
        f * scene.emitted(last, direction(last.position, v[k - 2].position()))
    }

    /// Checks the path invariants against the scene (for tests): camera origin first, a
    /// raster position, unoccluded area edges, specular successors on their specular
    /// direction (first hit), specular flags consistent with the materials, and the last
    /// vertex on an emitter. Returns a description of the first violation.
    pub fn check_valid<S: PathScene + ?Sized>(&self, scene: &S, tol: f64) -> Result<(), String> {
        let v = &self.vertices;
        let k = v.len();
        if k < 2 {
            return Err(format!("{k} vertices"));
        }
        if (v[0].position() - scene.origin()).length() > tol {
            return Err("first vertex is not the camera origin".into());
        }
        if self.raster(scene).is_none() {
            return Err("primary ray outside the image".into());
        }
        if !scene.is_emitter(&v[k - 1].point) {
            return Err("last vertex not on an emitter".into());
        }
        for i in 0..k - 1 {
            let a = v[i].position();
            if i > 0 && v[i].is_specular() != scene.is_specular(&v[i].point) {
                return Err(format!(
                    "vertex {i}: specular flag disagrees with the material"
                ));
            }
            match v[i].specular {
                Some(lobe) => {
                    let wo = direction(a, v[i - 1].position());
                    let Some(dir) = scene.specular_direction(&v[i].point, wo, lobe) else {
                        return Err(format!("vertex {i}: lobe {lobe:?} does not exist"));
                    };
                    let Some(hit) = scene.intersect(a, dir) else {
                        return Err(format!("vertex {i}: specular ray leaves the scene"));
                    };
                    if (hit.position - v[i + 1].position()).length() > tol {
                        return Err(format!("vertex {}: not the specular successor", i + 1));
                    }
                }
                None => {
                    if !scene.visible(a, v[i + 1].position()) {
                        return Err(format!("edge {i}-{} occluded", i + 1));
                    }
                }
            }
        }
        Ok(())
    }
}
