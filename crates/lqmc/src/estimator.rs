//! The local quasi-Monte Carlo estimator (paper Alg. 1, eq. 8-9): a seed's lattice set in its
//! tile, the caller's rebuilt members, and their balance-heuristic weights including the
//! probability of the breakup point.

use crate::error::LqmcError;
use crate::lattice::Rank1Lattice;
use crate::shift::ShiftedLattice;
use crate::tiling::Tiling;
use crate::torus::{torus_difference, wrap_unit};

/// What a [`LocalIntegrand`] reports for the path rebuilt from a perturbed prefix `u_bar_j`.
///
/// All densities are those of the seed technique `t` (paper section 3): `density` is
/// `p_t(X_j)` of the whole path (prefix re-traced, static suffix reconnected), and
/// `prefix_jacobian` is `J_j = |d u_bar / d X_bar| = p_t(X_bar_j)`, the density of the
/// prefix alone (eq. 11; 1 when the explored dimensions map to the path uniformly, e.g. an
/// aperture position with `b = 0`).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Rebuilt<P> {
    /// Caller data carried to the [`Splat`]: a raster position, an RGB contribution, ...
    pub payload: P,
    /// `w_t(X_j) f(X_j)`: the measurement contribution times the MIS weight of the seed
    /// technique (eq. 9 numerator; 1 if the technique is not combined with others). For a
    /// vector-valued contribution put it in `payload`, set this to 1 and use
    /// [`Splat::weight`].
    pub contribution: f64,
    /// `J_j = p_t(X_bar_j)`, the prefix density (eq. 11); finite and `> 0`.
    pub prefix_jacobian: f64,
    /// `p_t(X_j)`, the full path density (eq. 8); finite and `>= 0`.
    pub density: f64,
    /// `P(b | X_j)`: the probability that the seed sampler would choose this set's breakup
    /// point `b` (section 3.3) if `X_j` were the seed, e.g. from [`crate::breakup_probability`]
    /// over `X_j`'s vertex roughness; 1 if `b` is fixed for the class. In `[0, 1]`.
    pub breakup_probability: f64,
}

/// Rebuilds a path from perturbed random numbers: the caller's half of Alg. 1 (lines 9-11).
///
/// `rebuild(u_bar)` re-traces the prefix from the explored random numbers `u_bar` (the
/// seed's other random numbers — suffix, Russian roulette, layer selection — stay fixed inside
/// the implementor), reconnects it to the seed's static suffix and reports a [`Rebuilt`], or
/// `None` if the path "left its class" (section 3.3): any path whose class (and thus lattice
/// size `N`, tiling, breakup rule or explored dimensions) would differ from the seed's, or
/// that cannot be reconnected. Rejecting such paths is what keeps every member's weights
/// consistent over the whole set.
///
/// Closures `FnMut(&[f64]) -> Option<Rebuilt<P>>` implement it.
///
/// # Example
///
/// A two-vertex "path": the explored prefix is a position `x` drawn with density `2x` from
/// `u_bar[0]` (so `J = 2x`), the static suffix is a fixed light sample `y` with density 1;
/// the class is "x lies on the same side of 0.5 as the seed's", and the payload is a pixel.
///
/// ```
/// use lqmc::{LocalIntegrand, LocalQmc, Rank1Lattice, Rebuilt, Tiling};
///
/// struct TwoVertexPath {
///     y: f64,          // static suffix (not explored)
///     seed_side: bool, // the seed's class
/// }
///
/// impl TwoVertexPath {
///     fn trace(&self, u: f64) -> Rebuilt<usize> {
///         let x = u.sqrt();
///         let f = if x + self.y > 1.0 { 1.0 } else { 0.25 };
///         Rebuilt {
///             payload: (x * 8.0) as usize, // pixel of an 8-pixel image
///             contribution: f,
///             prefix_jacobian: 2.0 * x,
///             density: 2.0 * x, // times the suffix density 1
///             breakup_probability: 1.0,
///         }
///     }
/// }
///
/// impl LocalIntegrand for TwoVertexPath {
///     type Payload = usize;
///     fn rebuild(&mut self, u_bar: &[f64]) -> Option<Rebuilt<usize>> {
///         let x = u_bar[0].sqrt();
///         ((x < 0.5) == self.seed_side).then(|| self.trace(u_bar[0]))
///     }
/// }
///
/// let lqmc = LocalQmc::new(
///     Rank1Lattice::from_table(7, 1).unwrap(),
///     Tiling::new(vec![2]).unwrap(),
/// )
/// .unwrap();
/// let u = [0.6, 0.3]; // u[0] explored, u[1] the suffix
/// let mut path = TwoVertexPath { y: u[1], seed_side: u[0].sqrt() < 0.5 };
/// let seed = path.trace(u[0]);
/// let mut splats = Vec::new();
/// let stats = lqmc.explore(&u[..1], seed, &mut path, &mut splats);
/// assert_eq!(stats.members + stats.rejected, 7);
/// // Seven splats spread over the pixels of the seed's tile.
/// assert!(splats.iter().all(|s| s.payload >= 4));
/// ```
pub trait LocalIntegrand {
    /// The caller data carried from [`Rebuilt::payload`] to [`Splat::payload`].
    type Payload;

