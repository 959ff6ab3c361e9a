"""Corner scores and candidate peaks (sec. 2.3, eq. 12-13 and Step 5 of [1]_).

A corner score is computed at every position of a cluster; its local peaks are
the corner candidates, and the threshold sweep (:mod:`scanlines.steps.select`)
decides which candidates are corners.

``slope_scores``      eq. 13: ``Dk(i) = |rho_i - rho_{i-1}| / (rho_{i-1} dtheta)
                      - |rho_{i+1} - rho_i| / (rho_i dtheta)``, the change of
                      ``tan phi`` (eq. 12) from one side of ``i`` to the other.
                      With ``signed=True`` the absolute values are left out, so a
                      corner seen symmetrically (range rising into it and falling
                      after it, as every corner of a room seen from inside) still
                      scores; as printed, such a corner scores near zero.
``turn_scores``       the angle between total-least-squares lines fitted to the
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

from scanlines._jit import kernel
from scanlines.steps.breakpoints import neighbour_steps
from scanlines.steps.fit import prefix_moments, tls_axis

__all__ = [
    "SCORES",
    "SCORE_CODES",
    "peak_positions",
    "ring_anchor",
    "slope_scores",
    "turn_scores",
    "turn_window",
]

SCORES = ("turn", "dk", "dk_signed")
SCORE_CODES = {name: code for code, name in enumerate(SCORES)}
TURN, DK, DK_SIGNED = range(3)

MAX_TURN_WINDOW = 15
"""Most points :func:`turn_window` fits on each side."""


@kernel
def interior_mask(start, end, n):
    """Mask of positions with a neighbour on both sides inside their cluster."""
    inside = np.ones(n, dtype=np.bool_)
    inside[start] = False
    inside[end] = False
    return inside


@kernel
def slope_scores(r, gap, step, start, end, signed):
    """Eq. 13 at every position (0 where a neighbour lies outside the cluster).

    ``signed`` leaves out the printed absolute values.
    """
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


@kernel
def heading(x, y, moments, a, b):
    """Unit direction of the fitted line of run ``[a, b]``, oriented from ``a`` towards ``b``."""
    nx, ny = tls_axis(moments, a, b)[:2]
    if -ny * (x[b] - x[a]) + nx * (y[b] - y[a]) >= 0.0:
        return -ny, nx
    return ny, -nx


@kernel
def turn_scores(x, y, moments, start, end, window):
    """Absolute turn (radians) between lines fitted to ``window`` points on each side.

    The line before ``p``, ``[p - w, p]``, is the line after ``p - w``: each run is
    fitted once, except the shortened ones at a cluster's ends.
    """
    n = x.shape[0]
    score = np.zeros(n)
    after_x = np.empty(n)
    after_y = np.empty(n)
    for c in range(start.shape[0]):
        for p in range(start[c], end[c] + 1):
            after_x[p], after_y[p] = heading(x, y, moments, p, min(p + window, end[c]))
        for p in range(start[c] + 1, end[c]):
            if p - window >= start[c]:
                bx, by = after_x[p - window], after_y[p - window]
            else:
                bx, by = heading(x, y, moments, start[c], p)
            ux, uy = after_x[p], after_y[p]
            score[p] = abs(math.atan2(bx * uy - by * ux, bx * ux + by * uy))
    return score


@kernel
def turn_window(x, y, index, sigma):
    """Points fitted on each side for the turn score, grown with the noise.

    A line through ``w`` points ``h`` apart with noise ``sigma`` has a direction
    error near ``sigma / (h w^1.5 / sqrt(12))``; the window is
    ``w = 3 + 6 sigma / h`` (``h`` the median spacing of adjacent beams, ``w`` in
    3..15), so that at 1 deg and 1 cm noise a short wall still has a corner score,
    and at 0.33 deg and 2 cm the score is not noise.
    """
    steps = neighbour_steps(x, y)
    adjacent = np.empty(steps.shape[0], dtype=np.bool_)
    for p in range(steps.shape[0]):
        adjacent[p] = index[p + 1] - index[p] == 1
    if not adjacent.any():
        return 3
    spacing = np.median(steps[adjacent])
    wanted = 3 + 6 * sigma / spacing if spacing > 0.0 else math.inf
    return int(round(min(max(wanted, 3.0), MAX_TURN_WINDOW)))  # noqa: RUF046 (int for numba)


@kernel
def peak_positions(score, start, end):
    """Positions ``i`` with ``|s_i| > |s_{i-1}|`` and ``|s_i| > |s_{i+1}|`` inside a cluster."""
    n = score.shape[0]
    if n < 3:
        return np.zeros(0, dtype=np.int64)
    inside = interior_mask(start, end, n)
    peak = np.zeros(n, dtype=np.bool_)
    for i in range(1, n - 1):
        here = abs(score[i])
        peak[i] = inside[i] and here > abs(score[i - 1]) and here > abs(score[i + 1])
    return np.flatnonzero(peak)


@kernel
def ring_anchor(x, y, window):
    """Position of the largest turn angle of a closed ring, scored cyclically.

    The ring is scored twice, as it is and rotated by half, and each position
    takes the score from the copy in which it lies farther from the ends.
    """
    n = x.shape[0]
    half = n // 2
    start = np.zeros(1, dtype=np.int64)
    end = np.full(1, n - 1, dtype=np.int64)
    direct = turn_scores(x, y, prefix_moments(x, y), start, end, window)
    order = np.concatenate((np.arange(half, n), np.arange(0, half)))
    turned_x, turned_y = x[order], y[order]
    moments = prefix_moments(turned_x, turned_y)
    turned = turn_scores(turned_x, turned_y, moments, start, end, window)
    best, best_score = 0, -math.inf
    for p in range(n):
        shifted = (p - half) % n
        value = direct[p]
        if min(p, n - 1 - p) < min(shifted, n - 1 - shifted):
            value = turned[shifted]
        if value > best_score:
            best, best_score = p, value
    return best
