//! A 4-D PSS target with discrete choices: a "lobe" chosen by one number, a read set and a
//! set of discrete numbers that both depend on the state.

use mcmc_core::{DifferentiableTarget, Target};
use rand::{Rng, RngExt};

use super::exact::{ExactPssTarget, PssBins};
use crate::{PssError, PssState};

/// Cells of the bins of `u1` (eighths: they nest every boundary where the read set or the
/// discrete tags change).
const CELLS: usize = 8;

/// Classes of the bins of `u2` and `u3`: the half of `[0, 1)` times whether `g` is above 1.
const CLASSES: usize = 4;

/// A density on `[0, 1)^4` built like a path with discrete choices, read through
/// [`PssState::next_sample`] (continuous) and [`PssState::next_discrete`] (discrete):
///
/// - `u0` is a **discrete** choice (a lobe): branch A if `u0 < 1/2`, with weight `w_a`, else
///   branch B with weight `w_b = 2 - w_a`.
/// - Branch A reads `u1` (continuous); if `u1` lies in `[1/4, 3/4)` it also reads `u2`
///   (continuous): the **read set** depends on the state. `u3` is never read.
/// - Branch B reads `u1` (continuous), then `u2` and `u3`: if `u1 < 1/2`, `u2` is a
///   **discrete** choice (factor `c(u2)`: `3/2` below 1/2, `1/2` above) and `u3` continuous;
///   otherwise `u2` is continuous and `u3` the choice. *Which* numbers are discrete depends
///   on the state at the same read count and the same number of continuous numbers.
///
/// ```text
/// pi(u) = w(u0) g(u1) h(u1, u2, u3),    g(u) = 1 + a cos(4 pi u),  Z = 1,
/// h = product over u2, u3 of g where read continuously, c where a choice, 1 where unread.
/// ```
///
/// `g` integrates to 1 on `[0, 1)` and to 1/2 on `[0, 1/2)` and `[1/2, 1)`, so every branch
/// integrates to its weight over 2 and `Z = (w_a + w_b) / 2 = 1`. The boundaries where
/// branch B's tags change (`u1` = 0 and 1/2) are maxima of `g`, so Langevin moves cross them
/// often: a kernel that does not compare the tags of the current state and of the candidate
/// moves `(u1, u3)` forward and `(u1, u2)` back — a number discrete at one end differentiated
/// as if it were continuous at the other — and is visibly biased.
///
/// Exact sampler: the branch by its weight, `u0` uniform on its half; `u1` from `g` (by
/// rejection); `u2`, `u3` from `g`, from `c` or uniform as the branch and `u1` say. Every
/// coordinate is stored.
///
/// Bins (`2 x 8 x 4 x 4`): the half of `u0`, the eighth of `u1`, and for `u2` and `u3` the
/// half times whether `g > 1` there (whether or not they are read). Probabilities in closed
/// form: `int g = 1/8 + a (sin(pi (k + 1) / 2) - sin(pi k / 2)) / (4 pi)` over eighth `k`,
/// `1/4 +- a / (2 pi)` over the part of a half where `g` is above (below) 1.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct LobeChoice {
    amplitude: f64,
    weight_a: f64,
}

impl Default for LobeChoice {
    /// Amplitude `a = 0.9` (`g` from 0.1 to 1.9), branch weights `w_a = 0.8`, `w_b = 1.2`.
    fn default() -> Self {
        Self {
            amplitude: 0.9,
            weight_a: 0.8,
        }
    }
}

/// How the target reads `u2` or `u3`.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
enum Read {
    Continuous,
    Choice,
    Unread,
}

impl LobeChoice {
    /// A target with amplitude `a` in `[0, 1)` and branch-A weight `w_a` in `(0, 2)`.
    ///
    /// # Errors
    /// [`PssError::InvalidParameter`] naming the parameter out of range.
    pub fn new(amplitude: f64, weight_a: f64) -> Result<Self, PssError> {
        if !(0.0..1.0).contains(&amplitude) {
            return Err(PssError::InvalidParameter {
                name: "amplitude",
                value: amplitude.to_string(),
                allowed: "[0, 1)",
            });
        }
        if !(weight_a > 0.0 && weight_a < 2.0) {
            return Err(PssError::InvalidParameter {
                name: "weight_a",
                value: weight_a.to_string(),
                allowed: "(0, 2)",
            });
        }
        Ok(Self {
            amplitude,
            weight_a,
        })
    }

    fn g(&self, u: f64) -> f64 {
        1.0 + self.amplitude * (4.0 * std::f64::consts::PI * u).cos()
    }

    /// `d ln g / du`.
    fn dlog_g(&self, u: f64) -> f64 {
        let w = 4.0 * std::f64::consts::PI;
        -self.amplitude * w * (w * u).sin() / self.g(u)
    }