    /// The rebuilt path for the explored random numbers `u_bar`, or `None` if it left the
    /// seed's class.
    fn rebuild(&mut self, u_bar: &[f64]) -> Option<Rebuilt<Self::Payload>>;
}

impl<P, F> LocalIntegrand for F
where
    F: FnMut(&[f64]) -> Option<Rebuilt<P>>,
{
    type Payload = P;

    fn rebuild(&mut self, u_bar: &[f64]) -> Option<Rebuilt<P>> {
        self(u_bar)
    }
}

/// One weighted member of a lattice set, to accumulate at its payload (Alg. 1, line 15).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Splat<P> {
    /// Lattice index `j` of the member.
    pub index: u32,
    /// The payload of its [`Rebuilt`].
    pub payload: P,
    /// `P(b|X_j) / (J_j sum_k P(b|X_k) p_t(X_k) / J_k)`: multiply `w_t(X_j) f(X_j)` by this.
    pub weight: f64,
    /// `weight * contribution` (eq. 9 with the breakup probability).
    pub value: f64,
}

/// Reusable buffers of [`LocalQmc::explore_with`] (the seed's tile, its tile coordinates,
/// the shift, and one member's coordinates).
#[derive(Debug, Clone, Default, PartialEq)]
pub struct ExploreScratch {
    tile: Vec<u32>,
    t: Vec<f64>,
    shift: Vec<f64>,
    u_j: Vec<f64>,
    t_j: Vec<f64>,
}

/// Counts from one [`LocalQmc::explore`].
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default)]
pub struct Exploration {
    /// Lattice index of the seed.
    pub seed_index: u32,
    /// Members in the seed's class, seed included (those that were weighted).
    pub members: u32,
    /// Members that left the class (`rebuild` returned `None`).
    pub rejected: u32,
}

/// The lattice set of one seed: its tile and its Cranley-Patterson-shifted lattice.
#[derive(Debug, Clone, PartialEq)]
pub struct LocalSet {
    tile: Vec<u32>,
    shifted: ShiftedLattice,
}

impl LocalSet {
    /// The tile (per dimension) that contains the seed and every member.
    #[must_use]
    pub fn tile(&self) -> &[u32] {
        &self.tile
    }

    /// The shifted lattice in tile coordinates.
    #[must_use]
    pub fn shifted(&self) -> &ShiftedLattice {
        &self.shifted
    }

    /// Lattice index of the seed.
    #[must_use]
    pub fn seed_index(&self) -> u32 {
        self.shifted.seed_index()
    }
}

