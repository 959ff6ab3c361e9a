"""From sequence positions to an :class:`~scanlines.Extraction` in the sensor frame."""

from __future__ import annotations

import math
from collections.abc import Mapping
from typing import Any

import numpy as np

from scanlines._jit import jit
from scanlines.extraction import N_LINE_COLUMNS, Extraction
from scanlines.scan import is_full_circle
from scanlines.steps.fit import FIT_CODES, Moments, covariances, fit_many, run_labels
from scanlines.steps.points import Sequence

__all__ = [
    "CompiledMethod",
    "assemble",
    "assemble_runs",
    "empty_extraction",
    "empty_result",
    "from_arrays",
]


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
    ox, oy = moments.origin
    arrays = assemble_runs(
        seq.index,
        seq.x,
        seq.y,
        seq.r,
        np.asarray(a, dtype=np.int64),
        np.asarray(b, dtype=np.int64),
        FIT_CODES[fit],
        moments.table,
        ox,
        oy,
        float(angle_min),
        float(range_sigma),
        np.asarray(breakpoints, dtype=np.int64),
        np.asarray(corners, dtype=np.int64),
        np.asarray(outliers, dtype=np.int64),
    )
    return from_arrays(arrays, method, params)


def from_arrays(arrays: tuple[np.ndarray, ...], method: str, params: Mapping[str, Any]):
    """The :class:`Extraction` of :func:`assemble_runs`' output."""
    first, last, n_points, lines, covariance, breakpoints, corners, outliers = arrays
    return Extraction(
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


class CompiledMethod:
    """A method whose kernels go from a scan to :func:`assemble_runs`' arrays.

    What :class:`~scanlines.Extractor` calls when a method module defines a
    ``Compiled`` subclass. A subclass sets ``name``, ``scan_kernel(ranges, valid,
    cos, sin, step, full_circle, angle_min, *args)``, ``returns_kernel(index, r, x,
    y, n_beams, step, full_circle, angle_min, *args)`` (both as ``staticmethod``)
    and :meth:`arguments`, the kernels' last arguments built once from the
    parameters. ``cos`` and ``sin`` are the bearing tables of the beams relative
    to beam 0; ``valid`` the mask of beams with a return.
    """

    __slots__ = ("args", "params")
    name = ""

    def __init__(self, params: Mapping[str, Any]) -> None:
        self.params = params
        self.args = self.arguments(params)

    def arguments(self, params: Mapping[str, Any]) -> tuple[Any, ...]:
        raise NotImplementedError

    def one(self, ranges, valid, cos, sin, step: float, angle_min: float) -> Extraction:
        """The extraction of one scan."""
        full_circle = is_full_circle(ranges.shape[0], step)
        arrays = self.scan_kernel(
            ranges, valid, cos, sin, abs(step), full_circle, angle_min, *self.args
        )
        return from_arrays(arrays, self.name, self.params)

    def many(self, stack, valid, cos, sin, step: float, angle_min: float) -> list[Extraction]:
        """The extractions of a stack of scans of one sensor (C-contiguous float64 rows)."""
        full_circle = is_full_circle(stack.shape[1], step)
        kernel, args, step = self.scan_kernel, self.args, abs(step)
        return [
            from_arrays(
                kernel(row, mask, cos, sin, step, full_circle, angle_min, *args),
                self.name,
                self.params,
            )
            for row, mask in zip(stack, valid, strict=True)
        ]

    def sequence(self, seq: Sequence, angle_min: float) -> Extraction:
        """The extraction of the valid returns ``seq`` of one scan (its points as given)."""
        arrays = self.returns_kernel(
            np.ascontiguousarray(seq.index, dtype=np.int64),
            *(np.ascontiguousarray(v, dtype=np.float64) for v in (seq.r, seq.x, seq.y)),
            seq.n_beams,
            seq.step,
            is_full_circle(seq.n_beams, seq.step),
            float(angle_min),
            *self.args,
        )
        return from_arrays(arrays, self.name, self.params)


@jit
def assemble_runs(
    index, x, y, r, a, b, fit, table, ox, oy, angle_min, range_sigma, breakpoints, corners, outliers
):
    """Kernel of :func:`assemble`: ``first, last, n_points, lines, covariances, breakpoints,
    corners, outliers``, segments in beam order, events sorted."""
    rho, alpha, _ = fit_many(fit, table, ox, oy, a, b)
    position, run = run_labels(a, b, x.shape[0])
    covariance = covariances(x, y, r, rho, alpha, position, run, range_sigma)
    m = a.shape[0]
    lines = np.empty((m, 7))
    cos_t, sin_t = math.cos(angle_min), math.sin(angle_min)
    for k in range(m):
        c, s = math.cos(alpha[k]), math.sin(alpha[k])
        squares = 0.0
        for p in range(a[k], b[k] + 1):
            off = x[p] * c + y[p] * s - rho[k]
            squares += off * off
        lines[k, 0] = rho[k]
        lines[k, 1] = math.pi - (math.pi - (alpha[k] + angle_min)) % (2.0 * math.pi)
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
        np.sort(breakpoints),
        np.sort(corners),
        np.sort(outliers),
    )


@jit
def empty_result(breakpoints: np.ndarray, outliers: np.ndarray):
    """:func:`assemble_runs`' output without segments."""
    none = np.zeros(0, dtype=np.int64)
    return (
        none,
        none.copy(),
        none.copy(),
        np.zeros((0, 7)),
        np.zeros((0, 2, 2)),
        np.sort(breakpoints),
        none.copy(),
        np.sort(outliers),
    )