    /// The discrete factor `c`.
    fn choice(u: f64) -> f64 {
        if u < 0.5 {
            1.5
        } else {
            0.5
        }
    }

    /// How `u2` and `u3` are read in the branch and at `u1`.
    fn reads(branch_a: bool, u1: f64) -> [Read; 2] {
        match (branch_a, u1) {
            (true, u1) if (0.25..0.75).contains(&u1) => [Read::Continuous, Read::Unread],
            (true, _) => [Read::Unread, Read::Unread],
            (false, u1) if u1 < 0.5 => [Read::Choice, Read::Continuous],
            (false, _) => [Read::Continuous, Read::Choice],
        }
    }

    /// `int g` over the eighth `k` of `[0, 1)`.
    fn g_cell(&self, k: usize) -> f64 {
        let s = |k: usize| (std::f64::consts::FRAC_PI_2 * k as f64).sin();
        1.0 / CELLS as f64 + self.amplitude * (s(k + 1) - s(k)) / (4.0 * std::f64::consts::PI)
    }

    /// The class of `u2` or `u3` in the bins: `2 half + (g(u) <= 1)`.
    fn class(u: f64) -> usize {
        let r = u.rem_euclid(0.5);
        2 * usize::from(u >= 0.5) + usize::from((0.125..0.375).contains(&r))
    }

    /// The probability of class `c` under the way it is read.
    fn class_mass(&self, read: Read, c: usize) -> f64 {
        let low = c % 2 == 1;
        match read {
            Read::Unread => 0.25,
            Read::Choice => 0.25 * Self::choice(if c < 2 { 0.25 } else { 0.75 }),
            Read::Continuous => {
                let d = self.amplitude / (2.0 * std::f64::consts::PI);
                if low {
                    0.25 - d
                } else {
                    0.25 + d
                }
            }
        }
    }

    /// A draw from `g` by rejection from uniforms.
    fn sample_g<R: Rng + ?Sized>(&self, rng: &mut R) -> f64 {
        loop {
            let u: f64 = rng.random();
            if rng.random::<f64>() * (1.0 + self.amplitude) < self.g(u) {
                return u;
            }
        }
    }

    /// Reads the path; writes the gradient of `ln pi` with respect to the continuous numbers
    /// (in read order) into `grad` if given.
    fn read(&self, x: &mut PssState, grad: Option<&mut Vec<f64>>) -> f64 {
        x.begin();
        let branch_a = x.next_discrete() < 0.5;
        let u1 = x.next_sample();
        let mut f = self.g(u1)
            * if branch_a {
                self.weight_a
            } else {
                2.0 - self.weight_a
            };
        let mut g = [self.dlog_g(u1), 0.0, 0.0];
        let mut n = 1;
        for how in Self::reads(branch_a, u1) {
            match how {
                Read::Continuous => {
                    let u = x.next_sample();
                    f *= self.g(u);
                    g[n] = self.dlog_g(u);
                    n += 1;
                }
                Read::Choice => f *= Self::choice(x.next_discrete()),
                Read::Unread => {}
            }
        }
        if let Some(grad) = grad {
            grad.clear();
            grad.extend_from_slice(&g[..n]);
        }
        f.ln()
    }
}

impl Target for LobeChoice {
    type State = PssState;
    type Payload = ();

    fn evaluate(&self, x: &mut PssState, _payload: &mut ()) -> f64 {
        self.read(x, None)
    }
}

/// The exact gradient of `ln pi` with respect to the continuous numbers the evaluation read
/// ([`crate::langevin::PssCoordinates`] order); the discrete ones have none.
impl DifferentiableTarget for LobeChoice {
    fn evaluate_with_grad(&self, x: &mut PssState, _payload: &mut (), grad: &mut Vec<f64>) -> f64 {
        self.read(x, Some(grad))
    }
}

