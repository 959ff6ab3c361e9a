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

import numpy as np

from scanlines.steps.breakpoints import Clusters
from scanlines.steps.fit import Moments, tls_lines
from scanlines.steps.points import Sequence, rotate

__all__ = [
    "SCORES",
    "corner_side",
    "peak_candidates",
    "slope_difference",
    "strongest_turn",
    "turn_angle",
]

SCORES = ("turn", "dk", "dk_signed")


def _interior(clusters: Clusters, n: int) -> np.ndarray:
    """Mask of positions with a neighbour on both sides inside their cluster."""
    inside = np.ones(n, dtype=bool)
    inside[clusters.start] = False
    inside[clusters.end] = False
    return inside


def slope_difference(seq: Sequence, clusters: Clusters, *, signed: bool = False) -> np.ndarray:
    """Eq. 13 at every position (0 where a neighbour lies outside the cluster)."""
    n = len(seq)
    score = np.zeros(n)
    if n < 3:
        return score
    r = seq.r
    with np.errstate(all="ignore"):
        slope = np.diff(r) / (r[:-1] * seq.step * seq.gap)  # tan(phi_i) between i and i+1 (eq. 12)
    if not signed:
        slope = np.abs(slope)
    inside = _interior(clusters, n)
    with np.errstate(all="ignore"):
        score[1:-1] = slope[:-1] - slope[1:]
    score[~inside] = 0.0
    return np.nan_to_num(score, nan=0.0, posinf=0.0, neginf=0.0)


def turn_angle(seq: Sequence, clusters: Clusters, window: int, moments: Moments) -> np.ndarray:
    """Absolute turn (radians) between lines fitted to ``window`` points on each side."""
    n = len(seq)
    score = np.zeros(n)
    position = np.flatnonzero(_interior(clusters, n))
    if position.size == 0:
        return score
    cluster_of = np.searchsorted(clusters.start, position, side="right") - 1
    lo = np.maximum(position - window, clusters.start[cluster_of])
    hi = np.minimum(position + window, clusters.end[cluster_of])
    before = _direction(seq, moments, lo, position)
    after = _direction(seq, moments, position, hi)
    score[position] = np.abs(np.angle(np.exp(1j * (after - before))))
    return score


def _direction(seq: Sequence, moments: Moments, a: np.ndarray, b: np.ndarray) -> np.ndarray:
    """Heading of the fitted line of each run ``[a, b]``, oriented from ``a`` towards ``b``."""
    alpha = tls_lines(moments, a, b).alpha
    ux, uy = -np.sin(alpha), np.cos(alpha)
    forward = ux * (seq.x[b] - seq.x[a]) + uy * (seq.y[b] - seq.y[a]) >= 0.0
    return np.where(forward, alpha + np.pi / 2, alpha - np.pi / 2)


def peak_candidates(score: np.ndarray, clusters: Clusters) -> np.ndarray:
    """Positions ``i`` with ``|s_i| > |s_{i-1}|`` and ``|s_i| > |s_{i+1}|`` inside a cluster."""
    n = score.shape[0]
    if n < 3:
        return np.zeros(0, dtype=np.intp)
    magnitude = np.abs(score)
    peak = np.zeros(n, dtype=bool)
    peak[1:-1] = (magnitude[1:-1] > magnitude[:-2]) & (magnitude[1:-1] > magnitude[2:])
    peak &= _interior(clusters, n)
    return np.flatnonzero(peak)


def corner_side(score: np.ndarray, candidates: np.ndarray) -> np.ndarray:
    """The paper's position rule: -1 if the corner lies between ``i-1`` and ``i``, else +1.

    ``|Dk(i) - Dk(i-1)| < |Dk(i) - Dk(i+1)|`` puts the corner before ``i``.
    """
    s = score
    i = candidates
    before = np.abs(s[i] - s[i - 1]) < np.abs(s[i] - s[i + 1])
    return np.where(before, -1, 1)


def strongest_turn(seq: Sequence, window: int) -> int:
    """Position of the largest turn angle of a closed ring, scored cyclically.

    The ring is scored twice, as it is and rotated by half, and each position
    takes the score from the copy in which it lies farther from the ends.
    """
    n = len(seq)
    half = n // 2
    whole = Clusters(np.array([0]), np.array([n - 1]), np.zeros(0, dtype=np.intp))
    direct = turn_angle(seq, whole, window, Moments(seq.x, seq.y))
    turned_seq = rotate(seq, half)
    turned = turn_angle(turned_seq, whole, window, Moments(turned_seq.x, turned_seq.y))
    p = np.arange(n)
    shifted = (p - half) % n
    nearer_end = np.minimum(p, n - 1 - p) >= np.minimum(shifted, n - 1 - shifted)
    return int(np.argmax(np.where(nearer_end, direct, turned[shifted])))
