//! How MALA learns: the adaptation state `theta` and the proposal Gaussian it implies at a
//! point (plain, online, full online, cache-driven, hybrid).

use super::cache::Neighbours;
use super::cache_view::CacheView;
#[cfg(feature = "nalgebra")]
use super::full_online::FullOnline;
use super::gaussian::ProposalGaussian;
use super::params::{AdamStart, LangevinParams};

/// The adaptation of MALA with adaptation (Luan et al. 2020, Alg. 1-4): a parameter `theta` (the accumulated
/// gradient statistics, or the gradient cache) and the rule that forms the proposal
/// Gaussian at a point `u` from `theta` and the truncated gradient `g(u)`.
///
/// # The reverse density (controlled MCMC, sections 5.1 and 6)
/// A step at time `t` is an MH step of the kernel `P(. ; theta_t)`, whose proposal
/// `T(u -> v; theta_t) = N(v; u + Sigma(u) m(u) / 2, Sigma(u))` depends on the point it
/// starts from *only through* `u` and `g(u)`, with `theta_t` fixed for the whole step. So the
/// reverse density `T(v -> u; theta_t)` is [`Adaptation::gaussian`] at `v` with `g(v)` under
/// the *same* `theta_t`: Alg. 2's `G^(t) = beta G^(t-1) + (1 - beta) g^(t) (.) g^(t)` is, for
/// the reverse move, `beta G^(t-1) + (1 - beta) g(v) (.) g(v)`. Only after the decision does
/// [`Adaptation::adapt`] fold `g(u^(t))` into `theta` (`theta_{t+1}`). Each `P(.; theta)` is
/// then `pi`-invariant, which is condition C.1; C.3 (diminishing or finite adaptation) does
/// the rest. (The authors' code blends `g(v)` into the *current* chain statistics, which
/// already hold `g(u)`: forward and reverse then use different `theta`, and the pairwise
/// balance check fails; docs/methods/mala.md.)
pub trait Adaptation: Clone + Send + std::fmt::Debug {
    /// A short name (`"plain"`, `"online"`, ...).
    fn name(&self) -> &'static str;
    /// True if [`Adaptation::gaussian`] at a point of dimension `dim` reads the gradient there
    /// (false lets a kernel skip gradient evaluations, e.g. a frozen full cache).
    fn needs_gradient(&self, dim: usize) -> bool;
    /// Forms the proposal Gaussian at `u` with truncated gradient `g` under the current
    /// `theta` (does not change `theta`; `&mut` for scratch buffers).
    fn gaussian(
        &mut self,
        params: &LangevinParams,
        u: &[f64],
        g: &[f64],
        out: &mut ProposalGaussian,
    ) -> bool;
    /// Advances `theta` with the gradient at the state the step proposed from.
    /// `first_visit` is true the first time a step proposes from this state (the cache
    /// stores each visited state once: `C` is a set, eq. 21). No-op once frozen.
    fn adapt(&mut self, params: &LangevinParams, u: &[f64], g: &[f64], first_visit: bool);
    /// Stops adaptation: `theta` stays as it is (for the harness, and for finite adaptation
    /// by the user).
    fn freeze(&mut self);
    /// True once `theta` no longer changes.
    fn is_frozen(&self) -> bool;
    /// A large step was accepted: the chain is somewhere new. Adaptations whose statistics
    /// are local restart them ([`Online`] with [`AdamStart::FirstVisit`]); none by default.
    /// Like [`Adaptation::adapt`] it runs after a decision, so each step's kernel is still
    /// `pi`-invariant. No-op once frozen.
    fn restart(&mut self, params: &LangevinParams) {
        let _ = params;
    }
    /// Calls `f` on every gradient cache the adaptation holds (shared by the render loop
    /// through [`super::CacheSharing`]); none by default.
    fn for_each_cache(&mut self, f: &mut dyn FnMut(&mut CacheView)) {
        let _ = f;
    }
}