/// Local quasi-Monte Carlo exploration (paper section 3, Alg. 1) with one lattice and one
/// tiling: the configuration of one path class (section 3.3, "Adaptive number of samples").
///
/// For a seed whose explored random numbers are `u_bar_s` ([`LocalQmc::explore`]):
///
/// 1. `t_s = T(u_bar_s)` in its tile (eq. 12), `r_i` its closest lattice point, the shift
///    `Delta = t_s - r_i` (Alg. 1 line 3, eq. 3);
/// 2. members `u_bar_j = T^{-1}({r_j + Delta})`, `j = 0..N` (line 7); the seed is member `i`;
/// 3. the caller rebuilds each member `j != i` ([`LocalIntegrand`], lines 9-11);
/// 4. member `j` in the class gets `weight_j = P(b|X_j) / (J_j S)` with
///    `S = sum_k P(b|X_k) p_t(X_k) / J_k` over the members in the class (lines 12-15, eq. 9).
///
/// # Why the breakup probability is in the weights
///
/// The seed `X_s ~ p_t` picks `b` with probability `P(b|X_s)`; then `X_i`, a uniformly chosen
/// member of the set, has joint density with `b` (eq. 8 with the choice of `b`)
/// `p(X_i, b) = (1/N) (1/J_i) sum_k P(b|X_k) p_t(X_k) / J_k`: every member `k` could have been
/// the seed, and would have chosen `b` with its own probability. A path can be produced with
/// any `b`, so the one-sample MIS over `b` needs weights `c_b(X)` with `sum_b c_b(X) = 1`; we
/// take `c_b(X) = P(b|X)`, which is cheap (no other set is traced) and gives
/// `I_i = P(b|X_i) w_t f(X_i) / (N p(X_i, b))`, the weights above. If `P(b|.)` is constant
/// over the set this reduces to Alg. 1 exactly. Dropping `P` (as the authors' code does,
/// `bprob = 1`) is biased whenever `P(b|X)` varies inside a set; `tests/unbiased.rs` detects
/// that.
///
/// # Requirements for unbiasedness
///
/// - seeds `u ~ U[0,1)^s` (or a randomised QMC sequence), the jitter fixed while seeds run;
/// - the class (lattice, tiling, which `b` are possible, how `P(b|X)` is computed) is a
///   function of the path, and `rebuild` returns `None` exactly for members of another class;
/// - `P(b|X_j)`, `p_t(X_j)` and `J_j` are those the seed sampler would have for `X_j`.
///
/// # Example
///
/// The integrand `f(x, y) = [x + y < 1] + 2 [x < 0.3]` on the unit square (exact integral
/// 1.1), seeds from the Owen-scrambled Halton sequence, 2-D exploration with 23 points in
/// 4 x 4 jittered tiles:
///
/// ```
/// use lqmc::{Halton, LocalQmc, Rank1Lattice, Rebuilt, Scrambling, Tiling};
///
/// let f = |u: &[f64]| {
///     f64::from(u8::from(u[0] + u[1] < 1.0)) + 2.0 * f64::from(u8::from(u[0] < 0.3))
/// };
/// // Uniform seed sampler: p_t = 1, J = 1, one breakup point (P = 1).
/// let rebuilt = |u: &[f64]| Rebuilt {
///     payload: (),
///     contribution: f(u),
///     prefix_jacobian: 1.0,
///     density: 1.0,
///     breakup_probability: 1.0,
/// };
///
/// let lattice = Rank1Lattice::from_table(23, 2).unwrap();
/// let tiling = Tiling::new(vec![4, 4]).unwrap().with_jitter(&[0.3, 0.8]).unwrap();
/// let lqmc = LocalQmc::new(lattice, tiling).unwrap();
///
/// let halton = Halton::new(Scrambling::Owen, 1);
/// let (seeds, mut sum, mut splats) = (2000, 0.0, Vec::new());
/// for i in 0..seeds {
///     let mut u = [0.0; 2];
///     halton.fill(i, &mut u);
///     splats.clear();
///     let mut integrand = |v: &[f64]| Some(rebuilt(v));
///     let stats = lqmc.explore(&u, rebuilt(&u), &mut integrand, &mut splats);
///     assert_eq!(stats.members, 23);
///     sum += splats.iter().map(|s| s.value).sum::<f64>();
/// }
/// assert!((sum / seeds as f64 - 1.1).abs() < 0.01);
/// ```
#[derive(Debug, Clone, PartialEq)]
pub struct LocalQmc {
    lattice: Rank1Lattice,
    tiling: Tiling,
}

