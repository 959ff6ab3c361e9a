"""Scoring extractors against ground truth, timing them, and writing the results down.

The modules, by subject (import them by name; importing this package imports none of
them). The truth types they score against are :mod:`scanlines.truth`::

    scores            Tolerances and the score records (EventScore, ..., Summary)
    metrics           score(), aggregate() and the matching they are built on
    specs             method specs: METHOD[:PRESET][?NAME=VALUE&...][@LABEL]
    scenes            seeded simulated scenes, scene sets saved to .npz
    truth_row         the "truth" reference row (the one module using scanlines.steps)
    evaluate          evaluate(): specs on scenes, per-scan and pooled scores (scanlines eval)
    timing            the one timing rule every time here is taken by
    machine           the machine a time was measured on
    report            markdown tables, number formats, JSON values, CSV files
    cases             a scan with truth, labels or neither, and one method's score on it
    repeatability     scan-to-scan repeatability on real logs, no labels (eval --real)
    bench             the speed of every method (scanlines bench)
    bench_results     what bench measured, as JSON and tables

The figures are in :mod:`scanlines.viz`. The repository's own pages (``RESULTS.md``,
``PERFORMANCE.md``) are written by its ``tools/``, which are not installed.
"""

__all__ = [
    "bench",
    "bench_results",
    "cases",
    "evaluate",
    "machine",
    "metrics",
    "repeatability",
    "report",
    "scenes",
    "scores",
    "specs",
    "timing",
    "truth_row",
]
