//! The normalisation `b` of an MCMC image from every independent sample the render draws:
//! the bootstrap's and the chains' large-step candidates, pooled per target, with its
//! standard error.
//!
//! # The estimator
//! A target `d` (PSSMLT: the one target; MMLT: one path depth) has integral
//! `b_d = E_q[f_d / q]` over the density `q` of its independent states (primary sample
//! space: uniform, `q = 1`). The render draws two kinds of independent samples of it:
//!
//! 1. the bootstrap's `n_d` samples, mean `B_d` (pbrt's scheme; Kelemen et al. 2002, section
//!    4, eq. 5 needs `b`);
//! 2. the candidates of the chains' large steps ([`crate::Kernel::independent_density`]),
//!    `K_d` of them with values `y_k = f_d(u_k) / q`: a large step draws `u_k` from `q`
//!    whatever the chain's state, so `E[y_k | past] = b_d` (Kelemen et al. 2002, section 4,
//!    where the large steps are the independent technique of the MIS estimator).
//!
//! Every sample counts once (the balance weights of equal-density techniques):
//!
//! ```text
//! b'_d = (n_d B_d + sum_k y_k) / (n_d + K_d),      b' = sum_d b'_d,
//! Var b'_d = a^2 Var B_d + (1 - a)^2 s_d^2 / K_d,   a = n_d / (n_d + K_d),
//! ```
//!
//! with `s_d^2` the large-step values' sample variance and `Var B_d` the bootstrap's (targets
//! are independent, so the variances add). `b'` is **exactly unbiased** when the counts `K_d`
//! do not depend on the values (a fixed large-step probability under a mutation budget: the
//! large/small choice uses its own random number), and consistent otherwise (automatic
//! large-step control or a time budget make `K_d` depend weakly on the run). The *image*
//! `b' / N * sum splats` is consistent, not exactly unbiased: the bootstrap-only image is
//! exact because its `b` and its chain starts come from the same samples (Hachisuka et al.
//! 2014, section 4), while the large steps also steer the chains whose splats `b'` scales
//! (a bias of order `1 / K`, below the noise it removes). Its standard error falls as
//! `1 / sqrt(n_d + K_d)`: with the chains' time, where the bootstrap's stays fixed.
//!
//! # Determinism
//! The large-step sums are kept per job (and per target), each job's in its own fixed order
//! of steps, and combined in job order: the same bits for any thread count, and for the sum
//! of the parts of a sharded render ([`super::Shard`]: a part holds zeros for the jobs it
//! does not own, and `0 + x = x`).

use crate::McmcError;

/// One job's large-step candidates of one target: their count and the sums of `f / q` and
/// of its square.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct LargeStepSums {
    /// Large-step candidates counted.
    pub count: u64,
    /// `sum f / q`.
    pub sum: f64,
    /// `sum (f / q)^2`.
    pub sum_sq: f64,
}

impl LargeStepSums {
    /// Counts one candidate of value `y = f / q` (0 outside the support).
    #[inline]
    pub fn push(&mut self, y: f64) {
        self.count += 1;
        self.sum += y;
        self.sum_sq += y * y;
    }

    /// Adds another set of sums.
    pub fn add(&mut self, other: &LargeStepSums) {
        self.count += other.count;
        self.sum += other.sum;
        self.sum_sq += other.sum_sq;
    }
}

/// How a render loop normalises its image ([`super::LoopSettings::normalization`]).
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub enum NormalizationMode {
    /// The bootstrap pooled with every large-step candidate of the chains (the default;
    /// see the module docs). Kernels without large steps keep the bootstrap's estimate.
    #[default]
    Pooled,
    /// The bootstrap's estimate alone (pbrt's scheme).
    Bootstrap,
    /// The caller's `b` (e.g. the mean of a reference image, for comparisons on one
    /// footing): the image's brightness is then exactly that.
    Given(f64),
}

