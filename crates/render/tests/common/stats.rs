//! Replicate statistics of the MCMC convergence tests (see `mlt_convergence.rs`'s module docs):
//! the exact Student t distribution, means with standard errors, block and pixel statistics.

use render::image::Image;
use render::metrics::{relmse, RELMSE_EPSILON};

/// `P(|T| >= t)` for Student's t with `df >= 1` degrees of freedom, exact for integer `df`
/// (Abramowitz & Stegun 26.7.3 for odd, 26.7.4 for even `df`; `theta = atan(t / sqrt(df))`).
pub fn t_two_sided_p(t: f64, df: u32) -> f64 {
    assert!(df >= 1);
    let theta = (t.abs() / f64::from(df).sqrt()).atan();
    let (s, c) = theta.sin_cos();
    let c2 = c * c;
    let a = if df % 2 == 1 {
        // (2/pi) [theta + sin(theta) (cos + 2/3 cos^3 + ... + (2*4..(df-3))/(1*3..(df-2)) cos^(df-2))]
        let mut sum = 0.0;
        if df > 1 {
            let mut term = c;
            sum = term;
            for k in 1..=(df - 3) / 2 {
                term *= c2 * f64::from(2 * k) / f64::from(2 * k + 1);
                sum += term;
            }
        }
        2.0 / std::f64::consts::PI * (theta + s * sum)
    } else {
        // sin(theta) [1 + 1/2 cos^2 + 1*3/(2*4) cos^4 + ... + (1*3..(df-3))/(2*4..(df-2)) cos^(df-2)]
        let mut term = 1.0;
        let mut sum = 1.0;
        for k in 1..=(df - 2) / 2 {
            term *= c2 * f64::from(2 * k - 1) / f64::from(2 * k);
            sum += term;
        }
        s * sum
    };
    (1.0 - a).clamp(0.0, 1.0)
}

/// The two-sided critical value: `t` with `P(|T| >= t) = alpha` (bisection).
pub fn t_critical(alpha: f64, df: u32) -> f64 {
    let (mut lo, mut hi) = (0.0f64, 1e4f64);
    for _ in 0..200 {
        let mid = 0.5 * (lo + hi);
        if t_two_sided_p(mid, df) > alpha {
            lo = mid;
        } else {
            hi = mid;
        }
    }
    0.5 * (lo + hi)
}

/// Mean and standard error of the mean of i.i.d. values.
pub fn mean_se(xs: &[f64]) -> (f64, f64) {
    let n = xs.len() as f64;
    let m = xs.iter().sum::<f64>() / n;
    let var = xs.iter().map(|x| (x - m).powi(2)).sum::<f64>() / (n - 1.0);
    (m, (var / n).sqrt())
}

/// Asserts every pixel channel of `image` is finite and non-negative.
pub fn assert_finite_non_negative(image: &Image, what: &str) {
    for (i, p) in image.pixels.iter().enumerate() {
        assert!(
            p.iter().all(|c| c.is_finite() && *c >= 0.0),
            "{what}: pixel {i} = {p:?}"
        );
    }
}

/// Mean luminance of each of the `blocks x blocks` blocks (row-major).
pub fn block_means(image: &Image, blocks: usize) -> Vec<f64> {
    let (w, h) = (image.width, image.height);
    let mut sums = vec![0.0f64; blocks * blocks];
    let mut counts = vec![0usize; blocks * blocks];
    for y in 0..h {
        for x in 0..w {
            let k = (y * blocks / h) * blocks + x * blocks / w;
            sums[k] += f64::from(image.luminance(x, y));
            counts[k] += 1;
        }
    }
    sums.iter()
        .zip(&counts)
        .map(|(s, &c)| s / c as f64)
        .collect()
}

/// Per-pixel, per-channel mean over replicate images and the variance of that mean.
pub fn pixel_mean_and_var_of_mean(images: &[Image]) -> (Image, Vec<[f64; 3]>) {
    let (w, h) = (images[0].width, images[0].height);
    let mut mean = Image::new(w, h);
    let mut var = vec![[0.0f64; 3]; w * h];
    for (i, (m_px, v_px)) in mean.pixels.iter_mut().zip(&mut var).enumerate() {
        for (c, (m_c, v_c)) in m_px.iter_mut().zip(v_px.iter_mut()).enumerate() {
            let values: Vec<f64> = images.iter().map(|im| f64::from(im.pixels[i][c])).collect();
            let (m, se) = mean_se(&values);
            *m_c = m as f32;
            *v_c = se * se;
        }
    }
    (mean, var)
}

