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
   (0.05 m, the package's ``min_split_dist``), one vectorised pass per level
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

from collections.abc import Mapping
from typing import Any

import numpy as np

from scanlines.extraction import Extraction
from scanlines.params import Param, number, segment_params, with_default
from scanlines.steps.assemble import empty_extraction
from scanlines.steps.breakpoints import BREAKPOINT_PARAMS
from scanlines.steps.fit import Moments
from scanlines.steps.points import Sequence
from scanlines.steps.segments import (
    EVENT_PARAMS,
    LITERAL_CLUSTERING,
    cluster_sequence,
    drop_small,
    finish,
    merge_chi_square,
    split_runs,
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
    seq, outliers = _drop_outliers(seq, params["outlier_distance"], params["split_distance"])
    if len(seq) == 0:
        return empty_extraction(NAME, params, outliers=outliers)
    seq, clusters, ring = cluster_sequence(seq, params)
    moments = Moments(seq.x, seq.y)
    a, b, group = split_runs(
        seq,
        moments,
        clusters.start,
        clusters.end,
        np.arange(len(clusters)),
        threshold=params["split_distance"],
        reference="fit",
    )
    a, b, group = drop_small(
        seq, a, b, group, min_points=params["min_points"], min_length=params["min_length"]
    )
    a, b, group = merge_chi_square(
        seq,
        moments,
        a,
        b,
        group,
        range_sigma=params["range_sigma"],
        threshold=params["merge_chi2"],
    )
    return finish(
        seq,
        a,
        b,
        group,
        clusters=clusters,
        ring=ring,
        outliers=outliers,
        angle_min=angle_min,
        method=NAME,
        params=params,
    )


def _drop_outliers(
    seq: Sequence, outlier_distance: float, line_distance: float
) -> tuple[Sequence, np.ndarray]:
    """Step 1: the sequence without isolated returns, and their beams."""
    n = len(seq)
    if n < 3:
        return seq, np.zeros(0, dtype=np.intp)
    p = np.arange(n)
    one = np.clip(np.where(p == 0, 1, p - 1), 0, n - 1)
    other = np.clip(np.where(p == 0, 2, np.where(p == n - 1, n - 3, p + 1)), 0, n - 1)
    apart = (np.abs(seq.r - seq.r[one]) > outlier_distance) & (
        np.abs(seq.r - seq.r[other]) > outlier_distance
    )
    dx, dy = seq.x[other] - seq.x[one], seq.y[other] - seq.y[one]
    length = np.hypot(dx, dy)
    px, py = seq.x - seq.x[one], seq.y - seq.y[one]
    with np.errstate(invalid="ignore", divide="ignore"):
        off = np.abs(px * dy - py * dx) / length
    off = np.where(length > 0.0, off, np.hypot(px, py))
    outlier = apart & (off > line_distance)
    if not outlier.any():
        return seq, np.zeros(0, dtype=np.intp)
    return seq.subset(~outlier), seq.index[outlier]
