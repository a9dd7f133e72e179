//! The Halton sequence: radical inverses in the first 256 prime bases (plain, Faure-permuted,
//! randomly digit-permuted or Owen-scrambled), then a stateless hash-based PRNG.
//!
//! Paper section 3.4 ("Seed sampling"): seed paths are driven by the Halton sequence as
//! implemented by Grünschloß et al. \[GRK12\] (which uses Faure's digit permutations) up to 256
//! dimensions and by a PRNG (the Mersenne twister in the paper) after that.

use crate::hash::{hash_words, permute, unit_f64};

/// Number of dimensions served by radical inverses; dimension `d >= HALTON_DIMENSIONS` comes
/// from the PRNG (paper section 3.4: "Halton ... up to 256 dimensions").
pub const HALTON_DIMENSIONS: usize = 256;

/// The largest `f64` below one: every point returned lies in `[0, 1)`.
pub const ONE_MINUS_EPSILON: f64 = 1.0 - f64::EPSILON / 2.0;

/// The first 256 primes: dimension `d` of the Halton sequence uses base `HALTON_PRIMES[d]`
/// (2, 3, 5, ..., 1619).
pub const HALTON_PRIMES: [u32; HALTON_DIMENSIONS] = first_primes();

const fn first_primes() -> [u32; HALTON_DIMENSIONS] {
    let mut primes = [0u32; HALTON_DIMENSIONS];
    let mut count = 0;
    let mut candidate = 2u32;
    while count < HALTON_DIMENSIONS {
        let mut is_prime = true;
        let mut k = 0;
        while k < count {
            let p = primes[k];
            if p * p > candidate {
                break;
            }
            if candidate.is_multiple_of(p) {
                is_prime = false;
                break;
            }
            k += 1;
        }
        if is_prime {
            primes[count] = candidate;
            count += 1;
        }
        candidate += 1;
    }
    primes
}

/// The radical inverse of `index` in `base`: its base-`base` digits mirrored at the radix
/// point, `sum_k d_k base^-(k+1)` for `index = sum_k d_k base^k` (the Halton coordinate).
///
/// # Example
///
/// ```
/// // 6 = 110 in base 2, mirrored: 0.011 = 3/8.
/// assert_eq!(lqmc::radical_inverse(2, 6), 0.375);
/// // 7 = 12 in base 5, mirrored: 0.21 = 2/5 + 1/25.
/// assert!((lqmc::radical_inverse(5, 7) - 0.44).abs() < 1e-15);
/// ```
#[must_use]
pub fn radical_inverse(base: u32, mut index: u64) -> f64 {
    debug_assert!(base >= 2);
    let b = u64::from(base);
    // Digits are reversed into an integer (exact), then divided once (correctly rounded).
    let mut reversed: u128 = 0;
    let mut base_pow: u128 = 1;
    while index > 0 {
        let next = index / b;
        let digit = index - next * b;
        reversed = reversed * u128::from(b) + u128::from(digit);
        base_pow *= u128::from(b);
        index = next;
    }
    (reversed as f64 / base_pow as f64).min(ONE_MINUS_EPSILON)
}

/// How the digits of each radical inverse are permuted (paper section 3.4; \[GRK12\] uses Faure's).
#[derive(Debug, Clone, Copy, Default, PartialEq, Eq)]
pub enum Scrambling {
    /// The plain radical inverse.
    #[default]
    None,
    /// Faure's deterministic permutation per base (Faure 1992; the permutations of \[GRK12\]'s
    /// Halton implementation): one permutation `sigma_b` for every digit, `sigma_b(0) = 0`.
    Faure,
    /// A pseudo-random permutation per (seed, dimension, digit position): a random digit
    /// permutation (Matoušek 1998), deterministic in the seed.
    RandomDigitPermutation,
    /// Owen's nested uniform scrambling: the permutation of digit `k` also depends on the
    /// digits `0..k` before it (each node of the base-`b` tree gets its own permutation),
    /// deterministic in the seed.
    Owen,
}

