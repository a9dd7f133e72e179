#!/usr/bin/env bash
# PSSMLT with and without the raster (image-plane) mutation at EQUAL MUTATIONS (--spp), relMSE
# against a BDPT reference, plus mutations/s from short timed runs (issue 17, item 2;
# docs/performance.md "Raster mutation (issue 17, item 2)"). A raster step costs one path
# evaluation like a small step, so equal mutations is equal work up to the measured rate.
#
# Usage: [SCENES="a b"] [OUT=dir] [PROBS="off 0.25 0.5"] [SIZE=64] [DEPTH=5] [SPP=256] \
#        [INTEGRATOR=pssmlt] [RATE_SECS=5] scripts/raster_mutation_equal_spp.sh REF_DIR [SEEDS]
#   REF_DIR holds <scene>.exr BDPT references of the same size and depth, e.g.
#   target/release/chainlight render scenes/<scene>.gltf --integrator bdpt --spp 8192 \
#       --width 64 --height 64 --max-depth 5 --seed 1 --threads 2 -o REF_DIR/<scene>.exr
# Prints one line per run (scene raster seed relMSE mutations) and the medians.
set -euo pipefail
cd "$(dirname "$0")/.."
refs="$1"
seeds="${2:-5}"
out="${OUT:-out/raster_mutation}"
scenes="${SCENES:-cornell-glass glossy-highlight caustic-pool ajar-door}"
probs="${PROBS:-off 0.25 0.5}"
size="${SIZE:-64}"
depth="${DEPTH:-5}"
spp="${SPP:-256}"
integ="${INTEGRATOR:-pssmlt}"
rate_secs="${RATE_SECS:-5}"
mkdir -p "$out"
# A private copy: a concurrent `cargo build` must not replace the binary mid-measurement.
bin="$out/chainlight"
cp target/release/chainlight "$bin"
git rev-parse --short HEAD | sed 's/^/# commit /'
results="$out/results.txt"
rates="$out/rates.txt"
: > "$results"
: > "$rates"
echo "# start $(date -u '+%Y-%m-%d %H:%M:%S UTC'), loadavg $(cat /proc/loadavg)"
for seed in $(seq 0 $((seeds - 1))); do
    for scene in $scenes; do
        for q in $probs; do
            img="$out/$scene-$q-$seed.exr"
            "$bin" render "scenes/$scene.gltf" --integrator "$integ" --raster-mutation "$q" \
                --spp "$spp" --threads 2 --width "$size" --height "$size" --max-depth "$depth" \
                --seed "$seed" -o "$img" > "$out/render.log" 2>&1
            samples=$(awk '/^samples/{print $2}' "$out/render.log")
            rel=$("$bin" compare "$img" "$refs/$scene.exr" --error-map "$out/error.png" \
                | awk '/^relMSE/{print $2}')
            echo "$scene $q $seed $rel $samples" | tee -a "$results"
        done
    done
done
echo "# quality end $(date -u '+%Y-%m-%d %H:%M:%S UTC'), loadavg $(cat /proc/loadavg)"
if (( rate_secs > 0 )); then
    for scene in $scenes; do
        for q in $probs; do
            "$bin" render "scenes/$scene.gltf" --integrator "$integ" --raster-mutation "$q" \
                --time "$rate_secs" --threads 1 --width "$size" --height "$size" \
                --max-depth "$depth" --seed 0 -o "$out/rate.exr" > "$out/render.log" 2>&1
            samples=$(awk '/^samples/{print $2}' "$out/render.log")
            echo "$scene $q $samples" | tee -a "$rates"
        done
    done
    echo "# rates end $(date -u '+%Y-%m-%d %H:%M:%S UTC'), loadavg $(cat /proc/loadavg)"
fi
python3 - "$results" "$rates" "$rate_secs" <<'PY'
import sys, statistics
rows = [l.split() for l in open(sys.argv[1]) if l.strip()]
rates = {}
for l in open(sys.argv[2]):
    if l.strip():
        scene, q, n = l.split()
        rates[(scene, q)] = int(n) / float(sys.argv[3])
groups = {}
for scene, q, seed, rel, samples in rows:
    groups.setdefault((scene, q), {})[seed] = float(rel)
probs = list(dict.fromkeys(r[1] for r in rows))
base = probs[0]
print("scene q | median relMSE [min, max] | median / base | per-seed ratio median [min, max], better | mutations/s (1 thread)")
for scene in dict.fromkeys(r[0] for r in rows):
    b = groups[(scene, base)]
    mb = statistics.median(b.values())
    for q in probs:
        g = groups[(scene, q)]
        m = statistics.median(g.values())
        ratios = [g[s] / b[s] for s in g if s in b]
        better = sum(r < 1 for r in ratios)
        rate = rates.get((scene, q))
        print(f"{scene} {q} | {m:.4e} [{min(g.values()):.3e}, {max(g.values()):.3e}] | "
              f"{m / mb:.3f} | {statistics.median(ratios):.3f} [{min(ratios):.3f}, "
              f"{max(ratios):.3f}], {better}/{len(ratios)} | "
              f"{rate:.0f}" if rate else f"{scene} {q} | {m:.4e} | {m / mb:.3f}")
PY
