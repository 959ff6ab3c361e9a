"""Iterative end-point fit (IEPF): split clusters at the point farthest from their chord.

Algorithm (Duda and Hart [1]_, sec. 9.2; the recursive split of Pavlidis and
Horowitz [2]_; as compared by the paper [3]_, sec. 4.3-4.5):

1. cluster the returns by a fixed jump distance (``breakpoints="fixed"``,
   ``jump_distance = 0.3`` m) -- :mod:`scanlines.steps.breakpoints`;
2. in every cluster, find the point farthest from the chord between the
   cluster's first and last point (measured to the chord as a segment, so that
   a cluster closing on itself is first cut at its far corner); if that distance
   exceeds ``split_distance``,
   split there and repeat on both parts (one vectorised pass per recursion level,
   :func:`scanlines.steps.segments.split_runs`); the split point joins the part
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
    finish,
    split_runs,
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

_NO_OUTLIERS = np.zeros(0, dtype=np.intp)


def run(seq: Sequence, angle_min: float, params: Mapping[str, Any]) -> Extraction:
    """Extract features from the valid returns ``seq`` of one scan."""
    return split_extraction(seq, angle_min, params, method=NAME, reference="chord")


def split_extraction(
    seq: Sequence,
    angle_min: float,
    params: Mapping[str, Any],
    *,
    method: str,
    reference: str,
    outliers: np.ndarray = _NO_OUTLIERS,
) -> Extraction:
    """Cluster, split every cluster recursively (``reference`` chord or fit) and assemble.

    Shared by :mod:`~scanlines.methods.iepf` and :mod:`~scanlines.methods.pdbs`.
    """
    if len(seq) == 0:
        return empty_extraction(method, params, outliers=outliers)
    seq, clusters, ring = cluster_sequence(seq, params)
    moments = Moments(seq.x, seq.y)
    a, b, group = split_runs(
        seq,
        moments,
        clusters.start,
        clusters.end,
        np.arange(len(clusters)),
        threshold=params["split_distance"],
        reference=reference,
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
        method=method,
        params=params,
    )
