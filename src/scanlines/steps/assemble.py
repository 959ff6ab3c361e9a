"""From sequence positions to an :class:`~scanlines.Extraction` in the sensor frame."""

from __future__ import annotations

import math
from collections.abc import Mapping
from typing import Any

import numpy as np

from scanlines.extraction import N_LINE_COLUMNS, Extraction
from scanlines.steps.fit import Moments, fit_runs, line_covariances, point_residuals, run_labels
from scanlines.steps.points import Sequence

__all__ = ["assemble", "empty_extraction"]


def empty_extraction(method: str, params: Mapping[str, Any], *, breakpoints=None, outliers=None):
    """An extraction with no segments."""
    none = np.zeros(0, dtype=np.intp)
    return Extraction(
        first=none,
        last=none,
        n_points=none,
        lines=np.zeros((0, N_LINE_COLUMNS)),
        covariances=np.zeros((0, 2, 2)),
        breakpoints=none if breakpoints is None else breakpoints,
        corners=none,
        outliers=none if outliers is None else outliers,
        method=method,
        params=params,
    )


def assemble(
    seq: Sequence,
    a: np.ndarray,
    b: np.ndarray,
    *,
    fit: str,
    moments: Moments,
    corners: np.ndarray,
    breakpoints: np.ndarray,
    outliers: np.ndarray,
    angle_min: float,
    range_sigma: float,
    method: str,
    params: Mapping[str, Any],
) -> Extraction:
    """Fit the final runs ``[a, b]`` and express everything in the sensor frame.

    Lines are computed in the scan's local frame (beam 0 at bearing 0), which
    makes every decision independent of ``angle_min``; here they are rotated by
    ``angle_min``.
    """
    if a.size == 0:
        return empty_extraction(method, params, breakpoints=breakpoints, outliers=outliers)
    lines = fit_runs(fit, moments, a, b)
    position, run = run_labels(a, b, len(seq))
    residual = point_residuals(seq.x, seq.y, lines.rho, lines.alpha, position, run)
    count = (b - a + 1).astype(np.float64)
    rms = np.sqrt(np.bincount(run, residual * residual, minlength=a.size) / count)
    covariance = line_covariances(
        seq.x, seq.y, seq.r, lines.rho, lines.alpha, position, run, range_sigma
    )
    start = _project(seq.x[a], seq.y[a], lines.rho, lines.alpha)
    end = _project(seq.x[b], seq.y[b], lines.rho, lines.alpha)

    cos_t, sin_t = math.cos(angle_min), math.sin(angle_min)
    table = np.empty((a.size, N_LINE_COLUMNS))
    table[:, 0] = lines.rho
    table[:, 1] = np.pi - np.mod(np.pi - (lines.alpha + angle_min), 2.0 * np.pi)
    table[:, 2] = cos_t * start[0] - sin_t * start[1]
    table[:, 3] = sin_t * start[0] + cos_t * start[1]
    table[:, 4] = cos_t * end[0] - sin_t * end[1]
    table[:, 5] = sin_t * end[0] + cos_t * end[1]
    table[:, 6] = rms

    first, last = seq.index[a], seq.index[b]
    order = np.argsort(first, kind="stable")
    return Extraction(
        first=first[order],
        last=last[order],
        n_points=(b - a + 1)[order],
        lines=table[order],
        covariances=covariance[order],
        breakpoints=breakpoints,
        corners=np.sort(corners),
        outliers=np.sort(outliers),
        method=method,
        params=params,
    )


def _project(x, y, rho, alpha):
    """Foot of the perpendicular from ``(x, y)`` onto the line ``(rho, alpha)``."""
    c, s = np.cos(alpha), np.sin(alpha)
    off = x * c + y * s - rho
    return x - off * c, y - off * s
