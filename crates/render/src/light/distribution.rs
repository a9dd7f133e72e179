//! Piecewise-constant 1-D and 2-D distributions (pbrt-v3 section 13.3 and 13.6.7): sampling
//! by inverting the cumulative distribution, with the exact density of what was sampled.

use glam::Vec2;

/// A piecewise-constant density on `[0, 1)` with `n` equal cells, proportional to
/// non-negative cell values.
#[derive(Clone, Debug, PartialEq)]
pub struct Distribution1D {
    /// Cell values (the unnormalised density).
    func: Vec<f32>,
    /// `cdf[i]` = integral of the normalised density over `[0, i / n)`; `cdf[n] = 1`.
    cdf: Vec<f32>,
    /// Integral of `func` over `[0, 1)` (`sum / n`).
    integral: f32,
}

impl Distribution1D {
    /// The distribution of `func` (negative and non-finite values count as 0). If every value
    /// is 0 the density is uniform.
    #[must_use]
    pub fn new(func: &[f32]) -> Self {
        let n = func.len().max(1);
        let func: Vec<f32> = if func.is_empty() {
            vec![1.0]
        } else {
            func.iter()
                .map(|&f| if f.is_finite() && f > 0.0 { f } else { 0.0 })
                .collect()
        };
        let mut cdf = Vec::with_capacity(n + 1);
        cdf.push(0.0f32);
        let mut acc = 0.0f64;
        for &f in &func {
            acc += f64::from(f) / n as f64;
            cdf.push(acc as f32);
        }
        let integral = acc as f32;
        let (func, integral) = if integral > 0.0 && integral.is_finite() {
            for c in &mut cdf[1..] {
                *c = (f64::from(*c) / acc) as f32;
            }
            (func, integral)
        } else {
            for (i, c) in cdf.iter_mut().enumerate() {
                *c = i as f32 / n as f32;
            }
            (vec![1.0; n], 1.0)
        };
        cdf[n] = 1.0;
        Self {
            func,
            cdf,
            integral,
        }
    }

    /// Number of cells.
    #[must_use]
    pub fn len(&self) -> usize {
        self.func.len()
    }

    /// Never true (a distribution has at least one cell).
    #[must_use]
    pub fn is_empty(&self) -> bool {
        self.func.is_empty()
    }

    /// Integral of the unnormalised function over `[0, 1)`.
    #[must_use]
    pub fn integral(&self) -> f32 {
        self.integral
    }

    /// Samples `x` in `[0, 1)` from `u` in `[0, 1)`: `(x, density at x, cell)`.
    #[inline]
    #[must_use]
    pub fn sample(&self, u: f32) -> (f32, f32, usize) {
        let n = self.func.len();
        // Last cell whose cdf start is <= u, skipping empty cells.
        let cell = self.cdf[..n].partition_point(|&c| c <= u).saturating_sub(1);
        let mut cell = cell.min(n - 1);
        while self.func[cell] == 0.0 && cell + 1 < n {
            cell += 1;
        }
        let (c0, c1) = (self.cdf[cell], self.cdf[cell + 1]);
        let du = if c1 > c0 {
            ((u - c0) / (c1 - c0)).clamp(0.0, 1.0)
        } else {
            0.5
        };
        let x = ((cell as f32 + du) / n as f32).min(1.0 - f32::EPSILON / 2.0);
        (x, self.func[cell] / self.integral, cell)
    }

    /// Density at `x` in `[0, 1)` (0 outside).
    #[inline]
    #[must_use]
    pub fn pdf(&self, x: f32) -> f32 {
        if !(0.0..1.0).contains(&x) {
            return 0.0;
        }
        let n = self.func.len();
        let cell = ((x * n as f32) as usize).min(n - 1);
        self.func[cell] / self.integral
    }
}

/// A piecewise-constant density on `[0, 1)^2` over an `nu x nv` grid: the marginal in `v`
/// (rows) times the conditional in `u` within the row.
#[derive(Clone, Debug, PartialEq)]
pub struct Distribution2D {
    conditional: Vec<Distribution1D>,
    marginal: Distribution1D,
}

