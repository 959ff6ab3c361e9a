"""Line fitting for runs of points (sec. 2.4 and Step 8 of [1]_).

Two fits, each of a run ``[a, b]`` in O(1) from running sums (:class:`Moments`),
so the threshold sweep can score every segmentation it tries without refitting
points (``fit_run``, ``run_cost``; ``fit_many`` for arrays of runs):

``"tls"``    total least squares in Hesse normal form ``x cos a + y sin a = rho``:
             minimises orthogonal distances, represents every line (vertical
             ones too) and does not depend on the frame's orientation.
``"paper"``  eq. 15-17: the run is cut into five sub-sets, each replaced by its
             mean point, and ``y = kx + b`` is fitted to those five points by
             ordinary least squares; its error (eq. 14, squared, ``W_i = 1``) is
             the vertical distance ``y_i - (k x_i + b)``. A line parallel to the
             y axis has no slope: its parameters come out NaN.

References
----------
.. [1] Electronics 11(11), 1759, 2022 (doi:10.3390/electronics11111759).
.. [2] K. O. Arras and R. Siegwart, "Feature extraction and scene interpretation
   for map-based navigation and map building", SPIE Mobile Robotics XII, 1997
   (covariance of a line fitted to range readings).
"""

from __future__ import annotations

import math
from typing import NamedTuple

import numpy as np

from scanlines._jit import kernel

__all__ = [
    "FITS",
    "FIT_CODES",
    "PAPER",
    "TLS",
    "Moments",
    "RunCost",
    "fit_many",
    "fit_run",
    "hesse_difference",
    "inverse_square_sums",
    "line_intersection",
    "prefix_moments",
    "run_cost",
    "run_covariances",
    "run_labels",
    "tls_axis",
    "tls_run",
    "wrap_angle",
]

FITS = ("tls", "paper")
FIT_CODES = {"tls": 0, "paper": 1}
TLS, PAPER = 0, 1
PAPER_SUBSETS = 5


class Moments(NamedTuple):
    """Prefix sums of a point sequence; sums over any run ``[a, b]`` in O(1).

    ``table`` (shape (5, n + 1)) holds the running sums of ``x, y, xx, xy, yy``
    relative to the mean point ``(ox, oy)``, which keeps them well conditioned;
    the origin is added back where absolute positions matter.
    """

    table: np.ndarray
    ox: float
    oy: float


class RunCost(NamedTuple):
    """What the fitting error of a run needs: the fit code, the moments and, for a cost
    in noise units, the running sums of ``1 / r^2`` and of each return's noise variance
    (both empty for the plain error in square metres)."""

    fit: int
    moments: Moments
    inv_r2: np.ndarray
    variances: np.ndarray


@kernel
def prefix_moments(x, y):
    """:class:`Moments` of the points ``x, y``."""
    n = x.shape[0]
    ox = 0.0
    oy = 0.0
    for i in range(n):  # a plain loop: the same sum compiled or not (numpy's is pairwise)
        ox += x[i]
        oy += y[i]
    if n:
        ox, oy = ox / n, oy / n
    table = np.zeros((5, n + 1))
    for i in range(n):
        u = x[i] - ox
        v = y[i] - oy
        table[0, i + 1] = table[0, i] + u
        table[1, i + 1] = table[1, i] + v
        table[2, i + 1] = table[2, i] + u * u
        table[3, i + 1] = table[3, i] + u * v
        table[4, i + 1] = table[4, i] + v * v
    return Moments(table, ox, oy)


@kernel
def wrap_angle(angle):
    """``angle`` wrapped to ``(-pi, pi]``."""
    return math.pi - (math.pi - angle) % (2.0 * math.pi)


@kernel
def hesse(alpha, rho):
    """Normalise to ``rho >= 0`` and ``alpha`` in ``(-pi, pi]``."""
    if rho < 0.0:
        rho = -rho
        alpha = alpha + math.pi
    return wrap_angle(alpha), rho