/// Two zeroed scratch vectors of length `n` (on the stack up to 64 dimensions) for forming a
/// diagonal Gaussian without allocating.
fn with_buffers<R>(n: usize, f: impl FnOnce(&mut [f64], &mut [f64]) -> R) -> R {
    if n <= 64 {
        let (mut a, mut b) = ([0.0f64; 64], [0.0f64; 64]);
        f(&mut a[..n], &mut b[..n])
    } else {
        f(&mut vec![0.0; n], &mut vec![0.0; n])
    }
}

/// The diminishing-adaptation weights `(t^-c1, t^-c2)` of step `steps + 1` (eq. 19-20), or
/// `(1, 1)` without diminishing adaptation.
pub(super) fn diminishing_weights(
    params: &LangevinParams,
    steps: u64,
    diminishing: bool,
) -> (f64, f64) {
    if diminishing {
        let t = (steps + 1) as f64;
        (t.powf(-params.c1), t.powf(-params.c2))
    } else {
        (1.0, 1.0)
    }
}

/// Plain MALA (eq. 7): `M = I`, `m = g`; nothing adapts.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub struct Plain;

/// Fills a per-dimension buffer of ones (stack up to 64 dimensions).
fn ones_like<R>(d: usize, f: impl FnOnce(&[f64]) -> R) -> R {
    let stack = [1.0f64; 64];
    if d <= 64 {
        f(&stack[..d])
    } else {
        f(&vec![1.0; d])
    }
}

impl Adaptation for Plain {
    fn name(&self) -> &'static str {
        "plain"
    }
    fn needs_gradient(&self, _dim: usize) -> bool {
        true
    }
    fn gaussian(
        &mut self,
        params: &LangevinParams,
        _u: &[f64],
        g: &[f64],
        out: &mut ProposalGaussian,
    ) -> bool {
        ones_like(g.len(), |ones| out.set_diagonal(params, ones, g));
        true
    }
    fn adapt(&mut self, _: &LangevinParams, _: &[f64], _: &[f64], _: bool) {}
    fn freeze(&mut self) {}
    fn is_frozen(&self) -> bool {
        true
    }
}

/// Online adaptation (section 5, Alg. 2): Adam-like diagonal preconditioner and momentum.
///
/// At step `t` (1-based) from `u` with gradient `g`:
/// `G' = beta G + (1 - beta) g (.) g`, `d' = alpha d + (1 - alpha) g`,
/// `H = (1 - w1) 1 + w1 (delta 1 + sqrt(G'))`, `M = 1 (/) H`, `m = g + w2 d'`,
/// with `w1 = t^-c1`, `w2 = t^-c2` under diminishing adaptation and `w1 = w2 = 1` without
/// (the hybrid's first stage, Alg. 4, and the paper's biased Fig. 3g).
///
/// # Reading of eq. 19
/// Eq. 19 as printed, `H = delta I + t^-c1 sqrt(G)`, tends to `delta I`, i.e. `M -> I / delta`
/// (1000 I for `delta = 0.001`: a proposal standard deviation of `sqrt(10)` in primary sample
/// space), while the text says the process "converges to standard MALA without
/// preconditioning or momentum (eq. 7)". We implement what the text says: the Adam
/// preconditioner is blended towards the identity with weight `t^-c1`, so `M -> I` and
/// `m -> g` (plain MALA) as `t -> inf`. No bias correction (the paper's footnote 2). With the
/// switches [`Online::without_momentum`] / [`Online::without_preconditioning`] it gives the
/// ablations of Fig. 2.
///
/// # Start ([`LangevinParams::adam_start`])
/// With [`AdamStart::FirstVisit`] (the authors' code) the accumulators are *fresh* at the
/// start and after every accepted large step ([`Adaptation::restart`]): while fresh,
/// the Gaussian at `u` uses `G' = g (.) g`, `d' = g` (the Adam update with `G`, `d` equal to
/// the point's own gradient, an implicit bias correction), and the first [`Adaptation::adapt`]
/// sets `G = g (.) g`, `d = g`. The step counter `t` (the diminishing weights) is not reset,
/// so diminishing adaptation still holds. Freshness is part of `theta`: forward and reverse
/// densities of a step see the same value.
#[derive(Clone, Debug, PartialEq)]
pub struct Online {
    g2: Vec<f64>,
    d: Vec<f64>,
    /// No gradient folded in since the start or the last restart.
    fresh: bool,
    t: u64,
    diminishing: bool,
    momentum: bool,
    precondition: bool,
    frozen: bool,
}

