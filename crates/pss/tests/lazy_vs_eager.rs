//! Lazy mutation of the PSS state has the same distribution as eager mutation.
//!
//! Scenario: a state of three coordinates; the target reads only coordinate 0 for `k`
//! accepted small steps, then reads all three. Lazily, coordinates 1 and 2 are caught up with
//! `k + 1` perturbations at once; eagerly, each step perturbs every coordinate. The final values
//! of coordinate 1 must have the same distribution: a two-sample Kolmogorov-Smirnov test
//! (asymptotic critical value sqrt(-ln(alpha/2)/2) sqrt(2/N) for equal sample sizes N) at a
//! family-wise alpha = 0.001 over the 4 comparisons (Bonferroni: 0.001/4 each).

use pss::{KelemenParams, Pending, PssState, SmallMutation};
use rand::{RngExt, SeedableRng};

fn lazy_final(mutation: SmallMutation, k: u64, start: f64, rng: &mut rand_pcg::Pcg64) -> f64 {
    let mut x = PssState::from_values(&[0.5, start, 0.25]);
    for _ in 0..k {
        // An accepted small step whose evaluation read only coordinate 0.
        x.set_pending(
            Pending::Small {
                mutation,
                stream_mask: 0xff,
            },
            rng.random(),
        );
        x.get(0);
    }
    x.set_pending(
        Pending::Small {
            mutation,
            stream_mask: 0xff,
        },
        rng.random(),
    );
    x.get(1)
}

fn eager_final(mutation: SmallMutation, k: u64, start: f64, rng: &mut rand_pcg::Pcg64) -> f64 {
    let mut v = start;
    for _ in 0..=k {
        let key: u64 = rng.random();
        v = mutation.apply(v, 1, |d| pss::noise::uniform(key, 1, d));
    }
    v
}

fn ks_two_sample(mut a: Vec<f64>, mut b: Vec<f64>) -> f64 {
    a.sort_by(f64::total_cmp);
    b.sort_by(f64::total_cmp);
    let (n, m) = (a.len() as f64, b.len() as f64);
    let (mut i, mut j, mut d) = (0usize, 0usize, 0.0f64);
    while i < a.len() && j < b.len() {
        if a[i] <= b[j] {
            i += 1;
        } else {
            j += 1;
        }
        d = d.max((i as f64 / n - j as f64 / m).abs());
    }
    d
}

#[test]
fn lazy_catch_up_matches_eager_mutation() {
    let n = 20_000;
    let alpha: f64 = 0.001 / 4.0;
    let critical = (-(alpha / 2.0).ln() / 2.0).sqrt() * (2.0 / n as f64).sqrt();
    let mut rng = rand_pcg::Pcg64::seed_from_u64(2024);
    let cases = [
        (SmallMutation::Kelemen(KelemenParams::kelemen2002()), 5),
        (SmallMutation::Kelemen(KelemenParams::kelemen2002()), 40),
        (SmallMutation::Gaussian { sigma: 0.01 }, 7),
        // Mass crosses the torus seam: start next to 0.
        (SmallMutation::Gaussian { sigma: 0.02 }, 3),
    ];
    for (mutation, k) in cases {
        let start = if matches!(mutation, SmallMutation::Gaussian { sigma } if sigma > 0.015) {
            0.005
        } else {
            0.4
        };
        let lazy: Vec<f64> = (0..n)
            .map(|_| lazy_final(mutation, k, start, &mut rng))
            .collect();
        let eager: Vec<f64> = (0..n)
            .map(|_| eager_final(mutation, k, start, &mut rng))
            .collect();
        let d = ks_two_sample(lazy, eager);
        assert!(
            d < critical,
            "{mutation:?}, k = {k}: KS D = {d:.5} >= critical {critical:.5}"
        );
    }
}

#[test]
fn lazy_differs_from_wrong_step_count() {
    // Negative control: an eager reference with one step too few must be detected, so the
    // test above can fail.
    let n = 20_000;
    let alpha: f64 = 0.001;
    let critical = (-(alpha / 2.0).ln() / 2.0).sqrt() * (2.0 / n as f64).sqrt();
    let mut rng = rand_pcg::Pcg64::seed_from_u64(7);
    let mutation = SmallMutation::Gaussian { sigma: 0.01 };
    let lazy: Vec<f64> = (0..n)
        .map(|_| lazy_final(mutation, 3, 0.4, &mut rng))
        .collect();
    let eager: Vec<f64> = (0..n)
        .map(|_| eager_final(mutation, 1, 0.4, &mut rng))
        .collect();
    let d = ks_two_sample(lazy, eager);
    assert!(d > critical, "KS D = {d:.5} should exceed {critical:.5}");
}

#[test]
fn coordinates_stale_before_a_large_step_are_fresh_uniforms() {
    let n = 20_000;
    let mut rng = rand_pcg::Pcg64::seed_from_u64(11);
    let mutation = SmallMutation::Kelemen(KelemenParams::kelemen2002());
    let mut bins = [0u32; 10];
    for _ in 0..n {
        let mut x = PssState::from_values(&[0.5, 0.123]);
        x.set_pending(Pending::Large, rng.random());
        x.get(0);
        x.set_pending(
            Pending::Small {
                mutation,
                stream_mask: 0xff,
            },
            rng.random(),
        );
        let v = x.get(1);
        bins[(v * 10.0) as usize] += 1;
    }
    // Chi-square with 9 degrees of freedom; the 0.999 quantile is 27.88.
    let expected = n as f64 / 10.0;
    let chi2: f64 = bins
        .iter()
        .map(|&b| (b as f64 - expected).powi(2) / expected)
        .sum();
    assert!(chi2 < 27.88, "chi2 = {chi2}, bins {bins:?}");
}
