//! The caustic perturbation (Veach and Guibas 1997, section 5.3.3): perturb the direction
//! leaving the light side of a specular chain seen through one non-specular vertex, trace the
//! chain toward the eye in the same lobes, and join its new end to the pinhole.

use mcmc_core::{Proposal, Proposed};
use rand::Rng;

use super::angular::{angle_between, rotate_direction, DirectionKernel, TruncatedNormalDirection};
use crate::error::PathspaceError;
use crate::lightside::log_specular_conversion;
use crate::path::{direction, solid_angle_to_area, Path, Vertex};
use crate::scene::PathScene;

/// The index `m` (0-based) of the non-specular vertex that ends the caustic chain of `path`,
/// or `None` if the caustic perturbation does not apply: it needs `x_1` non-specular (seen
/// directly by the camera), `x_2 .. x_{m-1}` specular (at least one) and `x_m` non-specular
/// (possibly the emitter), the shape `E D S+ (D|L)` at the eye end (Veach and Guibas 1997,
/// section 5.3.3).
#[must_use]
pub fn caustic_chain_end(path: &Path) -> Option<usize> {
    let v = &path.vertices;
    if v.len() < 4 || v[1].is_specular() || !v[2].is_specular() {
        return None;
    }
    (3..v.len()).find(|&m| !v[m].is_specular())
}

/// The caustic perturbation: for a path `x_0 x_1 x_2 .. x_m ..` with [`caustic_chain_end`]
/// `m`, rotate the direction `x_m -> x_{m-1}` by an angle `θ` from `kernel` at scale `sigma`
/// (azimuth uniform), trace from `x_m` through new specular vertices in the same lobes (each
/// hit must be specular, the last one non-specular: the new `x_1`), and join it to the camera.
/// The rest of the path is kept.
///
/// # Transition density
/// `T(y | x) = p_ω(θ) J(x_m -> y_{m-1}) prod_{j=2}^{m-1} J(y_j -> y_{j-1}) / J(y_j -> y_{j+1})
/// dω_{j+1} / dω_{j-1}`: the kernel's solid-angle density at `x_m` converted to the area of
/// `y_{m-1}`, then, across each specular vertex, the Jacobian from the light walk's measure
/// to [`Path`]'s (as for [`crate::BidirectionalSampler`]'s light walk; the lobes are kept, so
/// no lobe probability). The kernel is symmetric, so the Hastings term is the ratio of the
/// Jacobians of `x` and `y`.
///
/// # Example
/// ```
/// use mcmc_core::Proposal;
/// use pathspace::analytic::AnalyticScene;
/// use pathspace::perturb::CausticPerturbation;
///
/// let scene = AnalyticScene::test_box().unwrap();
/// let caustic = CausticPerturbation::new(&scene, 0.05).unwrap();
/// assert_eq!(caustic.num_components(), 1);
/// ```
#[derive(Debug)]
pub struct CausticPerturbation<'a, S: ?Sized, K = TruncatedNormalDirection> {
    scene: &'a S,
    sigma: f64,
    kernel: K,
}

impl<S: ?Sized, K: Clone> Clone for CausticPerturbation<'_, S, K> {
    fn clone(&self) -> Self {
        Self {
            scene: self.scene,
            sigma: self.sigma,
            kernel: self.kernel.clone(),
        }
    }
}

impl<'a, S: PathScene + ?Sized> CausticPerturbation<'a, S> {
    /// The perturbation at angular scale `sigma` (radians) with the truncated-normal kernel.
    ///
    /// # Errors
    /// [`PathspaceError::InvalidParameter`] for `sigma` outside `(0, pi]`.
    pub fn new(scene: &'a S, sigma: f64) -> Result<Self, PathspaceError> {
        Self::with_kernel(scene, sigma, TruncatedNormalDirection)
    }
}

impl<'a, S: PathScene + ?Sized, K: DirectionKernel> CausticPerturbation<'a, S, K> {
    /// The perturbation with another angular kernel (tests use deliberately wrong ones).
    ///
    /// # Errors
    /// As [`CausticPerturbation::new`].
    pub fn with_kernel(scene: &'a S, sigma: f64, kernel: K) -> Result<Self, PathspaceError> {
        if !(sigma > 0.0 && sigma <= std::f64::consts::PI) {
            return Err(PathspaceError::InvalidParameter {
                name: "sigma",
                value: sigma,
                allowed: "(0, pi]".into(),
            });
        }
        Ok(Self {
            scene,
            sigma,
            kernel,
        })
    }

    fn propose_path<R: Rng + ?Sized>(&self, x: &Path, y: &mut Path, rng: &mut R) -> bool {
        let scene = self.scene;
        let Some(m) = caustic_chain_end(x) else {
            return false;
        };
        let xv = &x.vertices;
        let (theta, phi) = self.kernel.sample_angles(self.sigma, rng);
        let old = direction(xv[m].position(), xv[m - 1].position());
        let mut dir = rotate_direction(old, theta, phi);
        y.vertices.clear();
        y.vertices.extend_from_slice(xv);
        let mut from = xv[m].position();
        for j in (1..m).rev() {
            let Some(hit) = scene.intersect(from, dir) else {
                return false;
            };
            let specular = scene.is_specular(&hit);
            if specular != (j >= 2) {
                return false;
            }
            y.vertices[j] = Vertex {
                point: hit,
                specular: xv[j].specular,
            };
            if let Some(lobe) = xv[j].specular {
                let toward_light = direction(hit.position, from);
                let Some(next) = scene.specular_direction(&hit, toward_light, lobe) else {
                    return false;
                };
                dir = next;
            }
            from = hit.position;
        }
        scene.visible(y.vertices[0].position(), y.vertices[1].position())
            && y.raster(scene).is_some()
    }

    /// `ln T(from -> to)` (see the type's documentation); `NEG_INFINITY` unless both paths have
    /// the same structure, the same caustic chain end and the same vertices from it on.
    #[must_use]
    pub fn log_transition_density(&self, from: &Path, to: &Path) -> f64 {
        let Some(m) = caustic_chain_end(from) else {
            return f64::NEG_INFINITY;
        };
        let (x, y) = (&from.vertices, &to.vertices);
        if !from.same_structure(to)
            || caustic_chain_end(to) != Some(m)
            || x[m..]
                .iter()
                .zip(&y[m..])
                .any(|(a, b)| a.position() != b.position())
            || to.raster(self.scene).is_none()
        {
            return f64::NEG_INFINITY;
        }
        let p = y[m].position();
        let theta = angle_between(
            direction(p, x[m - 1].position()),
            direction(p, y[m - 1].position()),
        );
        let mut log_t = self.kernel.log_density(theta, self.sigma)
            + solid_angle_to_area(p, &y[m - 1].point).ln();
        for j in 2..m {
            log_t += log_specular_conversion(self.scene, y, j);
        }
        if log_t.is_nan() {
            f64::NEG_INFINITY
        } else {
            log_t
        }
    }
}

impl<S: PathScene + ?Sized, K: DirectionKernel> Proposal<Path> for CausticPerturbation<'_, S, K> {
    fn propose<R: Rng + ?Sized>(&self, x: &Path, y: &mut Path, rng: &mut R) -> Proposed {
        if !self.propose_path(x, y, rng) {
            return Proposed::Invalid { component: 0 };
        }
        let forward = self.log_transition_density(x, y);
        if !forward.is_finite() {
            return Proposed::Invalid { component: 0 };
        }
        Proposed::hastings(self.log_transition_density(y, x) - forward)
    }

    fn log_q(&self, from: &Path, to: &Path) -> f64 {
        self.log_transition_density(from, to)
    }
}
