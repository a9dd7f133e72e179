#!/usr/bin/env python3
"""Reference-free error of a method from independent renders: E[MSE(a, b)] = 2 MSE for two
unbiased renders a, b of the same method with different seeds (their errors are independent
and have mean zero), so half the MSE between two seeds estimates one render's MSE against the
true image, without a reference. Useful where the reference's own noise is not small against
the renders' (a BDPT reference of a caustic or a small highlight): the MSE against such a
reference adds the reference's MSE to every method alike.

Usage: scripts/pair_mse.py DIR [CHAINLIGHT]
  DIR holds the renders of scripts/langevin_tables.sh (or any `<scene>-<method>-<seed>.exr`
  files, with the method slug free of the last `-<seed>`) and its results.txt (read for the
  scene and method names). CHAINLIGHT is the binary (default DIR/chainlight).
Prints, per scene and method: the mean over all seed pairs of MSE(a, b) / 2 and the smallest
and largest pair, the number of pairs, and the median MSE against the reference from
results.txt; where the renders have parts (`render --write-parts`: `<name>_chains.exr`), the
same for the chains' parts alone (the direct-lighting pass's noise removed). Writes
DIR/pairs.txt with one line per pair (`-` where a part is missing).
"""

import itertools
import os
import re
import statistics
import subprocess
import sys
import tempfile


def mse(binary, a, b):
    """MSE of image a against image b, from `chainlight compare`."""
    error_map = os.path.join(tempfile.gettempdir(), "pair_mse_error.png")
    out = subprocess.run(
        [binary, "compare", a, b, "--error-map", error_map],
        capture_output=True,
        text=True,
        check=False,
    )
    for line in out.stdout.splitlines() + out.stderr.splitlines():
        parts = line.split()
        if len(parts) >= 2 and parts[0].lower() == "mse":
            return float(parts[1])
    raise RuntimeError(f"no MSE comparing {a} with {b}: {out.stderr.strip()}")


def main():
    if len(sys.argv) < 2:
        print(__doc__, file=sys.stderr)
        sys.exit(2)
    directory = sys.argv[1]
    binary = sys.argv[2] if len(sys.argv) > 2 else os.path.join(directory, "chainlight")
    rows = []
    with open(os.path.join(directory, "results.txt"), encoding="utf-8") as f:
        for line in f:
            if line.startswith("#") or not line.strip():
                continue
            regime, scene, method, seed, ref_mse = line.split()[:5]
            rows.append((scene, method, int(seed), float(ref_mse)))
    groups = {}
    for scene, method, seed, ref_mse in rows:
        groups.setdefault((scene, method), []).append((seed, ref_mse))
    pairs_out = []
    print(
        "scene method pair_mse_mean pair_min pair_max pairs ref_mse_median"
        " chains_mean chains_min chains_max chain_pairs"
    )
    for (scene, method), runs in groups.items():
        # The image name: the tables script's slug of the method name.
        slug = re.sub(r"[^A-Za-z0-9.]", "-", method.replace("_", " "))
        images = []
        for seed, _ in sorted(runs):
            path = os.path.join(directory, f"{scene}-{slug}-{seed}.exr")
            if os.path.exists(path):
                images.append((seed, path))
        values, chain_values = [], []
        for (sa, a), (sb, b) in itertools.combinations(images, 2):
            half = mse(binary, a, b) / 2.0
            values.append(half)
            ca, cb = (p[: -len(".exr")] + "_chains.exr" for p in (a, b))
            chain_half = "-"
            if os.path.exists(ca) and os.path.exists(cb):
                chain_values.append(mse(binary, ca, cb) / 2.0)
                chain_half = f"{chain_values[-1]:.6e}"
            pairs_out.append(f"{scene} {method} {sa} {sb} {half:.6e} {chain_half}")
        ref_median = statistics.median(r for _, r in runs)

        def summary(v):
            if not v:
                return "- - - 0"
            return f"{statistics.mean(v):.4e} {min(v):.4e} {max(v):.4e} {len(v)}"

        print(f"{scene} {method} {summary(values)} {ref_median:.4e} {summary(chain_values)}")
    with open(os.path.join(directory, "pairs.txt"), "w", encoding="utf-8") as f:
        f.write("# scene method seed_a seed_b mse_half chains_mse_half\n")
        f.write("\n".join(pairs_out) + "\n")


if __name__ == "__main__":
    main()
