//! A render split with `render --shard K/N` and added up with `merge`: for every integrator in
//! the table, the four shards of a `--spp` render merge to an EXR bit-identical to the
//! single-process render (in any order of the parts); `merge` refuses parts of different
//! renders (seed, settings, scene), a missing or duplicated shard and a truncated part with a
//! clear error. Negative control: the sum of the shards' own images is not the render.

mod common;

use std::path::{Path, PathBuf};

use common::{chainlight, path_str, stderr, temp_dir};

const SIZE: &str = "16";

fn render(dir: &Path, integrator: &str, extra: &[&str], out: &str) -> PathBuf {
    let path = dir.join(out);
    let mut args = vec![
        "render",
        "--integrator",
        integrator,
        "--spp",
        "2",
        "--width",
        SIZE,
        "--height",
        SIZE,
        "--threads",
        "2",
        "-o",
        path_str(&path),
    ];
    args.extend_from_slice(extra);
    if !extra.contains(&"--seed") {
        args.extend_from_slice(&["--seed", "5"]);
    }
    let o = chainlight(&args);
    assert!(o.status.success(), "{integrator} {extra:?}: {}", stderr(&o));
    path
}

fn shards(dir: &Path, integrator: &str, extra: &[&str], n: u32) -> Vec<PathBuf> {
    (0..n)
        .map(|k| {
            let shard = format!("{k}/{n}");
            let mut args = extra.to_vec();
            args.extend_from_slice(&["--shard", &shard]);
            render(dir, integrator, &args, &format!("part{k}.clpart"))
        })
        .collect()
}

fn merge(parts: &[PathBuf], out: &Path) -> std::process::Output {
    let mut args = vec!["merge"];
    args.extend(parts.iter().map(|p| path_str(p)));
    args.extend_from_slice(&["-o", path_str(out)]);
    chainlight(&args)
}

fn integrators() -> Vec<&'static str> {
    render::INTEGRATORS.iter().map(|row| row.name).collect()
}

#[test]
fn every_integrator_merges_bit_identically() {
    for integrator in integrators() {
        let dir = temp_dir(&format!("shards-{integrator}"));
        let whole = render(&dir, integrator, &[], "whole.exr");
        let mut parts = shards(&dir, integrator, &[], 4);
        // Any order of the parts on the command line: merge adds them in shard order.
        parts.reverse();
        parts.swap(0, 2);
        let merged = dir.join("merged.exr");
        let o = merge(&parts, &merged);
        assert!(o.status.success(), "{integrator}: {}", stderr(&o));
        let (a, b) = (
            std::fs::read(&whole).unwrap(),
            std::fs::read(&merged).unwrap(),
        );
        assert!(
            a == b,
            "{integrator}: the merged EXR differs from the single-process one"
        );
        std::fs::remove_dir_all(&dir).ok();
    }
}

/// Negative control for the comparison: two renders that differ only in the seed give
/// different EXR bytes, so the bit-identity above is not vacuous; and a merge of one part of
/// two is refused rather than written as if it were the render.
#[test]
fn the_comparison_sees_a_different_render() {
    let dir = temp_dir("shards-negative");
    let whole = render(&dir, "pssmlt", &[], "whole.exr");
    let other = render(&dir, "pssmlt", &["--seed", "6"], "other.exr");
    assert_ne!(
        std::fs::read(&whole).unwrap(),
        std::fs::read(&other).unwrap()
    );
    let part = shards(&dir, "pssmlt", &[], 2);
    let half = dir.join("half.exr");
    let o = merge(&part[..1], &half);
    assert!(!o.status.success());
    assert!(
        stderr(&o).contains("missing shard(s) 1/2"),
        "{}",
        stderr(&o)
    );
    assert!(!half.exists());
    std::fs::remove_dir_all(&dir).ok();
}

#[test]
fn merge_refuses_parts_that_do_not_belong_together() {
    let dir = temp_dir("shards-refuse");
    let parts = shards(&dir, "pt", &[], 3);
    let out = dir.join("out.exr");
    let expect = |parts: &[PathBuf], needle: &str| {
        let o = merge(parts, &out);
        assert!(!o.status.success(), "merge of {parts:?} succeeded");
        let e = stderr(&o);
        assert!(e.contains(needle), "expected '{needle}' in: {e}");
        assert!(!e.contains("panicked"), "{e}");
        assert!(!out.exists(), "a refused merge wrote {}", out.display());
    };
    expect(&parts[..2], "missing shard(s) 2/3");
    expect(
        &[parts[0].clone(), parts[1].clone(), parts[1].clone()],
        "given twice",
    );
    // Another seed, other settings, another scene, another shard count.
    let other = |extra: &[&str], name: &str| {
        let mut args = extra.to_vec();
        args.extend_from_slice(&["--shard", "1/3"]);
        let p = render(&dir, "pt", &args, name);
        vec![parts[0].clone(), p, parts[2].clone()]
    };
    let seed = other(&["--seed", "6"], "seed.clpart");
    expect(&seed, "seed differs");
    let depth = other(&["--max-depth", "3"], "depth.clpart");
    expect(&depth, "settings differs");
    let glass = env!("CARGO_MANIFEST_DIR").to_owned() + "/scenes/cornell-glass.gltf";
    let scene = other(&[&glass], "scene.clpart");
    expect(&scene, "scene differs");
    let two = shards(&dir, "pt", &[], 2);
    expect(
        &[parts[0].clone(), two[1].clone(), parts[2].clone()],
        "shard count differs",
    );
    // A truncated part and a file that is not a part.
    let bytes = std::fs::read(&parts[1]).unwrap();
    let cut = dir.join("cut.clpart");
    std::fs::write(&cut, &bytes[..bytes.len() / 2]).unwrap();
    expect(
        &[parts[0].clone(), cut.clone(), parts[2].clone()],
        "truncated",
    );
    std::fs::write(&cut, b"hello").unwrap();
    expect(
        &[parts[0].clone(), cut, parts[2].clone()],
        "not a chainlight part",
    );
    std::fs::remove_dir_all(&dir).ok();
}

#[test]
fn bad_shard_flags_are_clear_errors() {
    let dir = temp_dir("shards-flags");
    for bad in ["4/4", "1/0", "0/1", "x/2", "1", "0/5000"] {
        let out = dir.join("p.clpart");
        let o = chainlight(&[
            "render",
            "--spp",
            "1",
            "--width",
            "8",
            "--height",
            "8",
            "--shard",
            bad,
            "-o",
            path_str(&out),
        ]);
        assert!(!o.status.success(), "--shard {bad} accepted");
        assert!(stderr(&o).contains("--shard"), "{}", stderr(&o));
    }
    let o = chainlight(&[
        "render",
        "--spp",
        "1",
        "--shard",
        "0/2",
        "-o",
        path_str(&dir.join("p.exr")),
    ]);
    assert!(stderr(&o).contains(".clpart"), "{}", stderr(&o));
    std::fs::remove_dir_all(&dir).ok();
}
