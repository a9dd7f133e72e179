//! The Voronoi-congruence property (paper section 3, "A note on lattices", Fig. 3): from any
//! member of a shifted, tiled lattice set, the closest-point search recovers the same set.

use lqmc::{torus_difference, LocalQmc, Rank1Lattice, ShiftedLattice, Tiling, TABLE_SIZES};
use proptest::prelude::*;

/// A lattice from the table, a tiling with jitter, and a seed point.
fn case() -> impl Strategy<Value = (u32, Vec<u32>, Vec<f64>, Vec<f64>)> {
    (0usize..4, 1usize..=21).prop_flat_map(|(n, s)| {
        (
            Just(TABLE_SIZES[n]),
            prop::collection::vec(prop_oneof![Just(1u32), 1u32..8, 1u32..1000], s),
            prop::collection::vec(prop_oneof![Just(0.0), 0.0..1.0f64], s),
            prop::collection::vec(0.0..1.0f64, s),
        )
    })
}

proptest! {
    #![proptest_config(ProptestConfig { cases: 256, ..ProptestConfig::default() })]

    /// Every member `u_j = T^{-1}({r_j + Delta})` of the seed's set lies in the seed's tile
    /// and, taken as a seed, finds lattice point `j` and the same shift `Delta`.
    #[test]
    fn members_recover_the_same_shift_and_tile((n, tiles, jitter, seed) in case()) {
        let s = tiles.len();
        let lattice = Rank1Lattice::from_table(n, s).unwrap();
        let tiling = Tiling::new(tiles).unwrap().with_jitter(&jitter).unwrap();
        let qmc = LocalQmc::new(lattice, tiling).unwrap();
        let set = qmc.locate(&seed);
        let mut u = vec![0.0; s];
        for j in 0..n {
            qmc.member(&set, j, &mut u);
            prop_assert!(u.iter().all(|x| (0.0..1.0).contains(x)));
            let again = qmc.locate(&u);
            prop_assert_eq!(again.tile(), set.tile(), "member {} left the tile", j);
            prop_assert_eq!(again.seed_index(), j);
            for (a, b) in again.shifted().shift().iter().zip(set.shifted().shift()) {
                prop_assert!(torus_difference(*a, *b).abs() < 1e-9, "shift {} vs {}", a, b);
            }
        }
        // The seed is its own member.
        qmc.member(&set, set.seed_index(), &mut u);
        for (a, b) in u.iter().zip(&seed) {
            prop_assert!(torus_difference(*a, *b).abs() < 1e-9);
        }
    }

    /// The same without tiling, on the bare shifted lattice (eq. 3).
    #[test]
    fn shifted_lattice_members_agree((n, tiles, _jitter, seed) in case()) {
        let lattice = Rank1Lattice::from_table(n, tiles.len()).unwrap();
        let set = ShiftedLattice::through(&lattice, &seed);
        let mut t = vec![0.0; seed.len()];
        for j in 0..n {
            set.member(&lattice, j, &mut t);
            let again = ShiftedLattice::through(&lattice, &t);
            prop_assert_eq!(again.seed_index(), j);
            for (a, b) in again.shift().iter().zip(set.shift()) {
                prop_assert!(torus_difference(*a, *b).abs() < 1e-9);
            }
        }
    }
}

/// Fig. 3, left: a point set that is not a lattice (Voronoi cells not congruent) does not
/// have the property: some member of a shifted copy finds another point and another shift.
#[test]
fn a_non_lattice_point_set_fails_the_property() {
    let points = [[0.1, 0.1], [0.15, 0.2], [0.6, 0.5], [0.7, 0.9], [0.3, 0.7]];
    let closest = |t: [f64; 2]| {
        (0..points.len())
            .min_by(|&a, &b| {
                let d = |p: [f64; 2]| {
                    torus_difference(p[0], t[0]).powi(2) + torus_difference(p[1], t[1]).powi(2)
                };
                d(points[a]).partial_cmp(&d(points[b])).unwrap()
            })
            .unwrap()
    };
    let mut failures = 0;
    for k in 0..100 {
        let seed = [(k as f64 * 0.618_034) % 1.0, (k as f64 * 0.754_878) % 1.0];
        let i = closest(seed);
        let shift = [seed[0] - points[i][0], seed[1] - points[i][1]];
        for (j, p) in points.iter().enumerate() {
            let member = [
                (p[0] + shift[0]).rem_euclid(1.0),
                (p[1] + shift[1]).rem_euclid(1.0),
            ];
            if closest(member) != j {
                failures += 1;
            }
        }
    }
    assert!(failures > 0);
}
