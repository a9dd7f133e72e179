//! Fuzzing the scene loader: proptest mutates valid .gltf / .glb bytes (bit flips,
//! truncation, byte insertions and overwrites, JSON value edits re-packed into the container)
//! and every input must load or fail with an error, never panic. Loaded scenes are also
//! traced a little, so the BVH, lights and BSDFs see the fuzzed data.
//!
//! The full run (`fuzz_100k`, 100 000 inputs) is meant for release builds:
//! `cargo test --release -p render --test fuzz_gltf -- --include-ignored`; debug builds run
//! `fuzz_quick` (2 000 inputs). Every crash found is minimised by hand and kept in
//! `tests/fuzz_regressions/`, which `regressions_do_not_panic` replays.

use std::path::{Path, PathBuf};
use std::sync::atomic::{AtomicUsize, Ordering};

use glam::{UVec2, Vec2};
use gltf::json::Value;
use proptest::prelude::*;
use render::integrator::pt;
use render::sampler::IndependentSampler;
use render::scene::Scene;

fn data_dir() -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR")).join("tests/data")
}

/// The seed inputs: self-contained .gltf, .gltf with external files, .glb.
fn seeds() -> Vec<Vec<u8>> {
    ["tiny-embedded.gltf", "tiny.gltf", "tiny.glb"]
        .iter()
        .map(|f| std::fs::read(data_dir().join(f)).unwrap())
        .collect()
}

/// Loads `bytes` (relative URIs resolve in tests/data) and, if that works, traces a few
/// paths; returns whether it loaded. Panics propagate to proptest.
fn exercise(bytes: &[u8]) -> bool {
    let dir = data_dir();
    let Ok(mut scene) = Scene::from_gltf_slice(bytes, Some(&dir)) else {
        return false;
    };
    scene.set_resolution(4, 4);
    let mut sampler = IndependentSampler::new(1);
    for i in 0..4u32 {
        sampler.start_pixel_sample(u64::from(i), 0);
        let _ = pt::sample_pixel(&scene, scene.camera(), UVec2::new(i, i), &mut sampler, 4);
    }
    let lights = scene.lights();
    let _ = lights.sample_le(0.3, Vec2::splat(0.5), Vec2::splat(0.25));
    true
}

/// Splits a GLB into (JSON, BIN) or `None` for .gltf bytes.
fn glb_parts(bytes: &[u8]) -> Option<(Vec<u8>, Vec<u8>)> {
    if !bytes.starts_with(b"glTF") {
        return None;
    }
    let json_len = u32::from_le_bytes(bytes.get(12..16)?.try_into().ok()?) as usize;
    let json = bytes.get(20..20usize.checked_add(json_len)?)?.to_vec();
    let bin = bytes.get(20 + json_len + 8..)?.to_vec();
    Some((json, bin))
}

fn glb_pack(json: &[u8], bin: &[u8]) -> Vec<u8> {
    let mut json = json.to_vec();
    while !json.len().is_multiple_of(4) {
        json.push(b' ');
    }
    let total = 12 + 8 + json.len() + 8 + bin.len();
    let mut out = Vec::with_capacity(total);
    out.extend_from_slice(b"glTF");
    out.extend_from_slice(&2u32.to_le_bytes());
    out.extend_from_slice(&(total as u32).to_le_bytes());
    out.extend_from_slice(&(json.len() as u32).to_le_bytes());
    out.extend_from_slice(b"JSON");
    out.extend_from_slice(&json);
    out.extend_from_slice(&(bin.len() as u32).to_le_bytes());
    out.extend_from_slice(b"BIN\0");
    out.extend_from_slice(bin);
    out
}

/// Every JSON node's path, depth first.
fn paths(v: &Value, prefix: &mut Vec<PathStep>, out: &mut Vec<Vec<PathStep>>) {
    out.push(prefix.clone());
    match v {
        Value::Object(m) => {
            for (k, child) in m {
                prefix.push(PathStep::Key(k.clone()));
                paths(child, prefix, out);
                prefix.pop();
            }
        }
        Value::Array(a) => {
            for (i, child) in a.iter().enumerate() {
                prefix.push(PathStep::Index(i));
                paths(child, prefix, out);
                prefix.pop();
            }
        }
        _ => {}
    }
}

#[derive(Clone, Debug)]
enum PathStep {
    Key(String),
    Index(usize),
}

fn node_mut<'v>(v: &'v mut Value, path: &[PathStep]) -> Option<&'v mut Value> {
    let mut cur = v;
    for step in path {
        cur = match step {
            PathStep::Key(k) => cur.get_mut(k.as_str())?,
            PathStep::Index(i) => cur.get_mut(*i)?,
        };
    }
    Some(cur)
}

