//! A variable-length "path" PSS target: it reads coordinates until a Russian-roulette-like
//! stopping rule fires, with density a product of per-coordinate factors.

use mcmc_core::Target;
use rand::{Rng, RngExt};

use super::exact::{ExactPssTarget, PssBins};
use crate::{PssError, PssState};

/// Number of equal cells of `[0, 1)` on which the per-vertex factor is constant.
pub const ROULETTE_CELLS: usize = 16;

/// Cells where the path continues: `[3/4, 1) u [0, 1/4)`, across the torus seam.
fn continues(cell: usize) -> bool {
    !(4..12).contains(&cell)
}

/// The cell of `u`.
fn cell_of(u: f64) -> usize {
    ((u * ROULETTE_CELLS as f64) as usize).min(ROULETTE_CELLS - 1)
}

/// Length classes of the bins: 1, 2, 3, 4 and `>= 5`.
const LENGTH_CLASSES: usize = 5;

/// A path whose length depends on the state: evaluation reads `u_0, u_1, ...` (stream 0) and
/// continues after `u_k` while `u_k` lies in the continuation region `C = [3/4, 1) u [0, 1/4)`
/// (across the torus seam), stopping at the first `u_k` outside it (or giving density 0 if
/// `max_depth` coordinates were read without stopping). The density of a path of length `L`
/// is a product of per-vertex factors:
///
/// ```text
/// pi(u) = prod_{k < L} f(u_k) / Z,   f piecewise constant on 16 cells,
/// Z = F_s sum_{l=1}^{D} F_c^(l-1),   F_c = int_C f,  F_s = int_{[0,1) \ C} f.
/// ```
///
/// Coordinates after `u_{L-1}` are not read; under `pi` they are independent uniforms. This is
/// the structure of a path tracer with Russian roulette: a small step that moves `u_{L-1}`
/// into `C` makes the candidate read `u_L`, which the current state has not read for a while
/// (or ever). The default factors alternate between large and small values on neighbouring
/// cells (width 1/16), so what that newly read coordinate is changes acceptance a lot.
///
/// Exact sampler: `P(L = l) = F_c^(l-1) F_s / Z` (drawn by inverse CDF over `l <= D`); given
/// `L`, the coordinates are independent, `u_k` for `k < L - 1` from `f` restricted to `C`,
/// `u_{L-1}` from `f` restricted to the stop region (cell by its weight, uniform within).
/// The start stores the path plus `padding` further uniform coordinates (stale and unread).
///
/// Bins: (length class 1, 2, 3, 4, `>= 5`) x (cell of `u_0`) x (cell of `u_{L-1}`, for
/// `L >= 2`), plus one bin of probability 0 for paths of density 0. Probabilities, with cell
/// weights `w_c = f_c / 16`: `w_a / Z` for `L = 1` (`a` a stop cell) and
/// `w_a F_c^(l-2) w_b / Z` for `L = l >= 2` (`a` in `C`, `b` a stop cell), summed over
/// `l = 5..=D` for the last class: exact up to rounding.
#[derive(Clone, Debug, PartialEq)]
pub struct RoulettePath {
    factors: [f64; ROULETTE_CELLS],
    max_depth: usize,
    padding: usize,
}

impl Default for RoulettePath {
    /// Factors `2.6 0.6 2.0 0.4 | 0.5 2.0 0.4 1.8 0.6 2.4 0.3 1.6 | 0.5 2.1 0.4 2.8` (the bars
    /// separate the continuation and stop cells; cells 15 and 0, across the seam, are both
    /// large): `F_c = 0.7125`, `F_s = 0.6`, mean length 3.5, `P(L >= 5) = 0.26`. Depth at
    /// most 64, two padding coordinates.
    fn default() -> Self {
        Self {
            factors: [
                2.6, 0.6, 2.0, 0.4, 0.5, 2.0, 0.4, 1.8, 0.6, 2.4, 0.3, 1.6, 0.5, 2.1, 0.4, 2.8,
            ],
            max_depth: 64,
            padding: 2,
        }
    }
}