/// The Halton sequence in the first [`HALTON_DIMENSIONS`] dimensions, then a PRNG.
///
/// `sample(index, d)` is a pure function of `(scrambling, seed, index, d)`: points can be
/// computed in any order, on any thread. For `d >= 256` it is a 64-bit hash of
/// `(seed, index, d)` (a counter-based PRNG; the paper uses the Mersenne twister there, whose
/// sequential state would make the value depend on evaluation order).
///
/// # Example
///
/// ```
/// use lqmc::{Halton, Scrambling};
///
/// let plain = Halton::new(Scrambling::None, 0);
/// let mut u = [0.0; 3];
/// plain.fill(5, &mut u);
/// // 5 = 101 (base 2), 12 (base 3), 10 (base 5).
/// assert_eq!(u[0], 0.625);
/// assert!((u[1] - 7.0 / 9.0).abs() < 1e-15);
/// assert!((u[2] - 0.04).abs() < 1e-15);
///
/// // Faure's permutation for base 5 is (0 3 2 1 4): 1 -> 3/5.
/// let faure = Halton::new(Scrambling::Faure, 0);
/// assert!((faure.sample(1, 2) - 0.6).abs() < 1e-15);
///
/// // Beyond 256 dimensions: a deterministic PRNG keyed by (seed, index, dimension).
/// let x = plain.sample(3, 300);
/// assert!((0.0..1.0).contains(&x));
/// assert_eq!(x, plain.sample(3, 300));
/// ```
#[derive(Debug, Clone)]
pub struct Halton {
    scrambling: Scrambling,
    seed: u64,
    /// Faure permutations, one per prime base (built once per process, shared; empty
    /// unless [`Scrambling::Faure`]).
    faure: &'static [Vec<u16>],
}

impl Halton {
    /// A Halton sequence with the given digit scrambling; `seed` keys the random
    /// permutations and the PRNG beyond dimension 256 (ignored by the deterministic
    /// scramblings below 256 dimensions).
    #[must_use]
    pub fn new(scrambling: Scrambling, seed: u64) -> Self {
        // Building the permutations of all 256 prime bases (every base up to 1619 on the way)
        // takes milliseconds: once per process, not per sequence (samplers are made per tile).
        static FAURE: std::sync::OnceLock<Vec<Vec<u16>>> = std::sync::OnceLock::new();
        let faure: &'static [Vec<u16>] = if scrambling == Scrambling::Faure {
            FAURE.get_or_init(faure_permutations_for_primes)
        } else {
            &[]
        };
        Halton {
            scrambling,
            seed,
            faure,
        }
    }

    /// The scrambling this sequence uses.
    #[must_use]
    pub fn scrambling(&self) -> Scrambling {
        self.scrambling
    }

    /// The seed of the random scramblings and of the PRNG.
    #[must_use]
    pub fn seed(&self) -> u64 {
        self.seed
    }

    /// Coordinate `dimension` of point `index` (in `[0, 1)`). Point 0 is the origin in every
    /// dimension below 256 for `None` and `Faure`.
    #[must_use]
    pub fn sample(&self, index: u64, dimension: usize) -> f64 {
        if dimension >= HALTON_DIMENSIONS {
            return unit_f64(hash_words(&[self.seed, index, dimension as u64]));
        }
        let base = HALTON_PRIMES[dimension];
        match self.scrambling {
            Scrambling::None => radical_inverse(base, index),
            Scrambling::Faure => {
                let perm = &self.faure[dimension];
                digit_permuted(base, index, |_, _, d| u32::from(perm[d as usize]), false)
            }
            Scrambling::RandomDigitPermutation => {
                let seed = self.seed;
                digit_permuted(
                    base,
                    index,
                    |k, _, d| {
                        let key = hash_words(&[seed, dimension as u64, u64::from(k)]);
                        permute(d, base, key as u32)
                    },
                    true,
                )
            }
            Scrambling::Owen => {
                let seed = self.seed;
                digit_permuted(
                    base,
                    index,
                    |k, prefix, d| {
                        let key = hash_words(&[seed, dimension as u64, u64::from(k), prefix]);
                        permute(d, base, key as u32)
                    },
                    true,
                )
            }
        }
    }

    /// Dimensions `0..out.len()` of point `index`.
    pub fn fill(&self, index: u64, out: &mut [f64]) {
        for (d, x) in out.iter_mut().enumerate() {
            *x = self.sample(index, d);
        }
    }
}

