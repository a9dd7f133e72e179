//! Per-region angular scales over a path-space partition (regional-adaptive paper, section 5.2,
//! eq. 2-3), shared read-only by all chains between synchronisation points and written in
//! place at them.

use std::ops::Range;
use std::sync::atomic::{AtomicU64, Ordering};
use std::sync::Arc;

use mcmc_core::controller::{SharedRegionalScales, StateMove};
use mcmc_core::{Mh, Mixture, Partition};

use super::partition::PathPartition;
use crate::combine::PathMutation;
use crate::error::PathspaceError;
use crate::path::Path;
use crate::perturb::{DirectionKernel, Perturbation, ScaleSource};
use crate::scene::{Camera, PathScene};

/// `lambda_k = log sigma_k^2` for every region `k` of a partition, as a [`ScaleSource`]:
/// `sigmas(x) = [sigma_k, rho sigma_k]` with `k` the region of `x` and `sigma_k = e^{lambda_k / 2}`
/// (Alg. 1 line 9).
///
/// One `lambda` per region drives both scales of the multi-chain perturbation (`sigma_1` for
/// the primary ray, `sigma_2 = rho sigma_1` for the later chains, `rho` = `sigma_ratio`, 1 by
/// default): the paper adapts a single scalar per region from the acceptance of the whole
/// perturbation (section 9, "a single scalar parameter lambda is used to control the
/// perturbation of a high dimensional kernel"), so one acceptance rate tunes one number.
///
/// # Example
/// ```
/// use mcmc_core::Partition;
/// use pathspace::analytic::AnalyticScene;
/// use pathspace::regional::{PathPartition, PlanePartition, RegionalSigmas, ScreenPartition};
///
/// let scene = AnalyticScene::test_box().unwrap();
/// let screen = ScreenPartition::new(&scene, PlanePartition::quadtree(6).unwrap());
/// let mut sigmas = RegionalSigmas::new(PathPartition::Screen(screen), 1.0, 1.0).unwrap();
/// sigmas.set_lambda(0, (0.1f64 * 0.1).ln());
/// assert_eq!(sigmas.split(0), Some(1..4));
/// // Children inherit the parent's scale (section 6.2).
/// assert!(sigmas.lambdas().iter().all(|&l| (l - (0.01f64).ln()).abs() < 1e-12));
/// assert!((sigmas.sigmas_of_region(2)[0] - 0.1).abs() < 1e-12);
/// ```
#[derive(Debug)]
pub struct RegionalSigmas<P> {
    /// Behind its own `Arc`: a copy of the scales (a split while chains hold them) shares the
    /// partition until it is refined.
    partition: Arc<P>,
    /// `[lambda_k, sigma_k = e^{lambda_k / 2}]` as `f64` bits (the scale is kept so that a
    /// proposal reads it without an `exp`). Atomics so that a [`SharedSigmas`] handle can write
    /// in place at a synchronisation point while every chain's handle points at the same
    /// scales (no copy of the array per round); chains only read them between
    /// synchronisation points, so relaxed loads and stores suffice (the render loop's round
    /// boundary orders them).
    lambdas: Vec<[AtomicU64; 2]>,
    sigma_ratio: f64,
}

impl<P> Clone for RegionalSigmas<P> {
    fn clone(&self) -> Self {
        Self {
            partition: Arc::clone(&self.partition),
            lambdas: self
                .lambdas
                .iter()
                .map(|l| {
                    l.each_ref()
                        .map(|a| AtomicU64::new(a.load(Ordering::Relaxed)))
                })
                .collect(),
            sigma_ratio: self.sigma_ratio,
        }
    }
}

/// `sigma = e^{lambda / 2}` (Alg. 1 line 9).
#[inline]
fn sigma_of(lambda: f64) -> f64 {
    (0.5 * lambda).exp()
}

/// A region's stored `[lambda, sigma]`.
fn entry(lambda: f64) -> [AtomicU64; 2] {
    [
        AtomicU64::new(lambda.to_bits()),
        AtomicU64::new(sigma_of(lambda).to_bits()),
    ]
}

impl<P> RegionalSigmas<P> {
    /// `lambda_k` of a region.
    ///
    /// # Panics
    /// If `region >= num_regions()`.
    #[must_use]
    #[inline]
    pub fn lambda(&self, region: usize) -> f64 {
        f64::from_bits(self.lambdas[region][0].load(Ordering::Relaxed))
    }