impl LocalQmc {
    /// Exploration with `lattice` in the tiles of `tiling`.
    ///
    /// # Errors
    ///
    /// [`LqmcError::DimensionMismatch`] if their dimensions differ.
    pub fn new(lattice: Rank1Lattice, tiling: Tiling) -> Result<Self, LqmcError> {
        if lattice.dims() != tiling.dims() {
            return Err(LqmcError::DimensionMismatch {
                what: "tiling",
                found: tiling.dims(),
                expected: lattice.dims(),
            });
        }
        Ok(LocalQmc { lattice, tiling })
    }

    /// The lattice.
    #[must_use]
    pub fn lattice(&self) -> &Rank1Lattice {
        &self.lattice
    }

    /// The tiling.
    #[must_use]
    pub fn tiling(&self) -> &Tiling {
        &self.tiling
    }

    /// Number of explored dimensions `s_bar`.
    #[must_use]
    pub fn dims(&self) -> usize {
        self.lattice.dims()
    }

    /// Re-draws the tiling's global jitter (section 3.4): call between progressions only.
    ///
    /// # Errors
    ///
    /// As [`Tiling::set_jitter`].
    pub fn set_jitter(&mut self, uniforms: &[f64]) -> Result<(), LqmcError> {
        self.tiling.set_jitter(uniforms)
    }

    /// The set of the seed `u_bar` (its tile, closest lattice point and shift; Alg. 1 line 3).
    #[must_use]
    pub fn locate(&self, u_bar: &[f64]) -> LocalSet {
        let s = self.dims();
        assert_eq!(u_bar.len(), s, "seed and lattice dimensions differ");
        let mut tile = vec![0; s];
        let mut t = vec![0.0; s];
        self.tiling.to_tile(u_bar, &mut tile, &mut t);
        LocalSet {
            tile,
            shifted: ShiftedLattice::through(&self.lattice, &t),
        }
    }

    /// Member `j` of `set` in primary sample space: `T^{-1}({r_j + Delta})` (Alg. 1 line 7).
    pub fn member(&self, set: &LocalSet, j: u32, u_bar: &mut [f64]) {
        let mut t = vec![0.0; self.dims()];
        self.member_into(set, j, &mut t, u_bar);
    }

    fn member_into(&self, set: &LocalSet, j: u32, t: &mut [f64], u_bar: &mut [f64]) {
        set.shifted.member(&self.lattice, j, t);
        self.tiling.invert(&set.tile, t, u_bar);
    }

    /// Explores the seed with explored random numbers `u_bar` and its own [`Rebuilt`] `seed`
    /// (it is not rebuilt again): appends one [`Splat`] per member in the class with a
    /// positive weight to `splats` (Alg. 1 with the breakup probability; see the type docs).
    ///
    /// Members whose `rebuild` returns `None` or a non-finite or non-positive
    /// `prefix_jacobian` are rejected. Members with zero weight are not appended. If
    /// `S = sum_k P(b|X_k) p_t(X_k) / J_k` is zero or not finite (a seed the sampler could not
    /// have produced), nothing is appended.
    pub fn explore<I: LocalIntegrand>(
        &self,
        u_bar: &[f64],
        seed: Rebuilt<I::Payload>,
        integrand: &mut I,
        splats: &mut Vec<Splat<I::Payload>>,
    ) -> Exploration {
        self.explore_with(
            u_bar,
            seed,
            integrand,
            splats,
            &mut ExploreScratch::default(),
        )
    }