impl Online {
    /// Online adaptation, with diminishing adaptation (`true`: Alg. 2, ergodic) or without
    /// (`false`: biased when used alone; the hybrid uses it until its cache is full).
    #[must_use]
    pub fn new(diminishing: bool) -> Self {
        Self {
            g2: Vec::new(),
            d: Vec::new(),
            fresh: true,
            t: 0,
            diminishing,
            momentum: true,
            precondition: true,
            frozen: false,
        }
    }

    /// Without the momentum term (`m = g`).
    #[must_use]
    pub fn without_momentum(mut self) -> Self {
        self.momentum = false;
        self
    }

    /// Without the preconditioner (`M = I`).
    #[must_use]
    pub fn without_preconditioning(mut self) -> Self {
        self.precondition = false;
        self
    }

    /// Steps adapted so far.
    #[must_use]
    pub fn steps(&self) -> u64 {
        self.t
    }

    /// Sets the step counter (e.g. to test the state reached after a long run).
    pub fn set_steps(&mut self, t: u64) {
        self.t = t;
    }

    /// True with diminishing adaptation.
    #[must_use]
    pub fn is_diminishing(&self) -> bool {
        self.diminishing
    }

    fn ensure_dim(&mut self, d: usize) {
        if self.g2.len() != d {
            self.g2.clear();
            self.g2.resize(d, 0.0);
            self.d.clear();
            self.d.resize(d, 0.0);
        }
    }
}

impl Adaptation for Online {
    fn name(&self) -> &'static str {
        "online"
    }
    fn needs_gradient(&self, _dim: usize) -> bool {
        true
    }
    fn gaussian(
        &mut self,
        params: &LangevinParams,
        _u: &[f64],
        g: &[f64],
        out: &mut ProposalGaussian,
    ) -> bool {
        let n = g.len();
        self.ensure_dim(n);
        let (w1, w2) = diminishing_weights(params, self.t, self.diminishing);
        let first = self.fresh && params.adam_start == AdamStart::FirstVisit;
        with_buffers(n, |m_diag, drift| {
            for i in 0..n {
                m_diag[i] = if self.precondition {
                    let g2 = if first {
                        g[i] * g[i]
                    } else {
                        params.beta * self.g2[i] + (1.0 - params.beta) * g[i] * g[i]
                    };
                    1.0 / ((1.0 - w1) + w1 * (params.delta + g2.sqrt()))
                } else {
                    1.0
                };
                drift[i] = if self.momentum {
                    let d = if first {
                        g[i]
                    } else {
                        params.alpha * self.d[i] + (1.0 - params.alpha) * g[i]
                    };
                    g[i] + w2 * d
                } else {
                    g[i]
                };
            }
            out.set_diagonal(params, m_diag, drift);
        });
        true
    }
    fn adapt(&mut self, params: &LangevinParams, _u: &[f64], g: &[f64], _first_visit: bool) {
        if self.frozen {
            return;
        }
        self.ensure_dim(g.len());
        let first = self.fresh && params.adam_start == AdamStart::FirstVisit;
        for ((g2, d), &gi) in self.g2.iter_mut().zip(&mut self.d).zip(g) {
            if first {
                (*g2, *d) = (gi * gi, gi);
            } else {
                *g2 = params.beta * *g2 + (1.0 - params.beta) * gi * gi;
                *d = params.alpha * *d + (1.0 - params.alpha) * gi;
            }
        }
        self.fresh = false;
        self.t += 1;
    }
    fn restart(&mut self, params: &LangevinParams) {
        if !self.frozen && params.adam_start == AdamStart::FirstVisit {
            self.fresh = true;
        }
    }
    fn freeze(&mut self) {
        self.frozen = true;
    }
    fn is_frozen(&self) -> bool {
        self.frozen
    }
}

