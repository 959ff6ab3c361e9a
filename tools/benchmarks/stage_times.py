"""Where the adaptive kernel spends its time: each stage timed on its own, one simulated scan.

    python tools/benchmarks/stage_times.py [--sensor tim571] [--seed 3] [--repeats 300]

Each stage is called from Python with the inputs the full kernel would give it, so every line
includes about 1 us of call overhead and the boxing of its outputs; the stages add up to a
little more than the kernel. Times are taken by the package's one timing rule
(:func:`scanlines.evaluation.timing.time_calls`): the median of ``repeats`` samples per stage,
passes interleaved between stages. Speed is measured here, never asserted in tests.
"""

from __future__ import annotations

import argparse
import math

import numpy as np

from scanlines import Extractor
from scanlines.evaluation.timing import time_calls
from scanlines.methods import adaptive as ad
from scanlines.methods.base import as_record
from scanlines.sim import random_scene
from scanlines.steps import fit
from scanlines.steps.assemble import assemble
from scanlines.steps.clusters import cluster_returns
from scanlines.steps.corners import turn_window
from scanlines.steps.denoise import denoise
from scanlines.steps.events import junction_events
from scanlines.steps.noise import UNKNOWN_NOISE, noise_at, return_sigmas, scan_noise
from scanlines.steps.returns import beam_gaps, valid_returns
from scanlines.steps.split import cut_at, refine_cuts


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--sensor", default="tim571")
    parser.add_argument("--seed", type=int, default=3)
    parser.add_argument("--repeats", type=int, default=300)
    args = parser.parse_args()
    scan = random_scene(args.seed, args.sensor).scan(args.seed).scan
    extractor = Extractor()
    settings = ad.Adaptive.settings_of(extractor.params)
    record, grid = as_record(settings), np.zeros(0)
    s = record[0]
    local = scan.angle_increment * np.arange(len(scan))
    cos, sin = np.cos(local), np.sin(local)
    step, n_beams = abs(scan.angle_increment), len(scan)
    returns = valid_returns(scan.ranges, scan.valid, cos, sin)
    gap = beam_gaps(returns.index, n_beams)
    noise = scan_noise(returns, gap)
    sigma = noise_at(noise, np.median(returns.r))
    rule = ad.breakpoint_rule(s, noise, step)
    margin = settings["noise_k"] * math.sqrt(2.0) * sigma
    window = turn_window(returns.x, returns.y, returns.index, sigma)
    no_breaks = np.zeros(0, np.bool_)
    clustered = cluster_returns(returns, n_beams, step, False, rule, window, no_breaks)
    start, end, breakpoints = clustered[1], clustered[2], clustered[3]
    moments = fit.prefix_moments(returns.x, returns.y)
    sigmas = return_sigmas(returns.r, noise)
    cost = ad.run_cost_of(s, moments, returns, sigmas)
    scores = ad.corner_scores(
        returns, n_beams, step, moments, start, end, window, settings["corner_score"]
    )
    corners, scale = ad.choose_corners(cost, start, end, scores, True, s, grid)
    a, b, owner = ad.segments(returns, cost, start, end, corners, scale * scale, s, noise, sigmas)
    turn_sigmas = ad.direction_sigmas(returns, moments, a, b, sigmas)
    events, scan_shape = (breakpoints, corners, breakpoints), (n_beams, False)
    cut = cut_at(start, end, corners, False)
    rows = {
        "whole call (Extractor)": lambda: extractor(scan),
        "whole kernel": lambda: ad.adaptive_scan(
            scan.ranges,
            scan.valid,
            cos,
            sin,
            step,
            False,
            scan.angle_min,
            UNKNOWN_NOISE,
            record,
            grid,
        ),
        "noise estimate": lambda: scan_noise(returns, gap),
        "denoise (2 break passes)": lambda: denoise(
            returns,
            n_beams,
            step,
            False,
            rule,
            settings["denoise"],
            settings["window"],
            settings["min_cluster_points"],
            margin,
        ),
        "turn window (median)": lambda: turn_window(returns.x, returns.y, returns.index, sigma),
        "clustering": lambda: cluster_returns(
            returns, n_beams, step, False, rule, window, no_breaks
        ),
        "running sums": lambda: fit.prefix_moments(returns.x, returns.y),
        "turn-angle scores": lambda: ad.corner_scores(
            returns, n_beams, step, moments, start, end, window, settings["corner_score"]
        ),
        "candidates + sweep + choice": lambda: ad.choose_corners(
            cost, start, end, scores, True, s, grid
        ),
        "cut, refine, merge, split": lambda: ad.segments(
            returns, cost, start, end, corners, scale * scale, s, noise, sigmas
        ),
        "  of which: refine cuts": lambda: refine_cuts(cost, *cut),
        "corner beams": lambda: junction_events(
            returns, settings["fit"], moments, a, b, owner, False, False, scale * sigma, turn_sigmas
        ),
        "assembly (fits, covariances)": lambda: assemble(
            returns, settings["fit"], moments, a, b, 0.0, sigmas, events, scan_shape
        ),
    }
    timed = time_calls(
        {name: (lambda _, call=call: call()) for name, call in rows.items()}, [None], args.repeats
    )
    print(
        f"{args.sensor}, seed {args.seed}: {returns.r.size} returns, {len(start)} clusters, "
        f"{len(a)} segments; median of {args.repeats} calls"
    )
    for name, result in timed.items():
        print(f"{name:32s} {np.median(result.samples_ns) / 1000:8.1f} us")


if __name__ == "__main__":
    main()
