#!/usr/bin/env python3
"""Markdown tables of chainlight vs the peers at equal time, from the quality records the
side-by-side harness (../shared/peers/bench.py quality) appends to `quality.jsonl`.

    python3 scripts/peers/equal_time_table.py SCENE=RESULTS_DIR [SCENE=RESULTS_DIR ...]

One table per integrator family (PT vs Mitsuba 3 `path` and LuxCore PATHCPU, BDPT vs LuxCore
BIDIRCPU, PSSMLT vs LuxCore METROPOLIS over BIDIRCPU); one row per (scene, budget): the median
relMSE over seeds with its range, the ratio peer / chainlight of the medians (> 1: chainlight
lower), the number of seeds, and the median ratio of samples taken (chainlight / peer).
Records marked `superseded` are skipped; a (config, budget, seed) run more than once keeps the
last record.

Reference noise: if RESULTS_DIR holds `refnoise.json` (`{"ref_d5": n5, "ref_d10": n10}`, each
the relMSE of the reference's own noise, estimated as half the relMSE between the reference
and a second, independent render of the same kind), a last column gives the ratio with that
term subtracted from both medians: relMSE against a noisy reference is, in expectation, the
image's own relMSE plus the reference's (they are independent), and the common term pulls
every ratio towards 1 as the budget grows.
"""
import json, os, statistics as st, sys

PAIRS = [
    ('PT (depth 5)', 'cl-pt-d5', 'mitsuba-path-d5', 'Mitsuba 3 path'),
    ('PT (depth 5)', 'cl-pt-d5', 'lux-path-d5', 'LuxCore PATHCPU'),
    ('BDPT (depth 10)', 'cl-bdpt-d10', 'lux-bidir-d10', 'LuxCore BIDIRCPU'),
    ('PSSMLT (depth 10)', 'cl-pssmlt-d10', 'lux-metro-d10', 'LuxCore METROPOLIS'),
]


def load(path):
    runs = {}
    for line in open(os.path.join(path, 'quality.jsonl')):
        r = json.loads(line)
        if r.get('superseded'):
            continue
        runs[(r['name'], r['T'], r['seed'])] = r
    return runs


def fmt(v):
    return f'{st.median(v):.3g} ({min(v):.3g}-{max(v):.3g})'


def noise(path):
    p = os.path.join(path, 'refnoise.json')
    return json.load(open(p)) if os.path.exists(p) else {}


def main():
    scenes = [a.split('=', 1) for a in sys.argv[1:]]
    if not scenes:
        sys.exit(__doc__)
    data = [(name, load(path), noise(path)) for name, path in scenes]
    family = None
    for fam, cl, peer, peer_name in PAIRS:
        if fam != family:
            family = fam
            print(f'\n**{fam}**\n')
            print('| scene | time | peer | chainlight relMSE, median (range) | peer relMSE, median (range) '
                  '| peer / chainlight | seeds | samples chainlight / peer | ratio, reference noise removed |')
            print('|---|---|---|---|---|---|---|---|---|')
        for scene, runs, ref_noise in data:
            for T in sorted({k[1] for k in runs}):
                seeds = sorted(s for (n, t, s) in runs if n == cl and t == T and (peer, T, s) in runs)
                if not seeds:
                    continue
                a = [runs[(cl, T, s)]['relmse'] for s in seeds]
                b = [runs[(peer, T, s)]['relmse'] for s in seeds]
                n = [runs[(cl, T, s)]['samples'] / runs[(peer, T, s)]['samples'] for s in seeds]
                rn = ref_noise.get(runs[(cl, T, seeds[0])]['ref'])
                corrected = (f'{(st.median(b) - rn) / (st.median(a) - rn):.2f} (noise {rn:.2g})'
                             if rn is not None and st.median(a) > rn else 'n/a')
                print(f'| {scene} | {T:g} s | {peer_name} | {fmt(a)} | {fmt(b)} | '
                      f'**{st.median(b) / st.median(a):.2f}** | {len(seeds)} | {st.median(n):.2f} | {corrected} |')


if __name__ == '__main__':
    main()
