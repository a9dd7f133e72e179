//! Lens and multi-chain perturbations (Veach and Guibas 1997; regional-adaptive paper,
//! section 3.3) with exact transition densities and a state-dependent angular scale.

mod angular;
mod caustic;
mod scale;

pub use angular::{angle_between, rotate_direction, DirectionKernel, TruncatedNormalDirection};
pub use caustic::{caustic_chain_end, CausticPerturbation};
pub use scale::{FixedScale, ScaleSource};

use mcmc_core::proposal::ScaledProposal;
use mcmc_core::{Proposal, Proposed};
use rand::Rng;

use crate::path::{direction, solid_angle_to_area, Path};
use crate::scene::PathScene;
use crate::vec3::Vec3;

/// Which perturbation.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
pub enum PerturbationKind {
    /// Perturb the primary ray direction; the eye subpath is `x_1 .. x_s` with `x_2 .. x_{s-1}`
    /// specular and `x_s` the first non-specular vertex.
    Lens,
    /// Perturb the primary ray and the direction leaving every later non-specular vertex of
    /// the eye subpath, which may span several specular chains.
    MultiChain,
}

/// The index `s` (0-based) of the last eye-subpath vertex `y_s` that `kind` perturbs, or `None`
/// if the perturbation cannot apply to `path` (regional-adaptive paper, section 3.3).
///
/// The eye subpath `x_1 .. x_s` ends where either `x_s` is the light vertex, or `x_s` and
/// `x_{s+1}` are both non-specular (so that `x_s` reconnects to the unchanged light subpath
/// `x_{s+1} .. x_k` with an ordinary edge). Lens: `x_s` is the first non-specular vertex after
/// the camera (not applicable if `x_{s+1}` is specular, e.g. a caustic path). Multi-chain: the
/// first non-specular vertex satisfying the end condition (always exists: the light vertex
/// does); every non-specular vertex before it starts a perturbed chain.
#[must_use]
pub fn eye_subpath_end(kind: PerturbationKind, path: &Path) -> Option<usize> {
    let v = &path.vertices;
    let k = v.len();
    if k < 2 {
        return None;
    }
    let ends = |j: usize| j == k - 1 || !v[j + 1].is_specular();
    match kind {
        PerturbationKind::Lens => {
            let j = (1..k).find(|&j| !v[j].is_specular())?;
            ends(j).then_some(j)
        }
        PerturbationKind::MultiChain => (1..k).find(|&j| !v[j].is_specular() && ends(j)),
    }
}

/// A lens or multi-chain perturbation as an mcmc-core [`Proposal`] over [`Path`]s
/// (regional-adaptive paper, section 3.3, Fig. 2; Veach and Guibas 1997, section 5.3).
///
/// # What it does
/// Split `x` at `s = `[`eye_subpath_end`]; the light subpath `x_{s+1} .. x_k` stays. For each
/// chain start `c` (the camera, and for the multi-chain perturbation every later non-specular
/// vertex before `s`), in order: perturb the old direction `w_c = x_c -> x_{c+1}` by a
/// [`DirectionKernel`] at scale `sigma_1` (camera) or `sigma_2` (later chains), from the
/// *new* position `y_c`; trace it through the specular vertices, continuing each in the same
/// lobe ([`crate::Bsdfs::specular_direction`]), until a non-specular vertex, which becomes
/// `y_{c'}` for the next chain start `c'` (or `y_s`). Then connect `y_s` to `x_{s+1}`.
///
/// The candidate is [`Proposed::Invalid`] (immediate rejection) if the structure is not
/// reproduced: a ray leaves the scene or the image, a specular vertex is hit where the path had
/// a non-specular one or vice versa, a lobe does not exist (total internal reflection), the
/// light vertex is not on an emitter, or the connection `y_s - x_{s+1}` is occluded.
///
/// # Transition density
/// With respect to [`Path`]'s measure, each perturbed direction contributes its solid-angle
/// density converted to area at the next vertex (which follows a non-specular vertex); the
/// vertices after specular ones are determined (counting measure):
///
/// `T(y | x) = prod_c p_ω(angle(w_c(x), w_c(y)); sigma_c(x)) |cos θ_{y_{c+1}}| / |y_{c+1} - y_c|^2`
///
/// where `sigma(x)` comes from the [`ScaleSource`] *at the state perturbed from*: the
/// reverse density `T(x | y)` uses `sigma(y)` (section 5.2, eq. 2-3). Pairs where a perturbed
/// direction is exactly unchanged get density 0 (a null event for the perturbation, whose
/// solid-angle density is singular at `θ = 0`; other mutations of a mixture produce such
/// pairs with positive probability).
///
/// # Example
/// ```
/// use mcmc_core::{Proposal, Proposed};
/// use pathspace::analytic::AnalyticScene;
/// use pathspace::{IndependentSampler, Path, Perturbation, UnidirectionalParams, UnidirectionalSampler};
/// use rand::SeedableRng;
///
/// let scene = AnalyticScene::test_box().unwrap();
/// let sampler = UnidirectionalSampler::new(&scene, UnidirectionalParams::default()).unwrap();
/// let mut rng = rand_pcg::Pcg64::seed_from_u64(5);
/// let mut x = Path::new();
/// while !sampler.sample(&mut rng, &mut x) {}
/// // A scale that depends on the state: larger on the right half of the image.
/// let sigma = |p: &Path| if p.primary_direction().x > 0.0 { [0.1, 0.1] } else { [0.02, 0.02] };
/// let lens = Perturbation::multi_chain(&scene, sigma);
/// let mut y = Path::new();
/// if let Proposed::Move { log_hastings, .. } = lens.propose(&x, &mut y, &mut rng) {
///     // The reverse density uses the scale at y.
///     let expected = lens.log_q(&y, &x) - lens.log_q(&x, &y);
///     assert!((log_hastings - expected).abs() < 1e-12);
///     assert!(x.same_structure(&y));
/// }
/// ```
#[derive(Debug)]
pub struct Perturbation<'a, S: ?Sized, Sc = FixedScale, K = TruncatedNormalDirection> {
    scene: &'a S,
    kind: PerturbationKind,
    scale: Sc,
    kernel: K,
}

