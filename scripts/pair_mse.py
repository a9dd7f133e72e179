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
results.txt; and writes DIR/pairs.txt with one line per pair.
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
    print("scene method pair_mse_mean pair_min pair_max pairs ref_mse_median")
    for (scene, method), runs in groups.items():
        # The image name: the tables script's slug of the method name.
        slug = re.sub(r"[^A-Za-z0-9.]", "-", method.replace("_", " "))
        images = []
        for seed, _ in sorted(runs):
            path = os.path.join(directory, f"{scene}-{slug}-{seed}.exr")
            if os.path.exists(path):
                images.append((seed, path))
        values = []
        for (sa, a), (sb, b) in itertools.combinations(images, 2):
            half = mse(binary, a, b) / 2.0
            values.append(half)
            pairs_out.append(f"{scene} {method} {sa} {sb} {half:.6e}")
        ref_median = statistics.median(r for _, r in runs)
        if values:
            print(
                f"{scene} {method} {statistics.mean(values):.4e} {min(values):.4e} "
                f"{max(values):.4e} {len(values)} {ref_median:.4e}"
            )
        else:
            print(f"{scene} {method} - - - 0 {ref_median:.4e}")
    with open(os.path.join(directory, "pairs.txt"), "w", encoding="utf-8") as f:
        f.write("# scene method seed_a seed_b mse_half\n")
        f.write("\n".join(pairs_out) + "\n")


if __name__ == "__main__":
    main()
