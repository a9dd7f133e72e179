//! A 2-D PSS target that reads its second coordinate only when the first lies in some stripes.

use mcmc_core::Target;
use rand::{Rng, RngExt};

use super::exact::{ExactPssTarget, PssBins};
use crate::{PssError, PssState};

/// The quarter-period cell of `u` for a pattern with `periods` periods on `[0, 1)`: cells of
/// width `1 / (4 periods)`, index in `0..4 periods`.
pub(super) fn quarter_cell(u: f64, periods: usize) -> usize {
    let n = 4 * periods;
    ((u * n as f64) as usize).min(n - 1)
}

/// True if `u` lies in one of `periods` bands of width `1 / (2 periods)` centred on the
/// multiples of `1 / periods` (the band at 0 straddles the torus seam): quarter cells
/// `0` and `3` modulo 4.
pub(super) fn in_band(u: f64, periods: usize) -> bool {
    matches!(quarter_cell(u, periods) % 4, 0 | 3)
}

/// The largest number of periods of a pattern (cells stay far wider than rounding).
const MAX_PERIODS: usize = 1 << 12;

/// A density on `[0, 1)^2` whose *read set depends on the state*: evaluation reads `u0`;
/// outside the stripes the density is 1 and `u1` is not read; in the stripes it reads `u1`,
/// and the density is `high` on some bands of `u1` and `low` elsewhere:
///
/// ```text
/// pi(u0, u1) = f(u0, u1) / Z,  f = 1 outside the stripes, f = high or low inside,
/// Z = 1/2 + (high + low) / 4.
/// ```
///
/// The stripes are `stripe_periods` bands of width `1 / (2 stripe_periods)` centred on the
/// multiples of `1 / stripe_periods`, the one at 0 straddling the torus seam; the high bands
/// of `u1` are the same pattern with `band_periods` periods. Half of each axis is in a band.
///
/// It is the shape of a renderer whose path length depends on where the first vertex lands:
/// an MH chain sitting outside the stripes does not read `u1` for many steps, and a candidate
/// entering the stripes must see the current state's own `u1` (perturbed once), not a value
/// re-drawn at each proposal. Narrow stripes put most chains next to a stripe edge, narrow
/// bands make a re-drawn `u1` land in a different band, and a large `high / low` makes that
/// decide acceptance, so a lazy state that re-draws stale coordinates is visibly biased.
///
/// Exact sampler: `u0` in the stripes with probability `(high + low) / (4 Z)`, uniform on the
/// chosen region (by rejection from uniforms); `u1` uniform outside the stripes, else on the
/// high bands with probability `high / (high + low)`. Both coordinates are stored.
///
/// Bins (`8 stripe_periods`): the quarter-period cell of `u0` (each wholly in or out of the
/// stripes) times whether `u1` is on a high band, *whether or not the target reads `u1`* (an
/// unread coordinate must still be uniform). Probability of a cell and class:
/// `(1 / (4 stripe_periods)) (1/2) f / Z`, exact. `u1` is brought up to date by the bins'
/// assignment, as a target reading it would.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Stripes {
    stripe_periods: usize,
    band_periods: usize,
    high: f64,
    low: f64,
}

impl Default for Stripes {
    /// 4 stripes (width 1/8), 4 high bands of `u1` (width 1/8), `high = 1`, `low = 1/20`:
    /// 34% of the mass in the stripes, 95% of that on the high bands. With Kelemen 2002's
    /// small step or pbrt-v3's Gaussian (sigma 0.01), a re-drawn stale `u1` lands on the other
    /// kind of band often enough to matter within a few dozen steps.
    fn default() -> Self {
        Self {
            stripe_periods: 4,
            band_periods: 4,
            high: 1.0,
            low: 0.05,
        }
    }
}

impl Stripes {
    /// Stripes and bands with the given numbers of periods (`1..=4096`), and densities on the
    /// high and low bands inside the stripes (positive and finite; the density outside the
    /// stripes is 1).
    pub fn new(
        stripe_periods: usize,
        band_periods: usize,
        high: f64,
        low: f64,
    ) -> Result<Self, PssError> {
        for (name, v) in [
            ("stripe_periods", stripe_periods),
            ("band_periods", band_periods),
        ] {
            if !(1..=MAX_PERIODS).contains(&v) {
                return Err(PssError::InvalidParameter {
                    name,
                    value: v.to_string(),
                    allowed: "1..=4096",
                });
            }
        }
        for (name, v) in [("high", high), ("low", low)] {
            if !(v > 0.0 && v.is_finite()) {
                return Err(PssError::InvalidParameter {
                    name,
                    value: v.to_string(),
                    allowed: "(0, inf)",
                });
            }
        }
        Ok(Self {
            stripe_periods,
            band_periods,
            high,
            low,
        })
    }

