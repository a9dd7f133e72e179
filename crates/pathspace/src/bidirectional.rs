//! A bidirectional-style mutation: delete a subpath and regenerate it from the eye side
//! (Veach and Guibas 1997, section 5.2, restricted to eye-side generation).

use mcmc_core::{Proposal, Proposed};
use rand::{Rng, RngExt};

use crate::error::PathspaceError;
use crate::path::Path;
use crate::sampler::{camera_vertex, extend_walk, log_scatter_density};
use crate::scene::PathScene;

/// Parameters of [`BidirectionalMutation`].
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct BidirectionalParams {
    /// Candidates have at most this many edges (the chain's path-length cap).
    pub max_segments: usize,
}

impl Default for BidirectionalParams {
    /// At most 5 edges.
    fn default() -> Self {
        Self { max_segments: 5 }
    }
}

/// Deletes a subpath and regenerates it by a camera-side random walk, reconnecting to the
/// kept light-side suffix (Veach and Guibas 1997, section 5.2; the RA paper's "bidirectional
/// mutation", section 3.3, with new vertices generated from the eye side only).
///
/// # What it does
/// For `x = x_0 .. x_{k-1}` (0-based, camera first):
/// 1. choose `0 <= l < m <= k` with probability `p_d(l, m) = 2^{-(m-l)} / D_k`: keep the prefix
///    `x_0 .. x_l` and the suffix `x_m .. x_{k-1}` (empty if `m = k`: the light end is
///    regenerated too);
/// 2. choose the number `a` of new vertices in `[a_min, a_max]` (`a_min = 1` if `m = k`, else
///    0; `a_max` keeps at most `max_segments` edges) with probability `p_a ∝ 2^{-|a - (m-l-1)|}`
///    (new lengths near the deleted one);
/// 3. extend the prefix by `a` steps of a camera random walk (camera ray if `l = 0`, else BSDF
///    sampling at `x_l`, which may pick a new specular lobe there);
/// 4. if `m < k`, connect the last walk vertex to `x_m` (both must be non-specular, unoccluded);
///    if `m = k`, the last walk vertex must lie on an emitter.
///
/// The kept suffix must have been attached by a connectable edge (`x_{m-1}` and `x_m`
/// non-specular): otherwise the measure of the kept `x_m` would differ between `x` and `y`
/// (see [`Path`]'s measure), and the candidate is `Invalid`. With `l = 0, m = k` the whole path
/// is regenerated, so the mutation is ergodic on paths of at most `max_segments` edges.
///
/// # Transition density
/// `y` may arise from several choices (a regenerated vertex after a specular one can coincide
/// with the old one): `T(y | x)` sums over every `(l, m)` for which `y` keeps `x_0 .. x_l` and
/// `x_m .. x_{k-1}` and no regenerated vertex measured by area coincides with a vertex of `x`
/// (that has probability 0; the term of the larger kept set accounts for `y`):
///
/// `T(y | x) = sum_{(l, m)} p_d(l, m) p_a(a | l, m) prod_{i=l}^{l+a-1} q_i(y)`
///
/// where `q_i` is the walk's density of `y_{i+1}` (camera pdf times `J`, BSDF pdf times `J`, or
/// a lobe probability), w.r.t. [`Path`]'s measure; kept vertices are common to `x` and `y`
/// (reversible jump with unit Jacobian, Veach 1997).
///
/// # Example
/// ```
/// use mcmc_core::{Proposal, Proposed};
/// use pathspace::analytic::AnalyticScene;
/// use pathspace::{
///     BidirectionalMutation, BidirectionalParams, IndependentSampler, Path,
///     UnidirectionalParams, UnidirectionalSampler,
/// };
/// use rand::SeedableRng;
///
/// let scene = AnalyticScene::test_box().unwrap();
/// let sampler = UnidirectionalSampler::new(&scene, UnidirectionalParams::default()).unwrap();
/// let bidir = BidirectionalMutation::new(&scene, BidirectionalParams::default()).unwrap();
/// let mut rng = rand_pcg::Pcg64::seed_from_u64(2);
/// let mut x = Path::new();
/// while !sampler.sample(&mut rng, &mut x) {}
/// let mut y = Path::new();
/// for _ in 0..20 {
///     if let Proposed::Move { .. } = bidir.propose(&x, &mut y, &mut rng) {
///         assert!(y.check_valid(&scene, 1e-9).is_ok());
///         assert!(bidir.log_q(&x, &y).is_finite());
///     }
/// }
/// ```
///
/// Not implemented: light-side generation (it would need emitter direction sampling, and the
/// Jacobian between the two measures at specular vertices generated from the light side).
#[derive(Debug)]
pub struct BidirectionalMutation<'a, S: ?Sized> {
    scene: &'a S,
    params: BidirectionalParams,
}

