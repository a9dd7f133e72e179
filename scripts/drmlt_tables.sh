#!/usr/bin/env bash
# The tables docs/methods/drmlt.md requires, every method on one footing (examples/drmlt.rs
# --footing: the same direct pass, 16 spp over depths 0-1; the same normalisation per scene,
# the mean luminance of scenes/references/SCENE.exr; large steps 0.3 without MIS; max depth 5):
# DR orbital, Tierney-Mira and Green-Mira over PSSMLT (BDPT), PSSMLT over the path tracer and
# MMLT against PSSMLT/K, PSSMLT/G (sigma matched to DR orbital's acceptance; both bases) and
# MMLT/K. Equal time (128x128, SECONDS per render, SEEDS seeds), then equal mutations (MPP
# mutations per pixel). One thread per render; each (scene, seed) run of every method is one
# `--run-one` job (all methods of one scene and seed, in a fixed order), taken under
# `flock $LOCK` (default /work/measure.lock when that file exists; LOCK=none for no lock), so
# other measurements interleave between jobs; PAUSE seconds (default 2) between jobs let a
# waiting measurement take the lock. To use both cores, run one scene per process, each with
# its own LOCK and OUT; CPUS pins every render to those cores (`taskset -c CPUS`, inside the lock).
#
# Usage: [SCENES="a b"] [OUT=dir] [LOCK=file|none] [PAUSE=s] [FIRST_SEED=n] [CPUS=list]
#        [BIN=a built examples/drmlt, instead of building it] scripts/drmlt_tables.sh [SECONDS] [SEEDS] [MPP]
#   defaults: 30 s, 5 seeds from seed 0, 64 mutations per pixel; scenes cornell-glass
#   glossy-highlight caustic-pool thin-highlight thin-bar; OUT target/drmlt-footing.
# Duration: 14 methods x SECONDS x SEEDS x scenes for equal time (30 s, 5 seeds, 5 scenes:
# 175 min), plus the PSSMLT/G calibration, fitted once per scene (about 1 min each at
# 128x128) by the first job-list step and stored with its inputs in
# OUT/pssmlt-g-calibration.json, which every later process of both regimes reads (a stored
# fit on other inputs is refitted), plus the equal-mutation runs (at 64 mpp about 20 min).
# thin-highlight and thin-bar are the scenes built for the premise of the paper's Fig. 10
# (PSSMLT/G ahead of PSSMLT/K): docs/lab/2026-11-28-thin-highlight-scene.md and
# docs/lab/2026-11-28-thin-bar-scene.md.
set -euo pipefail
cd "$(dirname "$0")/.."
secs="${1:-30}"
seeds="${2:-5}"
mpp="${3:-64}"
out="${OUT:-target/drmlt-footing}"
scenes="${SCENES:-cornell-glass glossy-highlight caustic-pool thin-highlight thin-bar}"
first_seed="${FIRST_SEED:-0}"
mkdir -p "$out"
# A private copy: a concurrent `cargo build` must not replace the binary mid-measurement.
bin="$out/drmlt"
if [ -n "${BIN:-}" ]; then
    cp "$BIN" "$bin"
else
    cargo build --release --quiet --example drmlt
    cp target/release/examples/drmlt "$bin"
fi
lockfile="${LOCK:-/work/measure.lock}"
pin=()
if [ -n "${CPUS:-}" ]; then pin=(taskset -c "$CPUS"); fi
lock() {
    if [ "$lockfile" != none ] && [ -e "$lockfile" ]; then
        flock "$lockfile" "${pin[@]}" "$@"
    else
        "${pin[@]}" "$@"
    fi
}
for regime in "--time $secs" "--spp $mpp"; do
    name=$(echo "$regime" | tr -d ' -')
    jobs="$out/$name"
    common=(--footing --no-toy $regime --seeds "$seeds" --first-seed "$first_seed" --size 128
            --threads 1 --out "$jobs"
            --calibration "$out/pssmlt-g-calibration.json")
    # shellcheck disable=SC2086
    "$bin" "${common[@]}" --emit-jobs "$jobs/jobs" $scenes
    for id in $(grep -o '"id":"[^"]*"' "$jobs/jobs/jobs.jsonl" | cut -d'"' -f4); do
        # shellcheck disable=SC2086
        lock "$bin" "${common[@]}" --run-one "$id" $scenes
        sleep "${PAUSE:-2}"
    done
    # shellcheck disable=SC2086
    "$bin" "${common[@]}" --collect $scenes
    echo "wrote $jobs/results.md"
done
