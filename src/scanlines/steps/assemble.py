"""From runs of positions to the result arrays of an :class:`~scanlines.Extraction`.

:func:`assemble` fits the final runs and expresses lines, end points and events in
the sensor frame; :func:`finish` is the last stage of every comparison method: drop
small runs, find the events between the rest (``segment_events``)
and assemble. Both return the tuple :func:`to_extraction` turns into an
:class:`~scanlines.Extraction`: ``first, last, n_points, lines, covariances,
breakpoints, corners, outliers``.
"""

from __future__ import annotations

from collections.abc import Mapping
from typing import Any, NamedTuple

import numpy as np

from scanlines import _core
from scanlines.extraction import N_LINE_COLUMNS, Extraction
from scanlines.params import MAX_COUNT, MAX_METRES, Param, auto_or, integer, number
from scanlines.steps.arrays import float64s, int64s
from scanlines.steps.noise import NoiseLine
from scanlines.steps.returns import Returns

__all__ = [
    "Output",
    "assemble",
    "empty_result",
    "finish",
    "output_settings",
    "to_extraction",
]


def output_settings(
    min_points: int, min_length: float = 0.0, range_sigma: float | str = "auto"
) -> dict[str, Param]:
    """The ``output`` settings every method has (which segments are reported, with what
    covariances), with that method's defaults."""
    return {
        "min_points": Param(min_points, integer(2, MAX_COUNT), "fewest points of a segment"),
        "min_length": Param(min_length, number(low=0.0, high=MAX_METRES), "shortest segment (m)"),
        "range_sigma": Param(
            range_sigma,
            auto_or(number(low=0.0, high=MAX_METRES, low_open=True)),
            "range noise of the covariances (m), or auto: the noise model's",
        ),
    }


class Output(NamedTuple):
    """What a comparison method keeps and reports: the smallest segment (points,
    metres), the range noise of the covariances (m; NaN: the noise model's) and the
    bounds of the corner rule
    (``segment_events``; beams, metres, radians)."""

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


def assemble(
    returns: Returns,
    fit: int,
    a: np.ndarray,
    b: np.ndarray,
    angle_min: float,
    sigma: np.ndarray,
    events: tuple[np.ndarray, np.ndarray, np.ndarray],
    scan_shape: tuple[int, bool],
) -> tuple[np.ndarray, ...]:
    """The result arrays: runs ``[a, b]`` fitted (fit code ``fit``), in beam order, events
    sorted.

    ``events`` is ``(breakpoints, corners, outliers)`` (beams), ``scan_shape``
    ``(n_beams, wrap)``: the scan's beam count and whether its last return neighbours
    its first (a full circle), for what ends each segment
    (:data:`~scanlines.extraction.END_KINDS`). ``sigma`` is the range noise of each
    return, for the covariances (which grow where a segment's own residuals are larger
    than that noise explains). Lines are computed in the scan's local frame (beam 0 at
    bearing 0), which makes every decision independent of ``angle_min``; here they are
    rotated by ``angle_min``.
    """
    n_beams, wrap = scan_shape
    return _core.assemble(
        *returns, fit, int64s(a), int64s(b), float(angle_min), float64s(sigma),
        *(int64s(e) for e in events), int(n_beams), bool(wrap),
    )  # fmt: skip


def empty_result(breakpoints: np.ndarray, outliers: np.ndarray) -> tuple[np.ndarray, ...]:
    """:func:`assemble`'s output without segments."""
    none = np.zeros(0, dtype=np.int64)
    return (
        none, none.copy(), none.copy(), np.zeros((0, N_LINE_COLUMNS)), np.zeros((0, 2, 2)),
        np.sort(breakpoints), none.copy(), np.sort(outliers), np.zeros((0, 2), dtype=np.int8),
    )  # fmt: skip


def finish(
    returns: Returns,
    n_beams: int,
    full_circle: bool,
    runs: tuple[np.ndarray, np.ndarray, np.ndarray],
    clusters: tuple[bool, bool, np.ndarray],
    outliers: np.ndarray,
    angle_min: float,
    output: Output,
    noise: NoiseLine,
) -> tuple[np.ndarray, ...]:
    """The last stage of every comparison method: drop the runs with fewer than
    ``min_points`` points (two at least) or shorter end to end than ``min_length``, find
    the corners (and breakpoints) between the rest
    (``segment_events``) and :func:`assemble` the result.

    ``runs`` is ``(a, b, group)``; ``clusters`` is ``(clustered, ring, breakpoints)``:
    whether the breakpoints come from the method's clustering (else they are derived
    from the jumps between segments), whether the scan is one closed ring, and the
    clustering's breakpoint beams. ``noise`` is the sensor profile's
    :class:`~scanlines.steps.noise.NoiseLine` (NaN: measured from the scan) for the
    covariances.
    """
    a, b, group = (int64s(v) for v in runs)
    clustered, ring, breakpoints = clusters
    return _core.finish(
        *returns, int(n_beams), bool(full_circle), a, b, group, (bool(clustered), bool(ring)),
        int64s(breakpoints), int64s(outliers), float(angle_min), output._asdict(), tuple(noise),
    )  # fmt: skip