impl<S: ?Sized, Sc: Clone, K: Clone> Clone for Perturbation<'_, S, Sc, K> {
    fn clone(&self) -> Self {
        Self {
            scene: self.scene,
            kind: self.kind,
            scale: self.scale.clone(),
            kernel: self.kernel.clone(),
        }
    }
}

impl<'a, S: PathScene + ?Sized, Sc: ScaleSource> Perturbation<'a, S, Sc> {
    /// The lens perturbation with angular scales from `scale` (`sigma_1` is used).
    pub fn lens(scene: &'a S, scale: Sc) -> Self {
        Self::new(scene, PerturbationKind::Lens, scale)
    }

    /// The multi-chain perturbation with angular scales from `scale`.
    pub fn multi_chain(scene: &'a S, scale: Sc) -> Self {
        Self::new(scene, PerturbationKind::MultiChain, scale)
    }

    /// A perturbation of the given kind.
    pub fn new(scene: &'a S, kind: PerturbationKind, scale: Sc) -> Self {
        Self {
            scene,
            kind,
            scale,
            kernel: TruncatedNormalDirection,
        }
    }
}

impl<'a, S: PathScene + ?Sized, Sc: ScaleSource, K: DirectionKernel> Perturbation<'a, S, Sc, K> {
    /// The same perturbation with another direction kernel.
    pub fn with_kernel<K2: DirectionKernel>(self, kernel: K2) -> Perturbation<'a, S, Sc, K2> {
        Perturbation {
            scene: self.scene,
            kind: self.kind,
            scale: self.scale,
            kernel,
        }
    }

    /// The kind.
    #[must_use]
    pub fn kind(&self) -> PerturbationKind {
        self.kind
    }

    /// The scale source.
    #[must_use]
    pub fn scale(&self) -> &Sc {
        &self.scale
    }

    /// Mutable access to the scale source (for controllers).
    pub fn scale_mut(&mut self) -> &mut Sc {
        &mut self.scale
    }

    /// True if the perturbation can apply to `x` (its structure, not its geometry).
    #[must_use]
    pub fn applies(&self, x: &Path) -> bool {
        eye_subpath_end(self.kind, x).is_some()
    }

    /// Draws `y` from `x` with the given scales; false if the candidate is invalid.
    pub fn propose_with<R: Rng + ?Sized>(
        &self,
        x: &Path,
        y: &mut Path,
        rng: &mut R,
        sigmas: [f64; 2],
    ) -> bool {
        let Some(s) = eye_subpath_end(self.kind, x) else {
            return false;
        };
        let scene = self.scene;
        let xv = &x.vertices;
        let k = xv.len();
        y.clone_from(x);
        let mut c = 0;
        while c < s {
            let sigma = if c == 0 { sigmas[0] } else { sigmas[1] };
            let old = direction(xv[c].position(), xv[c + 1].position());
            let (theta, phi) = self.kernel.sample_angles(sigma, rng);
            let mut dir = rotate_direction(old, theta, phi);
            if c == 0 && scene.raster(dir).is_none() {
                return false;
            }
            let mut origin = y.vertices[c].position();
            let mut m = c + 1;
            loop {
                let Some(hit) = scene.intersect(origin, dir) else {
                    return false;
                };
                // A chain whose edge direction, recomputed from the vertices, is unchanged has
                // transition density 0 (see `log_q_with`): with exact geometry a null event,
                // but a scene that reports hits at finite (e.g. f32) resolution can map a tiny
                // angle onto the same vertex. Such a candidate is rejected rather than given
                // a 0/0 Hastings term.
                if m == c + 1 && angle_between(old, direction(origin, hit.position)) == 0.0 {
                    return false;
                }
                let specular = scene.is_specular(&hit);
                y.vertices[m].point = hit;
                match xv[m].specular {
                    Some(lobe) => {
                        if !specular {
                            return false;
                        }
                        let Some(next) = scene.specular_direction(&hit, -dir, lobe) else {
                            return false;
                        };
                        origin = hit.position;
                        dir = next;
                        m += 1;
                    }
                    None => {
                        if specular || (m == k - 1 && !scene.is_emitter(&hit)) {
                            return false;
                        }
                        break;
                    }
                }
            }
            c = m;
        }
        debug_assert_eq!(c, s);
        s == k - 1 || scene.visible(y.vertices[s].position(), xv[s + 1].position())
    }

    /// `ln T(from -> to)` with the given scales (`sigmas` are those of `from`); see the type's
    /// documentation. `NEG_INFINITY` if `to` cannot be reached: different structure, different
    /// light subpath or camera vertex, or outside the image.
    #[must_use]
    pub fn log_q_with(&self, from: &Path, to: &Path, sigmas: [f64; 2]) -> f64 {
        let Some(s) = eye_subpath_end(self.kind, from) else {
            return f64::NEG_INFINITY;
        };
        if !from.same_structure(to)
            || from.vertices[0].position() != to.vertices[0].position()
            || from.vertices[s + 1..]
                .iter()
                .zip(&to.vertices[s + 1..])
                .any(|(a, b)| a.position() != b.position())
            || to.raster(self.scene).is_none()
        {
            return f64::NEG_INFINITY;
        }
        let (f, t) = (&from.vertices, &to.vertices);
        let mut log_q = 0.0;
        for c in (0..s).filter(|&c| c == 0 || !f[c].is_specular()) {
            let sigma = if c == 0 { sigmas[0] } else { sigmas[1] };
            let w_from = direction(f[c].position(), f[c + 1].position());
            let w_to = direction(t[c].position(), t[c + 1].position());
            let theta = angle_between(w_from, w_to);
            if theta == 0.0 {
                // An unchanged direction: a null event for the kernel (whose solid-angle
                // density is singular at 0), but a positive-probability one for mutations that
                // keep vertices (the bidirectional mutation). The density is 0 there.
                return f64::NEG_INFINITY;
            }
            log_q += self.kernel.log_density(theta, sigma)
                + solid_angle_to_area(t[c].position(), &t[c + 1].point).ln();
        }
        log_q
    }
}

