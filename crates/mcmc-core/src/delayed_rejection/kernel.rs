//! The two-stage delayed-rejection kernel: a first-stage proposal, a conditional second stage.

use rand::{Rng, RngExt};

use super::arithmetic::{NoGhost, StateArithmetic};
use super::rule::{ln_accept_from_ratio, ln_one_minus, DrRule};
use crate::kernel::{mh_accept_prob, mh_log_accept_prob, Kernel, Observer, StepInfo};
use crate::proposal::{log_sum_exp, ConditionalProposal, Proposal, Proposed, MAX_COMPONENTS};
use crate::target::{Point, Sample, SampleOf, Target};
use crate::tunable::LargeStepTunable;
use crate::McmcError;

/// Two-stage delayed-rejection Metropolis-Hastings (Tierney & Mira 1999; Green & Mira 2001;
/// the DR paper, Rioux-Lavoie, Litalien et al. 2020, section 4 and Alg. 1;
/// docs/methods/drmlt.md).
///
/// A step proposes `y` from the current state `x` with the first-stage [`Proposal`] `Q1`
/// (possibly a [`crate::Mixture`]) and accepts it with the MH probability `a1` (eq. 5). If `y`
/// is rejected, the second-stage [`ConditionalProposal`] `Q2` proposes `z` from `x` *and* `y`,
/// accepted with the [`DrRule`]'s `a2` (eq. 6/7, 11 or 12-14). Both stages preserve the
/// target: the kernel satisfies detailed balance separately for moves to `y` and for moves
/// through a rejected `y` to `z`.
///
/// # Mixtures and large steps
/// The first stage is component-labelled like [`crate::Mh`]: the component `j` drawn at the
/// first stage stays fixed for the step, every first-stage term of `a2` uses that
/// component's density `Q1_j = s(j | .) T_j` (and its Hastings term in `a1_j(z, y*)`), and the
/// reverse path is the one through the same component. The second stage runs only after a
/// rejected candidate of a component in the kernel's *second-stage set* (default: every
/// component). [`DelayedRejection::second_stage_after_small_steps`] removes the large steps
/// from the set, which is the reference implementation's behaviour (no second stage after a
/// large step: an independent sample that failed says nothing about where to look next).
/// Because the set depends on `j` only, restricting it keeps detailed balance.
///
/// # Splatting (the [`Observer`] contract)
/// The kernel reports weights whose expectation over one step from `x` is `E[h(X') | x]`:
/// `y` with `a1` always; if the second stage runs (after a rejection of `y`), `z` with `a2`
/// and `x` with `1 - a2`; if it cannot run (component outside the set, invalid or
/// non-finite candidate), `x` with `1 - a1`. So `E[splat] = a1 h(y) + (1 - a1) (a2 h(z) +
/// (1 - a2) h(x))`, the law of the next state. The weights sum to 1 only in expectation
/// (to `a1` after an accepted `y`, to `1 + a1` after a rejected one). This departs from the
/// paper's Fig. 8 (`w_y = a1`, `w_z = (1 - a1) a2`, `w_x` the rest), which, with `z` drawn only
/// after a rejection, is biased; `testing::broken::PaperSplatWeights` keeps it as a negative
/// control (docs/methods/drmlt.md has the numbers). The ghost `y*` is never splatted
/// (section 4.6).
///
/// # Lazily materialised states
/// After evaluating and rejecting `y` the kernel calls [`Point::absorb_rejected`]`(x, y)`
/// *before* proposing `z`, so the second stage sees the coordinates of `x` that `y`'s
/// evaluation drew; after a rejected `z`, `absorb_rejected(x, z)`. With
/// [`DrRule::GreenMira`], once the step is decided the state the chain is in (`x`, or `z` if
/// accepted) also absorbs the evaluated ghost: a state type whose ghost can draw coordinates
/// of the common parent must accept them there (one that materialises `x`, `y`, `z` to a
/// fixed dimension before the second stage, as the reference implementation does, draws
/// nothing and needs nothing).
///
/// Under Tierney & Mira's and Green & Mira's rules the second stage's ratio reads the
/// first-stage density `Q1` of whole states (`Q1(y | x)`, `Q1(y* | z)`), and a lazily
/// mutated candidate stores stale values where its evaluation did not read. The kernel
/// therefore calls [`Point::catch_up_with`]`(y, x)` before absorbing `y`, and after
/// evaluating `z`, `catch_up_with(z, x)` then `catch_up_with(y, z)` (`y` extends to the
/// coordinates `z` drew of `x`): the densities see the eager candidates. States that are
/// fully defined when proposed (the default) are not touched.
///
/// # Statistics
/// [`StepInfo`]: `component` is `j`; `accept_prob = [a1, a2]` (`a2 = 0` when the second stage
/// did not run); `candidate_log_density = [log pi(y), log pi(z)]`; `stages_tried` is 1 or 2;
/// `accepted_stage` 0, 1 or 2. `a1 + a2` estimates the probability that the step moves
/// (`E[a1 + 1{second stage} a2] = E[a1 + (1 - a1) a2]`), the DR meaning of the small-step
/// acceptance `eta_s` of automatic large-step control: [`crate::stats::move_probability`].
/// A NaN or `+inf` density of `y`, `z` or the ghost, or a NaN ratio, is rejected and flagged
/// `non_finite` (the chain reports a ghost's as a non-finite Hastings term of stage 2).
///
/// # Random numbers
/// Per step, in order: the first stage's, one uniform for the first decision (only when
/// `0 < a1 < 1`), the second stage's, one uniform for the second decision (only when
/// `0 < a2 < 1`). No allocation: `y`, `z` and the ghost live in the chain's scratch samples
/// (`scratch[0]`, `scratch[1]`, `scratch[2]`; acceptance is a swap).
///
/// # Example
/// ```
/// use mcmc_core::delayed_rejection::IndependentSecondStage;
/// use mcmc_core::toy::UniformMixture;
/// use mcmc_core::{Chain, DelayedRejection, GaussianRandomWalk, NoAdaptation};
/// use rand::SeedableRng;
///
/// // The DR paper's 1-D example (section 4.2): a bold first stage, a timid second stage.
/// let target = UniformMixture::rioux_lavoie2020();
/// let kernel = DelayedRejection::tierney_mira(
///     GaussianRandomWalk::new(1.0).unwrap(),
///     IndependentSecondStage(GaussianRandomWalk::new(0.05).unwrap()),
/// )
/// .with_symmetric_second_stage();
/// let rng = rand_pcg::Pcg64::seed_from_u64(3);
/// let mut chain = Chain::new(&target, kernel, NoAdaptation, rng, vec![-0.05]).unwrap();
/// chain.run(2000, &mut ()).unwrap();
/// let stats = chain.stats();
/// assert!(stats.stage_tried[1] > 0 && stats.stage_accepted[1] > 0);
/// assert!(stats.acceptance_rate() > stats.stage_acceptance_rate(0) * 0.5);
/// ```
#[derive(Clone, Debug)]
pub struct DelayedRejection<P1, P2, A = NoGhost> {
    /// The first-stage proposal `Q1`.
    pub first: P1,
    /// The second-stage conditional proposal `Q2`.
    pub second: P2,
    rule: DrRule<A>,
    /// Bit `j` set: the second stage may follow a rejected candidate of component `j`.
    second_stage_set: u32,
    symmetric_second_stage: bool,
    /// Whether lazily mutated candidates are brought up to date before the densities of
    /// Tierney-Mira and Green-Mira read them (always, except in negative controls).
    catch_up: bool,
}

