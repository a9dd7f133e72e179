//! Query results of the gradient cache against a brute-force scan: bit-identical for every
//! dimension, size, radius, `K`, source mix and insertion history.

use rand::{RngExt, SeedableRng};
use rand_pcg::Pcg64;

use super::neighbours::squared_distance;
use super::{GradientCache, Neighbour, Neighbours};

/// Brute-force reference: the `k` smallest `(dist2, source, index)` over all sources.
fn brute(caches: &[(&GradientCache, u32)], v: &[f64], radius: f64, k: usize) -> Vec<Neighbour> {
    let mut all = Vec::new();
    if radius > 0.0 {
        let r2 = radius * radius;
        for &(cache, source) in caches {
            for index in 0..cache.len() {
                let dist2 = squared_distance(v, cache.point(index));
                if dist2 < r2 {
                    all.push(Neighbour {
                        dist2,
                        source,
                        index,
                    });
                }
            }
        }
    }
    all.sort_by(Neighbour::key_cmp);
    all.truncate(k);
    all
}

/// Bit-exact comparison of two result lists.
fn assert_same(got: &[Neighbour], want: &[Neighbour], context: &str) {
    assert_eq!(
        got.len(),
        want.len(),
        "{context}: lengths differ\n got {got:?}\nwant {want:?}"
    );
    for (g, w) in got.iter().zip(want) {
        assert!(
            g.dist2.to_bits() == w.dist2.to_bits() && g.source == w.source && g.index == w.index,
            "{context}: {g:?} != {w:?}\n got {got:?}\nwant {want:?}"
        );
    }
}

fn collect(out: &Neighbours) -> Vec<Neighbour> {
    out.iter().collect()
}

/// A random point: uniform, clustered, or on a coarse grid (many exact ties).
fn random_point(rng: &mut Pcg64, dim: usize, kind: u32, centres: &[Vec<f64>]) -> Vec<f64> {
    match kind {
        0 => (0..dim).map(|_| rng.random::<f64>()).collect(),
        1 => {
            let c = &centres[rng.random_range(0..centres.len())];
            c.iter()
                .map(|&x| x + 0.02 * (rng.random::<f64>() - 0.5))
                .collect()
        }
        _ => (0..dim)
            .map(|_| f64::from(rng.random_range(0..5u32)) * 0.25)
            .collect(),
    }
}

fn random_cache(rng: &mut Pcg64, dim: usize, n: usize, kind: u32) -> GradientCache {
    let centres: Vec<Vec<f64>> = (0..4)
        .map(|_| (0..dim).map(|_| rng.random::<f64>()).collect())
        .collect();
    let mut cache = GradientCache::new(dim, n);
    for _ in 0..n {
        let p = random_point(rng, dim, kind, &centres);
        let g: Vec<f64> = (0..dim).map(|_| rng.random::<f64>()).collect();
        assert!(cache.push(&p, &g));
    }
    cache
}

#[test]
fn query_matches_brute_force() {
    let mut rng = Pcg64::seed_from_u64(1);
    let mut out = Neighbours::default();
    for &dim in &[1usize, 2, 3, 5, 8, 16, 32] {
        for &n in &[0usize, 1, 7, 16, 17, 100, 255, 256, 257, 700, 2000] {
            for kind in 0..3 {
                let cache = random_cache(&mut rng, dim, n, kind);
                let centres = vec![vec![0.5; dim]];
                for _ in 0..6 {
                    let v = random_point(&mut rng, dim, kind, &centres);
                    let radius = [0.05, 0.2, 0.5, 1.0, f64::INFINITY][rng.random_range(0..5)]
                        * (dim as f64).sqrt();
                    let k = [1usize, 3, 10, 30][rng.random_range(0..4)];
                    out.reset(k);
                    cache.query(&v, radius, 0, &mut out);
                    let want = brute(&[(&cache, 0)], &v, radius, k);
                    assert_same(
                        &collect(&out),
                        &want,
                        &format!("dim {dim} n {n} kind {kind} r {radius} k {k}"),
                    );
                }
            }
        }
    }
}

