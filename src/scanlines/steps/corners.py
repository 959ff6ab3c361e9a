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

__all__ = [
    "SCORES",
    "SCORE_CODES",
]

SCORES = ("turn", "dk", "dk_signed")
SCORE_CODES = {name: code for code, name in enumerate(SCORES)}
TURN, DK, DK_SIGNED = range(3)