/// Every component in the second-stage set.
const ALL_COMPONENTS: u32 = (1 << MAX_COMPONENTS) - 1;

impl<P1, P2> DelayedRejection<P1, P2, NoGhost> {
    /// Tierney & Mira's rule (eq. 6).
    pub fn tierney_mira(first: P1, second: P2) -> Self {
        Self::new(first, second, DrRule::TierneyMira)
    }

    /// The pairwise orbital rule (eq. 11); `second` must keep `z` on the orbit of the first
    /// stage (see [`DrRule::Orbital`]), e.g. [`super::OrbitalWalk`] after
    /// [`super::RadialKelemen`].
    pub fn orbital(first: P1, second: P2) -> Self {
        Self::new(first, second, DrRule::Orbital)
    }
}

impl<P1, P2, A> DelayedRejection<P1, P2, A> {
    /// A kernel with the given stages and rule; the second stage may follow every component.
    pub fn new(first: P1, second: P2, rule: DrRule<A>) -> Self {
        Self {
            first,
            second,
            rule,
            second_stage_set: ALL_COMPONENTS,
            symmetric_second_stage: false,
            catch_up: true,
        }
    }

    /// Green & Mira's rule (eq. 12-14) with the ghost arithmetic `arithmetic`
    /// ([`super::Euclidean`] on `R^n`, [`super::Torus`] on `[0, 1)^n`).
    pub fn green_mira(first: P1, second: P2, arithmetic: A) -> Self {
        Self::new(first, second, DrRule::GreenMira(arithmetic))
    }

