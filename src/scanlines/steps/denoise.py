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
``N`` points centred on it (:func:`replace_by_window_mean`). The window never
spans a pair of returns that the raw breakpoint test separates, so smoothing
cannot move a breakpoint. The default instead drops an isolated point (it then
counts as one missing beam, which clustering bridges): no point is invented.

References
----------
.. [1] Electronics 11(11), 1759, 2022 (doi:10.3390/electronics11111759), sec. 2.1 and sec. 3.
"""

from __future__ import annotations

import math

import numpy as np

from scanlines.steps.breakpoints import (
    MAX_BRIDGED_GAP,
    BreakpointRule,
    thresholds,
)
from scanlines.steps.points import Sequence

__all__ = [
    "MIN_NOISE_SIGMA",
    "estimate_noise",
    "isolated_noise",
    "literal_noise",
    "replace_by_window_mean",
    "run_ids",
    "small_clusters",
]


def literal_noise(d: np.ndarray) -> np.ndarray:
    """Step 2 as written, on neighbour distances ``d`` (length n - 1): a mask of n points."""
    n = d.shape[0] + 1
    noise = np.zeros(n, dtype=bool)
    if n >= 5:
        i = np.arange(2, n - 2)
        noise[i] = (d[i - 1] > d[i - 2]) & (d[i] > d[i + 1])
    return noise


def isolated_noise(seq: Sequence, rule: BreakpointRule, breaks: np.ndarray) -> np.ndarray:
    """Points cut off from both neighbours that are themselves continuous (a spike).

    ``breaks`` is :func:`~scanlines.steps.breakpoints.is_break` of ``seq``.
    """
    n = len(seq)
    noise = np.zeros(n, dtype=bool)
    if n < 3:
        return noise
    centre = np.flatnonzero(breaks[:-1] & breaks[1:]) + 1
    if centre.size == 0:
        return noise
    skip_gap = seq.gap[centre - 1] + seq.gap[centre]
    before, after = centre - 1, centre + 1
    d_skip = np.hypot(seq.x[after] - seq.x[before], seq.y[after] - seq.y[before])
    limit = thresholds(rule, seq.r[before], seq.r[after], skip_gap, seq.step)
    noise[centre] = (skip_gap <= MAX_BRIDGED_GAP) & (d_skip < limit)
    return noise


def run_ids(breaks: np.ndarray) -> np.ndarray:
    """Cluster number of every position, given the break flags between positions."""
    return np.r_[0, np.cumsum(breaks)]


def replace_by_window_mean(
    seq: Sequence, noise: np.ndarray, window: int, breaks: np.ndarray
) -> Sequence:
    """Step 3: noise point ``i`` and its neighbours become the mean of ``window`` points.

    The window ``[i - window//2, i - window//2 + window - 1]`` is clipped to the
    raw cluster of ``i`` (``breaks`` from the raw data), and neighbours across a
    raw break are left alone.
    """
    centres = np.flatnonzero(noise)
    if centres.size == 0:
        return seq
    ids = run_ids(breaks)
    bounds = np.flatnonzero(np.r_[True, np.diff(ids) != 0, True])
    cluster_start, cluster_end = bounds[:-1], bounds[1:] - 1
    c = ids[centres]
    lo = np.maximum(centres - window // 2, cluster_start[c])
    hi = np.minimum(centres - window // 2 + window - 1, cluster_end[c])
    sum_x, sum_y = np.r_[0.0, np.cumsum(seq.x)], np.r_[0.0, np.cumsum(seq.y)]
    count = hi - lo + 1
    mean_x = (sum_x[hi + 1] - sum_x[lo]) / count
    mean_y = (sum_y[hi + 1] - sum_y[lo]) / count
    x, y = seq.x.copy(), seq.y.copy()
    for offset in (-1, 0, 1):
        target = centres + offset
        inside = (target >= 0) & (target < len(seq))
        inside[inside] &= ids[target[inside]] == c[inside]
        x[target[inside]] = mean_x[inside]
        y[target[inside]] = mean_y[inside]
    return seq.with_points(x, y)


MIN_NOISE_SIGMA = 1e-3
"""Floor (metres) of the estimated noise: ranges logged to 1 mm or 1 cm carry at
least this much quantisation noise, and a noise-free simulation must not make
the criterion divide by zero."""


def estimate_noise(seq: Sequence, cluster_start: np.ndarray, cluster_end: np.ndarray) -> float:
    """Robust range-noise estimate from the scan itself, in metres.

    On a smooth surface the second difference of three consecutive ranges,
    ``r_{i+1} - 2 r_i + r_{i-1}``, is noise with standard deviation ``sigma sqrt(6)``
    (its geometric part, ``r'' dtheta^2``, is far smaller at the resolutions of
    real scanners); the median absolute value, robust to the few corners and
    edges, gives ``sigma``. Triples across a missing beam or a cluster end are
    left out.
    """
    n = len(seq)
    interior = np.ones(n, dtype=bool)
    interior[cluster_start] = False
    interior[cluster_end] = False
    if n >= 2:
        interior[1:-1] &= (seq.gap[:-1] == 1) & (seq.gap[1:] == 1)
    i = np.flatnonzero(interior)
    if i.size < 3:
        return MIN_NOISE_SIGMA
    second = np.abs(seq.r[i + 1] - 2.0 * seq.r[i] + seq.r[i - 1])
    sigma = float(np.median(second)) / (0.6745 * math.sqrt(6.0))
    return max(sigma, MIN_NOISE_SIGMA)


def small_clusters(breaks: np.ndarray, min_points: int, *, seam_joined: bool = False) -> np.ndarray:
    """Mask of the points of clusters with fewer than ``min_points`` returns.

    A cluster of one or two returns between two jumps is, far more often than a
    real object, a mixed pixel (a return between two surfaces) or a spurious
    echo. ``seam_joined`` counts the first and last clusters of a full circle
    whose seam is continuous as one.
    """
    n = breaks.shape[0] + 1
    ids = run_ids(breaks)
    sizes = np.bincount(ids)
    if seam_joined and sizes.size > 1:
        sizes[0] = sizes[-1] = sizes[0] + sizes[-1]
    return sizes[ids] < min_points if n else np.zeros(0, dtype=bool)
