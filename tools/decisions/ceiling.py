"""Which tolerance the truth row's unmatched true segments fail on, per sensor preset.

    python tools/decisions/ceiling.py            # 300 scenes per sensor, seed 0
    python tools/decisions/ceiling.py -n 20 --seed 1

The truth row (``scanlines eval -m truth``, :func:`scanlines.evaluation.truth_row.truth_extraction`)
has one segment per true segment, over the same beams. Every counted true segment
(``>= min_segment_beams`` beams) left unmatched by the segment matching of
:func:`scanlines.evaluation.metrics.score` is put in one class, from the found segments that
overlap it by at least ``overlap`` of both spans:

* ``overlap``: none overlaps it enough;
* ``rho only``, ``alpha only``, ``both``: the best of them (lowest matching cost)
  fails ``|d rho|`` only, ``|d alpha|`` only, or both;
* ``taken``: one passes every tolerance but is matched to another true segment.

It also gives the truth row's TruePos by the true segment's span in beams, and with
one component of the preset's noise switched off (:data:`VARIANTS`). Same scenes,
seeds and tolerances as ``scanlines eval``; the matching is the metric's own (its
building blocks), and the matched count is checked against
:func:`~scanlines.evaluation.metrics.score`.
"""

from __future__ import annotations

import argparse
from collections import Counter
from dataclasses import replace

import numpy as np

from scanlines import Extraction, Scan
from scanlines.evaluation.metrics import (
    line_differences,
    match_one_to_one,
    score,
    segment_overlap,
)
from scanlines.evaluation.scenes import SceneCase, iter_scenes
from scanlines.evaluation.scores import Tolerances
from scanlines.evaluation.truth_row import truth_extraction
from scanlines.extraction import ALPHA, RHO
from scanlines.sim import SENSORS, get_sensor, random_scene
from scanlines.truth import Truth

REASONS = ("overlap", "rho only", "alpha only", "both", "taken")
SPAN_BINS = (("8-15", 8, 15), ("16-31", 16, 31), ("32-63", 32, 63), ("64+", 64, np.inf))
"""Span classes of the true segments in beams: label, smallest, largest."""


def classify(extraction: Extraction, truth: Truth, tol: Tolerances) -> tuple[list[str], list[int]]:
    """Class of each counted true segment (``"matched"`` or one of :data:`REASONS`), and spans."""
    ts, n = truth.segments, truth.n_beams
    f_span = (extraction.last - extraction.first) % n + 1
    t_span = (ts.last - ts.first) % n + 1
    shared = segment_overlap(extraction.first, extraction.last, ts.first, ts.last, n)
    overlapping = (shared >= tol.overlap * f_span[:, None]) & (
        shared >= tol.overlap * t_span[None, :]
    )
    drho, dalpha = line_differences(
        extraction.lines[:, RHO], extraction.lines[:, ALPHA], ts.rho, ts.alpha
    )
    cost = drho / tol.rho + dalpha / tol.alpha
    _, matched = match_one_to_one(overlapping & (drho <= tol.rho) & (dalpha <= tol.alpha), cost)
    classes, spans = [], []
    for j in np.flatnonzero(t_span >= tol.min_segment_beams):
        if j in matched:
            kind = "matched"
        elif not overlapping[:, j].any():
            kind = "overlap"
        else:
            best = np.flatnonzero(overlapping[:, j])[np.argmin(cost[overlapping[:, j], j])]
            bad_rho, bad_alpha = drho[best, j] > tol.rho, dalpha[best, j] > tol.alpha
            if bad_rho and bad_alpha:
                kind = "both"
            elif bad_rho or bad_alpha:
                kind = "rho only" if bad_rho else "alpha only"
            else:
                kind = "taken"
        classes.append(kind)
        spans.append(int(t_span[j]))
    return classes, spans


VARIANTS = {
    "realistic": {},
    "no per-scan bias": {"bias": 0.0, "bias_rel": 0.0},
    "no random range noise": {"sigma": 0.0, "sigma_rel": 0.0},
}
"""Noise of the truth-row TruePos table: the preset's model with these fields changed.

The simulator draws the same random numbers whatever the parameters, so every variant
is the same scene with the same draws, one component switched off."""


def variant(case: SceneCase, changes: dict[str, float]) -> tuple[Scan, Truth]:
    """The scan and truth of ``case`` with the preset's noise changed by ``changes``."""
    if not changes:
        return case.scan, case.truth
    noise = replace(get_sensor(case.sensor).noise, **changes)
    sim = random_scene(case.seed, case.sensor).scan(case.seed, noise=noise)
    return sim.scan, sim.truth


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("-n", type=int, default=300, help="scenes per sensor")
    parser.add_argument("--seed", type=int, default=0)
    args = parser.parse_args()
    tol = Tolerances()
    classes = {(s, v): Counter() for s in SENSORS for v in VARIANTS}
    spans = {s: (Counter(), Counter()) for s in SENSORS}  # counted, matched per span class
    for sensor in SENSORS:
        for case in iter_scenes([sensor], args.n, args.seed):
            for name, changes in VARIANTS.items():
                scan, truth = variant(case, changes)
                found = truth_extraction(scan, truth)
                kinds, widths = classify(found, truth, tol)
                if score(found, truth, scan, tol).segments.matched != kinds.count("matched"):
                    raise AssertionError(f"{sensor} #{case.index}: matching differs from score()")
                classes[sensor, name].update(kinds)
                if name == "realistic":
                    for kind, width in zip(kinds, widths, strict=True):
                        label = next(b for b, lo, hi in SPAN_BINS if lo <= width <= hi)
                        spans[sensor][0][label] += 1
                        spans[sensor][1][label] += kind == "matched"

    print(f"{args.n} scenes per sensor, seed {args.seed}, default tolerances.\n")
    print(
        "Unmatched true segments of the truth row (realistic noise), by the tolerance they fail:\n"
    )
    _row("sensor", "counted true", "matched", "unmatched", *REASONS)
    _row(*["---"] * (4 + len(REASONS)))
    for sensor in SENSORS:
        found = classes[sensor, "realistic"]
        missed = sum(found.values()) - found["matched"]
        share = [f"{found[r]} ({found[r] / missed:.0%})" if missed else "0" for r in REASONS]
        _row(sensor, sum(found.values()), found["matched"], missed, *share)

    labels = [name for name, _, _ in SPAN_BINS]
    print("\nTruePos of the truth row by the true segment's span in beams (segments):\n")
    _row("sensor", *labels)
    _row(*["---"] * (1 + len(labels)))
    for sensor, (counted, matched) in spans.items():
        _row(sensor, *(f"{matched[b] / counted[b]:.3f} ({counted[b]})" for b in labels))

    print("\nTruePos of the truth row with one noise component switched off:\n")
    _row("sensor", *VARIANTS)
    _row(*["---"] * (1 + len(VARIANTS)))
    for sensor in SENSORS:
        rates = (classes[sensor, v]["matched"] / sum(classes[sensor, v].values()) for v in VARIANTS)
        _row(sensor, *(f"{rate:.3f}" for rate in rates))


def _row(*cells: object) -> None:
    print("| " + " | ".join(str(c) for c in cells) + " |")


if __name__ == "__main__":
    main()