    /// `lambda_k` per region id (a copy, for diagnostics).
    #[must_use]
    pub fn lambdas(&self) -> Vec<f64> {
        (0..self.lambdas.len()).map(|k| self.lambda(k)).collect()
    }

    /// Number of regions.
    #[must_use]
    pub fn num_regions(&self) -> usize {
        self.lambdas.len()
    }

    /// Sets `lambda` of a region.
    ///
    /// # Panics
    /// If `region >= num_regions()`.
    pub fn set_lambda(&mut self, region: usize, lambda: f64) {
        self.lambdas[region] = entry(lambda);
    }

    /// Sets `lambda` of a region through a shared reference: only at a synchronisation point,
    /// when no chain reads the scales.
    fn store_lambda(&self, region: usize, lambda: f64) {
        let [l, s] = &self.lambdas[region];
        l.store(lambda.to_bits(), Ordering::Relaxed);
        s.store(sigma_of(lambda).to_bits(), Ordering::Relaxed);
    }

    /// `sigma_2 / sigma_1`.
    #[must_use]
    pub fn sigma_ratio(&self) -> f64 {
        self.sigma_ratio
    }

    /// `[sigma_1, sigma_2]` of a region.
    ///
    /// # Panics
    /// If `region >= num_regions()`.
    #[must_use]
    #[inline]
    pub fn sigmas_of_region(&self, region: usize) -> [f64; 2] {
        let s = f64::from_bits(self.lambdas[region][1].load(Ordering::Relaxed));
        [s, s * self.sigma_ratio]
    }
}

impl<P: Partition<Path>> RegionalSigmas<P> {
    /// Every region of `partition` at `lambda0` (the paper's `lambda_0 = 1`, section 8.1), with
    /// `sigma_2 = sigma_ratio * sigma_1`.
    ///
    /// # Errors
    /// [`PathspaceError::InvalidParameter`] for a non-finite `lambda0` or a ratio outside
    /// `[1e-6, 1e6]`.
    pub fn new(partition: P, lambda0: f64, sigma_ratio: f64) -> Result<Self, PathspaceError> {
        PathspaceError::check_range("lambda0", lambda0, -700.0, 700.0)?;
        PathspaceError::check_range("sigma_ratio", sigma_ratio, 1e-6, 1e6)?;
        let n = partition.num_regions();
        Ok(Self {
            partition: Arc::new(partition),
            lambdas: (0..n).map(|_| entry(lambda0)).collect(),
            sigma_ratio,
        })
    }

    /// The partition.
    #[must_use]
    pub fn partition(&self) -> &P {
        &self.partition
    }

    /// Splits a region of the partition; every child inherits its `lambda` (section 6.2).
    /// Returns the fresh ids (the split id is the first child), `None` if it cannot split.
    pub fn split(&mut self, region: usize) -> Option<Range<usize>>
    where
        P: Clone,
    {
        let fresh = Arc::make_mut(&mut self.partition).split(region)?;
        let parent = self.lambda(region);
        self.lambdas
            .resize_with(self.partition.num_regions(), || entry(parent));
        for k in fresh.clone() {
            self.lambdas[k] = entry(parent);
        }
        Some(fresh)
    }
}