#[test]
fn interleaved_push_and_query_across_rebuilds() {
    let mut rng = Pcg64::seed_from_u64(2);
    for &(dim, capacity) in &[(1usize, 600usize), (3, 1100), (12, 800)] {
        let mut cache = GradientCache::new(dim, capacity);
        let mut out = Neighbours::new(30);
        let mut step = 0usize;
        while !cache.is_full() {
            // Occasionally push several at once, through `extend_from`.
            if step.is_multiple_of(97) {
                let size = rng.random_range(1..40);
                let batch = random_cache(&mut rng, dim, size, 0);
                cache.extend_from(&batch);
            } else {
                let p: Vec<f64> = (0..dim).map(|_| rng.random::<f64>()).collect();
                assert!(cache.push(&p, &p));
            }
            step += 1;
            let v: Vec<f64> = (0..dim).map(|_| rng.random::<f64>()).collect();
            let radius = 0.3 * (dim as f64).sqrt();
            let k = 1 + step % 30;
            out.reset(k);
            cache.query(&v, radius, 0, &mut out);
            let want = brute(&[(&cache, 0)], &v, radius, k);
            assert_same(
                &collect(&out),
                &want,
                &format!("dim {dim} len {}", cache.len()),
            );
        }
        assert_eq!(cache.len(), capacity);
        assert_eq!(
            cache.n_tree, capacity,
            "a full cache is entirely in the tree"
        );
    }
}

#[test]
fn two_sources_merge_to_union() {
    let mut rng = Pcg64::seed_from_u64(3);
    for &dim in &[2usize, 6] {
        for kind in 0..3 {
            let shared = random_cache(&mut rng, dim, 900, kind);
            let local = random_cache(&mut rng, dim, 130, kind);
            for _ in 0..20 {
                let v: Vec<f64> = (0..dim).map(|_| rng.random::<f64>()).collect();
                let radius = 0.4;
                let k = rng.random_range(1..31);
                let want = brute(&[(&shared, 0), (&local, 1)], &v, radius, k);
                let mut a = Neighbours::new(k);
                shared.query(&v, radius, 0, &mut a);
                local.query(&v, radius, 1, &mut a);
                assert_same(&collect(&a), &want, "shared then local");
                let mut b = Neighbours::new(k);
                local.query(&v, radius, 1, &mut b);
                shared.query(&v, radius, 0, &mut b);
                assert_same(&collect(&b), &want, "local then shared");
            }
        }
    }
}

#[test]
fn ties_across_sources_break_by_source_then_index() {
    let mut a = GradientCache::new(1, 10);
    let mut b = GradientCache::new(1, 10);
    for _ in 0..3 {
        a.push(&[1.0], &[0.0]);
        b.push(&[1.0], &[0.0]);
    }
    let mut out = Neighbours::new(4);
    b.query(&[0.0], 2.0, 1, &mut out);
    a.query(&[0.0], 2.0, 0, &mut out);
    let keys: Vec<(u32, usize)> = out.iter().map(|n| (n.source, n.index)).collect();
    assert_eq!(keys, [(0, 0), (0, 1), (0, 2), (1, 0)]);
}

#[test]
fn duplicates_resolve_by_lowest_index() {
    let mut cache = GradientCache::new(3, 2000);
    for i in 0..1000 {
        // Alternate between two locations; the one at the origin is nearest.
        let p = if i % 2 == 0 {
            [0.0; 3]
        } else {
            [0.1, 0.0, 0.0]
        };
        cache.push(&p, &p);
    }
    let mut out = Neighbours::new(5);
    cache.query(&[0.0; 3], 1.0, 0, &mut out);
    let idx: Vec<usize> = out.iter().map(|n| n.index).collect();
    assert_eq!(idx, [0, 2, 4, 6, 8]);
    out.reset(30);
    cache.query(&[0.1, 0.0, 0.0], 1.0, 0, &mut out);
    let want: Vec<usize> = (0..30).map(|i| 2 * i + 1).collect();
    assert_eq!(out.iter().map(|n| n.index).collect::<Vec<_>>(), want);
    assert_same(
        &collect(&out),
        &brute(&[(&cache, 0)], &[0.1, 0.0, 0.0], 1.0, 30),
        "dups",
    );
}

#[test]
fn results_independent_of_history() {
    let mut rng = Pcg64::seed_from_u64(4);
    let dim = 4;
    let source = random_cache(&mut rng, dim, 1500, 2);
    // History 1: one push at a time.
    let mut one = GradientCache::new(dim, 2000);
    for i in 0..source.len() {
        one.push(source.point(i), source.gradient(i));
    }
    // History 2: chunks through `extend_from`, after filling and clearing with junk.
    let mut two = GradientCache::new(dim, 2000);
    let junk = random_cache(&mut rng, dim, 777, 0);
    two.extend_from(&junk);
    two.clear();
    assert!(two.is_empty());
    let mut chunk = GradientCache::new(dim, 300);
    for i in 0..source.len() {
        chunk.push(source.point(i), source.gradient(i));
        if chunk.is_full() || i + 1 == source.len() {
            two.extend_from(&chunk);
            chunk.clear();
        }
    }
    // History 3: a clone, then everything full (rebuilt once at capacity).
    let mut three = GradientCache::new(dim, source.len());
    three.extend_from(&source);
    let three = three.clone();
    assert_ne!(
        one.n_tree, three.n_tree,
        "histories should differ in tree layout"
    );
    for _ in 0..50 {
        let v: Vec<f64> = (0..dim)
            .map(|_| f64::from(rng.random_range(0..5u32)) * 0.25)
            .collect();
        let k = rng.random_range(1..31);
        let mut results = Vec::new();
        for cache in [&one, &two, &three] {
            let mut out = Neighbours::new(k);
            cache.query(&v, 0.6, 0, &mut out);
            results.push(collect(&out));
        }
        assert_same(&results[0], &results[1], "one vs two");
        assert_same(&results[0], &results[2], "one vs three");
        assert_same(
            &results[0],
            &brute(&[(&source, 0)], &v, 0.6, k),
            "one vs brute",
        );
    }
}

