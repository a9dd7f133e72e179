#!/usr/bin/env bash
# Renders the reference image of every bundled scene with long BDPT runs (256x256).
# Usage: scripts/make_references.sh [SPP] [THREADS]   (defaults: 256 spp, 2 threads)
# Writes scenes/references/<scene>.exr (+ .png preview) and appends the command, sample count
# and wall time of each run to scenes/references/runs.txt (copied into docs/scenes.md).
set -euo pipefail
cd "$(dirname "$0")/.."
spp="${1:-256}"
threads="${2:-2}"
cargo build --release --quiet
out=scenes/references
mkdir -p "$out"
for scene in scenes/*.gltf; do
    name=$(basename "$scene" .gltf)
    cmd=(target/release/chainlight render "$scene" --integrator bdpt --spp "$spp"
         --width 256 --height 256 --max-depth 5 --seed 1 --threads "$threads" -o "$out/$name.exr")
    start=$(date +%s.%N)
    "${cmd[@]}" > /dev/null
    end=$(date +%s.%N)
    printf '%s\t%s spp\t%.0f s\t%s\n' "$name" "$spp" "$(echo "$end - $start" | bc)" "${cmd[*]}" >> "$out/runs.txt"
done