impl<C: Camera> RegionalSigmas<PathPartition<C>> {
    /// A heat map of the learned scale over the screen: `sigma_1` at every pixel centre of a
    /// `width x height` raster (row-major, row 0 at raster `y = 0`). For a 4-D partition the
    /// pixel's top cell holds many direction regions; the map shows `e^{m/2}` with `m` the
    /// area-weighted mean of their `lambda` over `[0, 1)^2` (a geometric mean of `sigma`).
    ///
    /// # Example
    /// ```
    /// use pathspace::analytic::AnalyticScene;
    /// use pathspace::regional::{PathPartition, PlanePartition, RegionalSigmas, ScreenPartition};
    ///
    /// let scene = AnalyticScene::test_box().unwrap();
    /// let grid = ScreenPartition::new(&scene, PlanePartition::grid(2).unwrap());
    /// let mut sigmas = RegionalSigmas::new(PathPartition::Screen(grid), 0.0, 1.0).unwrap();
    /// sigmas.set_lambda(1, (0.25f64).ln()); // top-right cell: sigma = 0.5
    /// let map = sigmas.screen_sigma_map(4, 2);
    /// assert_eq!(map[0], 1.0);
    /// assert!((map[3] - 0.5).abs() < 1e-12);
    /// ```
    #[must_use]
    pub fn screen_sigma_map(&self, width: usize, height: usize) -> Vec<f64> {
        let sigma = |lambda: f64| (0.5 * lambda).exp();
        let centre = |i: usize, n: usize| (i as f64 + 0.5) / n as f64;
        let mut map = Vec::with_capacity(width * height);
        match &*self.partition {
            PathPartition::Single => map.resize(width * height, sigma(self.lambda(0))),
            PathPartition::Screen(p) => {
                for y in 0..height {
                    for x in 0..width {
                        let k = p.plane().region([centre(x, width), centre(y, height)]);
                        map.push(sigma(self.lambda(k)));
                    }
                }
            }
            PathPartition::Direction(p) => {
                let n = p.top_cells_per_axis();
                let cell_mean: Vec<f64> = (0..n * n)
                    .map(|c| {
                        let screen = [centre(c % n, n), centre(c / n, n)];
                        let leaves = p.cell_partition(c);
                        (0..leaves.num_regions())
                            .map(|l| {
                                let [lo, hi] = leaves.bounds(l);
                                let mid = [0.5 * (lo[0] + hi[0]), 0.5 * (lo[1] + hi[1])];
                                let area = (hi[0] - lo[0]) * (hi[1] - lo[1]);
                                area * self.lambda(p.region_of_point(screen, mid))
                            })
                            .sum::<f64>()
                    })
                    .collect();
                for y in 0..height {
                    for x in 0..width {
                        let cell = |v: f64| ((v * n as f64) as usize).min(n - 1);
                        let c = cell(centre(y, height)) * n + cell(centre(x, width));
                        map.push(sigma(cell_mean[c]));
                    }
                }
            }
        }
        map
    }
}

impl<P: Partition<Path>> ScaleSource for RegionalSigmas<P> {
    fn sigmas(&self, x: &Path) -> [f64; 2] {
        self.sigmas_of_region(self.partition.region(x))
    }
}

/// A [`RegionalSigmas`] behind an [`Arc`]: what every chain's perturbation holds. Chains read
/// it without locks; the shared controller
/// ([`crate::regional::SharedRegionalAdaptation`]) writes its `lambda`s in place at the
/// synchronisation points of the render loop (all clones see them from the next round) and
/// hands every chain a new handle only after a split. Cloning is cheap (a reference count).
///
/// Each handle can also track the region of its chain's current state, on request of the
/// controller ([`SharedRegionalScales::track_current_region`]): the perturbation looks up the
/// region of every candidate for the reverse density anyway (eq. 2-3), and once the candidate
/// is accepted that is the current state's region, so the next steps need no lookup of their
/// own. With the region it keeps the region's `sigma_1` as read in this round (the scales
/// change only at synchronisation points, after which the controller calls
/// [`SharedRegionalScales::scales_published`]), so a step reads the shared scales only for
/// its candidate. The record is the handle's own, never shared, and a clone does not track.
#[derive(Debug)]
pub struct SharedSigmas<P> {
    sigmas: Arc<RegionalSigmas<P>>,
    /// `NOT_TRACKING`, `UNKNOWN`, or the region of the chain's current state.
    current: AtomicU64,
    /// `UNKNOWN`, or the region of this step's candidate.
    candidate: AtomicU64,
    /// `sigma_1` of `current` read since the last synchronisation point (`f64` bits), or
    /// `NO_SIGMA`.
    current_sigma: AtomicU64,
    /// `sigma_1` of `candidate` (`f64` bits), valid while `candidate` is.
    candidate_sigma: AtomicU64,
}

/// [`SharedSigmas::current`]: not tracking.
const NOT_TRACKING: u64 = u64::MAX;
/// [`SharedSigmas::current`], [`SharedSigmas::candidate`]: tracking, region not known.
const UNKNOWN: u64 = u64::MAX - 1;
/// [`SharedSigmas::current_sigma`]: not read yet (a NaN pattern no scale has).
const NO_SIGMA: u64 = u64::MAX;

impl<P> Clone for SharedSigmas<P> {
    fn clone(&self) -> Self {
        Self::from_arc(Arc::clone(&self.sigmas))
    }
}

impl<P> SharedSigmas<P> {
    /// Shares `sigmas`.
    pub fn new(sigmas: RegionalSigmas<P>) -> Self {
        Self::from_arc(Arc::new(sigmas))
    }

