"""Merging neighbouring runs whose lines agree.

``merge_by_criterion``  joins two neighbouring runs of one cluster when the joined fit
                        explains the points as well, by the criterion the threshold
                        sweep uses: ``(SSE_joined - SSE_1 - SSE_2) / sigma^2 < penalty ln(n)``.
                        It undoes cuts at noise peaks that a single global threshold
                        lets through (the adaptive method).
``merge_by_chi_square`` joins neighbouring runs of one group whose lines agree within
                        a chi-square bound on ``(rho, alpha)``, with covariances
                        propagated from the range noise and the angle difference wrapped
                        to ``(-pi, pi]``, as the merge of split-and-merge [1]_ [2]_.

Both are greedy: the best pair first, refitted, until no pair passes.

References
----------
.. [1] V. Nguyen, A. Martinelli, N. Tomatis and R. Siegwart, "A comparison of line
   extraction algorithms using 2D laser rangefinder for indoor mobile robotics",
   IEEE/RSJ IROS 2005, 1929-1934.
.. [2] K. O. Arras and R. Siegwart, "Feature extraction and scene interpretation
   for map-based navigation and map building", SPIE Mobile Robotics XII, 1997.
"""

from __future__ import annotations

import math

import numpy as np

from scanlines._jit import kernel
from scanlines.steps.fit import TLS, fit_many, hesse_difference, run_cost, run_covariances, tls_run

__all__ = ["chi_square", "merge_by_chi_square", "merge_by_criterion", "pair_chi_squares"]


@kernel
def merge_by_criterion(cost, a, b, cluster, segment_cost):
    """Greedily merge the neighbour pair that lowers the criterion most, until none does.

    ``cost`` is a :class:`~scanlines.steps.fit.RunCost`, ``segment_cost`` the charge
    of one segment in its units. The costs of the parts and of each joined pair are
    kept between rounds; a merge changes only the pairs next to it.
    """
    a, b, cluster = a.copy(), b.copy(), cluster.copy()
    m = a.shape[0]
    part = np.empty(m)
    for k in range(m):
        part[k] = run_cost(cost, a[k], b[k])
    joined = np.full(max(m - 1, 0), math.nan)
    for k in range(m - 1):
        if cluster[k] == cluster[k + 1]:
            joined[k] = run_cost(cost, a[k], b[k + 1])
    while m >= 2:
        best, best_change = -1, math.inf
        for k in range(m - 1):
            change = joined[k] - part[k] - part[k + 1] - segment_cost
            if change < best_change:  # NaN (other cluster, no line) never wins
                best, best_change = k, change
        if best < 0 or not best_change < 0.0:
            break
        b[best] = b[best + 1]
        part[best] = joined[best]
        a[best + 1 : m - 1] = a[best + 2 : m]
        b[best + 1 : m - 1] = b[best + 2 : m]
        cluster[best + 1 : m - 1] = cluster[best + 2 : m]
        part[best + 1 : m - 1] = part[best + 2 : m]
        joined[best : m - 2] = joined[best + 1 : m - 1]
        m -= 1
        for k in (best - 1, best):
            if 0 <= k < m - 1:
                same = cluster[k] == cluster[k + 1]
                value = run_cost(cost, a[k], b[k + 1])
                joined[k] = value if same else math.nan
    return a[:m], b[:m], cluster[:m]


@kernel
def chi_square(rho_1, alpha_1, rho_2, alpha_2, covariance_1, covariance_2):
    """``dL^T (P_1 + P_2)^-1 dL`` of two lines; NaN where the sum is singular."""
    d_rho, d_alpha = hesse_difference(rho_1, alpha_1, rho_2, alpha_2)
    p = covariance_1[0, 0] + covariance_2[0, 0]
    q = covariance_1[0, 1] + covariance_2[0, 1]
    s = covariance_1[1, 1] + covariance_2[1, 1]
    det = p * s - q * q
    if not det > 0.0:  # degenerate runs carry inf/NaN covariances
        return math.nan
    return (s * d_rho * d_rho - 2.0 * q * d_rho * d_alpha + p * d_alpha * d_alpha) / det


@kernel
def pair_chi_squares(rho, alpha, covariance, first, second):
    """:func:`chi_square` of the line pairs ``(first[i], second[i])``."""
    out = np.empty(first.shape[0])
    for i in range(first.shape[0]):
        j, k = first[i], second[i]
        out[i] = chi_square(rho[j], alpha[j], rho[k], alpha[k], covariance[j], covariance[k])
    return out


@kernel
def merge_by_chi_square(returns, moments, a, b, group, sigma, threshold, inflate):
    """Merge neighbouring runs of one group while their lines pass the chi-square test.

    The pair with the smallest chi-square below ``threshold`` is merged (the runs
    and everything between them), refitted, and the test repeated; ``sigma`` is the
    range noise of each return, ``inflate`` as :func:`~scanlines.steps.fit.run_covariances`
    takes it. Returns new ``a, b, group`` arrays.
    """
    a, b, group = a.copy(), b.copy(), group.copy()
    m = a.shape[0]
    rho, alpha, _ = fit_many(np.int64(TLS), moments, a, b)
    covariance = run_covariances(returns, rho, alpha, a, b, sigma, inflate)
    while m >= 2:
        best, best_value = -1, math.inf
        for k in range(m - 1):
            if group[k] != group[k + 1]:
                continue
            value = chi_square(
                rho[k], alpha[k], rho[k + 1], alpha[k + 1], covariance[k], covariance[k + 1]
            )
            if value != value:
                value = math.inf
            if best < 0 or value < best_value:
                best, best_value = k, value
        if best < 0 or not best_value < threshold:
            break
        b[best] = b[best + 1]
        for k in range(best + 1, m - 1):  # delete run best + 1
            a[k], b[k], group[k] = a[k + 1], b[k + 1], group[k + 1]
            rho[k], alpha[k], covariance[k] = rho[k + 1], alpha[k + 1], covariance[k + 1]
        m -= 1
        rho[best], alpha[best], _ = tls_run(moments, a[best], b[best])
        one_a, one_b = np.full(1, a[best]), np.full(1, b[best])
        one_rho, one_alpha = np.full(1, rho[best]), np.full(1, alpha[best])
        one = run_covariances(returns, one_rho, one_alpha, one_a, one_b, sigma, inflate)
        covariance[best] = one[0]
    return a[:m], b[:m], group[:m]
