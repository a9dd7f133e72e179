//! Test fixtures of the delayed-rejection tests: a 4-state toy, a product Kelemen step, a
//! product of ridges, a lazily materialised state whose read set depends on the state, and a
//! broken ghost arithmetic.

use mcmc_core::delayed_rejection::Torus;
use mcmc_core::proposal::ConditionalProposal;
use mcmc_core::seed::mix64;
use mcmc_core::testing::FnBins;
use mcmc_core::toy::{wrap, Ridge, ToyTarget};
use mcmc_core::{Point, Proposal, Proposed, StateArithmetic, Target};
use rand::{Rng, RngExt};

// ---- a 4-state discrete toy ----

/// `pi` on the states `0.0, 1.0, 2.0, 3.0` (an `f64` state; every other value has density 0),
/// with masses `[0.1, 0.2, 0.3, 0.4]`.
#[derive(Clone, Copy, Debug)]
pub(crate) struct FourStates;

/// The masses of [`FourStates`].
pub(crate) const FOUR: [f64; 4] = [0.1, 0.2, 0.3, 0.4];

/// The index of a state of [`FourStates`], if it is one.
pub(crate) fn index(x: f64) -> Option<usize> {
    (0..4).find(|&i| x == i as f64)
}

impl Target for FourStates {
    type State = f64;
    type Payload = ();
    fn evaluate(&self, x: &mut f64, _: &mut ()) -> f64 {
        index(*x).map_or(f64::NEG_INFINITY, |i| FOUR[i].ln())
    }
}

/// First stage of the 4-state toy: one of the 3 other states, uniformly (symmetric).
#[derive(Clone, Copy, Debug)]
pub(crate) struct OtherState;

impl Proposal<f64> for OtherState {
    fn propose<R: Rng + ?Sized>(&self, x: &f64, y: &mut f64, rng: &mut R) -> Proposed {
        let k = rng.random_range(0..3usize);
        let i = index(*x).expect("a state of the toy");
        *y = if k >= i { k + 1 } else { k } as f64;
        Proposed::symmetric()
    }
    fn log_q(&self, from: &f64, to: &f64) -> f64 {
        match (index(*from), index(*to)) {
            (Some(a), Some(b)) if a != b => (1.0f64 / 3.0).ln(),
            _ => f64::NEG_INFINITY,
        }
    }
    fn is_symmetric(&self) -> bool {
        true
    }
}

/// Second stage of the 4-state toy: one of the 2 states other than `x` and `y`, uniformly
/// (symmetric in `x` and `z` for a given `y`).
#[derive(Clone, Copy, Debug)]
pub(crate) struct ThirdState;

impl ConditionalProposal<f64> for ThirdState {
    fn propose<R: Rng + ?Sized>(&self, x: &f64, y: &f64, z: &mut f64, rng: &mut R) -> Proposed {
        let (i, j) = (index(*x).unwrap(), index(*y).unwrap());
        let others: Vec<usize> = (0..4).filter(|&k| k != i && k != j).collect();
        *z = others[rng.random_range(0..others.len())] as f64;
        Proposed::symmetric()
    }
    fn log_q(&self, x: &f64, y: &f64, z: &f64) -> f64 {
        match (index(*x), index(*y), index(*z)) {
            (Some(i), Some(j), Some(k)) if i != j && k != i && k != j => 0.5f64.ln(),
            _ => f64::NEG_INFINITY,
        }
    }
}

// ---- Kelemen 2002's product step, and a product of ridges ----

/// Kelemen et al. 2002's mutation (DR paper eq. 9) on every coordinate of a `Vec<f64>`:
/// random sign, `|d|` log-uniform on `[s1, s2]`; density
/// `prod_i 1 / (2 |d_i| ln(s2 / s1))`, zero where any `|d_i|` is outside `[s1, s2]`.
#[derive(Clone, Copy, Debug)]
pub(crate) struct ProductKelemen {
    /// Smallest step.
    pub(crate) s1: f64,
    /// Largest step.
    pub(crate) s2: f64,
}

impl ProductKelemen {
    /// Kelemen 2002's bounds `[1/1024, 1/64]`.
    pub(crate) const fn kelemen2002() -> Self {
        Self {
            s1: 1.0 / 1024.0,
            s2: 1.0 / 64.0,
        }
    }
}

