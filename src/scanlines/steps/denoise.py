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

from scanlines._jit import jit
from scanlines.steps.breakpoints import MAX_BRIDGED_GAP, BreakpointRule, cluster_bounds, threshold
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


@jit
def literal_noise(d: np.ndarray) -> np.ndarray:
    """Step 2 as written, on neighbour distances ``d`` (length n - 1): a mask of n points."""
    n = d.shape[0] + 1
    noise = np.zeros(n, dtype=np.bool_)
    for i in range(2, n - 2):
        noise[i] = d[i - 1] > d[i - 2] and d[i] > d[i + 1]
    return noise


@jit
def isolated_noise_mask(x, y, r, gap, step: float, rule: np.ndarray, breaks) -> np.ndarray:
    """Kernel of :func:`isolated_noise` on the sequence's arrays."""
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


def isolated_noise(seq: Sequence, rule: BreakpointRule, breaks: np.ndarray) -> np.ndarray:
    """Points cut off from both neighbours that are themselves continuous (a spike).

    ``breaks`` is :func:`~scanlines.steps.breakpoints.is_break` of ``seq``.
    """
    return isolated_noise_mask(
        seq.x, seq.y, seq.r, seq.gap, seq.step, rule.as_array(), np.asarray(breaks, dtype=np.bool_)
    )


@jit
def run_ids(breaks: np.ndarray) -> np.ndarray:
    """Cluster number of every position, given the break flags between positions."""
    ids = np.zeros(breaks.shape[0] + 1, dtype=np.int64)
    for p in range(breaks.shape[0]):
        ids[p + 1] = ids[p] + breaks[p]
    return ids


@jit
def window_means(x, y, noise, window: int, breaks) -> tuple[np.ndarray, np.ndarray]:
    """Kernel of :func:`replace_by_window_mean`: the moved coordinates."""
    n = x.shape[0]
    ids = run_ids(breaks)
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


def replace_by_window_mean(
    seq: Sequence, noise: np.ndarray, window: int, breaks: np.ndarray
) -> Sequence:
    """Step 3: noise point ``i`` and its neighbours become the mean of ``window`` points.

    The window ``[i - window//2, i - window//2 + window - 1]`` is clipped to the
    raw cluster of ``i`` (``breaks`` from the raw data), and neighbours across a
    raw break are left alone.
    """
    if not np.any(noise):
        return seq
    x, y = window_means(
        seq.x, seq.y, np.asarray(noise, dtype=np.bool_), int(window), np.asarray(breaks, bool)
    )
    return seq.with_points(x, y)


MIN_NOISE_SIGMA = 1e-3
"""Floor (metres) of the estimated noise: ranges logged to 1 mm or 1 cm carry at
least this much quantisation noise, and a noise-free simulation must not make
the criterion divide by zero."""


@jit
def noise_from_ranges(r, gap, cluster_start, cluster_end) -> float:
    """Kernel of :func:`estimate_noise`."""
    n = r.shape[0]
    interior = np.ones(n, dtype=np.bool_)
    interior[cluster_start] = False
    interior[cluster_end] = False
    second = np.empty(n)
    count = 0
    for i in range(1, n - 1):
        if interior[i] and gap[i - 1] == 1 and gap[i] == 1:
            second[count] = abs(r[i + 1] - 2.0 * r[i] + r[i - 1])
            count += 1
    if count < 3:
        return MIN_NOISE_SIGMA
    sigma = np.median(second[:count]) / (0.6745 * math.sqrt(6.0))
    return max(sigma, MIN_NOISE_SIGMA)