impl RoulettePath {
    /// Per-cell factors (positive, finite), the largest path length `max_depth` (1..=256) and
    /// the number of unread coordinates stored after the path in exact starts (0..=64).
    pub fn new(
        factors: [f64; ROULETTE_CELLS],
        max_depth: usize,
        padding: usize,
    ) -> Result<Self, PssError> {
        if let Some(f) = factors.iter().find(|f| !(**f > 0.0 && f.is_finite())) {
            return Err(PssError::InvalidParameter {
                name: "factor",
                value: f.to_string(),
                allowed: "(0, inf)",
            });
        }
        if !(1..=256).contains(&max_depth) {
            return Err(PssError::InvalidParameter {
                name: "max_depth",
                value: max_depth.to_string(),
                allowed: "1..=256",
            });
        }
        if padding > 64 {
            return Err(PssError::InvalidParameter {
                name: "padding",
                value: padding.to_string(),
                allowed: "0..=64",
            });
        }
        Ok(Self {
            factors,
            max_depth,
            padding,
        })
    }

    /// `(F_c, F_s)`: the integrals of the factor over the continuation and stop regions.
    fn region_masses(&self) -> (f64, f64) {
        let (mut c, mut s) = (0.0, 0.0);
        for (cell, f) in self.factors.iter().enumerate() {
            if continues(cell) {
                c += f / ROULETTE_CELLS as f64;
            } else {
                s += f / ROULETTE_CELLS as f64;
            }
        }
        (c, s)
    }

    /// `P(L = l)` for `l = 1..=max_depth` (index `l - 1`).
    fn length_probabilities(&self) -> Vec<f64> {
        let (c, s) = self.region_masses();
        let unnormalised: Vec<f64> = (0..self.max_depth).map(|k| s * c.powi(k as i32)).collect();
        let z: f64 = unnormalised.iter().sum();
        unnormalised.iter().map(|p| p / z).collect()
    }

    /// The normalising constant `Z`.
    #[must_use]
    pub fn normaliser(&self) -> f64 {
        let (c, s) = self.region_masses();
        (0..self.max_depth).map(|k| s * c.powi(k as i32)).sum()
    }

    /// Reads the path from `x` (rewinding it): `(length, u_0, u_{L-1}, log of the product of
    /// factors)`, or `None` if it did not stop within `max_depth` coordinates.
    fn read(&self, x: &mut PssState) -> Option<(usize, f64, f64, f64)> {
        x.begin();
        let mut log_f = 0.0;
        let mut first = 0.0;
        for depth in 0..self.max_depth {
            let u = x.next_sample();
            if depth == 0 {
                first = u;
            }
            let cell = cell_of(u);
            log_f += self.factors[cell].ln();
            if !continues(cell) {
                return Some((depth + 1, first, u, log_f));
            }
        }
        None
    }

    /// A uniform draw from the cells with `continues(cell) == want`, each chosen with
    /// probability proportional to its factor.
    fn draw_in<R: Rng + ?Sized>(&self, rng: &mut R, want: bool) -> f64 {
        let total: f64 = (0..ROULETTE_CELLS)
            .filter(|&c| continues(c) == want)
            .map(|c| self.factors[c])
            .sum();
        let mut t = rng.random::<f64>() * total;
        let mut chosen = None;
        for c in (0..ROULETTE_CELLS).filter(|&c| continues(c) == want) {
            chosen = Some(c);
            if t < self.factors[c] {
                break;
            }
            t -= self.factors[c];
        }
        let c = chosen.expect("both regions have cells");
        (c as f64 + rng.random::<f64>()) / ROULETTE_CELLS as f64
    }
}

impl Target for RoulettePath {
    type State = PssState;
    type Payload = ();

    fn evaluate(&self, x: &mut PssState, _payload: &mut ()) -> f64 {
        match self.read(x) {
            Some((_, _, _, log_f)) => log_f - self.normaliser().ln(),
            None => f64::NEG_INFINITY,
        }
    }
}

