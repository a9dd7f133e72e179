//! A 2-D PSS target that reads its second coordinate only when the first lies in some stripes.

use mcmc_core::Target;
use rand::{Rng, RngExt};

use super::exact::{ExactPssTarget, PssBins};
use crate::{PssError, PssState};

/// Cells of `u0` (width 1/16) in the stripes: `[0, 1/8) u [3/8, 5/8) u [7/8, 1)`, one stripe
/// straddling the torus seam.
const STRIPE_CELLS: [bool; 16] = [
    true, true, false, false, false, false, true, true, true, true, false, false, false, false,
    true, true,
];

/// Cells of `u1` (width 1/32) of high density: `j mod 4 in {0, 3}`, i.e. bands of width 1/16
/// centred on the multiples of 1/8, the one at 0 straddling the seam.
fn is_high(u1: f64) -> bool {
    let j = ((u1 * 32.0) as usize).min(31);
    j % 4 == 0 || j % 4 == 3
}

/// The 1/16-cell of `u0`.
fn cell_of(u0: f64) -> usize {
    ((u0 * 16.0) as usize).min(15)
}

/// True if `u0` lies in the stripes.
fn in_stripes(u0: f64) -> bool {
    STRIPE_CELLS[cell_of(u0)]
}

/// A density on `[0, 1)^2` whose *read set depends on the state*: evaluation reads `u0`;
/// outside the stripes (`[1/8, 3/8) u [5/8, 7/8)`) the density is 1 and `u1` is not read;
/// in the stripes (`[0, 1/8) u [3/8, 5/8) u [7/8, 1)`, one across the torus seam) it reads
/// `u1` and the density is `high` on bands of width 1/16 around the multiples of 1/8 (the one
/// at 0 across the seam) and `low` elsewhere:
///
/// ```text
/// pi(u0, u1) = f(u0, u1) / Z,  f = 1 outside the stripes, f = high or low inside,
/// Z = 1/2 + (high + low) / 4.
/// ```
///
/// It is the shape of a renderer whose path length depends on where the first vertex lands:
/// an MH chain sitting outside the stripes does not read `u1` for many steps, and a candidate
/// entering the stripes must see the current state's own `u1` (perturbed once), not a value
/// re-drawn at each proposal. The bands are narrow (1/16, comparable to a few Kelemen steps)
/// and `high / low` is large, so re-drawing `u1` changes acceptance a lot.
///
/// Exact sampler: `u0` in the stripes with probability `(high + low) / (4 Z)`, uniform on the
/// chosen region (by rejection from uniforms); `u1` uniform outside the stripes, else on the
/// high bands with probability `high / (high + low)`. Both coordinates are stored.
///
/// Bins (32): the 1/16-cell of `u0` times whether `u1` is in a high band, *whether or not the
/// target reads `u1`* (an unread coordinate must be uniform). Probability of a cell `c` and
/// class `k`: `(1/16) (1/2) f(c, k) / Z`, exact. `u1` is brought up to date by the bins'
/// assignment, as a target reading it would.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Stripes {
    high: f64,
    low: f64,
}

impl Default for Stripes {
    /// `high = 3`, `low = 1/3`: 62.5% of the mass in the stripes, 90% of that on the high
    /// bands.
    fn default() -> Self {
        Self {
            high: 3.0,
            low: 1.0 / 3.0,
        }
    }
}

impl Stripes {
    /// Densities on the high and low bands inside the stripes (positive and finite; the
    /// density outside the stripes is 1).
    pub fn new(high: f64, low: f64) -> Result<Self, PssError> {
        for (name, v) in [("high", high), ("low", low)] {
            if !(v > 0.0 && v.is_finite()) {
                return Err(PssError::InvalidParameter {
                    name,
                    value: v.to_string(),
                    allowed: "(0, inf)",
                });
            }
        }
        Ok(Self { high, low })
    }

    /// The normalising constant `Z = 1/2 + (high + low) / 4`.
    #[must_use]
    pub fn normaliser(&self) -> f64 {
        0.5 + 0.25 * (self.high + self.low)
    }

    /// The unnormalised density inside the stripes at `u1`.
    fn inside(&self, u1: f64) -> f64 {
        if is_high(u1) {
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
        let f = if in_stripes(u0) {
            self.inside(x.next_sample())
        } else {
            1.0
        };
        (f / self.normaliser()).ln()
    }
}

/// A uniform draw from `[0, 1)` restricted to `{u : keep(u) == want}`, by rejection.
fn uniform_where<R: Rng + ?Sized>(rng: &mut R, keep: impl Fn(f64) -> bool, want: bool) -> f64 {
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
        let u0 = uniform_where(rng, in_stripes, inside);
        let u1 = if inside {
            let high = rng.random::<f64>() < self.high / (self.high + self.low);
            uniform_where(rng, is_high, high)
        } else {
            rng.random()
        };
        PssState::from_values(&[u0, u1])
    }

    fn bins(&self) -> PssBins {
        let z = self.normaliser();
        let probabilities = (0..32)
            .map(|b| {
                let (cell, high) = (b / 2, b % 2 == 1);
                let f = match (STRIPE_CELLS[cell], high) {
                    (false, _) => 1.0,
                    (true, true) => self.high,
                    (true, false) => self.low,
                };
                f / (32.0 * z)
            })
            .collect();
        PssBins::new(probabilities, |x: &PssState| {
            let mut x = x.clone();
            let (u0, u1) = (x.get(0), x.get(1));
            2 * cell_of(u0) + usize::from(is_high(u1))
        })
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use mcmc_core::testing::ExactBins;

    #[test]
    fn geometry_straddles_the_seam() {
        assert!(in_stripes(0.0) && in_stripes(0.999) && in_stripes(0.5));
        assert!(!in_stripes(0.2) && !in_stripes(0.8));
        assert!(is_high(0.0) && is_high(0.99) && is_high(0.125) && is_high(0.5));
        assert!(!is_high(0.06) && !is_high(0.2));
        // Half of [0, 1) is in the stripes, half of it on the high bands.
        let n = 1 << 12;
        let grid = (0..n).map(|i| (f64::from(i) + 0.5) / f64::from(n));
        assert_eq!(
            grid.clone().filter(|&u| in_stripes(u)).count(),
            n as usize / 2
        );
        assert_eq!(grid.filter(|&u| is_high(u)).count(), n as usize / 2);
    }

    #[test]
    fn density_is_normalised_and_matches_the_bins() {
        let t = Stripes::default();
        let bins = t.bins();
        let total: f64 = bins.probabilities().iter().sum();
        assert!((total - 1.0).abs() < 1e-12, "{total}");
        // Midpoint rule on a 128 x 128 grid (cell edges are multiples of 1/32: exact).
        let n = 128;
        let mut mass = vec![0.0; bins.len()];
        for i in 0..n {
            for j in 0..n {
                let u = [(f64::from(i) + 0.5) / 128.0, (f64::from(j) + 0.5) / 128.0];
                let mut x = PssState::from_values(&u);
                let p = t.evaluate(&mut x, &mut ()).exp() / f64::from(n * n);
                mass[bins.bin_of(&PssState::from_values(&u))] += p;
            }
        }
        for (m, p) in mass.iter().zip(bins.probabilities()) {
            assert!((m - p).abs() < 1e-12, "{m} vs {p}");
        }
    }

    #[test]
    fn rejects_bad_parameters() {
        assert!(Stripes::new(0.0, 1.0).is_err());
        assert!(Stripes::new(1.0, f64::INFINITY).is_err());
        assert!(Stripes::new(2.0, 0.5).is_ok());
    }
}
