#!/usr/bin/env bash
# The tables of docs/methods/mala.md ("Current results"): Langevin MLT against MMLT at equal
# time and at equal samples, 128x128, max depth 5, one thread, 5 seeds, on glossy-highlight,
# motion-blur, caustic-pool and glossy-diffuse (glossy and diffuse surfaces lighting each
# other: the glossy-interreflection scene). Methods, every one with the same direct pass
# (BDPT renders depths 0-1, balanced against the chains by the pilot: --direct-share auto
# --direct-depth 1) and the same large steps (--large-step 0.3):
#   MMLT/K                mmlt (Kelemen small step)
#   MMLT/G(0.005)         mmlt --small-step gaussian=0.005
#   MALA, online, cache, hybrid   mala* --mala-preset paper-values
#   cheap-then-expensive  mala --mala-kernel cheap-then-expensive --mala-preset paper-values
# For every seed the runs are interleaved (scene, then method) and the method order rotates
# with the seed, so that machine-load drift hits every method alike. Timed runs hold the
# measurement lock (/work/measure.lock, or $LOCK) for one render each; equal-sample runs
# do not need it.
#
# Timed runs are pinned to one core (CPU, default 1); every run's log (acceptance by step,
# gradient-cache fill, direct-pass share) is kept in OUT/logs. Every render also writes its
# direct pass and its chains' part (`--write-parts`): scripts/pair_mse.py OUT measures the
# error of both without a reference, from seed pairs.
#
# Usage: [SCENES="a b"] [OUT=dir] [SIZE=128] [LOCK=file] [CPU=k] \
#        scripts/langevin_tables.sh time|samples BUDGET [SEEDS]
#   time BUDGET: seconds per render (the table: 30); samples BUDGET: mutations per pixel
#   (the table: the median samples per pixel MMLT/K reached at equal time, e.g. 256).
#   References: OUT/refs/<scene>.exr, BDPT at the render's size and max depth (the bundled
#   references are 256x256); rendered first if missing, REF_SPP (default 4096) samples per
#   pixel on two threads (not timed, no lock; about 10-20 min per scene at 128x128).
#   Compared by `chainlight compare` (MSE, the paper's metric, and relMSE).
# Prints one line per run (regime scene method seed mse relmse samples seconds) into
# OUT/results.txt and the per-scene medians at the end. Duration: 4 scenes x 7 methods x
# SEEDS renders of BUDGET seconds plus about 2 s each (scene loading, bootstrap): 5 seeds at
# 30 s are about 140 renders, 75 minutes of one core; equal samples take about as long.
set -euo pipefail
cd "$(dirname "$0")/.."
regime="$1"
budget="$2"
seeds="${3:-5}"
size="${SIZE:-128}"
out="${OUT:-out/langevin_tables}"
lock="${LOCK:-/work/measure.lock}"
cpu="${CPU:-1}"
scenes="${SCENES:-glossy-highlight motion-blur caustic-pool glossy-diffuse}"
case "$regime" in
    time) budget_flag=(--time "$budget") ;;
    samples) budget_flag=(--spp "$budget") ;;
    *) echo "first argument: time or samples" >&2; exit 2 ;;
esac
mkdir -p "$out/logs"
cargo build --release --quiet
# A private copy: a concurrent `cargo build` must not replace the binary mid-measurement.
bin="$out/chainlight"
cp target/release/chainlight "$bin"
common=(--max-depth 5 --width "$size" --height "$size" --threads 1 --large-step 0.3
        --direct-share auto --direct-depth 1 --write-parts)
names=("MMLT/K" "MMLT/G(0.005)" "MALA" "MALA-online" "MALA-cache" "MALA-hybrid" "cheap-then-expensive")
args=(
    "--integrator mmlt"
    "--integrator mmlt --small-step gaussian=0.005"
    "--integrator mala --mala-preset paper-values"
    "--integrator mala-online --mala-preset paper-values"
    "--integrator mala-cache --mala-preset paper-values"
    "--integrator mala-hybrid --mala-preset paper-values"
    "--integrator mala --mala-kernel cheap-then-expensive --mala-preset paper-values"
)
results="$out/results.txt"
{
    echo "# commit $(git rev-parse --short HEAD), $regime $budget, ${size}x${size}, $seeds seeds"
    echo "# start $(date -u '+%Y-%m-%d %H:%M:%S UTC'), loadavg $(cat /proc/loadavg)"
    echo "# regime scene method seed mse relmse samples seconds"
} > "$results"
mkdir -p "$out/refs"
for scene in $scenes; do
    ref="$out/refs/$scene.exr"
    if [[ ! -f "$ref" ]]; then
        nice -n 5 "$bin" render "scenes/$scene.gltf" --integrator bdpt --spp "${REF_SPP:-4096}" \
            --width "$size" --height "$size" --max-depth 5 --seed 1000 --threads 2 -o "$ref" \
            > "$out/refs/$scene.log" 2>&1
    fi
done
n=${#names[@]}
for seed in $(seq 1 "$seeds"); do
    for scene in $scenes; do
        for k in $(seq 0 $((n - 1))); do
            i=$(( (k + seed) % n ))
            slug=$(echo "${names[$i]}" | tr -c 'A-Za-z0-9.\n' '-')
            img="$out/$scene-$slug-$seed.exr"
            log="$out/logs/$scene-$slug-$seed.log"
            # shellcheck disable=SC2086
            cmd=("$bin" render "scenes/$scene.gltf" ${args[$i]} "${common[@]}" \
                "${budget_flag[@]}" --seed "$seed" -o "$img")
            if [[ "$regime" == time ]]; then
                flock "$lock" taskset -c "$cpu" "${cmd[@]}" > "$log" 2>&1
            else
                nice -n 5 "${cmd[@]}" > "$log" 2>&1
            fi
            samples=$(awk '/^samples/{print $2}' "$log")
            secs=$(awk '/^elapsed/{print $2}' "$log")
            metrics=$("$bin" compare "$img" "$out/refs/$scene.exr" --error-map "$out/error.png" 2>&1)
            mse=$(echo "$metrics" | awk 'tolower($1)=="mse"{print $2; exit}')
            rel=$(echo "$metrics" | awk 'tolower($1)=="relmse"{print $2; exit}')
            echo "$regime $scene ${names[$i]// /_} $seed $mse $rel $samples $secs" | tee -a "$results"
        done
    done
done
echo "# end $(date -u '+%Y-%m-%d %H:%M:%S UTC'), loadavg $(cat /proc/loadavg)" >> "$results"
echo "# medians (scene method mse relmse)"
median() { # column, scene, method
    grep -v '^#' "$results" | awk -v c="$1" -v s="$2" -v m="$3" '$2 == s && $3 == m { print $c }' |
        sort -g | awk '{ v[NR] = $1 } END { print v[int((NR + 1) / 2)] }'
}
grep -v '^#' "$results" | awk '{ print $2, $3 }' | sort -u | while read -r scene method; do
    echo "$scene $method $(median 5 "$scene" "$method") $(median 6 "$scene" "$method")"
done