/// Values a JSON edit may write.
fn interesting_value(k: u8) -> Value {
    let s = |t: &str| Value::from(t);
    match k % 28 {
        0 => Value::from(0),
        1 => Value::from(-1),
        2 => Value::from(1),
        3 => Value::from(2),
        4 => Value::from(u64::from(u32::MAX)),
        5 => Value::from(1u64 << 53),
        6 => Value::from(u64::MAX),
        7 => Value::from(1e38),
        8 => Value::from(-1e308),
        9 => Value::from(0.5),
        10 => Value::Null,
        11 => Value::Bool(true),
        12 => Value::Array(vec![]),
        13 => Value::Object(Default::default()),
        14 => s(""),
        15 => s("%FF%FE.bin"),
        16 => s("data:application/octet-stream;base64,AAAA"),
        17 => s("data:image/png;base64,iVBORw0KGgo="),
        18 => s("http://example.com/x.bin"),
        19 => s("../../../../nonexistent"),
        20 => Value::from(vec![0, 1, 2]),
        21 => Value::from(vec![1e30, -1e30, f64::MAX]),
        22 => Value::from(4),
        // Files the loader must refuse (outside the folder, not regular), not read forever.
        23 => s("/dev/zero"),
        24 => s("file:///dev/zero"),
        25 => s("."),
        26 => s("../data/tiny.bin"),
        _ => Value::from(65536),
    }
}

/// A value of the same JSON type as `v` (numbers nudged or replaced by edge cases, strings
/// by odd URIs / names), so that the document more often stays valid glTF and the edit reaches
/// the loader's own checks.
fn similar_value(v: &Value, k: u8) -> Value {
    match v {
        Value::Number(n) => {
            let x = n.as_f64().unwrap_or(0.0);
            let choices = [
                x + 1.0,
                x - 1.0,
                x * 2.0,
                x + 4.0,
                (x / 2.0).floor(),
                x + 12.0,
                0.0,
                1.0,
                3.0,
                -1.0,
                0.5,
                1e-40,
                1e38,
                -1e38,
                65535.0,
                4_294_967_295.0,
                9_007_199_254_740_992.0,
            ];
            let y = choices[k as usize % choices.len()];
            if y.fract() == 0.0 && y.abs() < 9.3e18 {
                if y >= 0.0 {
                    Value::from(y as u64)
                } else {
                    Value::from(y as i64)
                }
            } else {
                Value::from(y)
            }
        }
        Value::String(_) => {
            let choices = [
                "",
                "tiny.bin",
                "checker.png",
                "tiny.glb",
                "%FF%FE.bin",
                "a%20b.bin",
                "data:application/octet-stream;base64,AAAAAAAAAAAAAAAAAAAAAA==",
                "data:image/png;base64,iVBORw0KGgo=",
                "data:;base64,!!!!",
                "file:///nonexistent",
                "POSITION",
                "KHR_materials_volume",
                "KHR_lights_punctual",
                "image/jpeg",
                "MASK",
                "VEC2",
                "SCALAR",
                "perspective",
                "orthographic",
                "TEXCOORD_1",
            ];
            Value::from(choices[k as usize % choices.len()])
        }
        Value::Bool(b) => Value::Bool(!b),
        Value::Array(a) if !a.is_empty() => {
            let mut a = a.clone();
            match k % 3 {
                0 => {
                    a.pop();
                }
                1 => a.reverse(),
                _ => a.truncate(1),
            }
            Value::Array(a)
        }
        _ => interesting_value(k),
    }
}

/// One mutation of the byte string.
#[derive(Clone, Debug)]
enum Mutation {
    BitFlip {
        at: usize,
        bit: u8,
    },
    Truncate {
        at: usize,
    },
    Insert {
        at: usize,
        bytes: Vec<u8>,
    },
    Overwrite {
        at: usize,
        bytes: Vec<u8>,
    },
    /// Replace the value at the `node`-th JSON node (mod count) with `interesting_value(kind)`,
    /// or delete it (kind >= 200), or duplicate it into its parent array (kind in 180..200).
    JsonEdit {
        node: usize,
        kind: u8,
    },
}

fn mutation() -> impl Strategy<Value = Mutation> {
    prop_oneof![
        2 => (any::<usize>(), 0u8..8).prop_map(|(at, bit)| Mutation::BitFlip { at, bit }),
        1 => any::<usize>().prop_map(|at| Mutation::Truncate { at }),
        1 => (any::<usize>(), prop::collection::vec(any::<u8>(), 1..8))
            .prop_map(|(at, bytes)| Mutation::Insert { at, bytes }),
        1 => (any::<usize>(), prop::collection::vec(any::<u8>(), 1..5))
            .prop_map(|(at, bytes)| Mutation::Overwrite { at, bytes }),
        3 => (any::<usize>(), any::<u8>()).prop_map(|(node, kind)| Mutation::JsonEdit { node, kind }),
    ]
}