    /// [`LocalQmc::explore`] with caller-owned buffers: once `scratch` has grown to the
    /// lattice's dimension, exploring allocates nothing (a renderer explores millions of
    /// seeds). The result is identical.
    pub fn explore_with<I: LocalIntegrand>(
        &self,
        u_bar: &[f64],
        seed: Rebuilt<I::Payload>,
        integrand: &mut I,
        splats: &mut Vec<Splat<I::Payload>>,
        scratch: &mut ExploreScratch,
    ) -> Exploration {
        let s = self.dims();
        assert_eq!(u_bar.len(), s, "seed and lattice dimensions differ");
        let ExploreScratch {
            tile,
            t,
            shift,
            u_j,
            t_j,
        } = scratch;
        for v in [&mut *t, &mut *shift, &mut *u_j, &mut *t_j] {
            v.clear();
            v.resize(s, 0.0);
        }
        tile.clear();
        tile.resize(s, 0);
        // Alg. 1 line 3 (as `locate` and `ShiftedLattice::through`, without allocating).
        self.tiling.to_tile(u_bar, tile, t);
        let closest = self.lattice.closest_point(t);
        let seed_index = closest.index;
        for ((d, &x), &r) in shift
            .iter_mut()
            .zip(t.iter())
            .zip(self.lattice.point(seed_index))
        {
            *d = torus_difference(x, r);
        }
        let start = splats.len();
        let mut stats = Exploration {
            seed_index,
            members: 0,
            rejected: 0,
        };
        let mut seed = Some(seed);
        // First pass (lines 5-13): rebuild, keep P/J in `weight`, accumulate S.
        let mut sum = 0.0;
        for j in 0..self.lattice.len() {
            let rebuilt = if j == seed_index {
                seed.take()
            } else {
                // Alg. 1 line 7: T^{-1}({r_j + Delta}).
                for ((o, &r), &d) in t_j.iter_mut().zip(self.lattice.point(j)).zip(shift.iter()) {
                    *o = wrap_unit(r + d);
                }
                self.tiling.invert(tile, t_j, u_j);
                integrand.rebuild(u_j)
            };
            let Some(r) =
                rebuilt.filter(|r| r.prefix_jacobian.is_finite() && r.prefix_jacobian > 0.0)
            else {
                stats.rejected += 1;
                continue;
            };
            debug_assert!(
                r.density.is_finite() && r.density >= 0.0,
                "density {}",
                r.density
            );
            debug_assert!(
                (0.0..=1.0).contains(&r.breakup_probability),
                "breakup probability {}",
                r.breakup_probability
            );
            stats.members += 1;
            let ratio = r.breakup_probability / r.prefix_jacobian;
            sum += ratio * r.density;
            splats.push(Splat {
                index: j,
                payload: r.payload,
                weight: ratio,
                value: r.contribution,
            });
        }
        // Second pass (lines 14-16): normalise.
        if sum > 0.0 && sum.is_finite() {
            for s in &mut splats[start..] {
                s.weight /= sum;
                s.value *= s.weight;
            }
            let mut k = start;
            for i in start..splats.len() {
                if splats[i].weight > 0.0 {
                    splats.swap(k, i);
                    k += 1;
                }
            }
            splats.truncate(k);
        } else {
            splats.truncate(start);
        }
        stats
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn uniform(u: &[f64]) -> Rebuilt<Vec<f64>> {
        Rebuilt {
            payload: u.to_vec(),
            contribution: 1.0,
            prefix_jacobian: 1.0,
            density: 1.0,
            breakup_probability: 1.0,
        }
    }

    #[test]
    fn constructor_checks_dimensions() {
        let l = Rank1Lattice::from_table(7, 2).unwrap();
        assert!(LocalQmc::new(l.clone(), Tiling::new(vec![2]).unwrap()).is_err());
        assert!(LocalQmc::new(l, Tiling::new(vec![2, 2]).unwrap()).is_ok());
    }

    /// Members lie in the seed's tile, are the shifted lattice, and include the seed.
    #[test]
    fn members_are_the_shifted_lattice_in_the_seed_tile() {
        let l = Rank1Lattice::from_table(23, 3).unwrap();
        let tiling = Tiling::new(vec![3, 1, 5])
            .unwrap()
            .with_jitter(&[0.4, 0.9, 0.1])
            .unwrap();
        let q = LocalQmc::new(l, tiling).unwrap();
        let seed = [0.93, 0.02, 0.5];
        let mut splats = Vec::new();
        let mut integrand = |u: &[f64]| Some(uniform(u));
        let stats = q.explore(&seed, uniform(&seed), &mut integrand, &mut splats);
        assert_eq!((stats.members, stats.rejected), (23, 0));
        assert_eq!(splats.len(), 23);
        let set = q.locate(&seed);
        for s in &splats {
            let again = q.locate(&s.payload);
            assert_eq!(again.tile(), set.tile());
            assert_eq!(again.seed_index(), s.index);
            assert!((s.weight - 1.0 / 23.0).abs() < 1e-15);
        }
        assert_eq!(splats[stats.seed_index as usize].payload, seed.to_vec());
    }

    /// The weights are a partition of unity in the sense of eq. 9: with `f = p_t`, the set's
    /// values sum to one, whatever the densities, Jacobians and breakup probabilities.
    #[test]
    fn weights_sum_to_one_when_f_is_the_density() {
        let l = Rank1Lattice::from_table(97, 2).unwrap();
        let q = LocalQmc::new(l, Tiling::new(vec![2, 7]).unwrap()).unwrap();
        let rebuilt = |u: &[f64]| {
            let p = 0.2 + 3.0 * u[0] * u[1];
            Rebuilt {
                payload: (),
                contribution: p,
                prefix_jacobian: 0.5 + u[1],
                density: p,
                breakup_probability: 0.1 + 0.8 * u[0],
            }
        };
        let mut integrand = |u: &[f64]| (u[0] < 0.9).then(|| rebuilt(u));
        for seed in [[0.1, 0.2], [0.55, 0.95], [0.3, 0.0]] {
            let mut splats = Vec::new();
            let stats = q.explore(&seed, rebuilt(&seed), &mut integrand, &mut splats);
            assert_eq!(stats.members + stats.rejected, 97);
            let total: f64 = splats.iter().map(|s| s.value).sum();
            assert!((total - 1.0).abs() < 1e-12, "{total}");
        }
    }

    #[test]
    fn rejected_members_and_degenerate_seeds() {
        let l = Rank1Lattice::from_table(7, 1).unwrap();
        let q = LocalQmc::new(l, Tiling::new(vec![1]).unwrap()).unwrap();
        let mut none = |_: &[f64]| -> Option<Rebuilt<Vec<f64>>> { None };
        let mut splats = Vec::new();
        let stats = q.explore(&[0.3], uniform(&[0.3]), &mut none, &mut splats);
        assert_eq!((stats.members, stats.rejected), (1, 6));
        assert_eq!(splats.len(), 1);
        assert_eq!(splats[0].value, 1.0);
        let mut zero = uniform(&[0.3]);
        zero.density = 0.0;
        splats.clear();
        let _ = q.explore(&[0.3], zero, &mut none, &mut splats);
        assert!(splats.is_empty());
    }

    /// One scratch reused across sets of different dimensions gives the splats of a fresh
    /// `explore` (negative control: a different seed gives different splats).
    #[test]
    fn reused_scratch_gives_the_same_splats() {
        let mut scratch = ExploreScratch::default();
        for (n, tiles, seed) in [
            (23, vec![3, 5, 2], vec![0.91, 0.12, 0.5]),
            (7, vec![2], vec![0.33]),
            (97, vec![4, 1, 6, 2, 9], vec![0.2, 0.4, 0.6, 0.8, 0.99]),
        ] {
            let l = Rank1Lattice::from_table(n, tiles.len()).unwrap();
            let jitter: Vec<f64> = (0..tiles.len()).map(|d| 0.1 * d as f64).collect();
            let q = LocalQmc::new(l, Tiling::new(tiles).unwrap().with_jitter(&jitter).unwrap())
                .unwrap();
            let mut integrand = |u: &[f64]| Some(uniform(u));
            let (mut a, mut b) = (Vec::new(), Vec::new());
            let sa = q.explore(&seed, uniform(&seed), &mut integrand, &mut a);
            let sb = q.explore_with(&seed, uniform(&seed), &mut integrand, &mut b, &mut scratch);
            assert_eq!((sa, &a), (sb, &b));
            let other: Vec<f64> = seed.iter().map(|x| (x + 0.37) % 1.0).collect();
            let mut c = Vec::new();
            let _ = q.explore_with(
                &other,
                uniform(&other),
                &mut integrand,
                &mut c,
                &mut scratch,
            );
            assert_ne!(a, c);
        }
    }

    #[test]
    fn public_types_are_send_and_sync() {
        fn check<T: Send + Sync>() {}
        check::<LocalQmc>();
        check::<LocalSet>();
        check::<Splat<()>>();
        check::<Rebuilt<()>>();
        check::<ExploreScratch>();
        check::<crate::Halton>();
        check::<crate::KorobovSpace>();
    }
}