impl<S: ?Sized> Clone for BidirectionalMutation<'_, S> {
    fn clone(&self) -> Self {
        *self
    }
}

impl<S: ?Sized> Copy for BidirectionalMutation<'_, S> {}

/// `D_k = sum_{0 <= l < m <= k} 2^{-(m - l)}`.
fn deletion_normaliser(k: usize) -> f64 {
    (1..=k)
        .map(|d| (k - d + 1) as f64 * 0.5f64.powi(d as i32))
        .sum()
}

impl<'a, S: PathScene + ?Sized> BidirectionalMutation<'a, S> {
    /// The mutation over `scene`.
    ///
    /// # Errors
    /// [`PathspaceError::InvalidParameter`] for `max_segments` outside `1..=64`.
    pub fn new(scene: &'a S, params: BidirectionalParams) -> Result<Self, PathspaceError> {
        PathspaceError::check_range("max_segments", params.max_segments as f64, 1.0, 64.0)?;
        Ok(Self { scene, params })
    }

    /// The range of new-vertex counts for deleting `(l, m)` from a path of `k` vertices.
    fn addition_range(&self, l: usize, m: usize, k: usize) -> Option<(usize, usize)> {
        let a_min = usize::from(m == k);
        // Edges of the candidate: l + a + (k - m).
        let fixed = l + k - m;
        let a_max = self.params.max_segments.checked_sub(fixed)?;
        (a_min <= a_max).then_some((a_min, a_max))
    }

    fn addition_weight(a: usize, deleted: usize) -> f64 {
        0.5f64.powi(a.abs_diff(deleted) as i32)
    }

    fn log_p_add(&self, a: usize, l: usize, m: usize, k: usize) -> f64 {
        let Some((lo, hi)) = self.addition_range(l, m, k) else {
            return f64::NEG_INFINITY;
        };
        if a < lo || a > hi {
            return f64::NEG_INFINITY;
        }
        let deleted = m - l - 1;
        let z: f64 = (lo..=hi).map(|b| Self::addition_weight(b, deleted)).sum();
        (Self::addition_weight(a, deleted) / z).ln()
    }

