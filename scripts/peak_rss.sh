#!/usr/bin/env bash
# Peak resident memory (GNU time's maximum RSS) of one render per integrator-table row at a
# given size, one sample / mutation per pixel, on the built-in Cornell box:
#
#   scripts/peak_rss.sh 1024          # every row at 1024 x 1024
#   scripts/peak_rss.sh 4096 pssmlt   # one row
#
# Prints `integrator  size  seconds  peak MiB  bytes/pixel`. Needs /usr/bin/time (Debian's
# `time` package). The numbers go to docs/performance.md ("Memory").
set -euo pipefail
cd "$(dirname "$0")/.."
size=${1:-1024}
shift || true
cargo build --release --quiet --bin chainlight
bin=target/release/chainlight
rows=("$@")
if [[ ${#rows[@]} -eq 0 ]]; then
  mapfile -t rows < <("$bin" render --help | sed -n '/Possible values:/,/^$/p' | sed -n 's/^ *- \([a-z-]*\):.*/\1/p')
fi
out=$(mktemp -d)
trap 'rm -rf "$out"' EXIT
printf '%-14s %6s %8s %9s %11s\n' integrator size seconds "peak MiB" bytes/pixel
for row in "${rows[@]}"; do
  /usr/bin/time -f '%e %M' -o "$out/time" \
    "$bin" render --integrator "$row" --spp 1 --width "$size" --height "$size" -o "$out/img.exr" \
    >/dev/null 2>&1 || { printf '%-14s %6s  failed\n' "$row" "$size"; continue; }
  read -r secs kib < "$out/time"
  awk -v r="$row" -v s="$size" -v t="$secs" -v k="$kib" 'BEGIN {
    printf "%-14s %6d %8.1f %9.0f %11.0f\n", r, s, t, k / 1024, k * 1024 / (s * s) }'
done