    /// Restricts the second stage to rejected candidates of the listed first-stage
    /// components (indices below [`MAX_COMPONENTS`]; an empty list turns the kernel into MH
    /// with the first stage).
    ///
    /// # Errors
    /// [`McmcError::InvalidParameter`] for an index `>= MAX_COMPONENTS`.
    pub fn second_stage_after(mut self, components: &[usize]) -> Result<Self, McmcError> {
        let mut set = 0;
        for &j in components {
            if j >= MAX_COMPONENTS {
                return Err(McmcError::InvalidParameter {
                    name: "second-stage component",
                    value: j as f64,
                    allowed: "0..8 (MAX_COMPONENTS)",
                });
            }
            set |= 1 << j;
        }
        self.second_stage_set = set;
        Ok(self)
    }

    /// Restricts the second stage to components the first stage does not call large steps
    /// ([`LargeStepTunable::is_large_step`]): the authors' code's rule (no second stage after a
    /// large step; docs/methods/drmlt.md, "Mixtures and large steps").
    #[must_use]
    pub fn second_stage_after_small_steps(mut self) -> Self
    where
        P1: LargeStepTunable,
    {
        self.second_stage_set = (0..MAX_COMPONENTS)
            .filter(|&j| !self.first.is_large_step(j))
            .fold(0, |set, j| set | (1 << j));
        self
    }

    /// Declares the second stage symmetric, `Q2(z | x, y) = Q2(x | z, y*)` for every path
    /// the kernel takes (e.g. [`super::IndependentSecondStage`] of a symmetric walk): the
    /// `Q2` terms of the Tierney-Mira and Green-Mira ratios are then skipped (eq. 7 and 14).
    /// A wrong declaration breaks detailed balance (the pairwise check sees it). The orbital
    /// rule always assumes it.
    #[must_use]
    pub fn with_symmetric_second_stage(mut self) -> Self {
        self.symmetric_second_stage = true;
        self
    }

    /// The kernel as it was before it brought lazy candidates up to date: the Tierney-Mira
    /// and Green-Mira densities then read the stale stored coordinates of lazily mutated
    /// candidates. Biased on lazy states; only for negative controls.
    #[cfg(feature = "testing")]
    #[doc(hidden)]
    #[must_use]
    pub fn with_stale_densities(mut self) -> Self {
        self.catch_up = false;
        self
    }

    /// The acceptance rule.
    #[must_use]
    pub fn rule(&self) -> &DrRule<A> {
        &self.rule
    }

    /// True if the second stage may follow a rejected candidate of component `component`.
    #[must_use]
    pub fn runs_second_stage_after(&self, component: usize) -> bool {
        component < MAX_COMPONENTS && self.second_stage_set & (1 << component) != 0
    }

    /// True if the second stage was declared symmetric.
    #[must_use]
    pub fn has_symmetric_second_stage(&self) -> bool {
        self.symmetric_second_stage
    }