#[test]
fn non_finite_entries_are_never_returned() {
    let mut cache = GradientCache::new(2, 400);
    for i in 0..300 {
        let x = f64::from(i) / 300.0;
        let p = match i % 3 {
            0 => [f64::NAN, x],
            1 => [x, f64::INFINITY],
            _ => [x, x],
        };
        cache.push(&p, &[0.0, 0.0]);
    }
    let mut out = Neighbours::new(30);
    cache.query(&[0.5, 0.5], f64::INFINITY, 0, &mut out);
    assert_eq!(out.len(), 30);
    assert!(out.iter().all(|n| n.index % 3 == 2 && n.dist2.is_finite()));
    assert_same(
        &collect(&out),
        &brute(&[(&cache, 0)], &[0.5, 0.5], f64::INFINITY, 30),
        "nan",
    );
    out.reset(30);
    cache.query(&[f64::NAN, 0.5], f64::INFINITY, 0, &mut out);
    assert!(out.is_empty());
}

#[test]
fn neighbours_reuse_does_not_reallocate() {
    let mut rng = Pcg64::seed_from_u64(6);
    let cache = random_cache(&mut rng, 5, 3000, 1);
    let mut out = Neighbours::new(30);
    let ptr = out.items.as_ptr();
    for _ in 0..100 {
        out.reset(rng.random_range(0..31));
        let v: Vec<f64> = (0..5).map(|_| rng.random::<f64>()).collect();
        cache.query(&v, 2.0, 0, &mut out);
        assert!(out.items.capacity() >= 30);
        assert_eq!(out.items.as_ptr(), ptr);
    }
}

#[test]
fn degenerate_radius_and_k_add_nothing() {
    let mut rng = Pcg64::seed_from_u64(5);
    let cache = random_cache(&mut rng, 3, 500, 2);
    let v = cache.point(0).to_vec();
    let mut out = Neighbours::new(10);
    for radius in [0.0, -0.0, -1.0, f64::NAN, f64::NEG_INFINITY] {
        cache.query(&v, radius, 0, &mut out);
        assert!(out.is_empty(), "radius {radius}");
    }
    // Strict inequality: an entry at exactly the radius is excluded.
    let mut line = GradientCache::new(1, 4);
    line.push(&[1.0], &[0.0]);
    line.push(&[0.5], &[0.0]);
    line.query(&[0.0], 1.0, 0, &mut out);
    assert_eq!(out.iter().map(|n| n.index).collect::<Vec<_>>(), [1]);
    // K = 0 accepts nothing.
    let mut none = Neighbours::new(0);
    cache.query(&v, f64::INFINITY, 0, &mut none);
    assert!(none.is_empty());
    let mut default = Neighbours::default();
    cache.query(&v, f64::INFINITY, 0, &mut default);
    assert!(default.is_empty());
}

#[test]
fn clear_keeps_allocations_and_works_again() {
    let mut rng = Pcg64::seed_from_u64(7);
    let mut cache = random_cache(&mut rng, 2, 1000, 0);
    let (pc, nc) = (cache.points.capacity(), cache.nodes.capacity());
    cache.clear();
    assert!(cache.is_empty() && !cache.is_full());
    assert_eq!(cache.points.capacity(), pc);
    assert_eq!(cache.nodes.capacity(), nc);
    let mut out = Neighbours::new(5);
    cache.query(&[0.5, 0.5], 10.0, 0, &mut out);
    assert!(out.is_empty());
    assert!(cache.push(&[0.25, 0.5], &[1.0, 2.0]));
    cache.query(&[0.5, 0.5], 10.0, 0, &mut out);
    assert_eq!(out.len(), 1);
    assert_eq!(cache.gradient(0), &[1.0, 2.0]);
    assert_eq!(cache.dim(), 2);
}
