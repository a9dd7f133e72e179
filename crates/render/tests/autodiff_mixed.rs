//! The mixed operations of `V3` (a vector of dual numbers with a constant vector) against the
//! full dual-number products they replace: same values and derivatives, with `f64` and `f32`
//! lanes, and a wrong mixed product (one that forgets to scale the lanes) detected.

use render::autodiff::{Dual, Lane, V3};

/// A vector of dual numbers with arbitrary values and lanes, from a seed.
fn dual_vec<L: Lane>(seed: f64) -> V3<Dual<3, L>> {
    let c = |k: f64| Dual {
        v: (seed * 1.7 + k * 0.61).sin() * 3.0,
        d: [0.3 * k - seed, seed * seed - k, (seed + k).cos()].map(L::from_f64),
    };
    V3::new(c(1.0), c(2.0), c(3.0))
}

fn constant(seed: f64) -> V3<f64> {
    V3::new(seed - 0.4, (seed * 2.3).cos() * 5.0, -1.5 * seed)
}

/// Equal values and lanes (`==`, so `-0 == 0`: a mixed form may differ from the full product
/// rule in the sign of a zero lane, and nowhere else at finite values).
fn same<L: Lane>(a: V3<Dual<3, L>>, b: V3<Dual<3, L>>) -> bool {
    [(a.x, b.x), (a.y, b.y), (a.z, b.z)]
        .iter()
        .all(|(p, q)| p.v == q.v && p.d == q.d)
}

fn check_mixed<L: Lane>() {
    for seed in [0.2, 1.1, -2.7, 3.9] {
        let (a, c, s) = (dual_vec::<L>(seed), constant(seed), dual_vec::<L>(-seed).y);
        let k = V3::cst(c);
        let splat = |x: Dual<3, L>| V3::new(x, x, x);
        assert!(same(splat(a.dot_c(c)), splat(a.dot(k))), "dot_c");
        assert!(same(a.cross_c(c), a.cross(k)), "cross_c");
        assert!(same(a.mul_c(c), a.mul_v(k)), "mul_c");
        assert!(same(a.add_c(c), a + k), "add_c");
        assert!(same(a.sub_c(c), a - k), "sub_c");
        assert!(same(c.times(s), k * s), "times");
    }
}

#[test]
fn mixed_operations_equal_the_full_dual_products() {
    check_mixed::<f64>();
    check_mixed::<f32>();
}

#[test]
fn wrong_mixed_product_is_detected() {
    // Negative control: a mixed product that keeps the dual operand's derivatives instead of
    // scaling them by the constant fails the comparison the mixed operations pass.
    for seed in [0.2, 1.1, -2.7, 3.9] {
        let (a, c) = (dual_vec::<f32>(seed), constant(seed));
        let wrong = |x: Dual<3, f32>, k: f64| Dual { v: x.v * k, d: x.d };
        let wrong_mul = V3::new(wrong(a.x, c.x), wrong(a.y, c.y), wrong(a.z, c.z));
        assert!(!same(wrong_mul, a.mul_v(V3::cst(c))));
        assert!(same(a.mul_c(c), a.mul_v(V3::cst(c))));
    }
}