/// Everything the final `b` rests on: the bootstrap's estimate per target and each job's
/// large-step sums. A sharded render's part carries it; [`Normalization::add`] combines the
/// parts so that [`Normalization::estimate`] gives the whole render's bits.
#[derive(Clone, Debug, PartialEq)]
pub struct Normalization {
    /// How the estimate is formed.
    pub mode: NormalizationMode,
    /// The bootstrap's estimate `B_d` per target (with a per-target normalisation given to
    /// the loop: those values).
    pub bootstrap_b: Vec<f64>,
    /// The variance of each `B_d`.
    pub bootstrap_variance: Vec<f64>,
    /// The bootstrap's samples `n_d` per target.
    pub bootstrap_samples: Vec<u64>,
    /// The bootstrap's standard error of `sum_d B_d` (from its row sums).
    pub bootstrap_standard_error: f64,
    /// Number of jobs: [`Normalization::large_steps`] holds `jobs x targets` sums.
    pub jobs: usize,
    /// Large-step sums, job-major (`large_steps[job * targets + target]`).
    pub large_steps: Vec<LargeStepSums>,
}

/// The normalisation a render used ([`Normalization::estimate`]).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct NormalizationEstimate {
    /// The normalisation `b` the image is scaled with.
    pub b: f64,
    /// Its standard error (0 for [`NormalizationMode::Given`]).
    pub standard_error: f64,
    /// Large-step candidates pooled in (0 unless [`NormalizationMode::Pooled`]).
    pub large_steps: u64,
}

impl Normalization {
    /// Empty large-step sums for `jobs` jobs over the bootstrap's targets.
    #[must_use]
    pub fn new(
        mode: NormalizationMode,
        bootstrap_b: Vec<f64>,
        bootstrap_variance: Vec<f64>,
        bootstrap_samples: Vec<u64>,
        bootstrap_standard_error: f64,
        jobs: usize,
    ) -> Self {
        let targets = bootstrap_b.len();
        Self {
            mode,
            bootstrap_b,
            bootstrap_variance,
            bootstrap_samples,
            bootstrap_standard_error,
            jobs,
            large_steps: vec![LargeStepSums::default(); jobs * targets],
        }
    }

    /// Number of targets.
    #[must_use]
    pub fn targets(&self) -> usize {
        self.bootstrap_b.len()
    }

    /// The sums of job `job`, one per target.
    pub fn job_mut(&mut self, job: usize) -> &mut [LargeStepSums] {
        let t = self.targets();
        &mut self.large_steps[job * t..(job + 1) * t]
    }

    /// The large-step sums of each target over all jobs, added in job order.
    #[must_use]
    pub fn target_sums(&self) -> Vec<LargeStepSums> {
        let t = self.targets();
        let mut out = vec![LargeStepSums::default(); t];
        if t == 0 {
            return out;
        }
        for job in self.large_steps.chunks(t) {
            for (o, s) in out.iter_mut().zip(job) {
                o.add(s);
            }
        }
        out
    }

    /// The normalisation and its standard error (module docs).
    #[must_use]
    pub fn estimate(&self) -> NormalizationEstimate {
        let bootstrap = NormalizationEstimate {
            b: self.bootstrap_b.iter().sum(),
            standard_error: self.bootstrap_standard_error,
            large_steps: 0,
        };
        match self.mode {
            NormalizationMode::Given(b) => NormalizationEstimate {
                b,
                standard_error: 0.0,
                large_steps: 0,
            },
            NormalizationMode::Bootstrap => bootstrap,
            NormalizationMode::Pooled => {
                let sums = self.target_sums();
                let large_steps: u64 = sums.iter().map(|s| s.count).sum();
                if large_steps == 0 {
                    return bootstrap;
                }
                let (mut b, mut variance) = (0.0, 0.0);
                for (d, s) in sums.iter().enumerate() {
                    let n = self.bootstrap_samples[d] as f64;
                    let k = s.count as f64;
                    let b_d = self.bootstrap_b[d];
                    let v_d = self.bootstrap_variance[d];
                    if s.count == 0 {
                        b += b_d;
                        variance += v_d;
                        continue;
                    }
                    let a = n / (n + k);
                    b += (n * b_d + s.sum) / (n + k);
                    let mean = s.sum / k;
                    // One large step has no sample variance of its own: take the
                    // bootstrap's per-sample variance (the same distribution).
                    let per_sample = if s.count > 1 {
                        ((s.sum_sq - k * mean * mean) / (k - 1.0)).max(0.0)
                    } else {
                        v_d * n
                    };
                    variance += a * a * v_d + (1.0 - a) * (1.0 - a) * per_sample / k;
                }
                NormalizationEstimate {
                    b,
                    standard_error: variance.sqrt(),
                    large_steps,
                }
            }
        }
    }

