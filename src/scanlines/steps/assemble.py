"""From runs of positions to the result arrays of an :class:`~scanlines.Extraction`.

:func:`assemble` fits the final runs and expresses lines, end points and events in
the sensor frame; :func:`finish` is the last stage of every comparison method: drop
small runs, find the events between the rest (:func:`~scanlines.steps.events.segment_events`)
and assemble. Both return the tuple :func:`to_extraction` turns into an
:class:`~scanlines.Extraction`: ``first, last, n_points, lines, covariances,
breakpoints, corners, outliers``.
"""

from __future__ import annotations

import math
from collections.abc import Mapping
from typing import Any, NamedTuple

import numpy as np

from scanlines._jit import kernel
from scanlines.extraction import N_LINE_COLUMNS, Extraction
from scanlines.steps.events import end_kinds, segment_events, sorted_distinct
from scanlines.steps.fit import TLS, fit_many, run_covariances, wrap_angle
from scanlines.steps.noise import covariance_sigmas
from scanlines.steps.returns import beam_gaps

__all__ = [
    "Output",
    "assemble",
    "drop_small",
    "empty_result",
    "finish",
    "to_extraction",
]


class Output(NamedTuple):
    """What a comparison method keeps and reports: the smallest segment (points,
    metres), the range noise of the covariances (m; NaN: the noise model's) and the
    bounds of the corner rule
    (:func:`~scanlines.steps.events.segment_events`; beams, metres, radians)."""

    min_points: int
    min_length: float
    range_sigma: float
    corner_beams: int
    corner_distance: float
    corner_angle: float


def to_extraction(arrays: tuple[np.ndarray, ...], method: str, params: Mapping[str, Any]):
    """The :class:`~scanlines.Extraction` of :func:`assemble`'s (or :func:`finish`'s) output."""
    first, last, n_points, lines, covariance, breakpoints, corners, outliers, ends = arrays
    return Extraction(
        end_kinds=ends,
        first=first,
        last=last,
        n_points=n_points,
        lines=lines,
        covariances=covariance,
        breakpoints=breakpoints,
        corners=corners,
        outliers=outliers,
        method=method,
        params=params,
    )


@kernel
def assemble(returns, fit, moments, a, b, angle_min, sigma, events, scan_shape):
    """The result arrays: runs ``[a, b]`` fitted, in beam order, events sorted.

    ``events`` is ``(breakpoints, corners, outliers)`` (beams), ``scan_shape``
    ``(n_beams, wrap)``: the scan's beam count and whether its last return neighbours
    its first (a full circle), for what ends each segment
    (:func:`~scanlines.steps.events.end_kinds`).

    ``sigma`` is the range noise of each return, for the covariances (which grow where
    a segment's own residuals are larger than that noise explains).

    Lines are computed in the scan's local frame (beam 0 at bearing 0), which
    makes every decision independent of ``angle_min``; here they are rotated by
    ``angle_min``.
    """
    index, _, x, y = returns
    breakpoints, corners, outliers = np.sort(events[0]), np.sort(events[1]), np.sort(events[2])
    n_beams, wrap = scan_shape
    rho, alpha, _ = fit_many(fit, moments, a, b)
    covariance = run_covariances(returns, rho, alpha, a, b, sigma, np.bool_(True))
    m = a.shape[0]
    lines = np.empty((m, N_LINE_COLUMNS))
    cos_t, sin_t = math.cos(angle_min), math.sin(angle_min)
    for k in range(m):
        c, s = math.cos(alpha[k]), math.sin(alpha[k])
        squares = 0.0
        for p in range(a[k], b[k] + 1):
            off = x[p] * c + y[p] * s - rho[k]
            squares += off * off
        lines[k, 0] = rho[k]
        lines[k, 1] = wrap_angle(alpha[k] + angle_min)
        for column, p in ((2, a[k]), (4, b[k])):
            off = x[p] * c + y[p] * s - rho[k]  # foot of the perpendicular onto the line
            px, py = x[p] - off * c, y[p] - off * s
            lines[k, column] = cos_t * px - sin_t * py
            lines[k, column + 1] = sin_t * px + cos_t * py
        lines[k, 6] = math.sqrt(squares / (b[k] - a[k] + 1))
    first, last = index[a], index[b]
    order = np.argsort(first)  # beam indices are distinct: any sort is stable
    return (
        first[order],
        last[order],
        (b - a + 1)[order],
        lines[order],
        covariance[order],
        breakpoints,
        corners,
        outliers,
        end_kinds(returns, a, b, n_beams, wrap, breakpoints, corners)[order],
    )


@kernel
def empty_result(breakpoints, outliers):
    """:func:`assemble`'s output without segments."""
    none = np.zeros(0, dtype=np.int64)
    return (
        none,
        none.copy(),
        none.copy(),
        np.zeros((0, N_LINE_COLUMNS)),
        np.zeros((0, 2, 2)),
        np.sort(breakpoints),
        none.copy(),
        np.sort(outliers),
        np.zeros((0, 2), dtype=np.int8),
    )


@kernel
def drop_small(x, y, a, b, group, min_points, min_length):
    """Runs with at least ``min_points`` points (two at least) and an end-to-end length
    of ``min_length``."""
    kept_a, kept_b, kept_group = a.copy(), b.copy(), group.copy()
    count = 0
    for k in range(a.shape[0]):
        length = math.hypot(x[b[k]] - x[a[k]], y[b[k]] - y[a[k]])
        if b[k] - a[k] + 1 >= max(min_points, 2.0) and length >= min_length:
            kept_a[count], kept_b[count], kept_group[count] = a[k], b[k], group[k]
            count += 1
    return kept_a[:count], kept_b[:count], kept_group[:count]


@kernel
def finish(
    returns, n_beams, full_circle, moments, runs, clusters, outliers, angle_min, output, noise
):
    """Drop small runs, find corners (and breakpoints) and assemble the result arrays.

    ``runs`` is ``(a, b, group)``; ``clusters`` is ``(clustered, ring,
    breakpoints)``: whether the breakpoints come from the method's clustering (else
    they are derived from the jumps between segments), whether the scan is one closed
    ring, and the clustering's breakpoint beams. ``output`` is an :class:`Output`;
    ``noise`` the sensor profile's :class:`~scanlines.steps.noise.NoiseLine` (NaN:
    measured from the scan) for the covariances.
    """
    a, b, group = runs
    clustered, ring, breakpoints = clusters
    a, b, group = drop_small(
        returns.x, returns.y, a, b, group, output.min_points, output.min_length
    )
    bounds = (output.corner_beams, output.corner_distance, output.corner_angle)
    wrap = ring if clustered else full_circle
    corners, jumps = segment_events(returns, n_beams, moments, a, b, group, clustered, wrap, bounds)
    if not clustered:
        breakpoints = jumps
    gap = beam_gaps(returns.index, n_beams)
    sigma = covariance_sigmas(output.range_sigma, noise, returns, gap)
    events = (sorted_distinct(breakpoints), corners, sorted_distinct(outliers))
    return assemble(
        returns, np.int64(TLS), moments, a, b, angle_min, sigma, events, (n_beams, full_circle)
    )
