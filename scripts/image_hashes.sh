#!/usr/bin/env bash
# Renders every integrator-table row and the named variants (DR rules and bases, MALA presets
# and gradients, path-space perturbation x adaptation, the PSSMLT/MMLT estimator options) at
# --spp 4 --seed 3 --width 32 --height 32 --threads 2 on the built-in Cornell box and on
# scenes/cornell-glass.gltf, and prints the SHA-256 of each EXR beside the recorded one.
#
#   scripts/image_hashes.sh            compare against scripts/image-hashes.txt
#   scripts/image_hashes.sh --record   (re)write scripts/image-hashes.txt
#
# A refactoring that must not change an image shows `same` on every line; the script exits
# non-zero if any line differs.
set -euo pipefail
cd "$(dirname "$0")/.."
baseline=scripts/image-hashes.txt
record=0
[[ "${1:-}" == "--record" ]] && record=1
cargo build --release --quiet --bin chainlight
bin=target/release/chainlight
out=$(mktemp -d)
trap 'rm -rf "$out"' EXIT

cases=(
  "pt|--integrator pt"
  "bdpt|--integrator bdpt"
  "pssmlt|--integrator pssmlt"
  "pssmlt-pt|--integrator pssmlt-pt"
  "mmlt|--integrator mmlt"
  "drmlt|--integrator drmlt"
  "qmc|--integrator qmc"
  "qmc-faure|--integrator qmc-faure"
  "lqmc|--integrator lqmc"
  "mala|--integrator mala"
  "mala-online|--integrator mala-online"
  "mala-cache|--integrator mala-cache"
  "mala-hybrid|--integrator mala-hybrid"
  "pathmlt|--integrator pathmlt"
  "pt-independent|--integrator pt --sampler independent"
  "bdpt-independent|--integrator bdpt --sampler independent"
  "pssmlt-auto|--integrator pssmlt --large-step auto"
  "pssmlt-plain|--integrator pssmlt --large-step-mis off --raster-mutation off --direct-samples 0"
  "pssmlt-direct16|--integrator pssmlt --direct-samples 16"
  "pssmlt-share|--integrator pssmlt --direct-share 0.15 --direct-depth 1"
  "pssmlt-gauss|--integrator pssmlt --small-step gaussian=0.01"
  "mmlt-auto|--integrator mmlt --large-step auto"
  "mmlt-mis|--integrator mmlt --large-step-mis on --raster-mutation 0.5"
  "mmlt-perdepth|--integrator mmlt --chain-allocation per-depth --strategy-strata on"
  "mmlt-bdptnorm|--integrator mmlt --bdpt-normalization 20000"
  "mmlt-direct|--integrator mmlt --direct-share auto"
  "pssmlt-bootstrap-b|--integrator pssmlt --normalization bootstrap"
  "drmlt-tm-pairwise|--integrator drmlt --dr-variant tierney-mira-pairwise"
  "drmlt-gm-pairwise|--integrator drmlt --dr-variant green-mira-pairwise"
  "drmlt-orbital-mis|--integrator drmlt --large-step-mis on"
  "lqmc-code|--integrator lqmc --lqmc-preset code"
  "drmlt-tm|--integrator drmlt --dr-variant tierney-mira"
  "drmlt-gm|--integrator drmlt --dr-variant green-mira"
  "drmlt-orbital-mmlt|--integrator drmlt --dr-on mmlt"
  "drmlt-tm-mmlt|--integrator drmlt --dr-variant tierney-mira --dr-on mmlt"
  "drmlt-gm-mmlt|--integrator drmlt --dr-variant green-mira --dr-on mmlt"
  "drmlt-cte|--integrator drmlt --dr-variant cheap-then-expensive"
  "drmlt-pt|--integrator drmlt --dr-on pssmlt-pt"
  "drmlt-tm-pt|--integrator drmlt --dr-variant tierney-mira --dr-on pssmlt-pt"
  "drmlt-direct|--integrator drmlt --direct-samples 4 --direct-depth 1"
  "drmlt-fixed-strategy|--integrator drmlt --dr-on mmlt --dr-fixed-strategy"
  "mala-values|--integrator mala --mala-preset paper-values"
  "mala-hybrid-values|--integrator mala-hybrid --mala-preset paper-values"
  "mala-cte|--integrator mala --mala-kernel cheap-then-expensive --mala-preset paper-values"
  "pathmlt-lens-paper-global|--integrator pathmlt --perturbation lens --adapt global --sigma paper"
  "pathmlt-mc-paper-fixed|--integrator pathmlt --perturbation multichain --adapt fixed --sigma paper"
  "mala-code|--integrator mala --mala-preset code"
  "mala-fd|--integrator mala --mala-gradient fd"
  "mala-online-code|--integrator mala-online --mala-preset code"
  "mala-cache-code|--integrator mala-cache --mala-preset code"
  "mala-hybrid-code|--integrator mala-hybrid --mala-preset code --mala-max-depth 5"
  "pathmlt-lens-global|--integrator pathmlt --perturbation lens --adapt global"
  "pathmlt-lens-grid|--integrator pathmlt --perturbation lens --adapt grid"
  "pathmlt-lens-quadtree|--integrator pathmlt --perturbation lens --adapt quadtree"
  "pathmlt-mc-fixed|--integrator pathmlt --perturbation multichain --adapt fixed"
  "pathmlt-mc-global|--integrator pathmlt --perturbation multichain --adapt global"
  "pathmlt-mc-grid|--integrator pathmlt --perturbation multichain --adapt grid"
  "pathmlt-mc-quadtree|--integrator pathmlt --perturbation multichain --adapt quadtree"
  "pathmlt-lens-global-c4|--integrator pathmlt --perturbation lens --adapt global --chains 4"
  "pathmlt-lens-grid-c4|--integrator pathmlt --perturbation lens --adapt grid --chains 4"
  "pathmlt-lens-quadtree-c4|--integrator pathmlt --perturbation lens --adapt quadtree --chains 4"
  "pathmlt-mc-fixed-c4|--integrator pathmlt --perturbation multichain --chains 4"
  "pathmlt-mc-grid-c4|--integrator pathmlt --perturbation multichain --adapt grid --chains 4"
  "pathmlt-mc-quadtree-c4|--integrator pathmlt --perturbation multichain --adapt quadtree --chains 4"
  "mala-hybrid-c8|--integrator mala-hybrid --chains 8 --bootstrap-samples 5000"
  "pssmlt-p01-c16|--integrator pssmlt --large-step 0.1 --chains 16"
)
scenes=("builtin|" "cornell-glass|scenes/cornell-glass.gltf")