@kernel
def hesse_difference(rho_1, alpha_1, rho_2, alpha_2):
    """``(rho_1 - rho_2, alpha_1 - alpha_2)`` of two Hesse lines, the angle wrapped.

    Hesse parameters are ambiguous for a line through the origin (``(rho, alpha)``
    and ``(-rho, alpha + pi)``); of the two the one with the smaller angle
    difference is used.
    """
    direct = wrap_angle(alpha_1 - alpha_2)
    flipped = wrap_angle(alpha_1 - alpha_2 + math.pi)
    if abs(flipped) < abs(direct):
        return rho_1 + rho_2, flipped
    return rho_1 - rho_2, direct


@kernel
def line_intersection(rho_i, alpha_i, rho_j, alpha_j):
    """Intersection ``(x, y)`` of two Hesse lines; NaN for parallel lines."""
    det = math.sin(alpha_j - alpha_i)
    if not abs(det) > 1e-12:
        return math.nan, math.nan
    x = (rho_i * math.sin(alpha_j) - rho_j * math.sin(alpha_i)) / det
    y = (rho_j * math.cos(alpha_i) - rho_i * math.cos(alpha_j)) / det
    return x, y


@kernel
def tls_axis(moments, a, b):
    """Normal of the total-least-squares line of run ``[a, b]``, up to its sign.

    Returns ``(nx, ny, sse, mx, my)``: the eigenvector of the smaller eigenvalue
    of the scatter matrix, from the half-angle formulas (no trigonometric calls:
    this is the innermost operation of the method), the orthogonal error, and
    the run's centroid relative to the moments' origin. The run must not be empty.
    """
    table = moments.table
    n = b + 1 - a
    sx = table[0, b + 1] - table[0, a]
    sy = table[1, b + 1] - table[1, a]
    mx, my = sx / n, sy / n
    cxx = table[2, b + 1] - table[2, a] - sx * mx
    cxy = table[3, b + 1] - table[3, a] - sx * my
    cyy = table[4, b + 1] - table[4, a] - sy * my
    spread = cyy - cxx
    h = math.sqrt(spread * spread + 4.0 * cxy * cxy)
    sse = max(0.5 * (cxx + cyy) - 0.5 * h, 0.0)
    if h > 0.0:  # normal angle alpha = atan2(-2 cxy, cyy - cxx) / 2, in (-pi/2, pi/2]
        nx = math.sqrt(max(0.5 * (1.0 + spread / h), 0.0))
        ny = math.copysign(math.sqrt(max(0.5 * (1.0 - spread / h), 0.0)), -cxy)
    else:
        nx, ny = 1.0, 0.0
    return nx, ny, sse, mx, my


@kernel
def tls_normal(moments, a, b):
    """Total-least-squares line of run ``[a, b]`` as ``(cos alpha, sin alpha, rho, sse)``.

    ``rho >= 0``; NaN for an empty run.
    """
    if b < a:
        return math.nan, math.nan, math.nan, math.nan
    nx, ny, sse, mx, my = tls_axis(moments, a, b)
    rho = (mx + moments.ox) * nx + (my + moments.oy) * ny
    if rho < 0.0:
        return -nx, -ny, -rho, sse
    return nx, ny, rho, sse


@kernel
def tls_run(moments, a, b):
    """Total-least-squares line ``(rho, alpha, sse)`` of run ``[a, b]``; NaN for an empty run."""
    nx, ny, rho, sse = tls_normal(moments, a, b)
    return rho, math.atan2(ny, nx), sse