    /// `ln a2` for the path `x -> (y rejected, component j) -> z`, where `ystar` is the state
    /// on the reverse path (`y`, or the evaluated ghost) and `ln_one_minus_a1 = ln(1 -
    /// a1_j(x, y))`. All samples are evaluated. NaN for a NaN term.
    fn ln_a2<S, Pl>(
        &self,
        j: usize,
        x: &Sample<S, Pl>,
        y: &Sample<S, Pl>,
        z: &Sample<S, Pl>,
        ystar: &Sample<S, Pl>,
        ln_one_minus_a1: f64,
    ) -> f64
    where
        P1: Proposal<S>,
        P2: ConditionalProposal<S>,
    {
        if z.log_density == f64::NEG_INFINITY {
            return f64::NEG_INFINITY;
        }
        let back = self.first.log_hastings(j, &z.state, &ystar.state);
        let a1_reverse = mh_accept_prob(z.log_density, ystar.log_density, back);
        let mut num = z.log_density + ln_one_minus(a1_reverse);
        let mut den = x.log_density + ln_one_minus_a1;
        if !matches!(self.rule, DrRule::Orbital) {
            // Only what the second stage moved: the shared factors cancel.
            let (forward, reverse) =
                self.first
                    .log_q_component_pair(j, &z.state, &ystar.state, &x.state, &y.state);
            num += forward;
            den += reverse;
            if !self.symmetric_second_stage {
                num += self.second.log_q(&z.state, &ystar.state, &x.state);
                den += self.second.log_q(&x.state, &y.state, &z.state);
            }
        }
        ln_accept_from_ratio(num, den)
    }

    /// The ghost of `(x, y, z)`, evaluated (for `log_flow` and `reverse_path`: allocates).
    fn evaluated_ghost<T>(&self, target: &T, path: &[SampleOf<T>]) -> Option<SampleOf<T>>
    where
        T: Target,
        A: StateArithmetic<T::State>,
    {
        let ([x, y, z], Some(arithmetic)) = (path, self.rule.arithmetic()) else {
            return None;
        };
        let mut ghost = z.state.clone();
        arithmetic.ghost(&x.state, &y.state, &z.state, &mut ghost);
        Some(Sample::evaluate(target, ghost))
    }
}

fn is_non_finite(log_density: f64) -> bool {
    log_density.is_nan() || log_density == f64::INFINITY
}