declare -A want=()
if [[ $record == 0 && -f $baseline ]]; then
  while read -r key hash; do want[$key]=$hash; done < <(grep -v '^#' "$baseline")
fi
lines=()
differ=0
for scene in "${scenes[@]}"; do
  sname=${scene%%|*}; spath=${scene#*|}
  for c in "${cases[@]}"; do
    name=${c%%|*}; flags=${c#*|}
    key="$sname/$name"
    # shellcheck disable=SC2086
    if "$bin" render $spath $flags --spp 4 --seed 3 --width 32 --height 32 --threads 2 \
        -o "$out/img.exr" >/dev/null 2>"$out/err"; then
      hash=$(sha256sum "$out/img.exr" | cut -c1-64)
    else
      hash="error:$(tail -1 "$out/err" | tr -c '[:alnum:]' '_' | cut -c1-40)"
    fi
    lines+=("$key $hash")
    if [[ $record == 0 ]]; then
      old=${want[$key]:-missing}
      if [[ "$old" == "$hash" ]]; then verdict=same; else verdict=DIFF; differ=1; fi
      printf '%-34s %-16.16s %-16.16s %s\n' "$key" "$old" "$hash" "$verdict"
    fi
  done
done
if [[ $record == 1 ]]; then
  {
    echo "# SHA-256 of each EXR at --spp 4 --seed 3 --width 32 --height 32 --threads 2"
    echo "# recorded at $(git rev-parse --short HEAD) by scripts/image_hashes.sh --record"
    printf '%s\n' "${lines[@]}"
  } > "$baseline"
  echo "recorded ${#lines[@]} hashes in $baseline"
fi
exit $differ