/// The relMSE between the replicate means of `images` and of `reference`, and its expectation
/// if both are unbiased: the mean over pixels and channels of `(var_images + var_reference) /
/// (R^2 + eps)`, the variances of the two means estimated from the replicates.
pub fn relmse_observed_and_expected(images: &[Image], reference: &[Image]) -> (f64, f64) {
    let (mlt_mean, mlt_var) = pixel_mean_and_var_of_mean(images);
    let (ref_mean, ref_var) = pixel_mean_and_var_of_mean(reference);
    let observed = relmse(&mlt_mean, &ref_mean).unwrap();
    let mut expected = 0.0;
    for ((v_mlt, v_ref), r) in mlt_var.iter().zip(&ref_var).zip(&ref_mean.pixels) {
        for c in 0..3 {
            let r = f64::from(r[c]);
            expected += (v_mlt[c] + v_ref[c]) / (r * r + RELMSE_EPSILON);
        }
    }
    expected /= (3 * mlt_var.len()) as f64;
    (observed, expected)
}

pub fn rounded(xs: &[f64]) -> Vec<f64> {
    xs.iter().map(|x| (x * 100.0).round() / 100.0).collect()
}

/// Per block: (t statistic against the reference, MCMC mean, its se, reference mean, its se).
pub fn block_t(images: &[Image], reference: &[Image], blocks: usize) -> Vec<[f64; 5]> {
    let mlt: Vec<Vec<f64>> = images.iter().map(|im| block_means(im, blocks)).collect();
    let rf: Vec<Vec<f64>> = reference.iter().map(|im| block_means(im, blocks)).collect();
    (0..blocks * blocks)
        .map(|k| {
            let (mm, sm) = mean_se(&mlt.iter().map(|b| b[k]).collect::<Vec<_>>());
            let (mr, sr) = mean_se(&rf.iter().map(|b| b[k]).collect::<Vec<_>>());
            [(mm - mr) / sm.hypot(sr), mm, sm, mr, sr]
        })
        .collect()
}

/// Image mean and `blocks x blocks` block means of MCMC replicates against reference
/// replicates (Welch t, critical value `crit`), plus the relMSE of the replicate average
/// against its expectation under no bias (`< 3x`; see `mlt_convergence.rs`'s `cornell_case`).
pub fn against_reference(
    what: &str,
    images: &[Image],
    reference: &[Image],
    blocks: usize,
    crit: f64,
) {
    let (mm, sm) = mean_se(&images.iter().map(Image::mean_luminance).collect::<Vec<_>>());
    let (mr, sr) = mean_se(
        &reference
            .iter()
            .map(Image::mean_luminance)
            .collect::<Vec<_>>(),
    );
    let t_mean = (mm - mr) / sm.hypot(sr);
    eprintln!(
        "{what}: mean {mm:.5} (se {sm:.2e} = {:.2}%) reference {mr:.5} (se {sr:.2e}) t {t_mean:.2} \
         critical {crit:.2}",
        100.0 * sm / mm
    );
    let block_stats = block_t(images, reference, blocks);
    let t_blocks: Vec<f64> = block_stats.iter().map(|b| b[0]).collect();
    eprintln!(
        "{what}: block t {:?}, max |t| {:.2}",
        rounded(&t_blocks),
        t_blocks.iter().map(|t| t.abs()).fold(0.0, f64::max)
    );
    let (observed, expected) = relmse_observed_and_expected(images, reference);
    eprintln!(
        "{what}: relMSE observed {observed:.3e} expected {expected:.3e} ratio {:.2}",
        observed / expected
    );
    assert!(
        t_mean.abs() < crit,
        "{what}: image mean {mm} (se {sm}) vs reference {mr} (se {sr}): t {t_mean}"
    );
    for (k, b) in block_stats.iter().enumerate() {
        assert!(
            b[0].abs() < crit,
            "{what}: block {k}: {} (se {}) vs reference {} (se {}): t {}, critical {crit}",
            b[1],
            b[2],
            b[3],
            b[4],
            b[0]
        );
    }
    assert!(
        observed < 3.0 * expected + 1e-6,
        "{what}: relMSE {observed} vs expected {expected}"
    );
}