/// A radical inverse whose digit at position `k` (counted from the radix point) is mapped by
/// `perm(k, prefix, digit)`, where `prefix = index mod base^k` (the digits before it).
/// If `all_digits`, digits past the last nonzero one are permuted too (until they fall below
/// `f64` resolution), as they must be when `perm(k, _, 0) != 0`.
#[inline]
fn digit_permuted(
    base: u32,
    mut index: u64,
    perm: impl Fn(u32, u64, u32) -> u32,
    all_digits: bool,
) -> f64 {
    let b = u64::from(base);
    let inv_base = 1.0 / f64::from(base);
    let mut inv_base_pow = inv_base;
    let mut result = 0.0;
    let mut prefix: u64 = 0;
    let mut base_pow: Option<u64> = Some(1);
    let mut k = 0u32;
    // 2^-54: below half an ulp of numbers near 1.
    while index > 0 || (all_digits && inv_base_pow > 5.55e-17) {
        let next = index / b;
        let digit = (index - next * b) as u32;
        let mapped = perm(k, prefix, digit);
        debug_assert!(mapped < base);
        result += f64::from(mapped) * inv_base_pow;
        if let Some(p) = base_pow {
            prefix += u64::from(digit) * p;
            base_pow = p.checked_mul(b);
        }
        inv_base_pow *= inv_base;
        index = next;
        k += 1;
    }
    result.min(ONE_MINUS_EPSILON)
}

/// Faure's permutation of `0..base` (Faure 1992), built recursively: `sigma_2 = (0 1)`; for even
/// `b`, `sigma_b = (2 sigma_{b/2}, 2 sigma_{b/2} + 1)`; for odd `b`, `sigma_{b-1}` with every value
/// `>= (b-1)/2` incremented and `(b-1)/2` inserted in the middle.
#[must_use]
pub fn faure_permutation(base: u32) -> Vec<u16> {
    assert!(
        (2..=u32::from(u16::MAX)).contains(&base),
        "base {base} out of range"
    );
    let mut all: Vec<Vec<u16>> = vec![Vec::new(), vec![0], vec![0, 1]];
    for b in 3..=base as usize {
        let next = faure_step(&all, b);
        all.push(next);
    }
    all.swap_remove(base as usize)
}

fn faure_step(all: &[Vec<u16>], b: usize) -> Vec<u16> {
    if b.is_multiple_of(2) {
        let half = &all[b / 2];
        let mut p = Vec::with_capacity(b);
        p.extend(half.iter().map(|&x| 2 * x));
        p.extend(half.iter().map(|&x| 2 * x + 1));
        p
    } else {
        let c = ((b - 1) / 2) as u16;
        let mut p: Vec<u16> = all[b - 1]
            .iter()
            .map(|&x| if x >= c { x + 1 } else { x })
            .collect();
        p.insert(c as usize, c);
        p
    }
}

