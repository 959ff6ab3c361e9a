"""Denoising before breakpoint detection (Steps 2-3, eq. 5 and 20 of [1]_).

Two readings of the paper's isolated-noise rule:

``literal_noise``  Step 2 as written: point ``i`` is noise when ``d_{i-1} > d_{i-2}``
                   and ``d_i > d_{i+1}``. On real scans this fires on a large share
                   of ordinary points (any local bump of the neighbour distance).
``isolated_noise`` the tighter reading used by default: point ``i`` is noise when
                   the breakpoint test separates it from *both* neighbours while
                   those two neighbours pass the test with each other (a spike
                   that would otherwise form a one-point cluster).

Step 3 replaces a noise point and its two neighbours by the mean of a window of
``N`` points centred on it (:func:`window_means`). The window never
spans a pair of returns that the raw breakpoint test separates, so smoothing
cannot move a breakpoint. The default instead drops an isolated point (it then
counts as one missing beam, which clustering bridges): no point is invented. It
also drops single-return clusters and two-return clusters that lie in depth between
their neighbours (mixed pixels); :func:`denoise` is the whole stage.

The kernels are C++ (``cpp/scanlines/steps/denoise.cpp``), called by the adaptive
method's kernel; the functions here call their bindings.

References
----------
.. [1] Electronics 11(11), 1759, 2022 (doi:10.3390/electronics11111759), sec. 2.1 and sec. 3.
"""

from __future__ import annotations

import numpy as np

from scanlines import _core
from scanlines.steps.arrays import bools, float64s, int64s
from scanlines.steps.breakpoints import BreakpointRule
from scanlines.steps.returns import Returns

__all__ = [
    "DENOISE",
    "DENOISE_CODES",
    "ISOLATED",
    "LITERAL",
    "NO_DENOISE",
    "denoise",
    "in_between_clusters",
    "isolated_noise",
    "literal_noise",
    "small_clusters",
    "window_means",
]

DENOISE = ("isolated", "paper", "none")
DENOISE_CODES = {name: code for code, name in enumerate(DENOISE)}
ISOLATED, LITERAL, NO_DENOISE = range(3)


def literal_noise(d) -> np.ndarray:
    """Step 2 as written, on neighbour distances ``d`` (length n - 1): a mask of n points."""
    return _core.literal_noise(float64s(d))


def isolated_noise(returns: Returns, gap, step: float, rule: BreakpointRule, breaks) -> np.ndarray:
    """Points cut off from both neighbours that are themselves continuous (a spike).

    ``breaks`` are the :func:`~scanlines.steps.breakpoints.break_flags` of ``returns``;
    the two neighbours must be at most two beams apart (no beam missing beside the point).
    """
    return _core.isolated_noise(
        _returns(returns), int64s(gap), float(step), tuple(rule), bools(breaks)
    )


def window_means(x, y, noise, window: int, breaks) -> tuple[np.ndarray, np.ndarray]:
    """Step 3: noise point ``i`` and its neighbours become the mean of ``window`` points.

    The window ``[i - window//2, i - window//2 + window - 1]`` is clipped to the
    raw cluster of ``i`` (``breaks`` from the raw data), and neighbours across a
    raw break are left alone. Left neighbours are moved first, then the points, then
    right neighbours: where two windows overlap, a point takes the mean of the noise
    point to its left. Returns the moved coordinates.
    """
    return _core.window_means(float64s(x), float64s(y), bools(noise), int(window), bools(breaks))


def small_clusters(breaks, min_points: int, seam_joined: bool) -> np.ndarray:
    """Mask of the points of clusters with fewer than ``min_points`` returns.

    A cluster of one or two returns between two jumps is, far more often than a
    real object, a mixed pixel (a return between two surfaces) or a spurious
    echo. ``seam_joined`` counts the first and last clusters of a full circle
    whose seam is continuous as one.
    """
    return _core.small_clusters(bools(breaks), int(min_points), bool(seam_joined))


def in_between_clusters(r, gap, breaks, small, margin: float) -> np.ndarray:
    """Mask of the returns of two-return clusters that lie in depth between their neighbours.

    A mixed pixel is a return between the two surfaces of a depth jump; two of them, or one
    with the last return of the near surface cut off by the jump, make a cluster of two
    whose ranges lie between the facing returns of the clusters on either side (within
    ``margin``). A small object in front of a wall is nearer than both sides and stays.
    Only clusters whose neighbours are at most one missing beam away, and are not ``small``
    themselves, are judged.
    """
    return _core.in_between_clusters(
        float64s(r), int64s(gap), bools(breaks), bools(small), float(margin)
    )


def denoise(returns: Returns, n_beams: int, step: float, full_circle: bool,
            rule: BreakpointRule, kind: int, window: int, min_cluster_points: int,
            margin: float) -> tuple[Returns, np.ndarray, np.ndarray]:  # fmt: skip
    """Steps 2-3 by ``kind`` (:data:`ISOLATED`, :data:`LITERAL` or :data:`NO_DENOISE`).

    ``window`` is the literal rule's mean-filter window, ``min_cluster_points`` the
    smallest cluster the isolated rule keeps and ``margin`` the breakpoint margin the
    two-return test allows. Returns the cleaned returns, the beams dropped as noise
    and the break flags of the cleaned returns when known (empty otherwise).

    The isolated rule drops the spikes, then (with ``min_cluster_points > 1``) the returns
    of clusters smaller than that once the spikes are gone (the breakpoint test redone
    without them) and, with ``min_cluster_points == 2``, of the two-return clusters in
    between (:func:`in_between_clusters`).
    """
    cleaned, outliers, breaks = _core.denoise(
        _returns(returns), int(n_beams), float(step), bool(full_circle), tuple(rule),
        int(kind), int(window), int(min_cluster_points), float(margin),
    )  # fmt: skip
    return Returns(*cleaned), outliers, breaks


def _returns(returns: Returns) -> tuple[np.ndarray, ...]:
    index, r, x, y = returns
    return int64s(index), float64s(r), float64s(x), float64s(y)