@jit
def chord_samples(x, y, r, gap, cluster_start, cluster_end) -> tuple[np.ndarray, np.ndarray]:
    """Range-noise samples from chords, and the range of each: ``(sample, at)``.

    Each interior return ``P_i`` with neighbours on both sides gives one sample: its
    distance from the chord ``P_{i-1} P_{i+1}`` over ``sqrt(1.5) cos(beta)`` (``beta`` the
    angle between its beam and the chord's normal; only ``beta`` < 60 deg). On a straight
    surface that distance is noise alone, at any incidence and resolution, where the
    second difference of the ranges also holds the surface's geometry (at 1 deg, on
    slanted walls far away, as much as the noise).
    """
    n = r.shape[0]
    interior = np.ones(n, dtype=np.bool_)
    interior[cluster_start] = False
    interior[cluster_end] = False
    sample = np.empty(n)
    at = np.empty(n)
    count = 0
    for i in range(1, n - 1):
        if not (interior[i] and gap[i - 1] == 1 and gap[i] == 1):
            continue
        cx, cy = x[i + 1] - x[i - 1], y[i + 1] - y[i - 1]
        length = math.hypot(cx, cy)
        if length == 0.0 or r[i] <= 0.0:
            continue
        nx, ny = -cy / length, cx / length
        cos_beta = abs(nx * x[i] + ny * y[i]) / r[i]
        if cos_beta < MIN_CHORD_COS:
            continue
        off = abs((x[i] - x[i - 1]) * nx + (y[i] - y[i - 1]) * ny)
        sample[count] = off / (cos_beta * math.sqrt(1.5))
        at[count] = r[i]
        count += 1
    return sample[:count], at[:count]


@jit
def noise_growth(x, y, r, gap, cluster_start, cluster_end) -> tuple[float, float, float]:
    """How the range noise grows with range: ``(sigma_far, slope, far_range)``.

    The samples of :func:`chord_samples` are split at their median range; the robust
    noise of each half and the median range of each half give a line
    ``sigma(r) = sigma_far + slope (r - far_range)`` (``slope >= 0``, 0 when the noise does
    not grow, as on sensors with a constant range error).
    """
    sample, at = chord_samples(x, y, r, gap, cluster_start, cluster_end)
    if sample.shape[0] < 6:
        return 0.0, 0.0, 0.0
    middle = np.median(at)
    near, far = at <= middle, at > middle
    if not far.any():
        return 0.0, 0.0, 0.0
    sigma_near, sigma_far = np.median(sample[near]) / 0.6745, np.median(sample[far]) / 0.6745
    near_range, far_range = np.median(at[near]), np.median(at[far])
    if far_range <= near_range:
        return 0.0, 0.0, 0.0
    return sigma_far, max((sigma_far - sigma_near) / (far_range - near_range), 0.0), far_range


MIN_CHORD_COS = 0.5
"""Chord samples of :func:`noise_growth` come from surfaces within 60 deg of facing the beam."""


def estimate_noise(seq: Sequence, cluster_start: np.ndarray, cluster_end: np.ndarray) -> float:
    """Robust range-noise estimate from the scan itself, in metres.

    On a smooth surface the second difference of three consecutive ranges,
    ``r_{i+1} - 2 r_i + r_{i-1}``, is noise with standard deviation ``sigma sqrt(6)``
    (its geometric part, ``r'' dtheta^2``, is far smaller at the resolutions of
    real scanners); the median absolute value, robust to the few corners and
    edges, gives ``sigma``. Triples across a missing beam or a cluster end are
    left out.
    """
    if len(seq) == 0:
        return MIN_NOISE_SIGMA
    return float(
        noise_from_ranges(
            seq.r,
            seq.gap,
            np.asarray(cluster_start, dtype=np.int64),
            np.asarray(cluster_end, dtype=np.int64),
        )
    )


@jit
def small_clusters(breaks: np.ndarray, min_points: int, seam_joined: bool = False) -> np.ndarray:
    """Mask of the points of clusters with fewer than ``min_points`` returns.

    A cluster of one or two returns between two jumps is, far more often than a
    real object, a mixed pixel (a return between two surfaces) or a spurious
    echo. ``seam_joined`` counts the first and last clusters of a full circle
    whose seam is continuous as one.
    """
    ids = run_ids(breaks)
    sizes = np.bincount(ids)
    if seam_joined and sizes.shape[0] > 1:
        sizes[0] = sizes[-1] = sizes[0] + sizes[-1]
    out = np.empty(ids.shape[0], dtype=np.bool_)
    for p in range(ids.shape[0]):
        out[p] = sizes[ids[p]] < min_points
    return out


@jit
def in_between_clusters(r, gap, breaks, small, margin: float) -> np.ndarray:
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