fn faure_permutations_for_primes() -> Vec<Vec<u16>> {
    let max = HALTON_PRIMES[HALTON_DIMENSIONS - 1] as usize;
    let mut all: Vec<Vec<u16>> = vec![Vec::new(), vec![0], vec![0, 1]];
    for b in 3..=max {
        let next = faure_step(&all, b);
        all.push(next);
    }
    HALTON_PRIMES
        .iter()
        .map(|&p| std::mem::take(&mut all[p as usize]))
        .collect()
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn primes_are_the_first_256() {
        assert_eq!(&HALTON_PRIMES[..10], &[2, 3, 5, 7, 11, 13, 17, 19, 23, 29]);
        assert_eq!(HALTON_PRIMES[255], 1619);
        for w in HALTON_PRIMES.windows(2) {
            assert!(w[0] < w[1]);
        }
    }

    /// The first points of the plain sequence, worked by hand (digits mirrored at the point).
    #[test]
    fn first_points_match_radical_inverse_by_hand() {
        let h = Halton::new(Scrambling::None, 0);
        // base 2: 0, 1/2, 1/4, 3/4, 1/8, 5/8, 3/8, 7/8
        let base2 = [0.0, 0.5, 0.25, 0.75, 0.125, 0.625, 0.375, 0.875];
        // base 3: 0, 1/3, 2/3, 1/9, 4/9, 7/9, 2/9, 5/9, 8/9
        let base3 = [0.0, 3.0, 6.0, 1.0, 4.0, 7.0, 2.0, 5.0].map(|x: f64| x / 9.0);
        // base 5: 1..=6 -> 1/5, 2/5, 3/5, 4/5, 1/25, 6/25
        let base5 = [0.0, 5.0, 10.0, 15.0, 20.0, 1.0, 6.0, 11.0].map(|x: f64| x / 25.0);
        for i in 0..8 {
            assert_eq!(h.sample(i, 0), base2[i as usize], "base 2, index {i}");
            assert!((h.sample(i, 1) - base3[i as usize]).abs() < 1e-15);
            assert!((h.sample(i, 2) - base5[i as usize]).abs() < 1e-15);
        }
        // 1000 = 1111101000 (base 2) -> 0.0001011111 = 95/1024.
        assert_eq!(radical_inverse(2, 1000), 95.0 / 1024.0);
        // The last base: 1620 = 1*1619 + 1 -> 1/1619 + 1/1619^2.
        let x = h.sample(1620, 255);
        assert!((x - (1.0 / 1619.0 + 1.0 / (1619.0 * 1619.0))).abs() < 1e-15);
    }

    #[test]
    fn faure_permutations_match_the_literature() {
        assert_eq!(faure_permutation(2), vec![0, 1]);
        assert_eq!(faure_permutation(3), vec![0, 1, 2]);
        assert_eq!(faure_permutation(4), vec![0, 2, 1, 3]);
        assert_eq!(faure_permutation(5), vec![0, 3, 2, 1, 4]);
        assert_eq!(faure_permutation(7), vec![0, 2, 5, 3, 1, 4, 6]);
        let h = Halton::new(Scrambling::Faure, 0);
        assert_eq!(h.faure.len(), 256);
        // Base 7, index 9 = 12 (base 7): 0.s(2)s(1) = 5/7 + 2/49.
        assert!((h.sample(9, 3) - (5.0 / 7.0 + 2.0 / 49.0)).abs() < 1e-15);
        for (perm, &p) in h.faure.iter().zip(HALTON_PRIMES.iter()) {
            let mut sorted = perm.clone();
            sorted.sort_unstable();
            assert!(
                sorted.iter().enumerate().all(|(i, &x)| x as usize == i),
                "base {p}"
            );
        }
    }

    /// Scrambling permutes the digits of the first `base^m` points of each coordinate: the
    /// one-dimensional projections stay stratified (one point per interval of length base^-m).
    #[test]
    fn scrambled_projections_stay_stratified() {
        for scrambling in [
            Scrambling::None,
            Scrambling::Faure,
            Scrambling::RandomDigitPermutation,
            Scrambling::Owen,
        ] {
            let h = Halton::new(scrambling, 7);
            for d in [0usize, 1, 2, 10, 100, 255] {
                let b = HALTON_PRIMES[d] as u64;
                let m = if b < 10 { 3 } else { 1 };
                let n = b.pow(m);
                let mut hit = vec![false; n as usize];
                for i in 0..n {
                    let x = h.sample(i, d);
                    assert!((0.0..1.0).contains(&x));
                    // (1e-9: rounding of x = k / n)
                    let cell = (x * n as f64 + 1e-9) as usize;
                    assert!(!hit[cell], "{scrambling:?} dim {d}: cell {cell} twice");
                    hit[cell] = true;
                }
            }
        }
    }

    #[test]
    fn seeds_change_random_scramblings_only() {
        for s in [Scrambling::RandomDigitPermutation, Scrambling::Owen] {
            let a = Halton::new(s, 1);
            let b = Halton::new(s, 2);
            assert_ne!(a.sample(5, 3), b.sample(5, 3));
            assert_eq!(a.sample(5, 3), Halton::new(s, 1).sample(5, 3));
        }
        assert_eq!(
            Halton::new(Scrambling::Faure, 1).sample(5, 3),
            Halton::new(Scrambling::Faure, 2).sample(5, 3)
        );
    }

    #[test]
    fn prng_dimensions_look_uniform() {
        let h = Halton::new(Scrambling::None, 3);
        let n = 20_000;
        let mut counts = [0u32; 10];
        let mut sum = 0.0;
        for i in 0..n {
            let x = h.sample(i, 256 + (i % 7) as usize);
            counts[(x * 10.0) as usize] += 1;
            sum += x;
        }
        let mean = sum / n as f64;
        assert!((mean - 0.5).abs() < 4.0 * (1.0 / 12.0f64 / n as f64).sqrt());
        // Chi-square with 9 degrees of freedom: 27.9 is its 0.999 quantile.
        let e = n as f64 / 10.0;
        let chi2: f64 = counts.iter().map(|&c| (c as f64 - e).powi(2) / e).sum();
        assert!(chi2 < 27.9, "chi2 {chi2}");
    }
}
