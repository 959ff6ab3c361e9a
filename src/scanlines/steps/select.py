"""The threshold sweep over ``dkth`` and its selection criterion (Steps 5-7 of [1]_).

For each threshold the clusters are cut at the candidates scoring above it, each
part is fitted and the sum of squared fitting errors is recorded; the cut with
the best criterion is kept. Thresholds are nested (a lower threshold keeps every
corner of a higher one), so the sweep inserts candidates in decreasing score
order and scores every threshold from running sums. Under ``"bic"`` the sweep stops as
soon as no lower threshold can win (below): each segment charges the
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

The sweep
---------
The candidates are ranked by ``|score|``, largest first (equal scores in position
order). Without a fixed range every distinct cut is tried (the candidates' own scores as
thresholds, at most ``max_evaluations``); a fixed ``dkth_range`` tries the thresholds
``low, low + step, ...`` up to ``high`` (at most ``max_evaluations``), and only candidates
scoring above the lowest of them can change a cut. Inserting the ``m``-th candidate cuts
the run that holds it, unless a part it would create is too short (Step 5: a corner needs
at least two points on each side of it): a cut at ``c`` splits ``[a, b]`` into ``[a, c]``
and ``[c + 1, b]``, or with the shared corner point of the paper into ``[a, c]`` and
``[c, b]``. ``sse[m]`` and ``segments[m]`` describe the cut with the ``m`` best
candidates, each from the one before and the costs of the two new runs (a
:class:`~scanlines.steps.fit.RunCost`: eq. 14, or in noise units). A tried threshold
``t`` selects the cut of the candidates scoring above it; the best criterion wins, the
first (highest threshold) on a tie, and a NaN SSE counts as infinite.

The stopping rule: the value of the cut with ``m`` candidates is at least
``penalty ln(n) segments[m]`` (its SSE term is not negative) and ``segments`` never
falls, so once that charge reaches the best value so far no later cut can win; the sweep
inserts :data:`SWEEP_CHUNK` candidates between two checks of that bound.

The kernels are C++ (``cpp/scanlines/steps/select.cpp``), called by the adaptive
method's kernel; ``scanlines._core`` binds them for the tests (``threshold_grid``,
``start_sweep``, ``extend_sweep``, ``sweep_decided``, ``sweep_levels``, ``best_level``,
``level_corners``).

References
----------
.. [1] Electronics 11(11), 1759, 2022 (doi:10.3390/electronics11111759), sec. 2.3 and sec. 3.
.. [2] G. Schwarz, "Estimating the dimension of a model", Annals of
   Statistics 6(2), 461-464, 1978.
"""

from __future__ import annotations

__all__ = ["BIC", "CRITERIA", "CRITERION_CODES", "SSE", "SWEEP_CHUNK"]

CRITERIA = ("bic", "sse")
CRITERION_CODES = {"bic": 0, "sse": 1}
BIC, SSE = 0, 1
#: Candidates the ``"bic"`` sweep inserts between two checks of its bound.
SWEEP_CHUNK = 8