impl Proposal<Vec<f64>> for ProductKelemen {
    fn propose<R: Rng + ?Sized>(&self, x: &Vec<f64>, y: &mut Vec<f64>, rng: &mut R) -> Proposed {
        let lr = (self.s2 / self.s1).ln();
        y.clear();
        y.extend(x.iter().map(|&v| {
            let d = self.s2 * (-lr * rng.random::<f64>()).exp();
            if rng.random::<bool>() {
                v + d
            } else {
                v - d
            }
        }));
        Proposed::symmetric()
    }
    fn log_q(&self, from: &Vec<f64>, to: &Vec<f64>) -> f64 {
        let lr = (self.s2 / self.s1).ln();
        from.iter()
            .zip(to)
            .map(|(a, b)| {
                let d = (b - a).abs();
                if d < self.s1 || d > self.s2 {
                    f64::NEG_INFINITY
                } else {
                    -(2.0 * d * lr).ln()
                }
            })
            .sum()
    }
    fn is_symmetric(&self) -> bool {
        true
    }
}

/// `pairs` independent copies of a 2-D [`Ridge`] (coordinates `(0, 1), (2, 3), ...`).
#[derive(Clone, Copy, Debug)]
pub(crate) struct Ridges {
    /// The ridge of each pair.
    pub(crate) ridge: Ridge,
    /// Number of pairs.
    pub(crate) pairs: usize,
}

impl Ridges {
    /// An exact draw.
    pub(crate) fn sample_exact<R: Rng + ?Sized>(&self, rng: &mut R) -> Vec<f64> {
        (0..self.pairs)
            .flat_map(|_| self.ridge.sample_exact(rng))
            .collect()
    }
}

impl Target for Ridges {
    type State = Vec<f64>;
    type Payload = ();
    fn evaluate(&self, x: &mut Vec<f64>, _: &mut ()) -> f64 {
        (0..self.pairs)
            .map(|p| self.ridge.log_density(&x[2 * p..2 * p + 2]))
            .sum()
    }
}

// ---- a broken ghost ----

/// A ghost arithmetic with a bug: `y* = z - y` (the displacement taken as `y` instead of
/// `y - x`). The map `(x, y, z) -> (z, y*, x)` is then no involution (the reverse path's ghost
/// is `x - z + y`, not `y`), so Green-Mira with it violates detailed balance.
#[derive(Clone, Copy, Debug)]
pub(crate) struct DisplacementBug;

impl StateArithmetic<Vec<f64>> for DisplacementBug {
    fn ghost(&self, _x: &Vec<f64>, y: &Vec<f64>, z: &Vec<f64>, out: &mut Vec<f64>) {
        out.clear();
        out.extend(z.iter().zip(y).map(|(a, b)| wrap(a - b)));
    }
}

// ---- a lazily materialised state whose read set depends on the state ----

/// A point of the torus `[0, 1)^2` whose second coordinate is lazily materialised, on the
/// target [`LazyStripes`] (which reads `u1` only inside its stripes).
///
/// `u1 = wrap(base + c[1])`, where `base` belongs to a *lineage* and may be unknown. Under
/// the target, `u1` given `u0` outside the stripes is uniform, so refreshing it there is a
/// Gibbs update that preserves the target; [`OnLazy`] does that lazily at the start of every
/// step from a state outside the stripes: the first-stage candidate starts a new lineage with
/// an unknown base, which the first evaluation that reads `u1` draws (from the reading
/// state's `key`). A rejected candidate that drew the base passes it to the current state
/// through [`Point::absorb_rejected`], so a second-stage candidate proposed afterwards sees
/// the *same* `u1` as the rejected first stage did, as an eager state would; without it (the
/// negative control `ABSORB = false`), the second stage draws its own base and the
/// delayed-rejection ratio compares `y` and `z` at inconsistent values of `u1`.
#[derive(Clone, Debug)]
pub(crate) struct LazyPoint<const ABSORB: bool> {
    /// `u0` and the offset of `u1` from the base.
    pub(crate) c: Vec<f64>,
    /// The lineage's base, if drawn.
    pub(crate) base: Option<f64>,
    /// Identifies the lineage (which base this state's `u1` is relative to).
    pub(crate) lineage: u64,
    /// Randomness for drawing the base.
    pub(crate) key: u64,
}

fn uniform_of(key: u64) -> f64 {
    (mix64(key) >> 11) as f64 * (1.0 / (1u64 << 53) as f64)
}