    /// Draws `y` from `x`; false if invalid.
    fn propose_path<R: Rng + ?Sized>(&self, x: &Path, y: &mut Path, rng: &mut R) -> bool {
        let scene = self.scene;
        let xv = &x.vertices;
        let k = xv.len();
        if k < 2 {
            return false;
        }
        // 1. (l, m) by inversion of the deletion weights.
        let mut u = rng.random::<f64>() * deletion_normaliser(k);
        let (mut l, mut m) = (0, k);
        'outer: for d in 1..=k {
            let w = 0.5f64.powi(d as i32);
            for l0 in 0..=k - d {
                if u < w {
                    (l, m) = (l0, l0 + d);
                    break 'outer;
                }
                u -= w;
            }
        }
        // 2. a.
        let Some((lo, hi)) = self.addition_range(l, m, k) else {
            return false;
        };
        let deleted = m - l - 1;
        let z: f64 = (lo..=hi).map(|b| Self::addition_weight(b, deleted)).sum();
        let mut u = rng.random::<f64>() * z;
        let mut a = hi;
        for b in lo..=hi {
            let w = Self::addition_weight(b, deleted);
            if u < w {
                a = b;
                break;
            }
            u -= w;
        }
        if m < k && (xv[m].is_specular() || xv[m - 1].is_specular()) {
            return false;
        }
        // 3. the walk.
        y.vertices.clear();
        y.vertices.extend_from_slice(&xv[..=l]);
        if l == 0 {
            y.vertices[0] = camera_vertex(scene);
        }
        for i in l..l + a {
            if !extend_walk(scene, rng, y, i) {
                return false;
            }
        }
        // 4. the end.
        let last = l + a;
        y.vertices[last].specular = None;
        let end = y.vertices[last].point;
        if m < k {
            // The camera (last == 0) connects like a non-specular vertex.
            if (last > 0 && scene.is_specular(&end))
                || !scene.visible(end.position, xv[m].position())
            {
                return false;
            }
            y.vertices.extend_from_slice(&xv[m..]);
        } else if !scene.is_emitter(&end) {
            return false;
        }
        y.raster(scene).is_some()
    }

    /// `ln T(from -> to)`: the sum over every deletion that keeps a prefix and a suffix common
    /// to both paths (see the type's documentation).
    #[must_use]
    pub fn log_transition_density(&self, from: &Path, to: &Path) -> f64 {
        let (x, y) = (&from.vertices, &to.vertices);
        let (kx, ky) = (x.len(), y.len());
        if kx < 2 || ky < 2 || ky - 1 > self.params.max_segments || to.raster(self.scene).is_none()
        {
            return f64::NEG_INFINITY;
        }
        let log_dk = deletion_normaliser(kx).ln();
        // Running log-sum-exp of the terms (no allocation).
        let (mut max, mut sum) = (f64::NEG_INFINITY, 0.0f64);
        for l in 0..kx.min(ky) {
            // Kept prefix x_0 .. x_l: positions equal, flags equal before l.
            if x[l].position() != y[l].position()
                || (l >= 1 && x[l - 1].specular != y[l - 1].specular)
            {
                break;
            }
            for m in l + 1..=kx {
                let c = kx - m;
                let a = if c > 0 {
                    if ky < c + l + 1 {
                        continue;
                    }
                    let j = ky - c;
                    if x[m - 1].is_specular()
                        || x[m].is_specular()
                        || y[j - 1].is_specular()
                        || x[m..]
                            .iter()
                            .zip(&y[j..])
                            .any(|(p, q)| p.position() != q.position() || p.specular != q.specular)
                    {
                        continue;
                    }
                    j - l - 1
                } else {
                    ky - 1 - l
                };
                // A regenerated vertex measured by area (its predecessor non-specular) cannot
                // coincide with a vertex of `x` (probability 0): such a term belongs to a
                // larger kept set, whose term is counted separately. Regenerated vertices
                // after a specular one can (the same lobe reproduces them): those count.
                if (l + 1..=l + a).any(|i| {
                    !y[i - 1].is_specular() && x.iter().any(|v| v.position() == y[i].position())
                }) {
                    continue;
                }
                let log_add = self.log_p_add(a, l, m, kx);
                if log_add == f64::NEG_INFINITY {
                    continue;
                }
                let walk: f64 = (l..l + a)
                    .map(|i| log_scatter_density(self.scene, y, i))
                    .sum();
                let term = -((m - l) as f64) * std::f64::consts::LN_2 - log_dk + log_add + walk;
                if term > max {
                    sum = sum * (max - term).exp() + 1.0;
                    max = term;
                } else if term > f64::NEG_INFINITY {
                    sum += (term - max).exp();
                }
            }
        }
        if max == f64::NEG_INFINITY || max.is_nan() {
            max
        } else {
            max + sum.ln()
        }
    }
}

impl<S: PathScene + ?Sized> Proposal<Path> for BidirectionalMutation<'_, S> {
    fn propose<R: Rng + ?Sized>(&self, x: &Path, y: &mut Path, rng: &mut R) -> Proposed {
        if !self.propose_path(x, y, rng) {
            return Proposed::Invalid { component: 0 };
        }
        Proposed::hastings(self.log_transition_density(y, x) - self.log_transition_density(x, y))
    }

    fn log_q(&self, from: &Path, to: &Path) -> f64 {
        self.log_transition_density(from, to)
    }
}