impl<T, P1, P2, A> Kernel<T> for DelayedRejection<P1, P2, A>
where
    T: Target,
    P1: Proposal<T::State>,
    P2: ConditionalProposal<T::State>,
    A: StateArithmetic<T::State>,
{
    fn stages(&self) -> usize {
        2
    }

    fn step<R, O>(
        &mut self,
        target: &T,
        current: &mut SampleOf<T>,
        scratch: &mut [SampleOf<T>],
        rng: &mut R,
        observer: &mut O,
    ) -> StepInfo
    where
        R: Rng + ?Sized,
        O: Observer<T::State, T::Payload> + ?Sized,
    {
        let [y, z, rest @ ..] = scratch else {
            panic!("DelayedRejection needs the chain's scratch samples (Kernel::stages() + 1)");
        };

        // Stage 1: plain MH with component j.
        let proposed = self.first.propose(&current.state, &mut y.state, rng);
        let j = proposed.component();
        let mut info = StepInfo::new(j);
        info.stages_tried = 1;
        let mut a1 = 0.0;
        let y_evaluated = matches!(proposed, Proposed::Move { .. });
        if let Proposed::Move { log_hastings, .. } = proposed {
            y.log_density = target.evaluate(&mut y.state, &mut y.payload);
            info.candidate_log_density[0] = y.log_density;
            if is_non_finite(y.log_density) || log_hastings.is_nan() {
                info.non_finite = true;
            } else {
                a1 = mh_accept_prob(current.log_density, y.log_density, log_hastings);
            }
        }
        info.accept_prob[0] = a1;
        if a1 > 0.0 {
            observer.splat(y, a1);
        }
        let second_stage =
            y_evaluated && !info.non_finite && a1 < 1.0 && self.runs_second_stage_after(j);
        if !second_stage {
            observer.splat(current, 1.0 - a1);
            if a1 >= 1.0 || (a1 > 0.0 && rng.random::<f64>() < a1) {
                std::mem::swap(current, y);
                info.accepted_stage = 1;
            } else if y_evaluated {
                current.state.absorb_rejected(&y.state);
            }
            observer.step(&info);
            return info;
        }
        if a1 > 0.0 && rng.random::<f64>() < a1 {
            std::mem::swap(current, y);
            info.accepted_stage = 1;
            observer.step(&info);
            return info;
        }
        let whole_states = self.catch_up && !matches!(self.rule, DrRule::Orbital);
        if whole_states {
            y.state.catch_up_with(&current.state);
        }
        current.state.absorb_rejected(&y.state);

        // Stage 2: z ~ Q2(. | x, y), accepted with the rule's a2.
        info.stages_tried = 2;
        let ln_one_minus_a1 = ln_one_minus(a1);
        let mut a2 = 0.0;
        let mut ghost_evaluated = false;
        let proposed = self
            .second
            .propose(&current.state, &y.state, &mut z.state, rng);
        let z_evaluated = matches!(proposed, Proposed::Move { .. });
        if z_evaluated {
            z.log_density = target.evaluate(&mut z.state, &mut z.payload);
            info.candidate_log_density[1] = z.log_density;
            if is_non_finite(z.log_density) {
                info.non_finite = true;
            } else if z.log_density > f64::NEG_INFINITY {
                if whole_states {
                    z.state.catch_up_with(&current.state);
                    y.state.catch_up_with(&z.state);
                }
                let ln_a2 = match (&self.rule, rest.first_mut()) {
                    (DrRule::GreenMira(arithmetic), Some(ghost)) => {
                        arithmetic.ghost(&current.state, &y.state, &z.state, &mut ghost.state);
                        ghost.log_density = target.evaluate(&mut ghost.state, &mut ghost.payload);
                        ghost_evaluated = true;
                        if is_non_finite(ghost.log_density) {
                            f64::NAN
                        } else {
                            self.ln_a2(j, current, y, z, ghost, ln_one_minus_a1)
                        }
                    }
                    (DrRule::GreenMira(_), None) => {
                        panic!("DelayedRejection (Green-Mira) needs a third scratch sample")
                    }
                    _ => self.ln_a2(j, current, y, z, y, ln_one_minus_a1),
                };
                if ln_a2.is_nan() {
                    info.non_finite = true;
                } else {
                    a2 = ln_a2.exp();
                }
            }
        }
        info.accept_prob[1] = a2;
        if a2 > 0.0 {
            observer.splat_at_stage(z, a2, 2);
        }
        observer.splat(current, 1.0 - a2);
        if a2 >= 1.0 || (a2 > 0.0 && rng.random::<f64>() < a2) {
            std::mem::swap(current, z);
            info.accepted_stage = 2;
        } else if z_evaluated {
            current.state.absorb_rejected(&z.state);
        }
        if ghost_evaluated {
            current.state.absorb_rejected(&rest[0].state);
        }
        observer.step(&info);
        info
    }

    /// Pairs `[x, y]`: `sum_j pi(x) Q1_j(y|x) a1_j(x, y)` (as [`crate::Mh`]). Triples
    /// `[x, y, z]`: `sum_j pi(x) Q1_j(y|x) (1 - a1_j(x, y)) Q2(z|x, y) a2_j(x, y, z)` over the
    /// components in the second-stage set, with the *true* proposal densities and `a2` as
    /// the kernel computes it (so a rule applied where its assumptions fail shows up as an
    /// imbalance). For [`DrRule::Orbital`], `Q2` is the density on the orbit that
    /// [`ConditionalProposal::log_q`] reports.
    fn log_flow(&self, target: &T, path: &[SampleOf<T>]) -> f64 {
        let n = self.first.num_components().min(MAX_COMPONENTS);
        let mut terms = [f64::NEG_INFINITY; MAX_COMPONENTS];
        match path {
            [x, y] => {
                for (j, t) in terms.iter_mut().enumerate().take(n) {
                    let h = self.first.log_hastings(j, &x.state, &y.state);
                    *t = x.log_density
                        + self.first.log_q_component(j, &x.state, &y.state)
                        + mh_log_accept_prob(x.log_density, y.log_density, h);
                }
            }
            [x, y, z] => {
                let ghost = self.evaluated_ghost(target, path);
                let ystar = ghost.as_ref().unwrap_or(y);
                for (j, t) in terms.iter_mut().enumerate().take(n) {
                    if !self.runs_second_stage_after(j) || x.log_density == f64::NEG_INFINITY {
                        continue;
                    }
                    let h = self.first.log_hastings(j, &x.state, &y.state);
                    let ln_one_minus_a1 =
                        ln_one_minus(mh_accept_prob(x.log_density, y.log_density, h));
                    let prefix = x.log_density
                        + self.first.log_q_component(j, &x.state, &y.state)
                        + ln_one_minus_a1
                        + self.second.log_q(&x.state, &y.state, &z.state);
                    if prefix > f64::NEG_INFINITY {
                        *t = prefix + self.ln_a2(j, x, y, z, ystar, ln_one_minus_a1);
                    }
                }
            }
            _ => {}
        }
        log_sum_exp(&terms[..n])
    }

    /// `[x, y]` reversed; `[x, y, z]` -> `[z, y*, x]` with `y* = y` (Tierney-Mira, orbital)
    /// or the evaluated ghost `z - (y - x)` (Green-Mira).
    fn reverse_path(&self, target: &T, path: &[SampleOf<T>]) -> Vec<SampleOf<T>> {
        match (self.evaluated_ghost(target, path), path) {
            (Some(ghost), [x, _, z]) => vec![z.clone(), ghost, x.clone()],
            _ => path.iter().rev().cloned().collect(),
        }
    }
}

