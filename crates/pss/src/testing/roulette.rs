//! A variable-length "path" PSS target: it reads coordinates until a Russian-roulette-like
//! stopping rule fires, with density a product of per-coordinate factors.

use mcmc_core::Target;
use rand::{Rng, RngExt};

use super::exact::{ExactPssTarget, PssBins};
use super::stripes::quarter_cell;
use crate::{PssError, PssState};

/// Length classes of the bins: 1, 2, 3, 4 and `>= 5`.
const LENGTH_CLASSES: usize = 5;

/// The kind of a quarter-period cell: 0 continue/high, 1 stop/high, 2 stop/low,
/// 3 continue/low.
fn kind(u: f64, periods: usize) -> usize {
    quarter_cell(u, periods) % 4
}

/// True if the path continues after a vertex in a cell of this kind.
fn continues(kind: usize) -> bool {
    matches!(kind, 0 | 3)
}

/// A path whose length depends on the state: evaluation reads `u_0, u_1, ...` (stream 0) and
/// continues after `u_k` while `u_k` lies in the continuation region `C`, stopping at the
/// first `u_k` outside it (or giving density 0 if `max_depth` coordinates were read without
/// stopping). The density of a path of length `L` is a product of per-vertex factors:
///
/// ```text
/// pi(u) = prod_{k < L} f(u_k) / Z,   Z = F_s sum_{l=1}^{D} F_c^(l-1),
/// F_c = int_C f = (f_ch + f_cl) / 4,  F_s = int_{[0,1) \ C} f = (f_sh + f_sl) / 4.
/// ```
///
/// `[0, 1)` is cut into `periods` periods of four quarter cells, with factors
/// `f_ch` (continue), `f_sh`, `f_sl` (stop), `f_cl` (continue): `C` is the union of bands of
/// width `1 / (2 periods)` centred on the multiples of `1 / periods`, the one at 0 across the
/// torus seam. Coordinates after `u_{L-1}` are not read; under `pi` they are independent
/// uniforms. This is the structure of a path tracer with Russian roulette: a small step that
/// moves `u_{L-1}` into `C` makes the candidate read `u_L`, which the current state has not
/// read for a while (or ever); with narrow cells and contrasting factors, what that newly read
/// coordinate is decides acceptance.
///
/// Exact sampler: `P(L = l) = F_c^(l-1) F_s / Z` (inverse CDF over `l <= D`); given `L`, the
/// coordinates are independent, `u_k` for `k < L - 1` from `f` restricted to `C`, `u_{L-1}`
/// from `f` restricted to the stop region (the kind of cell by its factor, then uniform on
/// the cells of that kind, by rejection). The start stores the path plus `padding` further
/// uniform coordinates (stale and unread).
///
/// Bins: (length class 1, 2, 3, 4, `>= 5`) x (quarter cell of `u_0`) x (kind of the cell of
/// `u_{L-1}`, for `L >= 2`), plus one bin of probability 0 for paths of density 0.
/// Probabilities: `P(L = 1) (f_a / (4 periods)) / F_s` for `L = 1`, `u_0` in cell `a` (a stop
/// cell), and `P(L = l) (f_a / (4 periods)) / F_c (f_b / 4) / F_s` for `L = l >= 2`, `u_0`
/// in cell `a` (of `C`) and `u_{L-1}` in a cell of kind `b`, summed over `l >= 5` for the
/// last class: exact up to rounding.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct RoulettePath {
    periods: usize,
    /// Factors by cell kind: continue/high, stop/high, stop/low, continue/low.
    factors: [f64; 4],
    max_depth: usize,
    padding: usize,
}

impl Default for RoulettePath {
    /// 8 periods (quarter cells of width 1/32, two Kelemen 2002 steps), factors
    /// `f_ch = 2.6, f_sh = 2, f_sl = 0.05, f_cl = 0.05` (`F_c = 0.6625`, `F_s = 0.5125`, mean
    /// length 3.0, `P(L >= 5) = 0.19`), depth at most 64, two padding coordinates.
    fn default() -> Self {
        Self {
            periods: 8,
            factors: [2.6, 2.0, 0.05, 0.05],
            max_depth: 64,
            padding: 2,
        }
    }
}

impl RoulettePath {
    /// `periods` (1..=4096) periods of four cells with factors `[f_ch, f_sh, f_sl, f_cl]`
    /// (positive, finite), the largest path length `max_depth` (1..=256) and the number of
    /// unread coordinates stored after the path in exact starts (0..=64).
    pub fn new(
        periods: usize,
        factors: [f64; 4],
        max_depth: usize,
        padding: usize,
    ) -> Result<Self, PssError> {
        let invalid = |name: &'static str, value: String, allowed: &'static str| {
            Err(PssError::InvalidParameter {
                name,
                value,
                allowed,
            })
        };
        if !(1..=4096).contains(&periods) {
            return invalid("periods", periods.to_string(), "1..=4096");
        }
        if let Some(f) = factors.iter().find(|f| !(**f > 0.0 && f.is_finite())) {
            return invalid("factor", f.to_string(), "(0, inf)");
        }
        if !(1..=256).contains(&max_depth) {
            return invalid("max_depth", max_depth.to_string(), "1..=256");
        }
        if padding > 64 {
            return invalid("padding", padding.to_string(), "0..=64");
        }
        Ok(Self {
            periods,
            factors,
            max_depth,
            padding,
        })
    }

