"""Helpers shared by the tests of scanlines.io (imported by module name)."""

from __future__ import annotations

from pathlib import Path

import numpy as np

from scanlines.extraction import Extraction

FIXTURES = Path(__file__).parent / "fixtures"


def make_extraction(
    n_segments: int = 2,
    *,
    breakpoints: tuple[int, ...] = (9, 30),
    corners: tuple[int, ...] = (10,),
    nan_rms: bool = False,
) -> Extraction:
    """A hand-made extraction: segment k runs from (k, 1) to (k + 1, 2), rho = k + 1."""
    k = np.arange(n_segments, dtype=float)
    rms = np.full(n_segments, 0.01)
    if nan_rms and n_segments:
        rms[-1] = np.nan
    lines = np.column_stack(
        (
            k + 1.0,
            np.full(n_segments, 0.25),
            k,
            np.ones(n_segments),
            k + 1,
            np.full(n_segments, 2.0),
            rms,
        )
    )
    return Extraction(
        first=np.arange(n_segments) * 10,
        last=np.arange(n_segments) * 10 + 9,
        n_points=np.full(n_segments, 10),
        lines=lines,
        covariances=np.tile(np.diag([1e-4, 1e-5]), (n_segments, 1, 1)),
        breakpoints=np.array(breakpoints, dtype=int),
        corners=np.array(corners, dtype=int),
        outliers=np.array([], dtype=int),
        method="handmade",
        params={"threshold": 0.05, "window": (1, 2), "max_gap": float("inf")},
    )
