"""The threshold sweep over ``dkth`` and its selection criterion (Steps 5-7 of [1]_).

For each threshold the clusters are cut at the candidates scoring above it, each
part is fitted and the sum of squared fitting errors is recorded; the cut with
the best criterion is kept. Thresholds are nested (a lower threshold keeps every
corner of a higher one), so the sweep inserts candidates in decreasing score
order and scores every threshold from running sums. Under ``"bic"`` the sweep stops as
soon as no lower threshold can win (:func:`sweep_decided`): each segment charges the
criterion ``penalty ln(n)``, the charge only grows as thresholds fall, and once it alone
reaches the best value found, the choice is made; the result is the full sweep's.

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
from typing import NamedTuple

import numpy as np

from scanlines._jit import kernel
from scanlines.steps.fit import run_cost

__all__ = [
    "BIC",
    "CRITERIA",
    "CRITERION_CODES",
    "SSE",
    "Sweep",
    "best_level",
    "extend_sweep",
    "level_corners",
    "start_sweep",
    "sweep_decided",
    "sweep_levels",
    "threshold_grid",
]

CRITERIA = ("bic", "sse")
CRITERION_CODES = {"bic": 0, "sse": 1}
BIC, SSE = 0, 1
#: Candidates :func:`sweep_decided` inserts between two checks of its bound.
SWEEP_CHUNK = 8


def threshold_grid(low: float, high: float, step: float, max_evaluations: int) -> np.ndarray:
    """``low, low + step, ...`` up to ``high``, at most ``max_evaluations`` values."""
    count = min(math.floor((high - low) / step + 1e-9) + 1, max_evaluations)
    return low + step * np.arange(count)


@kernel
def criterion_value(criterion, sse, segments, log_n, sigma, penalty):
    """The criterion of one segmentation (smaller is better); NaN SSE counts as inf.

    ``log_n`` is ``ln(max(n_points, 2))``, ``n_points`` the returns segmented.
    """
    if sse != sse:
        sse = math.inf
    if criterion == SSE:
        return sse
    return sse / (sigma * sigma) + penalty * log_n * segments


@kernel
def level_corners(ranked, accepted, level):
    """Sorted positions of the accepted candidates among the ``level`` best."""
    return np.sort(ranked[:level][accepted[:level]])


@kernel
def best_level(criterion, sse, segments, levels, n_points, sigma, penalty):
    """Index of the best tried threshold (the first on a tie) and every criterion value."""
    values = np.empty(levels.shape[0])
    log_n = math.log(max(n_points, 2))
    for t in range(levels.shape[0]):
        level = levels[t]
        values[t] = criterion_value(criterion, sse[level], segments[level], log_n, sigma, penalty)
    return np.argmin(values), values


@kernel
def rank_descending(values):
    """Order of ``values`` from largest to smallest, equal values in index order."""
    order = np.argsort(-values)
    for i in range(1, order.shape[0]):  # insertion pass: restores index order among ties
        j = i
        while j > 0 and values[order[j]] == values[order[j - 1]] and order[j] < order[j - 1]:
            order[j], order[j - 1] = order[j - 1], order[j]
            j -= 1
    return order


class Sweep(NamedTuple):
    """A threshold sweep in progress (:func:`start_sweep`, :func:`extend_sweep`).

    ``ranked`` are the candidates best first (``ranked_score`` their ``|score|``), of
    which the first ``useful`` can change a cut; ``sse[m]`` and ``segments[m]`` describe
    the cut with the ``m`` best, filled for ``m`` up to the candidates inserted so far
    (``accepted[j]`` False: candidate ``j`` does not cut, ``parent_a/b[j]`` the run it
    cut). ``run_end[a]`` is the end of the current run starting at ``a`` (-1 inside a
    run) and ``cost_from[a]`` its cost.
    """

    ranked: np.ndarray
    ranked_score: np.ndarray
    useful: int
    accepted: np.ndarray
    parent_a: np.ndarray
    parent_b: np.ndarray
    sse: np.ndarray
    segments: np.ndarray
    run_end: np.ndarray
    cost_from: np.ndarray


@kernel
def start_sweep(cost, start, end, candidates, scores, grid, use_grid, max_evaluations):
    """A :class:`Sweep` of the clusters ``[start, end]`` with no candidate inserted yet.

    ``use_grid`` tries the thresholds ``grid``; otherwise the candidates' own scores
    (every distinct segmentation, best first, at most ``max_evaluations``).
    """
    n = cost.moments.table.shape[1] - 1
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
    run_end = np.full(n, -1, dtype=np.int64)
    cost_from = np.empty(n + 1)
    base = 0.0
    for c in range(start.shape[0]):
        run_end[start[c]] = end[c]
        cost_from[start[c]] = run_cost(cost, start[c], end[c])
        base += cost_from[start[c]]
    sse = np.empty(useful + 1)
    segments = np.empty(useful + 1, dtype=np.int64)
    sse[0], segments[0] = base, start.shape[0]
    accepted = np.zeros(useful, dtype=np.bool_)
    parent_a = np.zeros(useful, dtype=np.int64)
    parent_b = np.zeros(useful, dtype=np.int64)
    return Sweep(
        ranked[:useful], ranked_score[:useful], useful, accepted, parent_a, parent_b,
        sse, segments, run_end, cost_from,
    )  # fmt: skip


@kernel
def extend_sweep(sweep, cost, shared, done, upto):
    """Insert candidates ``done .. upto - 1`` of ``sweep`` (in place) and score each cut.

    A candidate is dropped when a part it would create is too short (Step 5: a corner
    needs at least two points on each side of it). ``shared`` cuts a run ``[a, b]`` at
    ``c`` into ``[a, c]`` and ``[c, b]`` (the corner point ends one segment and starts the
    next, as in the paper); otherwise into ``[a, c]`` and ``[c + 1, b]``. Returns
    ``upto``, the count inserted.
    """
    run_end, cost_from, sse, segments = sweep.run_end, sweep.cost_from, sweep.sse, sweep.segments
    for j in range(done, upto):
        c = sweep.ranked[j]
        a = c
        while run_end[a] < 0:
            a -= 1
        b = run_end[a]
        gain = 0.0
        if not (c - a < (2 if shared else 1) or b - c < 2):
            sweep.accepted[j] = True
            sweep.parent_a[j], sweep.parent_b[j] = a, b
            second = c if shared else c + 1
            run_end[a] = c
            run_end[second] = b
            whole = cost_from[a]
            cost_from[a] = run_cost(cost, a, c)
            cost_from[second] = run_cost(cost, second, b)
            gain = cost_from[a] + cost_from[second] - whole
        sse[j + 1] = sse[j] + gain
        segments[j + 1] = segments[j] + sweep.accepted[j]
    return upto


@kernel
def sweep_decided(sweep, cost, shared, done, n_points, sigma, penalty):
    """Extend ``sweep`` (from ``done`` inserted) until the ``"bic"`` choice with noise
    ``sigma`` is certain; returns ``(best level, inserted)``.

    The value of the cut with ``m`` candidates is at least ``penalty ln(n) segments[m]``
    (its SSE term is not negative) and ``segments`` never falls, so once that charge
    reaches the best value so far no later cut can win (ties go to the first): the level
    is the full sweep's, found without inserting the rest.
    """
    log_n = math.log(max(n_points, 2))
    best, best_value = 0, math.inf
    scored = 0
    while True:
        for m in range(scored, done + 1):
            value = criterion_value(
                np.int64(BIC), sweep.sse[m], sweep.segments[m], log_n, sigma, penalty
            )
            if value < best_value:
                best, best_value = m, value
        scored = done + 1
        if done == sweep.useful or not penalty * log_n * sweep.segments[done] < best_value:
            return best, done
        done = extend_sweep(sweep, cost, shared, done, min(done + SWEEP_CHUNK, sweep.useful))


@kernel
def sweep_levels(cost, start, end, candidates, scores, grid, use_grid, max_evaluations, shared):
    """Score every cut of the clusters ``[start, end]`` at ``candidates`` that a threshold makes.

    Thresholds are nested (a lower one keeps every corner of a higher one), so the
    candidates are inserted in decreasing ``|score|`` order and each cut is scored
    from the one before (``cost``, a :class:`~scanlines.steps.fit.RunCost`: eq. 14,
    or in noise units); see :func:`start_sweep` and :func:`extend_sweep`.

    Returns ``ranked, accepted, sse, segments, thresholds, levels``: ``sse[m]`` and
    ``segments[m]`` describe the cut with the ``m`` best ``ranked`` candidates (those
    ``accepted`` is False for do not cut); ``levels[t]`` is the cut each tried
    threshold ``thresholds[t]`` gives.
    """
    sweep = start_sweep(cost, start, end, candidates, scores, grid, use_grid, max_evaluations)
    extend_sweep(sweep, cost, shared, np.int64(0), sweep.useful)
    useful = sweep.useful
    if not use_grid:
        levels = np.arange(min(useful, max_evaluations) + 1)
        thresholds = np.append(sweep.ranked_score, 0.0)[levels]
    else:
        thresholds = grid.copy()
        levels = np.searchsorted(-sweep.ranked_score, -thresholds)  # count of scores > t
    return sweep.ranked, sweep.accepted, sweep.sse, sweep.segments, thresholds, levels