@kernel
def paper_run(moments, a, b):
    """Eq. 15-17 on the five sub-set means of run ``[a, b]``; ``sse`` is eq. 14.

    NaN when the line has no slope (the x spread of the means is rounding
    error next to their y spread) or the run is empty.
    """
    table, ox, oy = moments
    n = b + 1 - a
    if n <= 0:
        return math.nan, math.nan, math.nan
    parts = min(n, PAPER_SUBSETS)
    m = 0.0
    sum_x = sum_y = sum_xx = sum_xy = sum_yy = 0.0
    for j in range(parts):
        lo = min(a + (j * n) // parts, a + n)
        hi = min(a + ((j + 1) * n) // parts, a + n)
        if hi <= lo:
            continue
        mean_x = (table[0, hi] - table[0, lo]) / (hi - lo)
        mean_y = (table[1, hi] - table[1, lo]) / (hi - lo)
        m += 1.0
        sum_x += mean_x
        sum_y += mean_y
        sum_xx += mean_x * mean_x
        sum_xy += mean_x * mean_y
        sum_yy += mean_y * mean_y
    denominator = m * sum_xx - sum_x * sum_x
    if denominator <= 1e-18 * (m * sum_yy - sum_y * sum_y):
        return math.nan, math.nan, math.nan
    k = (m * sum_xy - sum_x * sum_y) / denominator
    intercept = (sum_xx * sum_y - sum_x * sum_xy) / denominator
    sx = table[0, b + 1] - table[0, a]
    sy = table[1, b + 1] - table[1, a]
    sxx = table[2, b + 1] - table[2, a]
    sxy = table[3, b + 1] - table[3, a]
    syy = table[4, b + 1] - table[4, a]
    sse = syy - 2 * k * sxy - 2 * intercept * sy + k * k * sxx + 2 * k * intercept * sx
    sse = max(sse + n * intercept * intercept, 0.0)
    # y - oy = k (x - ox) + b  <=>  -k x + y = b + oy - k ox
    norm = math.hypot(k, 1.0)
    alpha = math.atan2(1.0 / norm, -k / norm)
    rho = (intercept + oy - k * ox) / norm
    alpha, rho = hesse(alpha, rho)
    return rho, alpha, sse


@kernel
def fit_run(fit, moments, a, b):
    """Line ``(rho, alpha, sse)`` of run ``[a, b]`` by fit code (:data:`TLS` or :data:`PAPER`)."""
    if fit == PAPER:
        return paper_run(moments, a, b)
    return tls_run(moments, a, b)


@kernel
def fit_many(fit, moments, a, b):
    """:func:`fit_run` over runs ``[a[k], b[k]]``: arrays ``rho, alpha, sse``."""
    count = a.shape[0]
    rho = np.empty(count)
    alpha = np.empty(count)
    sse = np.empty(count)
    for k in range(count):
        rho[k], alpha[k], sse[k] = fit_run(fit, moments, a[k], b[k])
    return rho, alpha, sse


MIN_INCIDENCE_WEIGHT = 0.1
"""Floor of :func:`run_cost`'s weight ``cos^2`` of the incidence (72 deg): on a wall
seen closer to grazing, model errors, not range noise, dominate the residuals."""


@kernel
def inverse_square_sums(r):
    """Running sums of ``1 / r^2`` (a micrometre floor keeps one absurd range harmless)."""
    out = np.zeros(r.shape[0] + 1)
    for i in range(r.shape[0]):
        ri = max(r[i], 1e-6)
        out[i + 1] = out[i] + 1.0 / (ri * ri)
    return out


@kernel
def run_cost(cost, a, b):
    """Fitting error of run ``[a, b]``; in noise units when ``cost.inv_r2`` is given.

    Range noise moves a return along its beam; on a line at incidence ``beta``
    only ``cos(beta)`` of it shows as an orthogonal residual, so the error is
    divided by the mean ``cos^2(beta_i) = (rho / r_i)^2`` of the run's points and by
    the mean noise variance of its returns. Empty arrays give the plain error.
    """
    if cost.fit == PAPER:
        rho, _, sse = paper_run(cost.moments, a, b)
    else:
        _, _, rho, sse = tls_normal(cost.moments, a, b)
    inv_r2 = cost.inv_r2
    if inv_r2.shape[0] == 0 or b < a:
        return sse
    mean_inv_r2 = (inv_r2[b + 1] - inv_r2[a]) / (b - a + 1)
    weight = rho * rho * mean_inv_r2
    if weight != weight:  # NaN line: the cost stays NaN
        return sse
    variance = (cost.variances[b + 1] - cost.variances[a]) / (b - a + 1)
    return sse / (min(max(weight, MIN_INCIDENCE_WEIGHT), 1.0) * variance)


@kernel
def run_labels(a, b, n):
    """Positions covered by runs ``[a, b]`` and the run number of each (runs may overlap)."""
    total = 0
    for k in range(a.shape[0]):
        total += max(b[k] - a[k] + 1, 0)
    position = np.empty(total, dtype=np.int64)
    run = np.empty(total, dtype=np.int64)
    i = 0
    for k in range(a.shape[0]):
        for p in range(a[k], b[k] + 1):
            position[i] = p
            run[i] = k
            i += 1
    return position, run


@kernel
def run_covariances(returns, rho, alpha, a, b, sigma, inflate):
    """Covariance of ``(rho, alpha)`` of the line of each run ``[a, b]``, shape (runs, 2, 2).

    First-order propagation for the orthogonal fit: a range error ``e`` (standard
    deviation ``sigma[p]`` at return ``p``) on a beam at incidence
    ``cos(theta - alpha) = rho / r`` moves the point ``e rho / r`` off the line. With
    ``s`` the point's position along the line from the run's centroid ``t0``,
    ``d alpha = -sum s e' / sum s^2`` and ``d rho = mean(e') + t0 d alpha`` (after
    [2]_). With ``inflate``, a run whose residuals are larger than that noise explains
    (reduced chi-square above 1: a rough or curved surface) has its covariance scaled
    by that chi-square. Degenerate runs (two points, a paper fit without slope) give inf
    or NaN entries, not errors.
    """
    _, r, x, y = returns
    position, run = run_labels(a, b, x.shape[0])
    runs = rho.shape[0]
    cos_a, sin_a = np.cos(alpha), np.sin(alpha)
    count = np.zeros(runs)
    along_sum = np.zeros(runs)
    for i in range(position.shape[0]):
        p, k = position[i], run[i]
        count[k] += 1.0
        along_sum[k] += -x[p] * sin_a[k] + y[p] * cos_a[k]
    t0 = along_sum / np.maximum(count, 1.0)
    s2 = np.zeros(runs)
    s2_var = np.zeros(runs)
    s_var = np.zeros(runs)
    var_sum = np.zeros(runs)
    chi2 = np.zeros(runs)
    for i in range(position.shape[0]):
        p, k = position[i], run[i]
        s = -x[p] * sin_a[k] + y[p] * cos_a[k] - t0[k]
        var = (sigma[p] * rho[k] / r[p]) ** 2
        off = x[p] * cos_a[k] + y[p] * sin_a[k] - rho[k]
        s2[k] += s * s
        s2_var[k] += s * s * var
        s_var[k] += s * var
        var_sum[k] += var
        chi2[k] += off * off / var if var > 0.0 else 0.0
    out = np.empty((runs, 2, 2))
    for k in range(runs):
        scale = 1.0
        if inflate and count[k] > 2.0:
            scale = max(chi2[k] / (count[k] - 2.0), 1.0)
        var_alpha = s2_var[k] / (s2[k] * s2[k])
        var_mean = var_sum[k] / (count[k] * count[k])
        cov_mean_alpha = -s_var[k] / (count[k] * s2[k])
        out[k, 0, 0] = scale * (var_mean + t0[k] * t0[k] * var_alpha + 2.0 * t0[k] * cov_mean_alpha)
        out[k, 0, 1] = out[k, 1, 0] = scale * (cov_mean_alpha + t0[k] * var_alpha)
        out[k, 1, 1] = scale * var_alpha
    return out