    /// A handle that does not track.
    fn from_arc(sigmas: Arc<RegionalSigmas<P>>) -> Self {
        Self {
            sigmas,
            current: AtomicU64::new(NOT_TRACKING),
            candidate: AtomicU64::new(UNKNOWN),
            current_sigma: AtomicU64::new(NO_SIGMA),
            candidate_sigma: AtomicU64::new(NO_SIGMA),
        }
    }

    /// The scales.
    #[must_use]
    pub fn get(&self) -> &RegionalSigmas<P> {
        &self.sigmas
    }

    /// Mutable access, copying the scales first if another holder still shares them.
    pub fn make_mut(&mut self) -> &mut RegionalSigmas<P>
    where
        P: Clone,
    {
        Arc::make_mut(&mut self.sigmas)
    }

    /// True if both share the same allocation.
    #[must_use]
    pub fn ptr_eq(&self, other: &Self) -> bool {
        Arc::ptr_eq(&self.sigmas, &other.sigmas)
    }
}

/// The handle mcmc-core's shared regional controller reads and publishes. `lambda` writes go
/// in place to the scales every chain's handle shares (the controller writes only at
/// synchronisation points, when no chain steps): a round costs no copy of the `lambda` array,
/// however many regions there are. Splits copy the scales first if another chain still holds
/// them (`Arc::make_mut`; once per refinement pass).
impl<P: Partition<Path> + Clone> SharedRegionalScales for SharedSigmas<P> {
    type Partition = P;
    fn partition(&self) -> &P {
        self.get().partition()
    }
    fn num_regions(&self) -> usize {
        self.get().num_regions()
    }
    fn log_scale_of(&self, region: usize) -> f64 {
        self.get().lambda(region)
    }
    fn set_log_scale_of(&mut self, region: usize, lambda: f64) {
        self.get().store_lambda(region, lambda);
    }
    fn split_region(&mut self, region: usize) -> Option<Range<usize>> {
        self.make_mut().split(region)
    }
    fn same_as(&self, other: &Self) -> bool {
        self.ptr_eq(other)
    }
    fn track_current_region(&self) -> bool {
        if self.current.load(Ordering::Relaxed) == NOT_TRACKING {
            self.current.store(UNKNOWN, Ordering::Relaxed);
        }
        true
    }
    fn current_region(&self) -> Option<usize> {
        let c = self.current.load(Ordering::Relaxed);
        (c < UNKNOWN).then_some(c as usize)
    }
    fn set_current_region(&self, region: usize) {
        if self.current.load(Ordering::Relaxed) != NOT_TRACKING {
            self.current.store(region as u64, Ordering::Relaxed);
            self.current_sigma.store(NO_SIGMA, Ordering::Relaxed);
        }
    }
    fn end_step(&self, moved: StateMove) {
        let candidate = self.candidate.load(Ordering::Relaxed);
        if candidate != UNKNOWN {
            self.candidate.store(UNKNOWN, Ordering::Relaxed);
        }
        if self.current.load(Ordering::Relaxed) == NOT_TRACKING {
            return;
        }
        match moved {
            StateMove::Stayed => {}
            StateMove::ByScaledProposal => {
                self.current.store(candidate, Ordering::Relaxed);
                let sigma = if candidate == UNKNOWN {
                    NO_SIGMA
                } else {
                    self.candidate_sigma.load(Ordering::Relaxed)
                };
                self.current_sigma.store(sigma, Ordering::Relaxed);
            }
            StateMove::ByOtherProposal => {
                self.current.store(UNKNOWN, Ordering::Relaxed);
                self.current_sigma.store(NO_SIGMA, Ordering::Relaxed);
            }
        }
    }
    fn scales_published(&self) {
        self.current_sigma.store(NO_SIGMA, Ordering::Relaxed);
    }
}

impl<P: Partition<Path>> ScaleSource for SharedSigmas<P> {
    fn sigmas(&self, x: &Path) -> [f64; 2] {
        self.sigmas
            .sigmas_of_region(self.sigmas.partition.region(x))
    }

