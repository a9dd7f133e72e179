#!/usr/bin/env python3
"""Tables of scripts/regional_adaptive.sh's runs (docs/methods/regional-adaptive.md).

Usage: scripts/regional_adaptive_collect.py OUT_DIR  (writes OUT_DIR/summary.md and prints it)
Reads OUT_DIR/runs/<T>s/<scene>/<config>/seed<S>/{results.csv,results.md} and OUT_DIR/overhead.csv.
"""
import csv
import glob
import os
import re
import statistics
import sys

out = sys.argv[1]
KINDS = ["lens", "multichain"]
ADAPTS = [("fixed", "FIXED"), ("global", "GLOBAL"), ("grid", "RA-GRID"), ("quadtree", "RA-QUADTREE")]
CLAIMS = [("quadtree", "grid"), ("grid", "global"), ("global", "fixed"), ("quadtree", "fixed")]

runs = {}  # (secs, scene, config) -> {seed: row}
notes = {}  # (secs, scene, config, seed) -> adaptation note
for path in glob.glob(os.path.join(out, "runs", "*s", "*", "*", "seed*", "results.csv")):
    parts = path.split(os.sep)
    secs, scene, config, seed = parts[-5][:-1], parts[-4], parts[-3], int(parts[-2][4:])
    with open(path) as f:
        rows = list(csv.DictReader(f))
    if not rows:
        continue
    runs.setdefault((float(secs), scene, config), {})[seed] = rows[0]
    md = open(os.path.join(os.path.dirname(path), "results.md")).read()
    m = re.search(r"acceptance within ([0-9.]+) \+- 0.1 in (\d+) of (\d+) regions", md)
    s = re.search(r"learned sigma \(rad\) min ([0-9.e+-]+), median ([0-9.e+-]+), max ([0-9.e+-]+)", md)
    notes[(float(secs), scene, config, seed)] = (m.groups() if m else None, s.groups() if s else None)


def med(values):
    return statistics.median(values) if values else float("nan")


def rr(secs, scene, config):
    return {s: float(r["rrmse"]) for s, r in runs.get((secs, scene, config), {}).items()}


lines = []
put = lines.append
for secs in sorted({k[0] for k in runs}):
    for scene in sorted({k[1] for k in runs if k[0] == secs}):
        put(f"\n### {scene}, {secs:g} s\n")
        put("| configuration | seeds | rRMSE median [min, max] | rRMSE / FIXED | Mmut/s | load | acceptance | near target (seed 0) | learned sigma median (seed 0) |")
        put("|---|---|---|---|---|---|---|---|---|")
        configs = sorted({k[2] for k in runs if k[0] == secs and k[1] == scene},
                         key=lambda c: (c.split("-")[0], [a for a, _ in ADAPTS].index(c.split("-")[1]) if c.count("-") == 1 else 9, c))
        for c in configs:
            rows = runs[(secs, scene, c)]
            v = [float(r["rrmse"]) for r in rows.values()]
            kind = c.split("-")[0]
            base = rr(secs, scene, f"{kind}-fixed")
            ratio = med(v) / med(list(base.values())) if base else float("nan")
            mps = med([float(r["samples_per_second"]) for r in rows.values()]) / 1e6
            acc = med([float(r["acceptance"]) for r in rows.values()])
            load = med([float(r["load1"]) for r in rows.values() if r.get("load1")])
            near, sig = notes.get((secs, scene, c, 0), (None, None)) or (None, None)
            near_s = f"{near[1]} of {near[2]} (target {near[0]})" if near else "-"
            sig_s = sig[1] if sig else "-"
            name = c if c.count("-") > 1 else f"{kind} {dict(ADAPTS)[c.split('-')[1]]}"
            if c.count("-") > 1:
                name = f"{kind} FIXED {c.split('-', 2)[2]} rad (tuned sweep)"
            put(f"| {name} | {len(v)} | {med(v):.4f} [{min(v):.4f}, {max(v):.4f}] | {ratio:.3f} | {mps:.2f} | {load:.1f} | {acc:.3f} | {near_s} | {sig_s} |")
        put("")
        for kind in KINDS:
            for a, b in CLAIMS:
                ra, rb = rr(secs, scene, f"{kind}-{a}"), rr(secs, scene, f"{kind}-{b}")
                seeds = sorted(set(ra) & set(rb))
                if not seeds:
                    continue
                wins = sum(ra[s] <= rb[s] for s in seeds)
                ma, mb = med([ra[s] for s in seeds]), med([rb[s] for s in seeds])
                verdict = "**holds**" if ma <= mb and wins * 2 > len(seeds) else ("mixed" if ma <= mb or wins * 2 > len(seeds) else "does not hold")
                put(f"- {kind}: {dict(ADAPTS)[a]} <= {dict(ADAPTS)[b]}: {verdict} ({ma:.4f} vs {mb:.4f}; {wins}/{len(seeds)} seeds)")

# The ladder: per scene, configurations x times.
scenes = sorted({k[1] for k in runs})
for scene in scenes:
    times = sorted({k[0] for k in runs if k[1] == scene})
    if len(times) < 3:
        continue
    put(f"\n### rRMSE against time, {scene} (median over seeds; seeds in brackets)\n")
    put("| configuration | " + " | ".join(f"{t:g} s" for t in times) + " |")
    put("|---|" + "---|" * len(times))
    for kind in KINDS:
        for a, name in ADAPTS:
            cells = []
            for t in times:
                v = list(rr(t, scene, f"{kind}-{a}").values())
                cells.append(f"{med(v):.4f} ({len(v)})" if v else "-")
            put(f"| {kind} {name} | " + " | ".join(cells) + " |")

ov = os.path.join(out, "overhead.csv")
if os.path.exists(ov):
    rows = list(csv.DictReader(open(ov)))
    key = "mutations_per_cpu_second" if rows and "mutations_per_cpu_second" in rows[0] else "mutations_per_second"
    put("\n### Adaptation overhead (mutations per CPU second, median of repetitions)\n")
    put("| perturbation | mode | repetitions | Mmut/s | vs FIXED |")
    put("|---|---|---|---|---|")
    for kind in KINDS:
        base = med([float(r[key]) for r in rows if r["perturbation"] == kind and r["adapt"] == "fixed"])
        for a, name in ADAPTS:
            v = [float(r[key]) for r in rows if r["perturbation"] == kind and r["adapt"] == a]
            if v:
                put(f"| {kind} | {name} | {len(v)} | {med(v) / 1e6:.3f} | {med(v) / base - 1:+.1%} |")

text = "\n".join(lines) + "\n"
open(os.path.join(out, "summary.md"), "w").write(text)
print(text)
