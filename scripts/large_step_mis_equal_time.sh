#!/usr/bin/env bash
# Equal-time relMSE of PSSMLT and MMLT with and without Kelemen et al. 2002's large-step MIS
# estimator (--large-step-mis on|off; issue 17, docs/performance.md "Equal-time efficiency
# (issue 17)"). One thread, 64x64, max depth 5, default large-step probability 0.3; for every
# seed the runs are interleaved (scene, integrator, off/on; the off/on order alternates with the
# seed) so that a change of machine load hits both settings alike.
#
# Usage: [SCENES="a b"] [OUT=dir] scripts/large_step_mis_equal_time.sh REF_DIR [SECONDS] [SEEDS]
#   (default scenes: cornell-glass caustic-pool; default OUT: out/large_step_mis)
#   REF_DIR holds <scene>.exr references at 64x64, e.g. rendered with
#   target/release/chainlight render scenes/<scene>.gltf --integrator bdpt --spp 8192 \
#       --width 64 --height 64 --max-depth 5 --seed 1 --threads 2 -o REF_DIR/<scene>.exr
# Prints one line per run (scene integrator mis seed relMSE samples) and the medians.
set -euo pipefail
cd "$(dirname "$0")/.."
refs="$1"
secs="${2:-5}"
seeds="${3:-7}"
out="${OUT:-out/large_step_mis}"
scenes="${SCENES:-cornell-glass caustic-pool}"
mkdir -p "$out"
cargo build --release --quiet
# A private copy: a concurrent `cargo build` must not replace the binary mid-measurement.
bin="$out/chainlight"
cp target/release/chainlight "$bin"
git rev-parse --short HEAD | sed 's/^/# commit /'
results="$out/results.txt"
: > "$results"
echo "# start $(date -u '+%Y-%m-%d %H:%M:%S UTC'), loadavg $(cat /proc/loadavg)"
for seed in $(seq 0 $((seeds - 1))); do
    if (( seed % 2 == 0 )); then order="off on"; else order="on off"; fi
    for scene in $scenes; do
        for integ in pssmlt mmlt; do
            for mis in $order; do
                img="$out/$scene-$integ-$mis-$seed.exr"
                "$bin" render "scenes/$scene.gltf" --integrator "$integ" --large-step-mis "$mis" \
                    --time "$secs" --threads 1 --width 64 --height 64 --max-depth 5 \
                    --seed "$seed" -o "$img" > "$out/render.log" 2>&1
                samples=$(awk '/^samples/{print $2}' "$out/render.log")
                rel=$("$bin" compare "$img" "$refs/$scene.exr" --error-map "$out/error.png" \
                    | awk '/^relMSE/{print $2}')
                echo "$scene $integ $mis $seed $rel $samples" | tee -a "$results"
            done
        done
    done
done
echo "# end $(date -u '+%Y-%m-%d %H:%M:%S UTC'), loadavg $(cat /proc/loadavg)"
python3 - "$results" <<'PY'
import sys, statistics
rows = [l.split() for l in open(sys.argv[1]) if l.strip()]
groups = {}
for scene, integ, mis, seed, rel, samples in rows:
    groups.setdefault((scene, integ, mis), []).append((float(rel), int(samples)))
print("scene integrator | median relMSE off | on | on/off | median mutations off | on | runs")
for scene in dict.fromkeys(r[0] for r in rows):
    for integ in ("pssmlt", "mmlt"):
        off = groups[(scene, integ, "off")]
        on = groups[(scene, integ, "on")]
        m_off = statistics.median(r for r, _ in off)
        m_on = statistics.median(r for r, _ in on)
        print(f"{scene} {integ} | {m_off:.4e} | {m_on:.4e} | {m_on / m_off:.3f} | "
              f"{statistics.median(s for _, s in off)} | {statistics.median(s for _, s in on)} | "
              f"{len(off)}+{len(on)}")
PY
