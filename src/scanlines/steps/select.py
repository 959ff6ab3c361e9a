"""The threshold sweep over ``dkth`` and its selection criterion (Steps 5-7 of [1]_).

For each threshold the clusters are cut at the candidates scoring above it, each
part is fitted and the sum of squared fitting errors is recorded; the cut with
the best criterion is kept. Thresholds are nested (a lower threshold keeps every
corner of a higher one), so the sweep inserts candidates in decreasing score
order and scores every threshold from running sums.

Criteria
--------
``"sse"``  the literal rule: the smallest total SSE (eq. 14). More corners never
           raise a least-squares SSE, so this always picks the lowest threshold.
``"bic"``  a criterion that over-segmenting cannot win:
           ``SSE / sigma^2 + penalty * ln(n) * segments`` (Schwarz' Bayesian
           information criterion for a Gaussian error of known ``sigma``). Each
           extra segment must explain more than ``penalty * ln(n)`` units of
           noise variance.

References
----------
.. [1] Electronics 11(11), 1759, 2022 (doi:10.3390/electronics11111759), sec. 2.3 and sec. 3.
.. [2] G. Schwarz, "Estimating the dimension of a model", Annals of
   Statistics 6(2), 461-464, 1978.
"""

from __future__ import annotations

import bisect
import math
from dataclasses import dataclass

import numpy as np

from scanlines.steps.breakpoints import Clusters
from scanlines.steps.fit import RunCost

__all__ = ["CRITERIA", "Selection", "Sweep", "criterion_values", "sweep", "threshold_grid"]

CRITERIA = ("bic", "sse")


@dataclass(frozen=True, slots=True)
class Selection:
    """The outcome of a sweep.

    ``corners`` are the chosen candidate positions (sorted); ``threshold`` the
    chosen ``dkth``; ``thresholds`` and ``values`` every evaluation made.
    """

    corners: np.ndarray
    threshold: float
    thresholds: np.ndarray
    values: np.ndarray


def threshold_grid(low: float, high: float, step: float, max_evaluations: int) -> np.ndarray:
    """``low, low + step, ...`` up to ``high``, at most ``max_evaluations`` values."""
    count = min(math.floor((high - low) / step + 1e-9) + 1, max_evaluations)
    return low + step * np.arange(count)


def _insert_in_rank_order(
    clusters: Clusters, candidates: np.ndarray, shared: bool
) -> tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray]:
    """Insert candidates best first; return, per candidate, accepted flag and its parent run.

    A candidate is dropped when a part it would create is too short (Step 5: a
    corner needs at least two points on each side of it).
    """
    starts = clusters.start.tolist()
    ends = dict(zip(starts, clusters.end.tolist(), strict=True))
    m = len(candidates)
    accepted = np.zeros(m, dtype=bool)
    parent_a = np.zeros(m, dtype=np.intp)
    parent_b = np.zeros(m, dtype=np.intp)
    for j, c in enumerate(candidates.tolist()):
        k = bisect.bisect_right(starts, c) - 1
        a = starts[k]
        b = ends[a]
        second = c if shared else c + 1
        if c - a < (2 if shared else 1) or b - c < 2:
            continue
        accepted[j] = True
        parent_a[j], parent_b[j] = a, b
        ends[a] = c
        bisect.insort(starts, second)
        ends[second] = b
    return accepted, parent_a, parent_b, np.where(shared, candidates, candidates + 1)


def criterion_values(
    criterion: str,
    sse: np.ndarray,
    segments: np.ndarray,
    n_points: int,
    sigma: float,
    penalty: float,
) -> np.ndarray:
    """The criterion for each evaluated segmentation (smaller is better)."""
    sse = np.where(np.isnan(sse), np.inf, sse)
    if criterion == "sse":
        return sse
    return sse / (sigma * sigma) + penalty * math.log(max(n_points, 2)) * segments


@dataclass(frozen=True, slots=True)
class Sweep:
    """Every segmentation the thresholds can produce, scored from running sums.

    ``sse[m]`` and ``segments[m]`` describe the cut with the ``m`` best candidates
    (those the removal rule dropped do not cut); ``levels[t]`` is the cut each
    tried threshold ``thresholds[t]`` gives.
    """

    ranked: np.ndarray
    accepted: np.ndarray
    sse: np.ndarray
    segments: np.ndarray
    thresholds: np.ndarray
    levels: np.ndarray
    n_points: int

    def corners(self, level: int) -> np.ndarray:
        """Positions of the corners of the cut at ``level``, sorted."""
        return np.sort(self.ranked[:level][self.accepted[:level]])

    def choose(self, criterion: str, sigma: float, penalty: float) -> Selection:
        """The best tried threshold by ``criterion`` (the first one on a tie)."""
        values = criterion_values(
            criterion,
            self.sse[self.levels],
            self.segments[self.levels],
            self.n_points,
            sigma,
            penalty,
        )
        best = int(np.argmin(values))
        level = int(self.levels[best])
        return Selection(self.corners(level), float(self.thresholds[best]), self.thresholds, values)


def sweep(
    cost: RunCost,
    clusters: Clusters,
    candidates: np.ndarray,
    scores: np.ndarray,
    *,
    grid: np.ndarray | None,
    max_evaluations: int,
    shared: bool,
) -> Sweep:
    """Score every cut of ``clusters`` at ``candidates`` (positions) that a threshold makes.

    ``cost`` gives the fitting error of runs (eq. 14, or in noise units).

    ``grid`` is the list of thresholds to try; ``None`` tries the candidates' own
    scores (every distinct segmentation, best first, at most ``max_evaluations``).
    ``shared`` cuts a run ``[a, b]`` at ``c`` into ``[a, c]`` and ``[c, b]`` (the corner
    point ends one segment and starts the next, as in the paper); otherwise into
    ``[a, c]`` and ``[c + 1, b]``.
    """
    magnitude = np.abs(scores)
    order = np.argsort(-magnitude, kind="stable")
    ranked, ranked_score = candidates[order], magnitude[order]
    # Only candidates that some tried threshold keeps can change a cut.
    if grid is None:
        useful = min(len(ranked), max_evaluations)
    else:
        useful = int(np.count_nonzero(ranked_score > np.min(grid))) if len(grid) else 0
    ranked, ranked_score = ranked[:useful], ranked_score[:useful]
    accepted, parent_a, parent_b, second = _insert_in_rank_order(clusters, ranked, shared)

    base = cost(clusters.start, clusters.end).sum() if len(clusters) else 0.0
    gain = np.zeros(len(ranked))
    if accepted.any():
        a, b, c, c2 = parent_a[accepted], parent_b[accepted], ranked[accepted], second[accepted]
        before, after, whole = cost.many((a, c), (c2, b), (a, b))
        gain[accepted] = before + after - whole
    if grid is None:
        levels = np.arange(min(len(ranked), max_evaluations) + 1)
        thresholds = np.r_[ranked_score, 0.0][levels]
    else:
        thresholds = np.asarray(grid, dtype=float)
        levels = np.searchsorted(-ranked_score, -thresholds, side="left")  # count of scores > t
    return Sweep(
        ranked=ranked,
        accepted=accepted,
        sse=base + np.r_[0.0, np.cumsum(gain)],
        segments=len(clusters) + np.r_[0, np.cumsum(accepted)],
        thresholds=thresholds,
        levels=levels,
        n_points=int((clusters.end - clusters.start + 1).sum()) if len(clusters) else 0,
    )