    /// The tracked region (and its scale) of the current state if known; otherwise looked
    /// up (and recorded when tracking).
    fn current_sigmas(&self, x: &Path) -> [f64; 2] {
        let c = self.current.load(Ordering::Relaxed);
        if c < UNKNOWN {
            debug_assert_eq!(c as usize, self.sigmas.partition.region(x));
            let s = self.current_sigma.load(Ordering::Relaxed);
            if s != NO_SIGMA {
                let s = f64::from_bits(s);
                return [s, s * self.sigmas.sigma_ratio];
            }
            let sigmas = self.sigmas.sigmas_of_region(c as usize);
            self.current_sigma
                .store(sigmas[0].to_bits(), Ordering::Relaxed);
            return sigmas;
        }
        let region = self.sigmas.partition.region(x);
        let sigmas = self.sigmas.sigmas_of_region(region);
        if c == UNKNOWN {
            self.current.store(region as u64, Ordering::Relaxed);
            self.current_sigma
                .store(sigmas[0].to_bits(), Ordering::Relaxed);
        }
        sigmas
    }

    /// Looked up, and recorded (with its scale) as the candidate's region when tracking.
    fn candidate_sigmas(&self, y: &Path) -> [f64; 2] {
        let region = self.sigmas.partition.region(y);
        let sigmas = self.sigmas.sigmas_of_region(region);
        if self.current.load(Ordering::Relaxed) != NOT_TRACKING {
            self.candidate.store(region as u64, Ordering::Relaxed);
            self.candidate_sigma
                .store(sigmas[0].to_bits(), Ordering::Relaxed);
        }
        sigmas
    }
}

/// A kernel (or a proposal inside one) that perturbs with [`SharedSigmas`]: how the shared
/// controller finds the scales to read regions from and to replace at synchronisation points.
///
/// Implemented by [`SharedSigmas`] itself, a [`Perturbation`] over them, a [`PathMutation`]
/// (its perturbation), a [`Mixture`] (its first component that has them) and [`Mh`].
pub trait HasSharedSigmas {
    /// The partition type.
    type Partition;
    /// The scales, if this kernel has them.
    fn shared_sigmas(&self) -> Option<&SharedSigmas<Self::Partition>>;
    /// Mutable access to the scales, if this kernel has them.
    fn shared_sigmas_mut(&mut self) -> Option<&mut SharedSigmas<Self::Partition>>;
}

impl<P> HasSharedSigmas for SharedSigmas<P> {
    type Partition = P;
    fn shared_sigmas(&self) -> Option<&SharedSigmas<P>> {
        Some(self)
    }
    fn shared_sigmas_mut(&mut self) -> Option<&mut SharedSigmas<P>> {
        Some(self)
    }
}

impl<S, K, P> HasSharedSigmas for Perturbation<'_, S, SharedSigmas<P>, K>
where
    S: PathScene + ?Sized,
    K: DirectionKernel,
    P: Partition<Path>,
{
    type Partition = P;
    fn shared_sigmas(&self) -> Option<&SharedSigmas<P>> {
        Some(self.scale())
    }
    fn shared_sigmas_mut(&mut self) -> Option<&mut SharedSigmas<P>> {
        Some(self.scale_mut())
    }
}

impl<X: HasSharedSigmas, G> HasSharedSigmas for PathMutation<X, G> {
    type Partition = X::Partition;
    fn shared_sigmas(&self) -> Option<&SharedSigmas<X::Partition>> {
        match self {
            Self::Perturb(p) => p.shared_sigmas(),
            Self::Global(_) => None,
        }
    }
    fn shared_sigmas_mut(&mut self) -> Option<&mut SharedSigmas<X::Partition>> {
        match self {
            Self::Perturb(p) => p.shared_sigmas_mut(),
            Self::Global(_) => None,
        }
    }
}

impl<X: HasSharedSigmas, Sel> HasSharedSigmas for Mixture<X, Sel> {
    type Partition = X::Partition;
    fn shared_sigmas(&self) -> Option<&SharedSigmas<X::Partition>> {
        self.components()
            .iter()
            .find_map(HasSharedSigmas::shared_sigmas)
    }
    fn shared_sigmas_mut(&mut self) -> Option<&mut SharedSigmas<X::Partition>> {
        self.components_mut()
            .iter_mut()
            .find_map(HasSharedSigmas::shared_sigmas_mut)
    }
}

impl<X: HasSharedSigmas> HasSharedSigmas for Mh<X> {
    type Partition = X::Partition;
    fn shared_sigmas(&self) -> Option<&SharedSigmas<X::Partition>> {
        self.proposal.shared_sigmas()
    }
    fn shared_sigmas_mut(&mut self) -> Option<&mut SharedSigmas<X::Partition>> {
        self.proposal.shared_sigmas_mut()
    }
}
