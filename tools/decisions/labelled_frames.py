"""Breakpoint and corner precision/recall of adaptive variants on the 10 hand-labelled Intel frames.

    python tools/decisions/labelled_frames.py

Matching: one-to-one within 2 beams, nearest first; a detection within 2 beams of an uncertain
label is neither true nor false, and uncertain labels are never missed.
"""

from __future__ import annotations

from scanlines import Extractor
from scanlines.data import sample
from scanlines.data.labels import intel_labels
from scanlines.io import open_log

VARIANTS = {
    "default": {},
    "min_cluster_points=1": {"min_cluster_points": 1},
    "min_cluster_points=3": {"min_cluster_points": 3},
    "abd_lambda=10": {"abd_lambda": 10},
    "abd_lambda=15": {"abd_lambda": 15},
    "abd_lambda=20": {"abd_lambda": 20},
    "abd_lambda=20, mcp=1": {"abd_lambda": 20, "min_cluster_points": 1},
    "noise_model=constant": {"noise_model": "constant"},
    "noise_model=range": {"noise_model": "range"},
}


def match(found, truth, dont_care, tolerance=2):
    """(true positives, false positives, false negatives) of one frame."""
    free = list(truth)
    tp = fp = 0
    for beam in sorted(found):
        nearest = min(free, key=lambda t: abs(t - beam), default=None)
        if nearest is not None and abs(nearest - beam) <= tolerance:
            free.remove(nearest)
            tp += 1
        elif not any(abs(beam - d) <= tolerance for d in dont_care):
            fp += 1
    return tp, fp, len(free)


def main() -> None:
    scans = list(open_log(sample("intel")))
    frames = intel_labels()
    print("variant                 bp P   bp R   corner P  corner R")
    for name, params in VARIANTS.items():
        extractor = Extractor(**params)
        bp = [0, 0, 0]
        corner = [0, 0, 0]
        for frame in frames:
            result = extractor(scans[frame.scan])
            counts = match(result.breakpoints, frame.breakpoints, frame.uncertain_breakpoints)
            bp = [x + y for x, y in zip(bp, counts, strict=True)]
            counts = match(result.corners, frame.corners, frame.uncertain_corners)
            corner = [x + y for x, y in zip(corner, counts, strict=True)]
        print(
            f"{name:22s} {bp[0] / max(bp[0] + bp[1], 1):5.2f}  {bp[0] / max(bp[0] + bp[2], 1):5.2f}"
            f"   {corner[0] / max(corner[0] + corner[1], 1):5.2f}     "
            f"{corner[0] / max(corner[0] + corner[2], 1):5.2f}"
        )


if __name__ == "__main__":
    main()
