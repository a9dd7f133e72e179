//! Value stability: pinned outputs of every scrambling (seed 42), of the PRNG dimensions and
//! of the embedded lattices. A change here changes every image rendered with a given seed.

use lqmc::{Halton, Rank1Lattice, Scrambling};

/// (index, dimension) pairs: low dimensions, the last Halton dimension, PRNG dimensions.
const QUERIES: [(u64, usize); 6] = [(1, 0), (7, 1), (100, 5), (12345, 255), (3, 256), (99, 1000)];

#[test]
fn halton_values_for_seed_42() {
    let pinned: [(Scrambling, [f64; 6]); 4] = [
        (
            Scrambling::None,
            [
                0.5,
                0.5555555555555556,
                0.7337278106508875,
                0.6250798787254961,
                0.2299878050638844,
                0.604758783140766,
            ],
        ),
        (
            Scrambling::Faure,
            [
                0.5,
                0.5555555555555556,
                0.7751479289940829,
                0.003332492738904631,
                0.2299878050638844,
                0.604758783140766,
            ],
        ),
        (
            Scrambling::RandomDigitPermutation,
            [
                0.6382798808899821,
                0.4195419356463792,
                0.5150097450569887,
                0.9002517131380763,
                0.2299878050638844,
                0.604758783140766,
            ],
        ),
        (
            Scrambling::Owen,
            [
                0.5396501154382277,
                0.8293680040637064,
                0.7069278164890272,
                0.45166160452094406,
                0.2299878050638844,
                0.604758783140766,
            ],
        ),
    ];
    for (scrambling, values) in pinned {
        let h = Halton::new(scrambling, 42);
        for (&(i, d), &v) in QUERIES.iter().zip(&values) {
            assert_eq!(h.sample(i, d), v, "{scrambling:?} index {i} dimension {d}");
        }
    }
}

#[test]
fn embedded_lattices() {
    assert_eq!(
        Rank1Lattice::from_table(7, 3).unwrap().generator(),
        &[1, 2, 3]
    );
    assert_eq!(
        Rank1Lattice::from_table(23, 5).unwrap().generator(),
        &[1, 7, 5, 3, 4]
    );
    assert_eq!(
        Rank1Lattice::from_table(97, 4).unwrap().generator(),
        &[1, 35, 41, 10]
    );
    assert_eq!(
        Rank1Lattice::from_table(313, 3).unwrap().generator(),
        &[1, 121, 82]
    );
}