impl ExactPssTarget for LobeChoice {
    fn name(&self) -> &'static str {
        "lobe choice (discrete u0; which of u2, u3 is discrete depends on the state)"
    }

    fn sample_exact<R: Rng + ?Sized>(&self, rng: &mut R) -> PssState {
        let branch_a = rng.random::<f64>() < self.weight_a / 2.0;
        let u0 = 0.5 * rng.random::<f64>() + if branch_a { 0.0 } else { 0.5 };
        let u1 = self.sample_g(rng);
        let mut u = [u0, u1, 0.0, 0.0];
        for (slot, how) in u[2..].iter_mut().zip(Self::reads(branch_a, u1)) {
            *slot = match how {
                Read::Continuous => self.sample_g(rng),
                Read::Choice => {
                    let low = rng.random::<f64>() < 0.75;
                    0.5 * rng.random::<f64>() + if low { 0.0 } else { 0.5 }
                }
                Read::Unread => rng.random(),
            };
        }
        PssState::from_values(&u)
    }

    fn bins(&self) -> PssBins {
        let mut probabilities = Vec::with_capacity(2 * CELLS * CLASSES * CLASSES);
        for half in 0..2 {
            let branch_a = half == 0;
            let w = if branch_a {
                self.weight_a / 2.0
            } else {
                1.0 - self.weight_a / 2.0
            };
            for k in 0..CELLS {
                let [r2, r3] = Self::reads(branch_a, (k as f64 + 0.5) / CELLS as f64);
                for c2 in 0..CLASSES {
                    for c3 in 0..CLASSES {
                        probabilities.push(
                            w * self.g_cell(k) * self.class_mass(r2, c2) * self.class_mass(r3, c3),
                        );
                    }
                }
            }
        }
        PssBins::new(probabilities, |x: &PssState| {
            let mut x = x.clone();
            let (u0, u1, u2, u3) = (x.get(0), x.get(1), x.get(2), x.get(3));
            let k = ((u1 * CELLS as f64) as usize).min(CELLS - 1);
            ((usize::from(u0 >= 0.5) * CELLS + k) * CLASSES + Self::class(u2)) * CLASSES
                + Self::class(u3)
        })
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use mcmc_core::testing::ExactBins;

    #[test]
    fn density_is_normalised_and_matches_the_bins() {
        let t = LobeChoice::default();
        let bins = t.bins();
        let total: f64 = bins.probabilities().iter().sum();
        assert!((total - 1.0).abs() < 1e-12, "{total}");
        // Midpoint rule on a grid nested in the cells and classes: relative error about
        // h^2 max|g''| / 24 per axis, 2e-4 for h = 1/160.
        let n = 8 * 20;
        let mid = |j: usize| (j as f64 + 0.5) / n as f64;
        let mut mass = vec![0.0; bins.len()];
        for i in 0..2 {
            for j in 0..n {
                for k in 0..n {
                    for l in 0..n {
                        let u = [0.25 + 0.5 * i as f64, mid(j), mid(k), mid(l)];
                        let p = t.evaluate(&mut PssState::from_values(&u), &mut ()).exp()
                            / (2 * n * n * n) as f64;
                        mass[bins.bin_of(&PssState::from_values(&u))] += p;
                    }
                }
            }
        }
        for (m, p) in mass.iter().zip(bins.probabilities()) {
            assert!((m - p).abs() < 2e-3 * p, "{m} vs {p}");
        }
    }

    #[test]
    fn tags_and_read_sets_depend_on_the_state() {
        let t = LobeChoice::default();
        let eval = |u: [f64; 4]| {
            let mut x = PssState::from_values(&u);
            let mut g = Vec::new();
            t.evaluate_with_grad(&mut x, &mut (), &mut g);
            (x.read_counts()[0], x.discrete_mask()[0], g.len())
        };
        assert_eq!(eval([0.2, 0.1, 0.3, 0.5]), (2, 0b1, 1));
        assert_eq!(eval([0.2, 0.3, 0.3, 0.5]), (3, 0b1, 2));
        assert_eq!(eval([0.7, 0.3, 0.3, 0.5]), (4, 0b101, 2));
        assert_eq!(eval([0.7, 0.6, 0.3, 0.5]), (4, 0b1001, 2));
    }

    #[test]
    fn gradient_matches_finite_differences() {
        let t = LobeChoice::default();
        let h = 1e-6;
        let f = |v: [f64; 4]| t.evaluate(&mut PssState::from_values(&v), &mut ());
        for u in [
            [0.2, 0.3, 0.6, 0.1],
            [0.7, 0.6, 0.2, 0.4],
            [0.7, 0.1, 0.9, 0.3],
        ] {
            let mut x = PssState::from_values(&u);
            let mut g = Vec::new();
            t.evaluate_with_grad(&mut x, &mut (), &mut g);
            let mut moved = Vec::new();
            crate::langevin::moved_indices(&x, &mut moved);
            assert_eq!(moved.len(), g.len());
            for (&i, &gi) in moved.iter().zip(&g) {
                let (mut p, mut m) = (u, u);
                p[i] += h;
                m[i] -= h;
                let fd = (f(p) - f(m)) / (2.0 * h);
                assert!(
                    (fd - gi).abs() < 1e-5 * (1.0 + gi.abs()),
                    "{u:?} {i}: {fd} vs {gi}"
                );
            }
        }
    }

    #[test]
    fn exact_sampler_matches_the_bins() {
        let report = super::super::exact::exact_sampler_test(&LobeChoice::default(), 200_000, 3);
        assert!(report.p_value > 1e-4, "{report}");
    }

    #[test]
    fn rejects_bad_parameters() {
        assert!(LobeChoice::new(1.0, 1.0).is_err());
        assert!(LobeChoice::new(0.5, 2.0).is_err());
        assert!(LobeChoice::new(0.5, f64::NAN).is_err());
        assert!(LobeChoice::new(0.5, 0.5).is_ok());
    }
}
