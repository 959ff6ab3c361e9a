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
from scanlines.steps.fit import Moments
from scanlines.steps.returns import Returns

__all__ = ["merge_by_chi_square", "pair_chi_squares"]


def pair_chi_squares(rho, alpha, covariance, first, second) -> np.ndarray:
    """The chi-square of the line pairs ``(first[i], second[i])`` (module docstring)."""
    return _core.pair_chi_squares(
        float64s(rho), float64s(alpha), float64s(covariance), int64s(first), int64s(second)
    )


def merge_by_chi_square(
    returns: Returns, moments: Moments, a, b, group, sigma, threshold: float, inflate: bool
):
    """Merge neighbouring runs of one group while their lines pass the chi-square test.

    The pair with the smallest chi-square below ``threshold`` is merged (the runs
    and everything between them), refitted, and the test repeated; ``sigma`` is the
    range noise of each return, ``inflate`` as :func:`~scanlines.steps.fit.run_covariances`
    takes it. Returns new ``a, b, group`` arrays.
    """
    return _core.merge_by_chi_square(
        *returns, *moments, int64s(a), int64s(b), int64s(group), float64s(sigma), float(threshold),
        bool(inflate),
    )  # fmt: skip
