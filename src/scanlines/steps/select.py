"""The threshold sweep over ``dkth`` and its selection criterion (Steps 5-7 of [1]_).

For each threshold the clusters are cut at the candidates scoring above it, each
part is fitted and the sum of squared fitting errors is recorded; the cut with
the best criterion is kept. Thresholds are nested (a lower threshold keeps every
corner of a higher one), so the sweep inserts candidates in decreasing score
order and scores every threshold from running sums (:func:`sweep_levels`; a sweep can
also be extended a few candidates at a time, :func:`start_sweep` and
:func:`extend_sweep`, as the adaptive method's early stop under ``"bic"`` does).

Criteria
--------
``"sse"``  the literal rule: the smallest total SSE (eq. 14). More corners never
           raise a least-squares SSE, so this always picks the lowest threshold.
``"bic"``  a criterion that over-segmenting cannot win:
           ``SSE / sigma^2 + penalty * ln(n) * segments`` (Schwarz' Bayesian
           information criterion for a Gaussian error of known ``sigma``). Each
           extra segment must explain more than ``penalty * ln(n)`` units of
           noise variance.

The kernels are C++ (``cpp/scanlines/steps/select.cpp``), called by the adaptive and
paper methods' kernels; the functions here call their bindings.

References
----------
.. [1] Electronics 11(11), 1759, 2022 (doi:10.3390/electronics11111759), sec. 2.3 and sec. 3.
.. [2] G. Schwarz, "Estimating the dimension of a model", Annals of
   Statistics 6(2), 461-464, 1978.
"""

from __future__ import annotations

import numpy as np

from scanlines import _core
from scanlines.steps.arrays import bools, float64s, int64s
from scanlines.steps.fit import RunCost

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
    "sweep_levels",
    "threshold_grid",
]

CRITERIA = ("bic", "sse")
CRITERION_CODES = {"bic": 0, "sse": 1}
BIC, SSE = 0, 1

Sweep = _core.Sweep
"""A threshold sweep in progress (:func:`start_sweep`, :func:`extend_sweep`).

``ranked`` are the candidates best first (``ranked_score`` their ``|score|``), of which
the first ``useful`` can change a cut; ``sse[m]`` and ``segments[m]`` describe the cut
with the ``m`` best, filled for ``m`` up to the candidates inserted so far
(``accepted[j]`` False: candidate ``j`` does not cut, ``parent_a/b[j]`` the run it cut).
Its arrays are copies, read-only views of the sweep's state."""


def threshold_grid(low: float, high: float, step: float, max_evaluations: int) -> np.ndarray:
    """``low, low + step, ...`` up to ``high``, at most ``max_evaluations`` values."""
    return _core.threshold_grid(float(low), float(high), float(step), int(max_evaluations))


def level_corners(ranked, accepted, level: int) -> np.ndarray:
    """Sorted positions of the accepted candidates among the ``level`` best."""
    return _core.level_corners(int64s(ranked), bools(accepted), int(level))


def best_level(criterion: int, sse, segments, levels, n_points: int, sigma: float, penalty: float):
    """Index of the best tried threshold (the first on a tie) and every criterion value.

    The criterion of one segmentation: the SSE (``"sse"``), or ``SSE / sigma^2 + penalty
    ln(max(n_points, 2)) segments`` (``"bic"``); a NaN SSE counts as inf."""
    return _core.best_level(
        int(criterion), float64s(sse), int64s(segments), int64s(levels), int(n_points),
        float(sigma), float(penalty),
    )  # fmt: skip


def start_sweep(cost: RunCost, start, end, candidates, scores, grid, use_grid: bool,
                max_evaluations: int) -> Sweep:  # fmt: skip
    """A :class:`Sweep` of the clusters ``[start, end]`` with no candidate inserted yet.

    ``use_grid`` tries the thresholds ``grid``; otherwise the candidates' own scores
    (every distinct segmentation, best first, at most ``max_evaluations``). Equal scores
    rank in position order.
    """
    return _core.start_sweep(
        cost, int64s(start), int64s(end), int64s(candidates), float64s(scores), float64s(grid),
        bool(use_grid), int(max_evaluations),
    )  # fmt: skip


def extend_sweep(sweep: Sweep, cost: RunCost, shared: bool, done: int, upto: int) -> int:
    """Insert candidates ``done .. upto - 1`` of ``sweep`` (in place) and score each cut.

    A candidate is dropped when a part it would create is too short (Step 5: a corner
    needs at least two points on each side of it). ``shared`` cuts a run ``[a, b]`` at
    ``c`` into ``[a, c]`` and ``[c, b]`` (the corner point ends one segment and starts the
    next, as in the paper); otherwise into ``[a, c]`` and ``[c + 1, b]``. Returns
    ``upto``, the count inserted.
    """
    return _core.extend_sweep(sweep, cost, bool(shared), int(done), int(upto))


def sweep_levels(cost: RunCost, start, end, candidates, scores, grid, use_grid: bool,
                 max_evaluations: int, shared: bool):  # fmt: skip
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
    return _core.sweep_levels(
        cost, int64s(start), int64s(end), int64s(candidates), float64s(scores), float64s(grid),
        bool(use_grid), int(max_evaluations), bool(shared),
    )  # fmt: skip