impl<S: PathScene + ?Sized, Sc: ScaleSource, K: DirectionKernel> Proposal<Path>
    for Perturbation<'_, S, Sc, K>
{
    fn propose<R: Rng + ?Sized>(&self, x: &Path, y: &mut Path, rng: &mut R) -> Proposed {
        let sx = self.scale.current_sigmas(x);
        if !self.propose_with(x, y, rng, sx) {
            return Proposed::Invalid { component: 0 };
        }
        let sy = self.scale.candidate_sigmas(y);
        Proposed::hastings(self.log_q_with(y, x, sy) - self.log_q_with(x, y, sx))
    }

    fn log_q(&self, from: &Path, to: &Path) -> f64 {
        self.log_q_with(from, to, self.scale.sigmas(from))
    }
}

/// The perturbation as a family indexed by `lambda = log sigma^2` (both scales equal to
/// `sigma`), so that mcmc-core's [`mcmc_core::proposal::Scaled`] and
/// [`mcmc_core::proposal::Regional`] wrappers and their controllers (global and regional
/// scale adaptation, regional-adaptive paper, sections 4-5) can drive it. The scale source
/// is ignored here.
impl<S: PathScene + ?Sized, Sc: ScaleSource, K: DirectionKernel> ScaledProposal<Path>
    for Perturbation<'_, S, Sc, K>
{
    fn propose_at_scale<R: Rng + ?Sized>(
        &self,
        lambda: f64,
        x: &Path,
        y: &mut Path,
        rng: &mut R,
    ) -> Proposed {
        let sigma = (0.5 * lambda).exp();
        if !self.propose_with(x, y, rng, [sigma; 2]) {
            return Proposed::Invalid { component: 0 };
        }
        Proposed::hastings(self.log_q_with(y, x, [sigma; 2]) - self.log_q_with(x, y, [sigma; 2]))
    }

    fn log_q_at_scale(&self, lambda: f64, from: &Path, to: &Path) -> f64 {
        self.log_q_with(from, to, [(0.5 * lambda).exp(); 2])
    }
}

/// Unit direction `x_c -> x_{c+1}` of a path (e.g. the direction a partition of the
/// multi-chain perturbation reads at the first non-specular vertex, section 5.4).
#[must_use]
pub fn edge_direction(path: &Path, c: usize) -> Vec3 {
    direction(path.vertices[c].position(), path.vertices[c + 1].position())
}