    /// `(F_c, F_s)`: the integrals of the factor over the continuation and stop regions.
    fn region_masses(&self) -> (f64, f64) {
        let f = &self.factors;
        ((f[0] + f[3]) / 4.0, (f[1] + f[2]) / 4.0)
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

    /// Number of coordinates an evaluation of `x` reads (the path length, or `max_depth` for
    /// a path that does not stop), computed on a copy.
    #[must_use]
    pub fn reads(&self, x: &PssState) -> usize {
        let mut x = x.clone();
        self.read(&mut x)
            .map_or(self.max_depth, |(length, ..)| length)
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
            let k = kind(u, self.periods);
            log_f += self.factors[k].ln();
            if !continues(k) {
                return Some((depth + 1, first, u, log_f));
            }
        }
        None
    }

    /// A draw from `f` restricted to the continuation (`want`) or stop region.
    fn draw_in<R: Rng + ?Sized>(&self, rng: &mut R, want: bool) -> f64 {
        let (a, b) = if want { (0, 3) } else { (1, 2) };
        let p_a = self.factors[a] / (self.factors[a] + self.factors[b]);
        let k = if rng.random::<f64>() < p_a { a } else { b };
        loop {
            let u: f64 = rng.random();
            if kind(u, self.periods) == k {
                return u;
            }
        }
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
        let cells = 4 * self.periods;
        let lengths = self.length_probabilities();
        let (c_mass, s_mass) = self.region_masses();
        let class_probability = |class: usize| -> f64 {
            if class + 1 < LENGTH_CLASSES {
                lengths.get(class).copied().unwrap_or(0.0)
            } else {
                lengths.iter().skip(class).sum()
            }
        };
        // Layout: L = 1 by cell of u_0; then per class >= 1, cell of u_0 x kind of u_{L-1}.
        let mut probabilities = vec![0.0; cells + (LENGTH_CLASSES - 1) * cells * 4 + 1];
        let cell_mass = |cell: usize| self.factors[cell % 4] / cells as f64;
        for a in (0..cells).filter(|a| !continues(a % 4)) {
            probabilities[a] = class_probability(0) * cell_mass(a) / s_mass;
        }
        for class in 1..LENGTH_CLASSES {
            for a in (0..cells).filter(|a| continues(a % 4)) {
                for b in [1, 2] {
                    probabilities[cells + ((class - 1) * cells + a) * 4 + b] =
                        class_probability(class)
                            * (cell_mass(a) / c_mass)
                            * (self.factors[b] / 4.0 / s_mass);
                }
            }
        }
        let overflow = probabilities.len() - 1;
        let target = *self;
        PssBins::new(probabilities, move |x: &PssState| {
            let mut x = x.clone();
            match target.read(&mut x) {
                None => overflow,
                Some((1, first, _, _)) => quarter_cell(first, target.periods),
                Some((length, first, last, _)) => {
                    let class = (length - 1).min(LENGTH_CLASSES - 1);
                    let a = quarter_cell(first, target.periods);
                    cells + ((class - 1) * cells + a) * 4 + kind(last, target.periods)
                }
            }
        })
    }
}

/// The density is piecewise constant: gradient 0 on every coordinate read (the order of
/// [`crate::langevin::PssCoordinates`]), so MALA on it is a Gaussian walk over the current
/// path's coordinates — what tests its read-set rule on varying path lengths.
impl mcmc_core::DifferentiableTarget for RoulettePath {
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
    use rand::SeedableRng;

    #[test]
    fn masses_and_bins_are_consistent() {
        let t = RoulettePath::default();
        let (c, s) = t.region_masses();
        assert!(
            (c - 0.6625).abs() < 1e-12 && (s - 0.5125).abs() < 1e-12,
            "{c} {s}"
        );
        let total: f64 = t.bins().probabilities().iter().sum();
        assert!((total - 1.0).abs() < 1e-12, "{total}");
        // The continuation band at 0 straddles the seam.
        let k = |u: f64| kind(u, t.periods);
        assert!(continues(k(0.0)) && continues(k(0.999)));
        assert!(!continues(k(1.5 / 32.0)) && !continues(k(2.5 / 32.0)));
    }

    /// The density the target evaluates agrees with the bin probabilities: for states of
    /// fresh uniforms `U`, `E[pi(U) 1_b(U)] = p_b` (importance sampling from the uniform
    /// measure on the unit cube, of which the read coordinates are a marginal). 400k fresh
    /// states; each bin's estimate must lie within 5 standard errors (+1e-4) of `p_b`
    /// (family-wise false-failure probability below 1e-4 over the bins).
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
        assert!(RoulettePath::new(16, f, 0, 2).is_err());
        assert!(RoulettePath::new(16, f, 64, 65).is_err());
        assert!(RoulettePath::new(0, f, 64, 2).is_err());
        let mut g = f;
        g[3] = 0.0;
        assert!(RoulettePath::new(16, g, 64, 2).is_err());
        assert!(RoulettePath::new(16, f, 64, 2).is_ok());
    }
}
