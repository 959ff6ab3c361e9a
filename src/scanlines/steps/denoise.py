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

References
----------
.. [1] Electronics 11(11), 1759, 2022 (doi:10.3390/electronics11111759), sec. 2.1 and sec. 3.
"""

from __future__ import annotations

import math

import numpy as np

from scanlines._jit import kernel
from scanlines.steps.breakpoints import break_flags, seam_break, threshold
from scanlines.steps.clusters import cluster_bounds, cluster_ids
from scanlines.steps.returns import MAX_BRIDGED_GAP, Returns, beam_gaps, without

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


@kernel
def literal_noise(d):
    """Step 2 as written, on neighbour distances ``d`` (length n - 1): a mask of n points."""
    n = d.shape[0] + 1
    noise = np.zeros(n, dtype=np.bool_)
    for i in range(2, n - 2):
        noise[i] = d[i - 1] > d[i - 2] and d[i] > d[i + 1]
    return noise


@kernel
def isolated_noise(returns, gap, step, rule, breaks):
    """Points cut off from both neighbours that are themselves continuous (a spike).

    ``breaks`` are the :func:`~scanlines.steps.breakpoints.break_flags` of ``returns``.
    """
    _, r, x, y = returns
    n = x.shape[0]
    noise = np.zeros(n, dtype=np.bool_)
    for i in range(1, n - 1):
        if not (breaks[i - 1] and breaks[i]):
            continue
        skip_gap = gap[i - 1] + gap[i]
        if skip_gap > MAX_BRIDGED_GAP:
            continue
        d_skip = math.hypot(x[i + 1] - x[i - 1], y[i + 1] - y[i - 1])
        noise[i] = d_skip < threshold(rule, r[i - 1], r[i + 1], skip_gap, step)
    return noise


@kernel
def window_means(x, y, noise, window, breaks):
    """Step 3: noise point ``i`` and its neighbours become the mean of ``window`` points.

    The window ``[i - window//2, i - window//2 + window - 1]`` is clipped to the
    raw cluster of ``i`` (``breaks`` from the raw data), and neighbours across a
    raw break are left alone. Returns the moved coordinates.
    """
    n = x.shape[0]
    ids = cluster_ids(breaks)
    cluster_start = np.zeros(n, dtype=np.int64)
    cluster_end = np.zeros(n, dtype=np.int64)
    for p in range(1, n):
        cluster_start[p] = cluster_start[p - 1] if ids[p] == ids[p - 1] else p
    cluster_end[n - 1] = n - 1
    for p in range(n - 2, -1, -1):
        cluster_end[p] = cluster_end[p + 1] if ids[p] == ids[p + 1] else p
    sum_x = np.zeros(n + 1)
    sum_y = np.zeros(n + 1)
    for p in range(n):
        sum_x[p + 1] = sum_x[p] + x[p]
        sum_y[p + 1] = sum_y[p] + y[p]
    centres = np.flatnonzero(noise)
    mean_x = np.empty(centres.shape[0])
    mean_y = np.empty(centres.shape[0])
    for j, i in enumerate(centres):
        lo = max(i - window // 2, cluster_start[i])
        hi = min(i - window // 2 + window - 1, cluster_end[i])
        mean_x[j] = (sum_x[hi + 1] - sum_x[lo]) / (hi - lo + 1)
        mean_y[j] = (sum_y[hi + 1] - sum_y[lo]) / (hi - lo + 1)
    new_x, new_y = x.copy(), y.copy()
    # Left neighbours first, then the points, then right neighbours: where two
    # windows overlap, a point takes the mean of the noise point to its left.
    for offset in (-1, 0, 1):
        for j, i in enumerate(centres):
            target = i + offset
            if 0 <= target < n and ids[target] == ids[i]:
                new_x[target] = mean_x[j]
                new_y[target] = mean_y[j]
    return new_x, new_y


@kernel
def small_clusters(breaks, min_points, seam_joined):
    """Mask of the points of clusters with fewer than ``min_points`` returns.

    A cluster of one or two returns between two jumps is, far more often than a
    real object, a mixed pixel (a return between two surfaces) or a spurious
    echo. ``seam_joined`` counts the first and last clusters of a full circle
    whose seam is continuous as one.
    """
    ids = cluster_ids(breaks)
    sizes = np.bincount(ids)
    if seam_joined and sizes.shape[0] > 1:
        sizes[0] = sizes[-1] = sizes[0] + sizes[-1]
    out = np.empty(ids.shape[0], dtype=np.bool_)
    for p in range(ids.shape[0]):
        out[p] = sizes[ids[p]] < min_points
    return out


@kernel
def in_between_clusters(r, gap, breaks, small, margin):
    """Mask of the returns of two-return clusters that lie in depth between their neighbours.

    A mixed pixel is a return between the two surfaces of a depth jump; two of them, or one
    with the last return of the near surface cut off by the jump, make a cluster of two
    whose ranges lie between the facing returns of the clusters on either side (within
    ``margin``). A small object in front of a wall is nearer than both sides and stays.
    Only clusters whose neighbours are at most one missing beam away, and are not ``small``
    themselves, are judged.
    """
    n = r.shape[0]
    out = np.zeros(n, dtype=np.bool_)
    start, end = cluster_bounds(breaks)
    for c in range(1, start.shape[0] - 1):
        a, b = start[c], end[c]
        if b - a != 1 or small[a] or small[a - 1] or small[b + 1]:
            continue
        if gap[a - 1] > MAX_BRIDGED_GAP or gap[b] > MAX_BRIDGED_GAP:
            continue
        low = min(r[a - 1], r[b + 1]) - margin
        high = max(r[a - 1], r[b + 1]) + margin
        if low < r[a] < high and low < r[b] < high:
            out[a] = out[b] = True
    return out


@kernel
def denoise(returns, n_beams, step, full_circle, rule, kind, window, min_cluster_points, margin):
    """Steps 2-3 by ``kind`` (:data:`ISOLATED`, :data:`LITERAL` or :data:`NO_DENOISE`).

    ``window`` is the literal rule's mean-filter window, ``min_cluster_points`` the
    smallest cluster the isolated rule keeps and ``margin`` the breakpoint margin the
    two-return test allows. Returns the cleaned returns, the beams dropped as noise
    and the break flags of the cleaned returns when known (empty otherwise).
    """
    none = np.zeros(0, dtype=np.int64)
    unknown = np.zeros(0, dtype=np.bool_)
    if kind == NO_DENOISE or returns.index.shape[0] < 3:
        return returns, none, unknown
    index, _, x, y = returns
    gap = beam_gaps(index, n_beams)
    raw_breaks = break_flags(returns, gap, step, rule)
    if kind == LITERAL:
        noise = literal_noise(np.hypot(x[1:] - x[:-1], y[1:] - y[:-1]))
        if not noise.any():
            return returns, none, raw_breaks
        x, y = window_means(x, y, noise, window, raw_breaks)
        return Returns(index, np.hypot(x, y), x, y), none, unknown
    noise = isolated_noise(returns, gap, step, rule, raw_breaks)
    if min_cluster_points > 1:
        noise |= _small_or_in_between(
            returns, noise, raw_breaks, n_beams, step, full_circle, rule, min_cluster_points, margin
        )
    if not noise.any():
        return returns, none, raw_breaks
    return without(returns, noise), index[noise], unknown


@kernel
def _small_or_in_between(
    returns, noise, raw_breaks, n_beams, step, full_circle, rule, least, margin
):
    """Mask of the returns (not yet ``noise``) in clusters smaller than ``least`` once the
    noise is dropped, and, for ``least == 2``, of the two-return clusters in between."""
    kept = np.flatnonzero(~noise)
    kept_returns = without(returns, noise)
    kept_gap = beam_gaps(kept_returns.index, n_beams)
    joined = (
        full_circle and kept.shape[0] >= 3 and not seam_break(kept_returns, n_beams, step, rule)
    )
    kept_breaks = raw_breaks
    if noise.any():  # else the kept returns are all returns: same breaks
        kept_breaks = break_flags(kept_returns, kept_gap, step, rule)
    small = small_clusters(kept_breaks, least, joined)
    if least == 2:
        small |= in_between_clusters(kept_returns.r, kept_gap, kept_breaks, small, margin)
    out = np.zeros(noise.shape[0], dtype=np.bool_)
    out[kept[small]] = True
    return out
