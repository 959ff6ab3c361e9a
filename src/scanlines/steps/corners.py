"""Corner scores and candidate peaks (sec. 2.3, eq. 12-13 and Step 5 of [1]_).

A corner score is computed at every position of a cluster; its local peaks are
the corner candidates, and the threshold sweep (:mod:`scanlines.steps.select`)
decides which candidates are corners.

``slope_difference``  eq. 13: ``Dk(i) = |rho_i - rho_{i-1}| / (rho_{i-1} dtheta)
                      - |rho_{i+1} - rho_i| / (rho_i dtheta)``, the change of
                      ``tan phi`` (eq. 12) from one side of ``i`` to the other.
                      With ``signed=True`` the absolute values are left out, so a
                      corner seen symmetrically (range rising into it and falling
                      after it, as every corner of a room seen from inside) still
                      scores; as printed, such a corner scores near zero.
``turn_angle``        the angle between total-least-squares lines fitted to the
                      ``w`` points before and after ``i``: the same slope change,
                      measured on fitted local slopes so that one noisy range
                      cannot dominate it (at 0.33 deg and 1 cm noise the two
                      neighbour slopes of eq. 13 carry errors near 1).

References
----------
.. [1] Electronics 11(11), 1759, 2022 (doi:10.3390/electronics11111759).
"""

from __future__ import annotations

import math

import numpy as np

from scanlines._jit import jit
from scanlines.steps.breakpoints import Clusters
from scanlines.steps.fit import Moments, prefix_moments, tls_axis
from scanlines.steps.points import Sequence

__all__ = [
    "SCORES",
    "corner_side",
    "peak_candidates",
    "slope_difference",
    "strongest_turn",
    "turn_angle",
]

SCORES = ("turn", "dk", "dk_signed")


@jit
def interior_mask(start: np.ndarray, end: np.ndarray, n: int) -> np.ndarray:
    """Mask of positions with a neighbour on both sides inside their cluster."""
    inside = np.ones(n, dtype=np.bool_)
    inside[start] = False
    inside[end] = False
    return inside


@jit
def slope_scores(r, gap, step: float, start, end, signed: bool) -> np.ndarray:
    """Kernel of :func:`slope_difference`."""
    n = r.shape[0]
    score = np.zeros(n)
    if n < 3:
        return score
    slope = np.empty(n - 1)
    for i in range(n - 1):
        # tan(phi_i) between i and i+1 (eq. 12); a zero range gives no slope (score 0)
        denominator = r[i] * step * gap[i]
        slope[i] = (r[i + 1] - r[i]) / denominator if denominator != 0.0 else math.nan
        if not signed:
            slope[i] = abs(slope[i])
    inside = interior_mask(start, end, n)
    for i in range(1, n - 1):
        value = slope[i - 1] - slope[i]
        if inside[i] and math.isfinite(value):
            score[i] = value
    return score


def slope_difference(seq: Sequence, clusters: Clusters, *, signed: bool = False) -> np.ndarray:
    """Eq. 13 at every position (0 where a neighbour lies outside the cluster)."""
    return slope_scores(seq.r, seq.gap, seq.step, clusters.start, clusters.end, signed)


@jit(inline=True)
def heading(x, y, table, a: int, b: int) -> tuple[float, float]:
    """Unit direction of the fitted line of run ``[a, b]``, oriented from ``a`` towards ``b``."""
    nx, ny = tls_axis(table, a, b)[:2]
    if -ny * (x[b] - x[a]) + nx * (y[b] - y[a]) >= 0.0:
        return -ny, nx
    return ny, -nx


@jit
def turn_scores(x, y, table, start, end, window: int) -> np.ndarray:
    """Kernel of :func:`turn_angle`.

    The line before ``p``, ``[p - w, p]``, is the line after ``p - w``: each run is
    fitted once, except the shortened ones at a cluster's ends.
    """
    n = x.shape[0]
    score = np.zeros(n)
    after_x = np.empty(n)
    after_y = np.empty(n)
    for c in range(start.shape[0]):
        for p in range(start[c], end[c] + 1):
            after_x[p], after_y[p] = heading(x, y, table, p, min(p + window, end[c]))
        for p in range(start[c] + 1, end[c]):
            if p - window >= start[c]:
                bx, by = after_x[p - window], after_y[p - window]
            else:
                bx, by = heading(x, y, table, start[c], p)
            ux, uy = after_x[p], after_y[p]
            score[p] = abs(math.atan2(bx * uy - by * ux, bx * ux + by * uy))
    return score


def turn_angle(seq: Sequence, clusters: Clusters, window: int, moments: Moments) -> np.ndarray:
    """Absolute turn (radians) between lines fitted to ``window`` points on each side."""
    return turn_scores(seq.x, seq.y, moments.table, clusters.start, clusters.end, int(window))


@jit
def peak_positions(score: np.ndarray, start: np.ndarray, end: np.ndarray) -> np.ndarray:
    """Kernel of :func:`peak_candidates`."""
    n = score.shape[0]
    if n < 3:
        return np.zeros(0, dtype=np.int64)
    inside = interior_mask(start, end, n)
    peak = np.zeros(n, dtype=np.bool_)
    for i in range(1, n - 1):
        here = abs(score[i])
        peak[i] = inside[i] and here > abs(score[i - 1]) and here > abs(score[i + 1])
    return np.flatnonzero(peak)


def peak_candidates(score: np.ndarray, clusters: Clusters) -> np.ndarray:
    """Positions ``i`` with ``|s_i| > |s_{i-1}|`` and ``|s_i| > |s_{i+1}|`` inside a cluster."""
    return peak_positions(np.asarray(score, dtype=np.float64), clusters.start, clusters.end)


def corner_side(score: np.ndarray, candidates: np.ndarray) -> np.ndarray:
    """The paper's position rule: -1 if the corner lies between ``i-1`` and ``i``, else +1.

    ``|Dk(i) - Dk(i-1)| < |Dk(i) - Dk(i+1)|`` puts the corner before ``i``.
    """
    s = score
    i = candidates
    before = np.abs(s[i] - s[i - 1]) < np.abs(s[i] - s[i + 1])
    return np.where(before, -1, 1)


@jit
def ring_anchor(x: np.ndarray, y: np.ndarray, window: int) -> int:
    """Position of the largest turn angle of a closed ring, scored cyclically.

    The ring is scored twice, as it is and rotated by half, and each position
    takes the score from the copy in which it lies farther from the ends.
    """
    n = x.shape[0]
    half = n // 2
    start = np.zeros(1, dtype=np.int64)
    end = np.full(1, n - 1, dtype=np.int64)
    direct = turn_scores(x, y, prefix_moments(x, y)[0], start, end, window)
    order = np.concatenate((np.arange(half, n), np.arange(0, half)))
    turned_x, turned_y = x[order], y[order]
    table = prefix_moments(turned_x, turned_y)[0]
    turned = turn_scores(turned_x, turned_y, table, start, end, window)
    best, best_score = 0, -math.inf
    for p in range(n):
        shifted = (p - half) % n
        value = direct[p]
        if min(p, n - 1 - p) < min(shifted, n - 1 - shifted):
            value = turned[shifted]
        if value > best_score:
            best, best_score = p, value
    return best


def strongest_turn(seq: Sequence, window: int) -> int:
    """Position of the largest turn angle of a closed ring (see :func:`ring_anchor`)."""
    return int(ring_anchor(seq.x, seq.y, int(window)))