/// Cache-driven adaptation (section 6, eq. 21-28, Alg. 3).
///
/// The proposal at `u` uses the query `Q` of the `K` nearest cache entries within `r`:
/// `G = mean over Q of g (.) g`, `M = 1 (/) (delta + sqrt(G))`, `m = mean over Q of g`.
/// While the cache is not full, `Q` is taken over `C u {(u, g(u))}` (Alg. 3 inserts the
/// current state before querying; we make the insertion part of the proposal rule, so that
/// the reverse density at `v` uses `C u {(v, g(v))}` under the same `C`), and each visited
/// state is stored once, after its first step. Once the cache holds `H` entries it stops
/// growing (finite adaptation) and the proposal no longer reads the gradient at `u`. If `Q`
/// is empty (a frozen cache with nothing within `r`), the proposal is the isotropic
/// `N(0, epsilon I)` without drift ("no preconditioning", section 6).
#[derive(Clone, Debug)]
pub struct CacheDriven {
    view: CacheView,
    neighbours: Neighbours,
    frozen: bool,
}

impl CacheDriven {
    /// An empty cache of capacity `params.cache_size`.
    #[must_use]
    pub fn new(params: &LangevinParams) -> Self {
        Self {
            view: CacheView::new(params.cache_size),
            neighbours: Neighbours::new(params.neighbours),
            frozen: false,
        }
    }

    /// The cache.
    #[must_use]
    pub fn cache(&self) -> &CacheView {
        &self.view
    }
}

impl Adaptation for CacheDriven {
    fn name(&self) -> &'static str {
        "cache"
    }
    fn needs_gradient(&self, _dim: usize) -> bool {
        !self.view.is_full()
    }
    fn gaussian(
        &mut self,
        params: &LangevinParams,
        u: &[f64],
        g: &[f64],
        out: &mut ProposalGaussian,
    ) -> bool {
        let n = u.len();
        self.view.query(
            u,
            params.query_radius(u.len()),
            params.neighbours,
            &mut self.neighbours,
        );
        let include_self = !self.view.is_full()
            && g.len() == n
            && !self.neighbours.iter().any(|nb| nb.dist2 == 0.0);
        // With the virtual self entry (distance 0, always nearest), keep K - 1 others.
        let others = if include_self {
            params.neighbours - 1
        } else {
            params.neighbours
        };
        with_buffers(n, |g2, mean| {
            let mut count = 0usize;
            if include_self {
                for i in 0..n {
                    g2[i] += g[i] * g[i];
                    mean[i] += g[i];
                }
                count += 1;
            }
            for nb in self.neighbours.iter().take(others) {
                let gc = self.view.gradient(nb.source, nb.index);
                for i in 0..n {
                    g2[i] += gc[i] * gc[i];
                    mean[i] += gc[i];
                }
                count += 1;
            }
            if count == 0 {
                ones_like(n, |ones| {
                    mean.fill(0.0);
                    out.set_diagonal(params, ones, mean);
                });
                return;
            }
            let s = 1.0 / count as f64;
            for i in 0..n {
                g2[i] = 1.0 / (params.delta + (g2[i] * s).sqrt());
                mean[i] *= s;
            }
            out.set_diagonal(params, g2, mean);
        });
        true
    }
    fn adapt(&mut self, _params: &LangevinParams, u: &[f64], g: &[f64], first_visit: bool) {
        if !self.frozen && first_visit && g.len() == u.len() {
            self.view.push(u, g);
        }
    }
    fn freeze(&mut self) {
        self.frozen = true;
    }
    fn is_frozen(&self) -> bool {
        self.frozen || self.view.is_full()
    }
    fn for_each_cache(&mut self, f: &mut dyn FnMut(&mut CacheView)) {
        f(&mut self.view);
    }
}