impl ExactPssTarget for RoulettePath {
    fn name(&self) -> &'static str {
        "roulette path (reads until a stopping rule fires)"
    }

    fn sample_exact<R: Rng + ?Sized>(&self, rng: &mut R) -> PssState {
        let lengths = self.length_probabilities();
        let mut t: f64 = rng.random();
        let mut length = self.max_depth;
        for (k, p) in lengths.iter().enumerate() {
            if t < *p {
                length = k + 1;
                break;
            }
            t -= p;
        }
        let mut values: Vec<f64> = (0..length - 1).map(|_| self.draw_in(rng, true)).collect();
        values.push(self.draw_in(rng, false));
        values.extend((0..self.padding).map(|_| rng.random::<f64>()));
        PssState::from_values(&values)
    }

    fn bins(&self) -> PssBins {
        let n = ROULETTE_CELLS;
        let lengths = self.length_probabilities();
        let (c_mass, s_mass) = self.region_masses();
        // P(L = l, u_0 in a, u_{L-1} in b) = P(L = l) (w_a / F_c) (w_b / F_s) for l >= 2.
        let w = |cell: usize| self.factors[cell] / n as f64;
        let class_probability = |class: usize| -> f64 {
            if class + 1 < LENGTH_CLASSES {
                lengths.get(class).copied().unwrap_or(0.0)
            } else {
                lengths.iter().skip(class).sum()
            }
        };
        let mut probabilities = vec![0.0; n + (LENGTH_CLASSES - 1) * n * n + 1];
        for a in (0..n).filter(|&a| !continues(a)) {
            probabilities[a] = class_probability(0) * w(a) / s_mass;
        }
        for class in 1..LENGTH_CLASSES {
            for a in (0..n).filter(|&a| continues(a)) {
                for b in (0..n).filter(|&b| !continues(b)) {
                    probabilities[n + (class - 1) * n * n + a * n + b] =
                        class_probability(class) * (w(a) / c_mass) * (w(b) / s_mass);
                }
            }
        }
        let overflow = probabilities.len() - 1;
        let target = self.clone();
        PssBins::new(probabilities, move |x: &PssState| {
            let mut x = x.clone();
            match target.read(&mut x) {
                None => overflow,
                Some((1, first, _, _)) => cell_of(first),
                Some((length, first, last, _)) => {
                    let class = (length - 1).min(LENGTH_CLASSES - 1);
                    n + (class - 1) * n * n + cell_of(first) * n + cell_of(last)
                }
            }
        })
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use mcmc_core::testing::ExactBins;
    use rand::SeedableRng;

    #[test]
    fn masses_and_bins_are_consistent() {
        let t = RoulettePath::default();
        let (c, s) = t.region_masses();
        assert!(
            (c - 0.7125).abs() < 1e-12 && (s - 0.6).abs() < 1e-12,
            "{c} {s}"
        );
        let total: f64 = t.bins().probabilities().iter().sum();
        assert!((total - 1.0).abs() < 1e-12, "{total}");
        assert!(continues(0) && continues(15) && !continues(4) && !continues(11));
    }

    /// The density the target evaluates agrees with the bin probabilities: for states of
    /// fresh uniforms `U`, `E[pi(U) 1_b(U)] = p_b` (importance sampling from the uniform
    /// measure on the unit cube, of which the read coordinates are a marginal). 400k fresh
    /// states; each bin's estimate must lie within 5 standard errors (+1e-4) of `p_b`
    /// (family-wise false-failure probability below 1e-4 over the 265 bins).
    #[test]
    fn evaluation_matches_the_bins() {
        let t = RoulettePath::default();
        let bins = t.bins();
        let n = 400_000;
        let mut sum = vec![0.0; bins.len()];
        let mut sum_sq = vec![0.0; bins.len()];
        let mut rng = rand_pcg::Pcg64::seed_from_u64(5);
        for _ in 0..n {
            let mut x = PssState::new(1, rng.random());
            let p = t.evaluate(&mut x, &mut ()).exp();
            let b = bins.bin_of(&x);
            sum[b] += p;
            sum_sq[b] += p * p;
        }
        let nf = f64::from(n);
        for (b, &p) in bins.probabilities().iter().enumerate() {
            let mean = sum[b] / nf;
            let se = ((sum_sq[b] / nf - mean * mean) / nf).sqrt();
            assert!(
                (mean - p).abs() < 5.0 * se + 1e-4,
                "bin {b}: {mean} +- {se} vs {p}"
            );
        }
    }

    #[test]
    fn exact_starts_are_materialised_paths() {
        let t = RoulettePath::default();
        let mut rng = rand_pcg::Pcg64::seed_from_u64(3);
        for _ in 0..1000 {
            let mut x = t.sample_exact(&mut rng);
            let stored = x.len();
            let (length, _, _, _) = t.read(&mut x).expect("exact draws stop");
            assert_eq!(stored, length + 2);
            assert_eq!(x.len(), stored, "reading the path did not grow the state");
            assert!(t.evaluate(&mut x, &mut ()).is_finite());
        }
    }

    #[test]
    fn rejects_bad_parameters() {
        let f = RoulettePath::default().factors;
        assert!(RoulettePath::new(f, 0, 2).is_err());
        assert!(RoulettePath::new(f, 64, 65).is_err());
        let mut g = f;
        g[3] = 0.0;
        assert!(RoulettePath::new(g, 64, 2).is_err());
        assert!(RoulettePath::new(f, 64, 2).is_ok());
    }
}