impl<const ABSORB: bool> LazyPoint<ABSORB> {
    /// `u1`, drawing the base if needed (what a target reading `u1` does).
    fn read_u1(&mut self) -> f64 {
        let base = self.base.unwrap_or_else(|| uniform_of(self.key));
        self.base = Some(base);
        wrap(base + self.c[1])
    }

    /// `u1` as the bins see it: inside the stripes the value the target read; outside, a
    /// fresh uniform (the Gibbs refresh the next step would apply).
    fn peek_u1(&self) -> f64 {
        match self.base {
            Some(base) if in_band(self.c[0]) => wrap(base + self.c[1]),
            _ => uniform_of(self.key ^ 0x7065_656b),
        }
    }
}

impl<const ABSORB: bool> Point for LazyPoint<ABSORB> {
    /// Takes the base a rejected candidate drew for this state's `u1`: of this lineage if it
    /// was unknown, or of the refreshed lineage of the current step if this state is outside
    /// the stripes (its own `u1` was refreshed).
    fn absorb_rejected(&mut self, rejected: &Self) {
        if !ABSORB || rejected.base.is_none() {
            return;
        }
        let same = rejected.lineage == self.lineage && self.base.is_none();
        let refreshed = rejected.lineage != self.lineage && !in_band(self.c[0]);
        if same || refreshed {
            self.lineage = rejected.lineage;
            self.base = rejected.base;
        }
    }
}

/// Quarter cells of the stripe pattern of `u0` (8 stripes of width 1/16, one across the seam).
const CELLS: usize = 32;

fn cell(u: f64) -> usize {
    ((u * CELLS as f64) as usize).min(CELLS - 1)
}

/// True in the stripes of `u0` (quarter cells 0 and 3 modulo 4).
fn in_band(u: f64) -> bool {
    matches!(cell(u) % 4, 0 | 3)
}

/// True on the band of `u1`: `[0, 1/4)` and `[3/4, 1)` (one band, across the seam).
fn on_band(u: f64) -> bool {
    !(0.25..0.75).contains(&u)
}

/// Density inside the stripes on and off the bands of `u1`.
const HIGH: f64 = 1.0;
const LOW: f64 = 0.05;
/// The normalising constant `1/2 + (HIGH + LOW) / 4`.
const Z: f64 = 0.5 + 0.25 * (HIGH + LOW);

/// A density on the torus whose read set depends on the state: it reads `u0`, and `u1` only
/// when `u0` is in a stripe (half of `[0, 1)`: four stripes, one across the seam); there the
/// density is [`HIGH`] on the bands of `u1` (half of the circle) and [`LOW`] elsewhere;
/// outside the stripes it is 1.
#[derive(Clone, Copy, Debug)]
pub(crate) struct LazyStripes<const ABSORB: bool>;

impl<const ABSORB: bool> Target for LazyStripes<ABSORB> {
    type State = LazyPoint<ABSORB>;
    type Payload = ();
    fn evaluate(&self, x: &mut LazyPoint<ABSORB>, _: &mut ()) -> f64 {
        let f = if in_band(x.c[0]) {
            if on_band(x.read_u1()) {
                HIGH
            } else {
                LOW
            }
        } else {
            1.0
        };
        f.ln() - Z.ln()
    }
}

/// A uniform point in the stripes (`stripe = true`) or outside.
fn uniform_in<R: Rng + ?Sized>(stripe: bool, rng: &mut R) -> f64 {
    let k = rng.random_range(0..CELLS / 2);
    let offset = if stripe { [0, 3] } else { [1, 2] }[k % 2];
    ((k / 2) * 4 + offset) as f64 / CELLS as f64 + rng.random::<f64>() / CELLS as f64
}

/// A uniform point on the band of `u1` (`band = true`) or off it.
fn uniform_u1<R: Rng + ?Sized>(band: bool, rng: &mut R) -> f64 {
    let u = 0.5 * rng.random::<f64>();
    if band {
        wrap(u + 0.75)
    } else {
        u + 0.25
    }
}

impl<const ABSORB: bool> LazyStripes<ABSORB> {
    /// An exact draw: outside the stripes (probability `1 / (2 Z)`) `u1` is left unread.
    pub(crate) fn sample_exact<R: Rng + ?Sized>(&self, rng: &mut R) -> LazyPoint<ABSORB> {
        let inside = rng.random::<f64>() >= 0.5 / Z;
        let u0 = uniform_in(inside, rng);
        let base = inside.then(|| uniform_u1(rng.random::<f64>() < HIGH / (HIGH + LOW), rng));
        LazyPoint {
            c: vec![u0, 0.0],
            base,
            lineage: rng.random(),
            key: rng.random(),
        }
    }