impl Distribution2D {
    /// The distribution of `func`, `nu` values per row, row-major (`func.len() = nu * nv`).
    ///
    /// # Panics
    /// If `nu` is 0 or `func.len()` is not a multiple of `nu`.
    #[must_use]
    pub fn new(func: &[f32], nu: usize) -> Self {
        assert!(
            nu > 0 && func.len().is_multiple_of(nu),
            "bad Distribution2D shape"
        );
        let conditional: Vec<Distribution1D> = func.chunks(nu).map(Distribution1D::new).collect();
        // Rows whose values are all 0 have integral 0 in the marginal (Distribution1D::new
        // made them uniform internally, so use the raw sums).
        let row_integrals: Vec<f32> = func
            .chunks(nu)
            .map(|row| {
                row.iter()
                    .map(|&f| if f.is_finite() && f > 0.0 { f } else { 0.0 })
                    .sum::<f32>()
                    / nu as f32
            })
            .collect();
        let marginal = Distribution1D::new(&row_integrals);
        Self {
            conditional,
            marginal,
        }
    }

    /// Samples `(u, v)` from `u2`: the point and its density.
    #[inline]
    #[must_use]
    pub fn sample(&self, u2: Vec2) -> (Vec2, f32) {
        let (v, pdf_v, row) = self.marginal.sample(u2.y);
        let (u, pdf_u, _) = self.conditional[row].sample(u2.x);
        (Vec2::new(u, v), pdf_u * pdf_v)
    }

    /// Density at `(u, v)`.
    #[inline]
    #[must_use]
    pub fn pdf(&self, p: Vec2) -> f32 {
        let pdf_v = self.marginal.pdf(p.y);
        if pdf_v == 0.0 {
            return 0.0;
        }
        let nv = self.conditional.len();
        let row = ((p.y * nv as f32) as usize).min(nv - 1);
        pdf_v * self.conditional[row].pdf(p.x)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn one_d_sampling_matches_pdf() {
        let d = Distribution1D::new(&[0.0, 1.0, 3.0, 0.0]);
        assert!((d.integral() - 1.0).abs() < 1e-6);
        let (x, pdf, cell) = d.sample(0.0);
        assert_eq!(cell, 1);
        assert!((0.25..0.5).contains(&x));
        assert!((pdf - 1.0).abs() < 1e-6);
        let (x, pdf, cell) = d.sample(0.999);
        assert_eq!(cell, 2);
        assert!((0.5..0.75).contains(&x));
        assert!((pdf - 3.0).abs() < 1e-6);
        assert_eq!(d.pdf(0.1), 0.0);
        assert!((d.pdf(0.6) - 3.0).abs() < 1e-6);
        // u at a cell boundary with an empty cell after it never lands in the empty cell.
        let (_, pdf, _) = d.sample(1.0 - 1e-7);
        assert!(pdf > 0.0);
    }

    #[test]
    fn all_zero_is_uniform() {
        let d = Distribution1D::new(&[0.0, 0.0]);
        assert!((d.pdf(0.3) - 1.0).abs() < 1e-6);
        let d2 = Distribution2D::new(&[0.0; 6], 3);
        assert!((d2.pdf(Vec2::new(0.2, 0.7)) - 1.0).abs() < 1e-5);
    }

    #[test]
    fn two_d_pdf_integrates_to_one_and_matches_samples() {
        let func: Vec<f32> = (0..12).map(|i| (i % 5) as f32).collect();
        let d = Distribution2D::new(&func, 4);
        let mut integral = 0.0;
        for v in 0..3 {
            for u in 0..4 {
                integral += d.pdf(Vec2::new((u as f32 + 0.5) / 4.0, (v as f32 + 0.5) / 3.0)) / 12.0;
            }
        }
        assert!((integral - 1.0).abs() < 1e-5, "{integral}");
        for i in 0..100 {
            let u = Vec2::new((i as f32 * 0.618_034) % 1.0, (i as f32 * 0.414_213) % 1.0);
            let (p, pdf) = d.sample(u);
            assert!(pdf > 0.0);
            assert!((d.pdf(p) - pdf).abs() <= 1e-4 * pdf, "{p} {pdf}");
        }
    }
}