/// Hybrid adaptation (section 6, Alg. 4): [`Online`] adaptation *without* diminishing
/// adaptation while the cache holds fewer than `H` entries (filling the cache with every
/// visited state), then [`CacheDriven`] only, with the cache frozen. Ergodic by finite
/// adaptation: after the switch the kernel no longer changes.
///
/// # Reading
/// Alg. 4's listing writes the first-stage momentum as `m = alpha m + (1 - alpha) g` (no `g`
/// term) while its text says "online adaptation as in Algorithm 2 with `c1 = c2 = 0`", which
/// gives `m = g + d`. We follow the text.
#[derive(Clone, Debug)]
pub struct Hybrid {
    online: Online,
    cache: CacheDriven,
}

impl Hybrid {
    /// An empty hybrid adaptation.
    #[must_use]
    pub fn new(params: &LangevinParams) -> Self {
        Self {
            online: Online::new(false),
            cache: CacheDriven::new(params),
        }
    }

    /// The cache.
    #[must_use]
    pub fn cache(&self) -> &CacheView {
        self.cache.cache()
    }

    /// True while the online stage runs.
    #[must_use]
    pub fn is_online(&self) -> bool {
        !self.cache.view.is_full()
    }
}

impl Adaptation for Hybrid {
    fn name(&self) -> &'static str {
        "hybrid"
    }
    fn needs_gradient(&self, _dim: usize) -> bool {
        self.is_online()
    }
    fn gaussian(
        &mut self,
        params: &LangevinParams,
        u: &[f64],
        g: &[f64],
        out: &mut ProposalGaussian,
    ) -> bool {
        if self.is_online() {
            self.online.gaussian(params, u, g, out)
        } else {
            self.cache.gaussian(params, u, g, out)
        }
    }
    fn adapt(&mut self, params: &LangevinParams, u: &[f64], g: &[f64], first_visit: bool) {
        if self.is_online() && !self.cache.frozen {
            self.online.adapt(params, u, g, first_visit);
            self.cache.adapt(params, u, g, first_visit);
        }
    }
    fn restart(&mut self, params: &LangevinParams) {
        if self.is_online() {
            self.online.restart(params);
        }
    }
    fn freeze(&mut self) {
        self.online.freeze();
        self.cache.freeze();
    }
    fn is_frozen(&self) -> bool {
        self.cache.is_frozen()
    }
    fn for_each_cache(&mut self, f: &mut dyn FnMut(&mut CacheView)) {
        self.cache.for_each_cache(f);
    }
}

/// One adaptation per dimension: a copy of `prototype` is made for each dimension the chain
/// meets, and the Gaussian at a point uses the copy for the point's dimension. For targets
/// whose states differ in dimension (primary sample space: paths of different lengths or
/// MMLT strategies), so that statistics and caches are never mixed across dimensions (the
/// authors' code keeps one cache per dimension). Each copy adapts only at points of its
/// dimension; the whole is frozen once every copy made so far is (a new dimension starts a
/// fresh copy).
#[derive(Clone, Debug)]
pub struct PerDimension<A> {
    prototype: A,
    entries: Vec<(usize, A)>,
    frozen: bool,
}

impl<A: Adaptation> PerDimension<A> {
    /// Copies of `prototype` per dimension.
    #[must_use]
    pub fn new(prototype: A) -> Self {
        Self {
            prototype,
            entries: Vec::new(),
            frozen: false,
        }
    }

    /// The adaptation of dimension `dim`, if the chain met it.
    #[must_use]
    pub fn get(&self, dim: usize) -> Option<&A> {
        self.entries.iter().find(|(d, _)| *d == dim).map(|(_, a)| a)
    }