fn apply(bytes: &mut Vec<u8>, m: &Mutation) {
    if bytes.is_empty() {
        return;
    }
    let n = bytes.len();
    match m {
        Mutation::BitFlip { at, bit } => bytes[at % n] ^= 1 << bit,
        Mutation::Truncate { at } => bytes.truncate(at % n),
        Mutation::Insert { at, bytes: b } => {
            let at = at % (n + 1);
            bytes.splice(at..at, b.iter().copied());
        }
        Mutation::Overwrite { at, bytes: b } => {
            for (k, &x) in b.iter().enumerate() {
                let i = (at + k) % n;
                bytes[i] = x;
            }
        }
        Mutation::JsonEdit { node, kind } => {
            let (json_bytes, bin) = match glb_parts(bytes) {
                Some((j, b)) => (j, Some(b)),
                None => (bytes.clone(), None),
            };
            let Ok(mut v) = gltf::json::deserialize::from_slice::<Value>(&json_bytes) else {
                return;
            };
            let mut all = Vec::new();
            paths(&v, &mut Vec::new(), &mut all);
            let path = &all[node % all.len()];
            if *kind >= 200 || (180..200).contains(kind) {
                let Some((last, parent_path)) = path.split_last() else {
                    return;
                };
                let Some(parent) = node_mut(&mut v, parent_path) else {
                    return;
                };
                match (parent, last) {
                    (Value::Object(m), PathStep::Key(k)) if *kind >= 200 => {
                        m.remove(k);
                    }
                    (Value::Array(a), PathStep::Index(i)) if *kind >= 200 => {
                        a.remove(*i);
                    }
                    (Value::Array(a), PathStep::Index(i)) => {
                        let dup = a[*i].clone();
                        a.push(dup);
                    }
                    _ => {}
                }
            } else if let Some(target) = node_mut(&mut v, path) {
                *target = if *kind < 128 {
                    similar_value(target, *kind)
                } else {
                    interesting_value(*kind)
                };
            }
            let Ok(out) = gltf::json::serialize::to_vec(&v) else {
                return;
            };
            *bytes = match bin {
                Some(bin) => glb_pack(&out, &bin),
                None => out,
            };
        }
    }
}

/// Runs `cases` mutated inputs (`FUZZ_CASES` in the environment overrides the count).
fn run_fuzz(cases: u32) {
    let cases = std::env::var("FUZZ_CASES")
        .ok()
        .and_then(|v| v.parse().ok())
        .unwrap_or(cases);
    let seeds = seeds();
    let config = ProptestConfig {
        cases,
        max_shrink_iters: 2000,
        ..ProptestConfig::default()
    };
    // Half the cases only edit JSON values (so the document often stays valid glTF and the
    // loader's own checks are reached); the other half mix all byte-level mutations.
    let json_only = prop::collection::vec(
        (any::<usize>(), any::<u8>()).prop_map(|(node, kind)| Mutation::JsonEdit { node, kind }),
        1..3,
    );
    let mixed = prop::collection::vec(mutation(), 1..5);
    // Inputs that loaded (the rest were rejected with an error), over all cases run
    // (shrinking included).
    let loaded = AtomicUsize::new(0);
    proptest!(config, |(seed in 0usize..3, muts in prop_oneof![json_only, mixed])| {
        let mut bytes = seeds[seed].clone();
        for m in &muts {
            apply(&mut bytes, m);
        }
        if exercise(&bytes) {
            loaded.fetch_add(1, Ordering::Relaxed);
        }
    });
    println!(
        "{cases} inputs, {} loaded (the others were rejected with an error)",
        loaded.load(Ordering::Relaxed)
    );
}

/// 2 000 mutated inputs (debug and release).
#[test]
fn fuzz_quick() {
    run_fuzz(2_000);
}

/// 100 000 mutated inputs: run in release with `--include-ignored`.
#[test]
#[cfg_attr(debug_assertions, ignore = "slow in debug builds; run with --release")]
fn fuzz_100k() {
    run_fuzz(100_000);
}

/// Every minimised crash input ever found loads without panicking.
#[test]
fn regressions_do_not_panic() {
    let dir = Path::new(env!("CARGO_MANIFEST_DIR")).join("tests/fuzz_regressions");
    let mut count = 0;
    for entry in std::fs::read_dir(&dir).unwrap() {
        let path = entry.unwrap().path();
        if matches!(
            path.extension().and_then(|e| e.to_str()),
            Some("gltf" | "glb")
        ) {
            let bytes = std::fs::read(&path).unwrap();
            let _ = exercise(&bytes);
            // Also through the file path API.
            let _ = Scene::load(&path);
            count += 1;
        }
    }
    assert!(count > 0, "no regression inputs found in {}", dir.display());
}

/// The seeds themselves load (so mutations start from valid files).
#[test]
fn seeds_are_valid() {
    for bytes in seeds() {
        Scene::from_gltf_slice(&bytes, Some(&data_dir())).unwrap();
        if let Some((j, b)) = glb_parts(&bytes) {
            assert_eq!(glb_pack(&j, &b), bytes, "GLB re-packing is faithful");
        }
    }
}
