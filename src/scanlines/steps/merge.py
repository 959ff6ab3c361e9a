"""Merging neighbouring runs whose lines agree.

``merge_by_chi_square`` joins neighbouring runs of one group whose lines agree within
                        a chi-square bound on ``(rho, alpha)``, with covariances
                        propagated from the range noise and the angle difference wrapped
                        to ``(-pi, pi]``, as the merge of split-and-merge [1]_ [2]_ (and
                        of the adaptive method, after its merge by its criterion).

Greedy: the best pair first, refitted, until no pair passes. The chi-square of two lines
is ``dL^T (P_1 + P_2)^-1 dL``, NaN (never merged) where the sum is singular.

References
----------
.. [1] V. Nguyen, A. Martinelli, N. Tomatis and R. Siegwart, "A comparison of line
   extraction algorithms using 2D laser rangefinder for indoor mobile robotics",
   IEEE/RSJ IROS 2005, 1929-1934.
.. [2] K. O. Arras and R. Siegwart, "Feature extraction and scene interpretation
   for map-based navigation and map building", SPIE Mobile Robotics XII, 1997.
"""

from __future__ import annotations

import numpy as np

from scanlines import _core
from scanlines.steps.arrays import float64s, int64s

__all__ = ["pair_chi_squares"]


def pair_chi_squares(rho, alpha, covariance, first, second) -> np.ndarray:
    """The chi-square of the line pairs ``(first[i], second[i])`` (module docstring)."""
    return _core.pair_chi_squares(
        float64s(rho), float64s(alpha), float64s(covariance), int64s(first), int64s(second)
    )