    fn entry(&mut self, dim: usize) -> &mut A {
        let i = match self.entries.iter().position(|(d, _)| *d == dim) {
            Some(i) => i,
            None => {
                let mut a = self.prototype.clone();
                if self.frozen {
                    a.freeze();
                }
                self.entries.push((dim, a));
                self.entries.len() - 1
            }
        };
        &mut self.entries[i].1
    }
}

impl<A: Adaptation> Adaptation for PerDimension<A> {
    fn name(&self) -> &'static str {
        self.prototype.name()
    }
    fn needs_gradient(&self, dim: usize) -> bool {
        self.get(dim).unwrap_or(&self.prototype).needs_gradient(dim)
    }
    fn gaussian(
        &mut self,
        params: &LangevinParams,
        u: &[f64],
        g: &[f64],
        out: &mut ProposalGaussian,
    ) -> bool {
        self.entry(u.len()).gaussian(params, u, g, out)
    }
    fn adapt(&mut self, params: &LangevinParams, u: &[f64], g: &[f64], first_visit: bool) {
        if !self.frozen {
            self.entry(u.len()).adapt(params, u, g, first_visit);
        }
    }
    fn restart(&mut self, params: &LangevinParams) {
        for (_, a) in &mut self.entries {
            a.restart(params);
        }
    }
    fn freeze(&mut self) {
        self.frozen = true;
        for (_, a) in &mut self.entries {
            a.freeze();
        }
    }
    fn is_frozen(&self) -> bool {
        self.frozen
    }
    fn for_each_cache(&mut self, f: &mut dyn FnMut(&mut CacheView)) {
        for (_, a) in &mut self.entries {
            a.for_each_cache(f);
        }
    }
}

/// Any of the adaptations, chosen at run time (a command-line `--integrator mala-online`, a
/// table of variants in a test): one type for kernels that must hold any of them.
#[derive(Clone, Debug)]
pub enum AnyAdaptation {
    /// [`Plain`].
    Plain(Plain),
    /// [`Online`].
    Online(Online),
    /// [`FullOnline`] (feature `nalgebra`).
    #[cfg(feature = "nalgebra")]
    Full(FullOnline),
    /// [`CacheDriven`].
    Cache(CacheDriven),
    /// [`Hybrid`].
    Hybrid(Hybrid),
}

macro_rules! each_adaptation {
    ($self:expr, $a:ident => $e:expr) => {
        match $self {
            AnyAdaptation::Plain($a) => $e,
            AnyAdaptation::Online($a) => $e,
            #[cfg(feature = "nalgebra")]
            AnyAdaptation::Full($a) => $e,
            AnyAdaptation::Cache($a) => $e,
            AnyAdaptation::Hybrid($a) => $e,
        }
    };
}

impl Adaptation for AnyAdaptation {
    fn name(&self) -> &'static str {
        each_adaptation!(self, a => a.name())
    }
    fn needs_gradient(&self, dim: usize) -> bool {
        each_adaptation!(self, a => a.needs_gradient(dim))
    }
    fn gaussian(
        &mut self,
        params: &LangevinParams,
        u: &[f64],
        g: &[f64],
        out: &mut ProposalGaussian,
    ) -> bool {
        each_adaptation!(self, a => a.gaussian(params, u, g, out))
    }
    fn adapt(&mut self, params: &LangevinParams, u: &[f64], g: &[f64], first_visit: bool) {
        each_adaptation!(self, a => a.adapt(params, u, g, first_visit))
    }
    fn restart(&mut self, params: &LangevinParams) {
        each_adaptation!(self, a => a.restart(params))
    }
    fn freeze(&mut self) {
        each_adaptation!(self, a => a.freeze())
    }
    fn is_frozen(&self) -> bool {
        each_adaptation!(self, a => a.is_frozen())
    }
    fn for_each_cache(&mut self, f: &mut dyn FnMut(&mut CacheView)) {
        each_adaptation!(self, a => a.for_each_cache(f))
    }
}