    /// 16 stripes and 16 bands (each of width 1/32), `high = 1.9`, `low = 0.1`: half the
    /// mass in the stripes (`Z = 1`), 95% of it on the high bands. Stripes as narrow as the
    /// usual small steps (sigma 0.03 to 0.05) put a stripe edge, where the read set changes,
    /// within reach of most moves: the target of the two-stage kernels' read-set tests, with
    /// [`Stripes::stripe_bins`] (a kernel that mishandles read-set changes moves the stripe
    /// share away from one half).
    #[must_use]
    pub fn narrow() -> Self {
        Self {
            stripe_periods: 16,
            band_periods: 16,
            high: 1.9,
            low: 0.1,
        }
    }

    /// The normalising constant `Z = 1/2 + (high + low) / 4`.
    #[must_use]
    pub fn normaliser(&self) -> f64 {
        0.5 + 0.25 * (self.high + self.low)
    }

    /// True if `u0` lies in the stripes (where the target reads `u1`).
    #[must_use]
    pub fn in_stripes(&self, u0: f64) -> bool {
        in_band(u0, self.stripe_periods)
    }

    /// True if `u1` lies on a high band.
    #[must_use]
    pub fn is_high(&self, u1: f64) -> bool {
        in_band(u1, self.band_periods)
    }

    /// Number of coordinates an evaluation of `x` reads (1 outside the stripes, 2 inside),
    /// computed on a copy.
    #[must_use]
    pub fn reads(&self, x: &PssState) -> usize {
        let mut x = x.clone();
        if self.in_stripes(x.get(0)) {
            2
        } else {
            1
        }
    }

    /// Two bins, outside and inside the stripes (whether `u0` is in them), with exact
    /// probabilities `1 / (2 Z)` and `(high + low) / (4 Z)`: a chi-square with one degree of
    /// freedom on the share of states in the stripes, the statistic that a kernel mishandling
    /// read-set changes moves (it moves mass across the stripe edges, where the read set
    /// changes).
    #[must_use]
    pub fn stripe_bins(&self) -> PssBins {
        let inside = 0.25 * (self.high + self.low) / self.normaliser();
        let target = *self;
        PssBins::new(vec![1.0 - inside, inside], move |x: &PssState| {
            let mut x = x.clone();
            usize::from(target.in_stripes(x.get(0)))
        })
    }

    /// The unnormalised density inside the stripes at `u1`.
    fn inside(&self, u1: f64) -> f64 {
        if self.is_high(u1) {
            self.high
        } else {
            self.low
        }
    }
}

impl Target for Stripes {
    type State = PssState;
    type Payload = ();

    fn evaluate(&self, x: &mut PssState, _payload: &mut ()) -> f64 {
        x.begin();
        let u0 = x.next_sample();
        let f = if self.in_stripes(u0) {
            self.inside(x.next_sample())
        } else {
            1.0
        };
        (f / self.normaliser()).ln()
    }
}

/// A uniform draw from `[0, 1)` restricted to `{u : keep(u) == want}`, by rejection.
pub(super) fn uniform_where<R: Rng + ?Sized>(
    rng: &mut R,
    keep: impl Fn(f64) -> bool,
    want: bool,
) -> f64 {
    loop {
        let u: f64 = rng.random();
        if keep(u) == want {
            return u;
        }
    }
}

impl ExactPssTarget for Stripes {
    fn name(&self) -> &'static str {
        "stripes (reads u1 only in the stripes)"
    }

    fn sample_exact<R: Rng + ?Sized>(&self, rng: &mut R) -> PssState {
        let p_stripes = 0.25 * (self.high + self.low) / self.normaliser();
        let inside = rng.random::<f64>() < p_stripes;
        let u0 = uniform_where(rng, |u| self.in_stripes(u), inside);
        let u1 = if inside {
            let high = rng.random::<f64>() < self.high / (self.high + self.low);
            uniform_where(rng, |u| self.is_high(u), high)
        } else {
            rng.random()
        };
        PssState::from_values(&[u0, u1])
    }

    fn bins(&self) -> PssBins {
        let z = self.normaliser();
        let cells = 4 * self.stripe_periods;
        let probabilities = (0..2 * cells)
            .map(|b| {
                let (cell, high) = (b / 2, b % 2 == 1);
                let f = match (matches!(cell % 4, 0 | 3), high) {
                    (false, _) => 1.0,
                    (true, true) => self.high,
                    (true, false) => self.low,
                };
                f / (2.0 * cells as f64 * z)
            })
            .collect();
        let target = *self;
        PssBins::new(probabilities, move |x: &PssState| {
            let mut x = x.clone();
            let (u0, u1) = (x.get(0), x.get(1));
            2 * quarter_cell(u0, target.stripe_periods) + usize::from(target.is_high(u1))
        })
    }
}