    /// 64 exact bins: the quarter cell of `u0` times whether `u1` is on a band (also outside
    /// the stripes, where `u1` must be uniform).
    pub(crate) fn bins(&self) -> FnBins<fn(&LazyPoint<ABSORB>) -> usize> {
        let probabilities = (0..2 * CELLS)
            .map(|b| {
                let f = match (matches!((b / 2) % 4, 0 | 3), b % 2 == 1) {
                    (true, true) => HIGH,
                    (true, false) => LOW,
                    (false, _) => 1.0,
                };
                f / (2.0 * CELLS as f64 * Z)
            })
            .collect();
        FnBins {
            probabilities,
            bin_of: |x: &LazyPoint<ABSORB>| 2 * cell(x.c[0]) + usize::from(on_band(x.peek_u1())),
        }
    }
}

/// Runs a `Vec<f64>` stage on the coordinates `c` of a [`LazyPoint`]. First stage: from a
/// state outside the stripes the candidate starts a fresh lineage with an unknown base (the
/// lazy Gibbs refresh of `u1`), from inside it keeps the parent's. Second stage: the
/// candidate belongs to the first-stage candidate's lineage, with the base the current state
/// knows for it (after absorbing the rejected candidate) or an unknown one. Offsets and `u1`
/// differ by the common base, so torus densities of the offsets are those of `u1`.
#[derive(Clone, Copy, Debug)]
pub(crate) struct OnLazy<P>(pub(crate) P);

impl<const A: bool, P: Proposal<Vec<f64>>> Proposal<LazyPoint<A>> for OnLazy<P> {
    fn propose<R: Rng + ?Sized>(
        &self,
        x: &LazyPoint<A>,
        y: &mut LazyPoint<A>,
        rng: &mut R,
    ) -> Proposed {
        let p = self.0.propose(&x.c, &mut y.c, rng);
        if in_band(x.c[0]) {
            y.lineage = x.lineage;
            y.base = x.base;
        } else {
            y.lineage = rng.random();
            y.base = None;
        }
        y.key = rng.random();
        p
    }
    fn log_q(&self, from: &LazyPoint<A>, to: &LazyPoint<A>) -> f64 {
        self.0.log_q(&from.c, &to.c)
    }
    fn is_symmetric(&self) -> bool {
        self.0.is_symmetric()
    }
}

impl<const A: bool, P: ConditionalProposal<Vec<f64>>> ConditionalProposal<LazyPoint<A>>
    for OnLazy<P>
{
    fn propose<R: Rng + ?Sized>(
        &self,
        x: &LazyPoint<A>,
        y: &LazyPoint<A>,
        z: &mut LazyPoint<A>,
        rng: &mut R,
    ) -> Proposed {
        let p = self.0.propose(&x.c, &y.c, &mut z.c, rng);
        z.lineage = y.lineage;
        z.base = if x.lineage == y.lineage { x.base } else { None };
        z.key = rng.random();
        p
    }
    fn log_q(&self, x: &LazyPoint<A>, y: &LazyPoint<A>, z: &LazyPoint<A>) -> f64 {
        self.0.log_q(&x.c, &y.c, &z.c)
    }
}

/// Torus ghost arithmetic for [`LazyPoint`]: the offsets' ghost in the step's lineage, with
/// the base if `z`, `y` or (having absorbed it) `x` knows it, and a key derived from `z`'s
/// fresh key otherwise.
#[derive(Clone, Copy, Debug)]
pub(crate) struct LazyTorus;

impl<const A: bool> StateArithmetic<LazyPoint<A>> for LazyTorus {
    fn ghost(&self, x: &LazyPoint<A>, y: &LazyPoint<A>, z: &LazyPoint<A>, out: &mut LazyPoint<A>) {
        Torus.ghost(&x.c, &y.c, &z.c, &mut out.c);
        let known_to_x = if x.lineage == y.lineage { x.base } else { None };
        out.base = z.base.or(y.base).or(known_to_x);
        out.lineage = y.lineage;
        out.key = mix64(z.key ^ 0x6768_6f73_7421);
    }
}
