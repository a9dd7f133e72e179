#!/usr/bin/env bash
# Regional adaptive MLT (Otsu et al. 2018) as the paper compares it: FIXED at lambda = 1,
# GLOBAL, RA-GRID, RA-QUADTREE for the lens and multi-chain perturbations, equal time, 128 x 128,
# one thread, 5 seeds; chainlight's tuned-FIXED frontier; the adaptation overhead
# (docs/methods/regional-adaptive.md, docs/performance.md).
#
# Usage: [OUT=dir] [LOCK=/path/to/lock] [SEEDS=5] scripts/regional_adaptive.sh PHASE...
#   overhead  mutations/s of every --adapt mode vs FIXED at the same sigma (equal mutations,
#             examples/regional_overhead.rs), 3 repetitions interleaved
#   p5        5 s: cornell and ajar-door at target acceptance 0.5, glossy-diffuse at 0.8
#             (the paper's Necklace setting); the 8 paper configurations
#   sweep     5 s: FIXED at 0.005 0.02 0.1 rad, both perturbations, the same scenes
#   p5sweep   p5 and sweep in one batch, all 14 configurations interleaved within each seed
#             (so that the tuned-FIXED frontier compares at equal time with the paper's four)
#   ladder    ajar-door at 1 2 10 20 s (5 s comes from p5, 60 s from p60)
#   t<N>      one rung: ajar-door at N s (e.g. t20)
#   p60       ajar-door at 60 s
#   collect   the tables (scripts/regional_adaptive_collect.py)
# Every render is its own process; with LOCK set each runs under `flock $LOCK` (one render per
# lock). For every seed the configurations run interleaved (scene, configuration), so that load
# drift hits all of them alike; renders already done (results.csv present) are skipped, so a
# phase resumes.
set -euo pipefail
cd "$(dirname "$0")/.."
out="${OUT:-target/regional_adaptive}"
seeds="${SEEDS:-5}"
mkdir -p "$out"
cargo build --release --quiet --example regional_adaptive --example regional_overhead
# Private copies: a concurrent `cargo build` must not replace a binary mid-measurement.
cp target/release/examples/regional_adaptive "$out/regional_adaptive"
cp target/release/examples/regional_overhead "$out/regional_overhead"
locked() { if [ -n "${LOCK:-}" ]; then flock "$LOCK" "$@"; else "$@"; fi; }
configs="lens-fixed lens-global lens-grid lens-quadtree multichain-fixed multichain-global multichain-grid multichain-quadtree"
sweep_configs=""
for k in lens multichain; do for s in 0.005 0.02 0.1; do sweep_configs+="$k-fixed-$s "; done; done
target_of() { if [ "$1" = glossy-diffuse ]; then echo 0.8; else echo 0.5; fi; }

# run SECONDS SCENE CONFIG SEED
run() {
    local dir="$out/runs/$1s/$2/$3/seed$4"
    [ -f "$dir/results.csv" ] && return 0
    mkdir -p "$dir"
    locked "$out/regional_adaptive" --time "$1" --seeds 1 --first-seed "$4" --size 128 \
        --threads 1 --only "$3" --target-acceptance "$(target_of "$2")" --ladder-seeds 0 \
        --no-report --out "$dir" "$2" > "$dir/log.txt" 2>&1 || { echo "failed: $dir"; return 0; }
    echo "$(date -u +%H:%M:%S) $1s $2 $3 seed$4 $(tail -n +2 "$dir/results.csv" | cut -d, -f10 | head -1)"
}

phase() {
    local secs="$1" scenes="$2" cfgs="$3"
    for seed in $(seq 0 $((seeds - 1))); do
        for scene in $scenes; do
            for c in $cfgs; do run "$secs" "$scene" "$c" "$seed"; done
        done
    done
}

echo "# commit $(git rev-parse --short HEAD), start $(date -u '+%Y-%m-%d %H:%M:%S UTC'), loadavg $(cat /proc/loadavg)"
for p in "$@"; do
    case "$p" in
    overhead)
        f="$out/overhead.csv"
        echo "scene,perturbation,adapt,mutations,cpu_seconds,mutations_per_cpu_second,regions,wall_seconds" > "$f"
        for rep in 1 2 3; do
            for k in lens multichain; do
                for a in fixed global grid quadtree; do
                    locked "$out/regional_overhead" cornell "$k" "$a" 1000 64 | tee -a "$f"
                done
            done
        done ;;
    p5) phase 5 "cornell glossy-diffuse ajar-door" "$configs" ;;
    sweep) phase 5 "cornell glossy-diffuse ajar-door" "$sweep_configs" ;;
    p5sweep) phase 5 "cornell glossy-diffuse ajar-door" "$configs $sweep_configs" ;;
    ladder) for s in 1 2 10 20; do phase "$s" ajar-door "$configs"; done ;;
    p60) phase 60 ajar-door "$configs" ;;
    t[0-9]*) phase "${p#t}" ajar-door "$configs" ;;
    collect) python3 scripts/regional_adaptive_collect.py "$out" ;;
    *) echo "unknown phase $p"; exit 2 ;;
    esac
done
echo "# end $(date -u '+%Y-%m-%d %H:%M:%S UTC'), loadavg $(cat /proc/loadavg)"
