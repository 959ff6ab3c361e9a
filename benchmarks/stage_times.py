"""Where the adaptive kernel spends its time: each stage timed on its own, one simulated scan.

    python benchmarks/stage_times.py [--sensor tim571] [--seed 3] [--repeats 300]

Each stage is called from Python with the inputs the full kernel would give it, so every line
includes about 1 us of call overhead and the boxing of its outputs; the stages add up to a
little more than the kernel. Speed is measured here, never asserted in tests.
"""

from __future__ import annotations

import argparse
import math
import time

import numpy as np

from scanlines import Extractor
from scanlines.methods import adaptive as ad
from scanlines.sim import random_scene
from scanlines.steps import fit
from scanlines.steps.denoise import noise_from_ranges


def best_us(call, repeats: int) -> float:
    call()
    best = math.inf
    for _ in range(3):
        start = time.perf_counter()
        for _ in range(repeats):
            call()
        best = min(best, (time.perf_counter() - start) / repeats)
    return 1e6 * best


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--sensor", default="tim571")
    parser.add_argument("--seed", type=int, default=3)
    parser.add_argument("--repeats", type=int, default=300)
    args = parser.parse_args()
    scan = random_scene(args.seed, args.sensor).scan(args.seed).scan
    extractor = Extractor()
    s, grid = ad.settings(extractor.params)
    cos, sin = extractor._bearings(len(scan), scan.angle_increment)
    step, n_beams = abs(scan.angle_increment), len(scan)
    index = np.flatnonzero(scan.valid)
    r = scan.ranges[index]
    x, y = r * cos[index], r * sin[index]
    gap = ad._gaps(index, n_beams)
    first, last = np.zeros(1, np.int64), np.full(1, r.size - 1)
    sigma = noise_from_ranges(r, gap, first, last)
    rule = ad._rule(s, sigma)
    window = ad._slope_window(x, y, index, sigma, s[ad.SLOPE_WINDOW])
    no_breaks = np.zeros(0, np.bool_)
    clustered = ad._cluster_scan(index, r, x, y, n_beams, step, False, rule, window, no_breaks)
    start, end, breakpoints = clustered[4], clustered[5], clustered[6]
    table, ox, oy = fit.prefix_moments(x, y)
    inv_r2 = fit.inverse_square_sums(r)
    scores = ad._scores(x, y, r, index, n_beams, step, table, start, end, window, s)
    corners, sigma2 = ad._choose_corners(table, ox, oy, inv_r2, start, end, scores, sigma, s, grid)
    a, b, owner = ad._segments(x, y, table, ox, oy, inv_r2, start, end, corners, sigma2, s)
    cut = ad._cut(start, end, corners, False)
    rows = {
        "whole call (Extractor)": lambda: extractor(scan),
        "whole kernel": lambda: ad.extract_scan(
            scan.ranges, scan.valid, cos, sin, step, False, scan.angle_min, s, grid
        ),
        "noise estimate": lambda: noise_from_ranges(r, gap, first, last),
        "denoise (2 break passes)": lambda: ad._denoise(
            index, r, x, y, n_beams, step, False, rule, s
        ),
        "slope window (median)": lambda: ad._slope_window(x, y, index, sigma, s[ad.SLOPE_WINDOW]),
        "clustering": lambda: ad._cluster_scan(
            index, r, x, y, n_beams, step, False, rule, window, no_breaks
        ),
        "running sums": lambda: fit.prefix_moments(x, y),
        "turn-angle scores": lambda: ad._scores(
            x, y, r, index, n_beams, step, table, start, end, window, s
        ),
        "candidates + sweep + choice": lambda: ad._choose_corners(
            table, ox, oy, inv_r2, start, end, scores, sigma, s, grid
        ),
        "cut, refine, merge, split": lambda: ad._segments(
            x, y, table, ox, oy, inv_r2, start, end, corners, sigma2, s
        ),
        "  of which: refine splits": lambda: ad._refine_splits(0, table, ox, oy, inv_r2, *cut),
        "corner beams": lambda: ad._corner_beams(
            x, y, index, table, ox, oy, 0, a, b, owner, False, False, sigma2
        ),
        "assembly (fits, covariances)": lambda: ad.assemble_runs(
            index, x, y, r, a, b, 0, table, ox, oy, 0.0, 0.01, breakpoints, corners, breakpoints
        ),
    }
    print(
        f"{args.sensor}, seed {args.seed}: {r.size} returns, {len(start)} clusters, "
        f"{len(a)} segments; best of 3 x {args.repeats} calls"
    )
    for name, call in rows.items():
        print(f"{name:32s} {best_us(call, args.repeats):8.1f} us")


if __name__ == "__main__":
    main()
