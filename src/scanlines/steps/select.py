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

import math
from dataclasses import dataclass

import numpy as np

from scanlines._jit import jit
from scanlines.steps.breakpoints import Clusters
from scanlines.steps.fit import FIT_CODES, RunCost, run_cost

__all__ = ["CRITERIA", "Selection", "Sweep", "criterion_values", "sweep", "threshold_grid"]

CRITERIA = ("bic", "sse")
CRITERION_CODES = {"bic": 0, "sse": 1}
BIC, SSE = 0, 1


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


@jit
def insert_in_rank_order(
    start: np.ndarray, end: np.ndarray, n: int, candidates: np.ndarray, shared: bool
) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Insert candidates best first; return, per candidate, accepted flag and its parent run.

    A candidate is dropped when a part it would create is too short (Step 5: a
    corner needs at least two points on each side of it).
    """
    run_end = np.full(n, -1, dtype=np.int64)  # end of the run starting at a position
    for c in range(start.shape[0]):
        run_end[start[c]] = end[c]
    m = candidates.shape[0]
    accepted = np.zeros(m, dtype=np.bool_)
    parent_a = np.zeros(m, dtype=np.int64)
    parent_b = np.zeros(m, dtype=np.int64)
    for j in range(m):
        c = candidates[j]
        a = c
        while run_end[a] < 0:
            a -= 1
        b = run_end[a]
        if c - a < (2 if shared else 1) or b - c < 2:
            continue
        accepted[j] = True
        parent_a[j], parent_b[j] = a, b
        run_end[a] = c
        run_end[c if shared else c + 1] = b
    return accepted, parent_a, parent_b


@jit(inline=True)
def criterion_value(criterion: int, sse: float, segments: int, log_n: float, sigma, penalty):
    """The criterion of one segmentation (smaller is better); NaN SSE counts as inf.

    ``log_n`` is ``ln(max(n_points, 2))``, ``n_points`` the returns segmented.
    """
    if sse != sse:
        sse = math.inf
    if criterion == SSE:
        return sse
    return sse / (sigma * sigma) + penalty * log_n * segments


def criterion_values(
    criterion: str,
    sse: np.ndarray,
    segments: np.ndarray,
    n_points: int,
    sigma: float,
    penalty: float,
) -> np.ndarray:
    """The criterion for each evaluated segmentation (smaller is better)."""
    code = CRITERION_CODES[criterion]
    log_n = math.log(max(n_points, 2))
    pairs = zip(sse, segments, strict=True)
    return np.array([criterion_value(code, v, k, log_n, sigma, penalty) for v, k in pairs])


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
        return level_corners(self.ranked, self.accepted, level)

    def choose(self, criterion: str, sigma: float, penalty: float) -> Selection:
        """The best tried threshold by ``criterion`` (the first one on a tie)."""
        code = CRITERION_CODES[criterion]
        best, values = best_level(
            code, self.sse, self.segments, self.levels, self.n_points, sigma, penalty
        )
        level = int(self.levels[best])
        return Selection(self.corners(level), float(self.thresholds[best]), self.thresholds, values)


@jit
def level_corners(ranked: np.ndarray, accepted: np.ndarray, level: int) -> np.ndarray:
    """Sorted positions of the accepted candidates among the ``level`` best."""
    return np.sort(ranked[:level][accepted[:level]])


@jit
def best_level(criterion: int, sse, segments, levels, n_points: int, sigma, penalty):
    """Index of the best tried threshold (the first on a tie) and every criterion value."""
    values = np.empty(levels.shape[0])
    log_n = math.log(max(n_points, 2))
    for t in range(levels.shape[0]):
        level = levels[t]
        values[t] = criterion_value(criterion, sse[level], segments[level], log_n, sigma, penalty)
    return np.argmin(values), values


@jit
def rank_descending(values: np.ndarray) -> np.ndarray:
    """Order of ``values`` from largest to smallest, equal values in index order."""
    order = np.argsort(-values)
    for i in range(1, order.shape[0]):  # insertion pass: restores index order among ties
        j = i
        while j > 0 and values[order[j]] == values[order[j - 1]] and order[j] < order[j - 1]:
            order[j], order[j - 1] = order[j - 1], order[j]
            j -= 1
    return order


@jit
def sweep_levels(
    fit: int,
    table: np.ndarray,
    ox: float,
    oy: float,
    inv_r2: np.ndarray,
    start: np.ndarray,
    end: np.ndarray,
    n: int,
    candidates: np.ndarray,
    scores: np.ndarray,
    grid: np.ndarray,
    use_grid: bool,
    max_evaluations: int,
    shared: bool,
):
    """Kernel of :func:`sweep`: ``ranked, accepted, sse, segments, thresholds, levels``."""
    magnitude = np.abs(scores)
    order = rank_descending(magnitude)
    ranked, ranked_score = candidates[order], magnitude[order]
    # Only candidates that some tried threshold keeps can change a cut.
    if not use_grid:
        useful = min(ranked.shape[0], max_evaluations)
    elif grid.shape[0]:
        useful = np.count_nonzero(ranked_score > np.min(grid))
    else:
        useful = 0
    ranked, ranked_score = ranked[:useful], ranked_score[:useful]
    accepted, parent_a, parent_b = insert_in_rank_order(start, end, n, ranked, shared)

    cost_from = np.empty(n + 1)  # cost of the current run starting at a position
    base = 0.0
    for c in range(start.shape[0]):
        cost_from[start[c]] = run_cost(fit, table, ox, oy, inv_r2, start[c], end[c])
        base += cost_from[start[c]]
    sse = np.empty(useful + 1)
    segments = np.empty(useful + 1, dtype=np.int64)
    sse[0], segments[0] = base, start.shape[0]
    for j in range(useful):
        gain = 0.0
        if accepted[j]:
            a, b, c = parent_a[j], parent_b[j], ranked[j]
            second = c if shared else c + 1
            whole = cost_from[a]
            cost_from[a] = run_cost(fit, table, ox, oy, inv_r2, a, c)
            cost_from[second] = run_cost(fit, table, ox, oy, inv_r2, second, b)
            gain = cost_from[a] + cost_from[second] - whole
        sse[j + 1] = sse[j] + gain
        segments[j + 1] = segments[j] + accepted[j]
    if not use_grid:
        levels = np.arange(min(useful, max_evaluations) + 1)
        thresholds = np.append(ranked_score, 0.0)[levels]
    else:
        thresholds = grid.copy()
        levels = np.searchsorted(-ranked_score, -thresholds)  # count of scores > t
    return ranked, accepted, sse, segments, thresholds, levels


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
    ox, oy = cost.moments.origin
    n = cost.moments.table.shape[1] - 1
    ranked, accepted, sse, segments, thresholds, levels = sweep_levels(
        FIT_CODES[cost.fit],
        cost.moments.table,
        ox,
        oy,
        cost.inv_r2,
        clusters.start,
        clusters.end,
        n,
        np.asarray(candidates, dtype=np.int64),
        np.asarray(scores, dtype=np.float64),
        np.zeros(0) if grid is None else np.asarray(grid, dtype=np.float64),
        grid is not None,
        int(max_evaluations),
        bool(shared),
    )
    return Sweep(
        ranked=ranked,
        accepted=accepted,
        sse=sse,
        segments=segments,
        thresholds=thresholds,
        levels=levels,
        n_points=int((clusters.end - clusters.start + 1).sum()) if len(clusters) else 0,
    )
