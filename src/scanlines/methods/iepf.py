"""Iterative end-point fit (IEPF): split clusters at the point farthest from their chord.

Algorithm (Duda and Hart [1]_, sec. 9.2; the recursive split of Pavlidis and
Horowitz [2]_; as compared by the paper [3]_, sec. 4.3-4.5):

1. cluster the returns by a fixed jump distance (``breakpoints="fixed"``,
   ``jump_distance = 0.3`` m) -- :mod:`scanlines.steps.breakpoints`;
2. in every cluster, find the point farthest from the chord between the
   cluster's first and last point (measured to the chord as a segment, so that
   a cluster closing on itself is first cut at its far corner); if that distance
   exceeds ``split_distance``,
   split there and repeat on both parts
   (:func:`scanlines.steps.segments.split_runs`); the split point joins the part
   whose line it is nearer;
3. fit each part by total least squares (:mod:`scanlines.steps.fit`), drop parts
   with fewer than ``min_points`` points or shorter than ``min_length``;
4. corners where consecutive parts of one cluster meet (the shared rule of
   :func:`scanlines.steps.segments.segment_events`); breakpoints from step 1.

Defaults: ``split_distance = 0.1`` m: with the 1-2 cm range noise of indoor
laser scanners it is 5 to 10 standard deviations, so noise alone rarely splits
a wall, yet a 90 deg corner is cut as soon as each side is longer than about
10 cm. ``min_points = 5``,
``min_length = 0``, ``range_sigma = 0.01`` m (covariances only).

There is no denoising and the threshold is fixed: at fine angular resolution the
farthest point of a noisy wall is a noise peak, and a threshold near the noise
cuts the wall there -- the over-segmentation the paper shows for IEPF (its
Fig. 10a).

References
----------
.. [1] R. O. Duda and P. E. Hart, *Pattern Classification and Scene Analysis*,
   Wiley, 1973.
.. [2] T. Pavlidis and S. L. Horowitz, "Segmentation of plane curves", IEEE
   Trans. Computers C-23(8), 860-870, 1974.
.. [3] "An adaptive threshold line segment feature extraction algorithm for laser
   radar scanning environments", Electronics 11(11), 1759, 2022.
   doi:10.3390/electronics11111759
"""

from __future__ import annotations

from collections.abc import Mapping
from typing import Any

import numpy as np

from scanlines._jit import jit
from scanlines.extraction import Extraction
from scanlines.params import Param, number, segment_params, with_default
from scanlines.steps.assemble import CompiledMethod, empty_result
from scanlines.steps.breakpoints import BREAKPOINT_PARAMS
from scanlines.steps.fit import prefix_moments
from scanlines.steps.points import Sequence
from scanlines.steps.segments import (
    EVENT_PARAMS,
    LITERAL_CLUSTERING,
    SPLIT_DISTANCE,
    SPLIT_REFERENCE,
    cluster_returns,
    finish_runs,
    settings,
    split_runs_at_farthest,
    valid_returns,
)

NAME = "iepf"

PARAMS: dict[str, Param] = {
    **segment_params(5),
    **BREAKPOINT_PARAMS,
    **LITERAL_CLUSTERING,
    "breakpoints": with_default(
        BREAKPOINT_PARAMS["breakpoints"], "fixed", "IEPF: fixed jump distance"
    ),
    "split_distance": Param(
        0.1, number(low=0.0, low_open=True), "split where a point is this far from the chord (m)"
    ),
    **EVENT_PARAMS,
}

PRESETS: dict[str, dict[str, Any]] = {}


def run(seq: Sequence, angle_min: float, params: Mapping[str, Any]) -> Extraction:
    """Extract features from the valid returns ``seq`` of one scan."""
    return Compiled(params).sequence(seq, angle_min)


class Compiled(CompiledMethod):
    """The method in kernel form (see :class:`~scanlines.steps.assemble.CompiledMethod`)."""

    __slots__ = ()
    name = NAME

    def arguments(self, params: Mapping[str, Any]) -> tuple[np.ndarray]:
        return (settings(params, reference="chord"),)

    @staticmethod
    def scan_kernel(*args):
        return extract_scan(*args)

    @staticmethod
    def returns_kernel(*args):
        return extract_returns(*args)


# --------------------------------------------------------------------------- the kernel


@jit
def extract_scan(ranges, valid, cos, sin, step, full_circle, angle_min, s):
    """The whole method on one scan; arrays of the result.

    ``valid`` marks the beams with a return, ``cos, sin`` are the bearing tables
    relative to beam 0. Returns ``first, last, n_points, lines, covariances,
    breakpoints, corners, outliers`` as :func:`~scanlines.steps.assemble.from_arrays`
    takes them.
    """
    index, r, x, y = valid_returns(ranges, valid, cos, sin)
    return extract_returns(index, r, x, y, ranges.shape[0], step, full_circle, angle_min, s)


# Inlined: extract_scan is its only compiled caller, and compiling it on its own would
# optimise the whole method a second time (seconds of the cold start).
@jit(inline=True)
def extract_returns(index, r, x, y, n_beams, step, full_circle, angle_min, s):
    """The whole method on the valid returns (beam ``index``, range, local ``x, y``) of a scan."""
    none = np.zeros(0, dtype=np.int64)
    if index.shape[0] == 0:
        return empty_result(none, none)
    index, r, x, y, _, start, end, breakpoints, ring = cluster_returns(
        index, r, x, y, n_beams, step, full_circle, s
    )
    table, ox, oy = prefix_moments(x, y)
    clusters = np.arange(start.shape[0])
    a, b, group = split_runs_at_farthest(
        x, y, table, ox, oy, start, end, clusters, s[SPLIT_DISTANCE], int(s[SPLIT_REFERENCE])
    )
    return finish_runs(
        index, r, x, y, n_beams, full_circle, table, ox, oy, a, b, group, True, ring,
        breakpoints, none, angle_min, s,
    )  # fmt: skip