impl<P1: LargeStepTunable, P2, A> LargeStepTunable for DelayedRejection<P1, P2, A> {
    fn large_step_probability(&self) -> f64 {
        self.first.large_step_probability()
    }
    fn set_large_step_probability(&mut self, p: f64) {
        self.first.set_large_step_probability(p);
    }
    fn is_large_step(&self, component: usize) -> bool {
        self.first.is_large_step(component)
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use rand::SeedableRng;

    /// A 1-D state that logs which candidates it absorbed (1 = y, 2 = z, 3 = ghost) and, for
    /// a second-stage candidate, how many absorptions its parent had made when it was
    /// proposed.
    #[derive(Clone, Debug, Default)]
    struct Logged {
        v: f64,
        tag: u8,
        absorbed: Vec<u8>,
        parent_absorbed: usize,
    }

    impl Point for Logged {
        fn absorb_rejected(&mut self, rejected: &Self) {
            self.absorbed.push(rejected.tag);
        }
    }

    /// `pi(v) = 2 v` on `(0, 1)`; NaN at `v = -1` (a broken target).
    struct Ramp;

    impl Target for Ramp {
        type State = Logged;
        type Payload = ();
        fn evaluate(&self, x: &mut Logged, _: &mut ()) -> f64 {
            if x.v == -1.0 {
                f64::NAN
            } else if x.v > 0.0 && x.v < 1.0 {
                (2.0 * x.v).ln()
            } else {
                f64::NEG_INFINITY
            }
        }
    }

    /// First stage: `y = x + shift` (symmetric by fiat: the tests here check mechanics, not
    /// balance), or `Invalid` when `shift` is NaN; two components (the second called large).
    #[derive(Clone, Debug)]
    struct Shift(f64);

    impl Proposal<Logged> for Shift {
        fn propose<R: Rng + ?Sized>(&self, x: &Logged, y: &mut Logged, rng: &mut R) -> Proposed {
            let j = usize::from(rng.random::<bool>());
            if self.0.is_nan() {
                return Proposed::Invalid { component: j };
            }
            *y = Logged {
                v: x.v + self.0,
                tag: 1,
                ..Logged::default()
            };
            Proposed::symmetric().with_component(j)
        }
        fn log_q(&self, _: &Logged, _: &Logged) -> f64 {
            0.0
        }
        fn num_components(&self) -> usize {
            2
        }
        fn log_q_component(&self, _: usize, _: &Logged, _: &Logged) -> f64 {
            0.5f64.ln()
        }
    }

    impl LargeStepTunable for Shift {
        fn large_step_probability(&self) -> f64 {
            0.5
        }
        fn set_large_step_probability(&mut self, _: f64) {}
        fn is_large_step(&self, component: usize) -> bool {
            component == 1
        }
    }

    /// Second stage: `z` uniform on `(-0.5, 1.5)`.
    #[derive(Clone, Debug)]
    struct Anywhere;

    impl ConditionalProposal<Logged> for Anywhere {
        fn propose<R: Rng + ?Sized>(
            &self,
            x: &Logged,
            _: &Logged,
            z: &mut Logged,
            rng: &mut R,
        ) -> Proposed {
            *z = Logged {
                v: -0.5 + 2.0 * rng.random::<f64>(),
                tag: 2,
                absorbed: Vec::new(),
                parent_absorbed: x.absorbed.len(),
            };
            Proposed::symmetric()
        }
        fn log_q(&self, _: &Logged, _: &Logged, _: &Logged) -> f64 {
            0.5f64.ln()
        }
    }

    #[derive(Clone, Copy, Debug)]
    struct Tagging;

    impl StateArithmetic<Logged> for Tagging {
        fn ghost(&self, x: &Logged, y: &Logged, z: &Logged, out: &mut Logged) {
            *out = Logged {
                v: z.v - (y.v - x.v),
                tag: 3,
                ..Logged::default()
            };
        }
    }

    /// Records splats by the address of the sample.
    #[derive(Default)]
    struct Splats(Vec<(*const Sample<Logged, ()>, f64)>);

    impl Observer<Logged, ()> for Splats {
        fn splat(&mut self, sample: &Sample<Logged, ()>, weight: f64) {
            self.0.push((std::ptr::from_ref(sample), weight));
        }
    }

    /// Runs `n` steps by hand from `v0`, resetting the logs, and checks every step with
    /// `check(info, current before the step, samples after it, splats)`.
    fn drive<K: Kernel<Ramp>>(
        kernel: &mut K,
        v0: f64,
        n: usize,
        mut check: impl FnMut(&StepInfo, &Logged, &Sample<Logged, ()>, &[Sample<Logged, ()>], &Splats),
    ) {
        let mut rng = rand_pcg::Pcg64::seed_from_u64(17);
        let start = Logged {
            v: v0,
            ..Logged::default()
        };
        let mut current = Sample::evaluate(&Ramp, start);
        let mut scratch = vec![current.clone(); 3];
        for _ in 0..n {
            current.state.absorbed.clear();
            current.state.tag = 0;
            let before = current.state.clone();
            let mut splats = Splats::default();
            let info = kernel.step(&Ramp, &mut current, &mut scratch, &mut rng, &mut splats);
            check(&info, &before, &current, &scratch, &splats);
        }
    }

    fn weight_of(splats: &Splats, sample: &Sample<Logged, ()>) -> f64 {
        splats
            .0
            .iter()
            .filter(|(p, _)| std::ptr::eq(*p, sample))
            .map(|(_, w)| w)
            .sum()
    }

    /// The kernel absorbs `y` before proposing `z`, `z` (and the ghost) after a rejected
    /// second stage, and the ghost into an accepted `z`; it splats `y` with `a1`, and after a
    /// second stage `z` with `a2` and `x` with `1 - a2`, never the ghost.
    #[test]
    fn absorbs_and_splats_in_order() {
        for green_mira in [false, true] {
            let mut kernel = DelayedRejection::new(
                Shift(-0.3),
                Anywhere,
                if green_mira {
                    DrRule::GreenMira(Tagging)
                } else {
                    DrRule::TierneyMira
                },
            );
            let mut seen = [0usize; 3];
            drive(
                &mut kernel,
                0.9,
                400,
                |info, before, current, scratch, splats| {
                    let (a1, a2) = (info.accept_prob[0], info.accept_prob[1]);
                    let total: f64 = splats.0.iter().map(|(_, w)| w).sum();
                    assert!(splats.0.iter().all(|(p, _)| !std::ptr::eq(*p, &scratch[2])));
                    match (info.stages_tried, info.accepted_stage) {
                        (1, 1) => {
                            seen[0] += 1;
                            assert!((total - a1).abs() < 1e-12, "{info:?}");
                            assert!(current.state.absorbed.is_empty());
                        }
                        (2, stage) => {
                            // Splats go to the slots as they were before any swap: y in
                            // scratch[0], z in scratch[1], x in the current slot.
                            assert!((weight_of(splats, &scratch[0]) - a1).abs() < 1e-12);
                            assert!((weight_of(splats, &scratch[1]) - a2).abs() < 1e-12);
                            assert!((weight_of(splats, current) - (1.0 - a2)).abs() < 1e-12);
                            let (x, z) = if stage == 2 {
                                (&scratch[1], current)
                            } else {
                                (current, &scratch[1])
                            };
                            assert_eq!(z.state.parent_absorbed, 1, "z proposed before absorbing y");
                            let ghost = green_mira && z.log_density > f64::NEG_INFINITY;
                            if stage == 2 {
                                seen[1] += 1;
                                assert_eq!(x.state.absorbed, [1]);
                                assert_eq!(
                                    current.state.absorbed,
                                    if ghost { vec![3] } else { vec![] }
                                );
                            } else {
                                seen[2] += 1;
                                let expected = if ghost { vec![1, 2, 3] } else { vec![1, 2] };
                                assert_eq!(current.state.absorbed, expected, "{info:?}");
                                assert_eq!(current.state.v, before.v);
                            }
                        }
                        other => panic!("unexpected outcome {other:?}: {info:?}"),
                    }
                },
            );
            assert!(seen.iter().all(|&c| c > 10), "{seen:?}");
        }
    }

    /// No second stage after a component outside the set (here: the "large step"), after an
    /// invalid candidate, or after a non-finite one; then the splats are MH's.
    #[test]
    fn second_stage_only_where_allowed() {
        let mut kernel =
            DelayedRejection::tierney_mira(Shift(-0.3), Anywhere).second_stage_after_small_steps();
        assert!(kernel.runs_second_stage_after(0) && !kernel.runs_second_stage_after(1));
        assert!(!kernel.runs_second_stage_after(MAX_COMPONENTS));
        drive(
            &mut kernel,
            0.9,
            200,
            |info, _, current, scratch, splats| {
                if info.component == 1 {
                    assert_eq!(info.stages_tried, 1);
                    let a1 = info.accept_prob[0];
                    assert!((weight_of(splats, current) - (1.0 - a1)).abs() < 1e-12);
                    assert!((weight_of(splats, &scratch[0]) - a1).abs() < 1e-12);
                }
            },
        );
        let mut invalid = DelayedRejection::tierney_mira(Shift(f64::NAN), Anywhere);
        drive(&mut invalid, 0.9, 20, |info, _, current, _, splats| {
            assert_eq!((info.stages_tried, info.accepted_stage), (1, 0));
            assert!(current.state.absorbed.is_empty());
            assert_eq!(splats.0.len(), 1);
            assert_eq!(weight_of(splats, current), 1.0);
        });
        let mut broken = DelayedRejection::tierney_mira(Shift(-1.5), Anywhere);
        drive(&mut broken, 0.5, 5, |info, _, current, _, _| {
            assert!(info.non_finite && info.stages_tried == 1 && !info.accepted());
            assert_eq!(current.state.absorbed, [1]);
        });
        assert!(DelayedRejection::tierney_mira(Shift(0.1), Anywhere)
            .second_stage_after(&[0, 8])
            .is_err());
    }

    /// Random numbers per step: the first stage's, a uniform only for `0 < a1 < 1`, the
    /// second stage's, a uniform only for `0 < a2 < 1` (value stability for a seed).
    #[test]
    fn value_stability() {
        let gm = DelayedRejection::green_mira(Shift(-0.3), Anywhere, Tagging);
        assert_eq!(gm.rule().name(), "green-mira");
        let mut kernel =
            DelayedRejection::tierney_mira(Shift(-0.3), Anywhere).with_symmetric_second_stage();
        assert!(kernel.has_symmetric_second_stage());
        let mut trace = Vec::new();
        drive(&mut kernel, 0.9, 12, |info, _, current, _, _| {
            trace.push((info.accepted_stage, (current.state.v * 1e6).round() / 1e6));
        });
        let expected = [
            (1, 0.6),
            (0, 0.6),
            (0, 0.6),
            (0, 0.6),
            (1, 0.3),
            (0, 0.3),
            (0, 0.3),
            (0, 0.3),
            (2, 0.668_274),
            (0, 0.668_274),
            (1, 0.368_274),
            (2, 0.670_109),
        ];
        assert_eq!(trace, expected, "{trace:?}");
    }
}
