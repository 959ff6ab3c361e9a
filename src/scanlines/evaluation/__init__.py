"""Scoring extractors against ground truth and writing the scores down.

The modules, by subject (import them by name; importing this package imports none of
them). The truth types they score against are :mod:`scanlines.truth`::

    scores            Tolerances and the score records (EventScore, ..., Summary)
    metrics           score(), aggregate() and the matching they are built on
    specs             method specs: METHOD[:PRESET][?NAME=VALUE&...][@LABEL]
    scenes            seeded simulated scenes, scene sets saved to .npz
    truth_row         the "truth" reference row (the one module using scanlines.steps)
    evaluate          evaluate(): specs on scenes, per-scan and pooled scores (scanlines eval)
    cases             a scan with truth, labels or neither, and one method's score on it
    repeatability     scan-to-scan repeatability on real logs, no labels (eval real)

Times are taken by :mod:`scanlines.bench.timing`, tables and numbers written by
:mod:`scanlines.report`; the figures are in :mod:`scanlines.viz`. The repository's own
pages (``RESULTS.md``, ``PERFORMANCE.md``) are written by its ``tools/``, which are not
installed.
"""

__all__ = [
    "cases",
    "evaluate",
    "metrics",
    "repeatability",
    "scenes",
    "scores",
    "specs",
    "truth_row",
]