    /// Adds the large-step sums of another part of the same render.
    ///
    /// # Errors
    /// [`McmcError::InvalidParameter`] if the parts differ in their bootstrap, mode or job
    /// list (they are not parts of one render).
    pub fn add(&mut self, other: &Normalization) -> Result<(), McmcError> {
        let same_bits = |a: &[f64], b: &[f64]| {
            a.len() == b.len() && a.iter().zip(b).all(|(x, y)| x.to_bits() == y.to_bits())
        };
        if self.mode != other.mode
            || self.jobs != other.jobs
            || !same_bits(&self.bootstrap_b, &other.bootstrap_b)
            || !same_bits(&self.bootstrap_variance, &other.bootstrap_variance)
            || self.bootstrap_samples != other.bootstrap_samples
            || self.large_steps.len() != other.large_steps.len()
        {
            return Err(McmcError::InvalidParameter {
                name: "normalization",
                value: other.bootstrap_b.iter().sum(),
                allowed: "parts of one render (the same bootstrap, mode and jobs)",
            });
        }
        for (a, b) in self.large_steps.iter_mut().zip(&other.large_steps) {
            a.add(b);
        }
        Ok(())
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn one_target(mode: NormalizationMode) -> Normalization {
        // B = 2 from 100 samples of variance 4 (variance of the mean 0.04).
        Normalization::new(mode, vec![2.0], vec![0.04], vec![100], 0.2, 2)
    }

    #[test]
    fn without_large_steps_it_is_the_bootstrap() {
        let n = one_target(NormalizationMode::Pooled);
        let e = n.estimate();
        assert_eq!((e.b, e.standard_error, e.large_steps), (2.0, 0.2, 0));
    }

    #[test]
    fn pools_every_sample_once() {
        let mut n = one_target(NormalizationMode::Pooled);
        for y in [1.0, 3.0] {
            n.job_mut(0)[0].push(y);
        }
        n.job_mut(1)[0].push(5.0);
        n.job_mut(1)[0].push(3.0);
        let e = n.estimate();
        // (100 * 2 + 12) / 104.
        assert!((e.b - 212.0 / 104.0).abs() < 1e-12, "{}", e.b);
        assert_eq!(e.large_steps, 4);
        assert!(e.standard_error < 0.2 && e.standard_error > 0.0);
        let given = one_target(NormalizationMode::Given(7.0)).estimate();
        assert_eq!((given.b, given.standard_error), (7.0, 0.0));
        let mut boot = one_target(NormalizationMode::Bootstrap);
        boot.job_mut(0)[0].push(9.0);
        assert_eq!(boot.estimate().b, 2.0);
    }

    #[test]
    fn parts_add_to_the_whole() {
        let mut whole = one_target(NormalizationMode::Pooled);
        whole.job_mut(0)[0].push(0.1);
        whole.job_mut(1)[0].push(0.7);
        let mut a = one_target(NormalizationMode::Pooled);
        a.job_mut(0)[0].push(0.1);
        let mut b = one_target(NormalizationMode::Pooled);
        b.job_mut(1)[0].push(0.7);
        a.add(&b).unwrap();
        assert_eq!(a, whole);
        assert_eq!(a.estimate().b.to_bits(), whole.estimate().b.to_bits());
        let other = Normalization::new(
            NormalizationMode::Pooled,
            vec![3.0],
            vec![0.04],
            vec![100],
            0.2,
            2,
        );
        assert!(a.add(&other).is_err());
    }
}
