"""The threshold sweep over ``dkth`` and its selection criterion (Steps 5-7 of [1]_).

For each threshold the clusters are cut at the candidates scoring above it, each
part is fitted and the sum of squared fitting errors is recorded; the cut with
the best criterion is kept. Thresholds are nested (a lower threshold keeps every
corner of a higher one), so the sweep inserts candidates in decreasing score
order and scores every threshold from running sums (``sweep_levels``; a sweep can
also be extended a few candidates at a time, ``start_sweep`` and
``extend_sweep``, as the adaptive method's early stop under ``"bic"`` does).

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
paper methods' kernels; their bindings in :mod:`scanlines._core` serve the tests.

References
----------
.. [1] Electronics 11(11), 1759, 2022 (doi:10.3390/electronics11111759), sec. 2.3 and sec. 3.
.. [2] G. Schwarz, "Estimating the dimension of a model", Annals of
   Statistics 6(2), 461-464, 1978.
"""

from __future__ import annotations

import numpy as np

from scanlines import _core

__all__ = [
    "BIC",
    "CRITERIA",
    "CRITERION_CODES",
    "SSE",
    "Sweep",
    "threshold_grid",
]

CRITERIA = ("bic", "sse")
CRITERION_CODES = {"bic": 0, "sse": 1}
BIC, SSE = 0, 1

Sweep = _core.Sweep
"""A threshold sweep in progress (``start_sweep``, ``extend_sweep``).

``ranked`` are the candidates best first (``ranked_score`` their ``|score|``), of which
the first ``useful`` can change a cut; ``sse[m]`` and ``segments[m]`` describe the cut
with the ``m`` best, filled for ``m`` up to the candidates inserted so far
(``accepted[j]`` False: candidate ``j`` does not cut, ``parent_a/b[j]`` the run it cut).
Its arrays are copies, read-only views of the sweep's state."""


def threshold_grid(low: float, high: float, step: float, max_evaluations: int) -> np.ndarray:
    """``low, low + step, ...`` up to ``high``, at most ``max_evaluations`` values."""
    return _core.threshold_grid(float(low), float(high), float(step), int(max_evaluations))
