"""Split-and-merge with a chi-square merge, after laser_line_extraction.

Algorithm (Pavlidis and Horowitz [1]_, as described by Nguyen et al. [2]_; the
parameters and their meaning as documented by the ROS package
laser_line_extraction [3]_):

1. outlier filter: a return whose range differs by more than ``outlier_distance``
   from both neighbours' and that lies farther than ``split_distance`` from the
   line through them is dropped (reported as an outlier); at the ends of the
   scan the two neighbours on one side are used;
2. clustering by a fixed jump distance: ``breakpoints="fixed"`` with
   ``jump_distance = 0.4`` m, the package's ``max_line_gap`` (points of one line
   are never farther apart);
3. split: fit a total-least-squares line to each run, split at the interior
   point farthest from it while that distance exceeds ``split_distance``
   (0.05 m, the package's ``min_split_dist``)
   (:func:`scanlines.steps.segments.split_runs`, ``reference="fit"``); the split
   point joins the part whose line it is nearer, so no point is lost;
4. filter: runs with fewer than ``min_points`` (9, ``min_line_points``) points or
   shorter than ``min_length`` (0.5 m, ``min_line_length``) are dropped, as the
   package does before merging (the line of a fragment of a few returns is
   mostly noise, and its first-order covariance understates that, so a fragment
   left between two halves of a wall would keep them apart);
5. merge: neighbouring runs of one cluster whose ``(rho, alpha)`` agree,
   ``dL^T (P_1 + P_2)^-1 dL < merge_chi2`` (3, the package's bound), with
   covariances propagated from ``range_sigma`` (0.02 m, the package's
   ``range_std_dev``) and the angle difference wrapped to ``(-pi, pi]``; the most
   similar pair first, refitted over everything from the first's start to the
   second's end (returns of a dropped fragment between them included), until
   none passes (:func:`scanlines.steps.segments.merge_chi_square`);
6. corners by the shared rule of :func:`scanlines.steps.segments.segment_events`,
   breakpoints from step 2.

Differences from the package, on purpose: its split drops the point before the
split and the last point of every part (no point is lost here, and a merged
line takes the returns between its parts); its merge compares angles without
wrapping, so two halves of a wall seen at ``alpha`` near ``+-pi`` never merge
(wrapped here); it merges across gaps (here only within a cluster, which keeps
the breakpoints consistent with the segments); it merges left to right (here
the most similar pair first); its lines come from Pfister et al.'s weighted fit
with bearing noise (total least squares and range noise only, here); its
``min_range`` is the scan's ``range_min``.

References
----------
.. [1] T. Pavlidis and S. L. Horowitz, "Segmentation of plane curves", IEEE
   Trans. Computers C-23(8), 860-870, 1974.
.. [2] V. Nguyen, A. Martinelli, N. Tomatis and R. Siegwart, "A comparison of
   line extraction algorithms using 2D laser rangefinder for indoor mobile
   robotics", IEEE/RSJ IROS 2005.
.. [3] M. Gallant, laser_line_extraction (ROS package),
   https://github.com/kam3k/laser_line_extraction, README "Parameters".
"""

from __future__ import annotations

import math
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
    MERGE_CHI2,
    MIN_LENGTH,
    MIN_POINTS,
    OUTLIER_DISTANCE,
    RANGE_SIGMA,
    SPLIT_DISTANCE,
    SPLIT_REFERENCE,
    cluster_returns,
    drop_small_runs,
    finish_runs,
    merge_runs_chi_square,
    settings,
    split_runs_at_farthest,
    valid_returns,
)

NAME = "split_merge"

PARAMS: dict[str, Param] = {
    **segment_params(9, min_length=0.5, range_sigma=0.02),
    **BREAKPOINT_PARAMS,
    **LITERAL_CLUSTERING,
    "breakpoints": with_default(
        BREAKPOINT_PARAMS["breakpoints"], "fixed", "split-and-merge: fixed, max_line_gap"
    ),
    "jump_distance": Param(
        0.4,
        BREAKPOINT_PARAMS["jump_distance"].check,
        "fixed rule: largest neighbour distance, metres (laser_line_extraction max_line_gap)",
    ),
    "split_distance": Param(
        0.05,
        number(low=0.0, low_open=True),
        "split where a point is this far from the run's fitted line (m; min_split_dist)",
    ),
    "outlier_distance": Param(
        0.05,
        number(low=0.0, low_open=True),
        "outlier: range difference to both neighbours (m; outlier_dist)",
    ),
    "merge_chi2": Param(
        3.0, number(low=0.0), "merge neighbours while chi-square of (rho, alpha) is below this"
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
        return (settings(params, reference="fit"),)

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
    index, r, x, y, outliers = _drop_outliers(
        index, r, x, y, s[OUTLIER_DISTANCE], s[SPLIT_DISTANCE]
    )
    if index.shape[0] == 0:
        return empty_result(np.zeros(0, dtype=np.int64), outliers)
    index, r, x, y, _, start, end, breakpoints, ring = cluster_returns(
        index, r, x, y, n_beams, step, full_circle, s
    )
    table, ox, oy = prefix_moments(x, y)
    clusters = np.arange(start.shape[0])
    a, b, group = split_runs_at_farthest(
        x, y, table, ox, oy, start, end, clusters, s[SPLIT_DISTANCE], int(s[SPLIT_REFERENCE])
    )
    a, b, group = drop_small_runs(x, y, a, b, group, s[MIN_POINTS], s[MIN_LENGTH])
    a, b, group = merge_runs_chi_square(
        x, y, r, table, ox, oy, a, b, group, s[RANGE_SIGMA], s[MERGE_CHI2]
    )
    return finish_runs(
        index, r, x, y, n_beams, full_circle, table, ox, oy, a, b, group, True, ring,
        breakpoints, outliers, angle_min, s,
    )  # fmt: skip


@jit
def _drop_outliers(index, r, x, y, outlier_distance: float, line_distance: float):
    """Step 1: the returns without isolated ones, and the beams of those dropped.

    A return is isolated when its range differs by more than
    ``outlier_distance`` from both neighbours' and it lies farther than
    ``line_distance`` from the line through them (at the ends of the scan, the
    two neighbours on one side).
    """
    n = index.shape[0]
    if n < 3:
        return index, r, x, y, np.zeros(0, dtype=np.int64)
    outlier = np.zeros(n, dtype=np.bool_)
    for p in range(n):
        one = 1 if p == 0 else p - 1
        other = 2 if p == 0 else (n - 3 if p == n - 1 else p + 1)
        apart = abs(r[p] - r[one]) > outlier_distance and abs(r[p] - r[other]) > outlier_distance
        if not apart:
            continue
        dx, dy = x[other] - x[one], y[other] - y[one]
        px, py = x[p] - x[one], y[p] - y[one]
        length = math.hypot(dx, dy)
        off = abs(px * dy - py * dx) / length if length > 0.0 else math.hypot(px, py)
        outlier[p] = off > line_distance
    dropped = np.flatnonzero(outlier)
    if dropped.shape[0] == 0:
        return index, r, x, y, dropped
    kept = np.flatnonzero(~outlier)
    return index[kept], r[kept], x[kept], y[kept], index[dropped]
