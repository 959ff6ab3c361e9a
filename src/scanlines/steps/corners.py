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

import numpy as np

from scanlines import _core
from scanlines.steps.arrays import float64s, int64s
from scanlines.steps.fit import Moments

__all__ = [
    "SCORES",
    "SCORE_CODES",
    "peak_positions",
    "slope_scores",
    "turn_scores",
]

SCORES = ("turn", "dk", "dk_signed")
SCORE_CODES = {name: code for code, name in enumerate(SCORES)}
TURN, DK, DK_SIGNED = range(3)


def slope_scores(r, gap, step: float, start, end, signed: bool) -> np.ndarray:
    """Eq. 13 at every position (0 where a neighbour lies outside the cluster, or a zero
    range gives no slope); ``signed`` leaves out the printed absolute values."""
    return _core.slope_scores(
        float64s(r), int64s(gap), float(step), int64s(start), int64s(end), signed
    )


def turn_scores(x, y, moments: Moments, start, end, window: int) -> np.ndarray:
    """Absolute turn (radians) between lines fitted to ``window`` points on each side.

    The line before ``p``, ``[p - w, p]``, is the line after ``p - w``: each run is
    fitted once, except the shortened ones at a cluster's ends.
    """
    return _core.turn_scores(float64s(x), float64s(y), *moments, int64s(start), int64s(end), window)


def peak_positions(score, start, end) -> np.ndarray:
    """Positions ``i`` with ``|s_i| > |s_{i-1}|`` and ``|s_i| > |s_{i+1}|`` inside a cluster."""
    return _core.peak_positions(float64s(score), int64s(start), int64s(end))