/// The density is piecewise constant: its gradient is 0 wherever it is defined (one entry per
/// coordinate the evaluation read, the order of [`crate::langevin::PssCoordinates`]), so
/// MALA on it is a Gaussian walk on the read coordinates — what tests its read-set rule.
impl mcmc_core::DifferentiableTarget for Stripes {
    fn evaluate_with_grad(&self, x: &mut PssState, payload: &mut (), grad: &mut Vec<f64>) -> f64 {
        let value = self.evaluate(x, payload);
        grad.clear();
        grad.resize(x.read_counts()[0], 0.0);
        value
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use mcmc_core::testing::ExactBins;

    #[test]
    fn geometry_straddles_the_seam() {
        let t = Stripes::default();
        assert!(t.in_stripes(0.0) && t.in_stripes(0.999) && t.in_stripes(0.5));
        assert!(!t.in_stripes(0.0625) && !t.in_stripes(0.4));
        assert!(t.is_high(0.0) && t.is_high(0.99) && t.is_high(0.25) && t.is_high(0.5));
        assert!(!t.is_high(0.1) && !t.is_high(0.4));
        // Half of [0, 1) is in the stripes, half of it on the high bands.
        let n = 1 << 12;
        let grid = (0..n).map(|i| (f64::from(i) + 0.5) / f64::from(n));
        let half = n as usize / 2;
        assert_eq!(grid.clone().filter(|&u| t.in_stripes(u)).count(), half);
        assert_eq!(grid.filter(|&u| t.is_high(u)).count(), half);
    }

    #[test]
    fn density_is_normalised_and_matches_the_bins() {
        for t in [
            Stripes::default(),
            Stripes::new(3, 2, 3.0, 0.5).unwrap(),
            Stripes::narrow(),
        ] {
            let bins = t.bins();
            let total: f64 = bins.probabilities().iter().sum();
            assert!((total - 1.0).abs() < 1e-12, "{total}");
            // Midpoint rule on a grid whose cells nest in the pattern's quarter cells.
            let n = 4 * 24 * 16;
            let mut mass = vec![0.0; bins.len()];
            for i in 0..n {
                for j in 0..n {
                    let u = [
                        (f64::from(i) + 0.5) / f64::from(n),
                        (f64::from(j) + 0.5) / f64::from(n),
                    ];
                    let mut x = PssState::from_values(&u);
                    let p = t.evaluate(&mut x, &mut ()).exp() / f64::from(n * n);
                    mass[bins.bin_of(&PssState::from_values(&u))] += p;
                }
            }
            for (m, p) in mass.iter().zip(bins.probabilities()) {
                assert!((m - p).abs() < 1e-12, "{t:?}: {m} vs {p}");
            }
            // The stripe bins are sums of the fine bins.
            let stripes = t.stripe_bins();
            let mut share = [0.0; 2];
            for (b, p) in bins.probabilities().iter().enumerate() {
                share[usize::from(matches!((b / 2) % 4, 0 | 3))] += p;
            }
            for (s, p) in share.iter().zip(stripes.probabilities()) {
                assert!((s - p).abs() < 1e-12, "{t:?}: {s} vs {p}");
            }
            for u0 in [0.0, 0.2, 0.3, 0.999] {
                let x = PssState::from_values(&[u0, 0.3]);
                assert_eq!(stripes.bin_of(&x), usize::from(t.in_stripes(u0)));
            }
        }
    }

    #[test]
    fn rejects_bad_parameters() {
        assert!(Stripes::new(8, 16, 0.0, 1.0).is_err());
        assert!(Stripes::new(8, 16, 1.0, f64::INFINITY).is_err());
        assert!(Stripes::new(0, 16, 1.0, 1.0).is_err());
        assert!(Stripes::new(8, 5000, 1.0, 1.0).is_err());
        assert!(Stripes::new(8, 16, 2.0, 0.5).is_ok());
    }
}
