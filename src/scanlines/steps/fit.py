"""Line fitting for runs of points (sec. 2.4 and Step 8 of [1]_).

Two fits, both evaluated for many runs at once from prefix sums, so the
threshold sweep can score a whole segmentation in a few array operations:

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

from dataclasses import dataclass

import numpy as np

__all__ = [
    "FITS",
    "Lines",
    "Moments",
    "RunCost",
    "line_covariances",
    "paper_lines",
    "point_residuals",
    "tls_lines",
]

FITS = ("tls", "paper")
PAPER_SUBSETS = 5


class Moments:
    """Prefix sums of a point sequence; sums over any run ``[a, b]`` in O(1).

    Coordinates are taken relative to their mean, which keeps the sums well
    conditioned; ``origin`` is added back where absolute positions matter.
    """

    __slots__ = ("origin", "sx", "sxx", "sxy", "sy", "syy")

    def __init__(self, x: np.ndarray, y: np.ndarray) -> None:
        ox = float(x.mean()) if x.size else 0.0
        oy = float(y.mean()) if y.size else 0.0
        self.origin = (ox, oy)
        u, v = x - ox, y - oy
        zero = np.zeros(1)
        self.sx = np.concatenate((zero, np.cumsum(u)))
        self.sy = np.concatenate((zero, np.cumsum(v)))
        self.sxx = np.concatenate((zero, np.cumsum(u * u)))
        self.sxy = np.concatenate((zero, np.cumsum(u * v)))
        self.syy = np.concatenate((zero, np.cumsum(v * v)))

    def sums(self, a: np.ndarray, b: np.ndarray) -> tuple[np.ndarray, ...]:
        """``n, Sx, Sy, Sxx, Sxy, Syy`` over inclusive runs ``[a, b]`` (relative coordinates)."""
        lo, hi = a, b + 1
        return (
            (hi - lo).astype(np.float64),
            self.sx[hi] - self.sx[lo],
            self.sy[hi] - self.sy[lo],
            self.sxx[hi] - self.sxx[lo],
            self.sxy[hi] - self.sxy[lo],
            self.syy[hi] - self.syy[lo],
        )


@dataclass(frozen=True, slots=True)
class Lines:
    """Fitted lines of many runs: Hesse parameters and the fit's own error."""

    rho: np.ndarray
    alpha: np.ndarray
    sse: np.ndarray


def _hesse(alpha: np.ndarray, rho: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Normalise to ``rho >= 0`` and ``alpha`` in ``(-pi, pi]``."""
    flip = rho < 0.0
    rho = np.where(flip, -rho, rho)
    alpha = np.where(flip, alpha + np.pi, alpha)
    alpha = np.pi - np.mod(np.pi - alpha, 2.0 * np.pi)
    return alpha, rho


def tls_lines(moments: Moments, a: np.ndarray, b: np.ndarray) -> Lines:
    """Total-least-squares lines of runs ``[a, b]``; ``sse`` is the orthogonal error."""
    n, sx, sy, sxx, sxy, syy = moments.sums(a, b)
    with np.errstate(invalid="ignore", divide="ignore"):
        mx, my = sx / n, sy / n
        cxx, cxy, cyy = sxx - sx * mx, sxy - sx * my, syy - sy * my
    half_diff = 0.5 * (cxx - cyy)
    alpha = 0.5 * np.arctan2(-2.0 * cxy, cyy - cxx)
    sse = np.maximum(0.5 * (cxx + cyy) - np.hypot(half_diff, cxy), 0.0)
    ox, oy = moments.origin
    rho = (mx + ox) * np.cos(alpha) + (my + oy) * np.sin(alpha)
    alpha, rho = _hesse(alpha, rho)
    return Lines(rho, alpha, sse)


def _subset_means(moments: Moments, a: np.ndarray, b: np.ndarray) -> tuple[np.ndarray, ...]:
    """Mean points of the (up to) five sub-sets of each run: arrays of shape (runs, 5)."""
    n = b - a + 1
    parts = np.minimum(n, PAPER_SUBSETS)
    j = np.arange(PAPER_SUBSETS + 1)
    edges = a[:, None] + (j[None, :] * n[:, None]) // np.maximum(parts, 1)[:, None]
    edges = np.minimum(edges, (a + n)[:, None])
    lo, hi = edges[:, :-1], edges[:, 1:]
    used = (j[None, :-1] < parts[:, None]) & (hi > lo)
    count = np.where(used, hi - lo, 1)
    mean_x = np.where(used, (moments.sx[hi] - moments.sx[lo]) / count, 0.0)
    mean_y = np.where(used, (moments.sy[hi] - moments.sy[lo]) / count, 0.0)
    return mean_x, mean_y, used


def paper_lines(moments: Moments, a: np.ndarray, b: np.ndarray) -> Lines:
    """Eq. 15-17 on the five sub-set means of each run; ``sse`` is eq. 14 (vertical, squared)."""
    mean_x, mean_y, used = _subset_means(moments, a, b)
    m = used.sum(axis=1).astype(np.float64)
    sum_x, sum_y = mean_x.sum(axis=1), mean_y.sum(axis=1)
    sum_xx, sum_xy = (mean_x * mean_x).sum(axis=1), (mean_x * mean_y).sum(axis=1)
    sum_yy = (mean_y * mean_y).sum(axis=1)
    denominator = m * sum_xx - sum_x * sum_x
    # No slope: the x spread is rounding error next to the y spread (slope beyond 1e9).
    vertical = denominator <= 1e-18 * (m * sum_yy - sum_y * sum_y)
    with np.errstate(invalid="ignore", divide="ignore"):
        k = np.where(vertical, np.nan, (m * sum_xy - sum_x * sum_y) / denominator)
        intercept = np.where(vertical, np.nan, (sum_xx * sum_y - sum_x * sum_xy) / denominator)
    n, sx, sy, sxx, sxy, syy = moments.sums(a, b)
    # Intercept in relative coordinates is the same line; shift back to absolute below.
    with np.errstate(invalid="ignore", over="ignore"):
        sse = syy - 2 * k * sxy - 2 * intercept * sy + k * k * sxx + 2 * k * intercept * sx
        sse = sse + n * intercept * intercept
    sse = np.where(vertical, np.nan, np.maximum(sse, 0.0))
    ox, oy = moments.origin
    # y - oy = k (x - ox) + b  <=>  -k x + y = b + oy - k ox
    norm = np.hypot(k, 1.0)
    with np.errstate(invalid="ignore"):
        alpha = np.arctan2(1.0 / norm, -k / norm)
        rho = (intercept + oy - k * ox) / norm
    alpha, rho = _hesse(alpha, rho)
    return Lines(rho, alpha, sse)


def fit_runs(fit: str, moments: Moments, a: np.ndarray, b: np.ndarray) -> Lines:
    """Dispatch to :func:`tls_lines` or :func:`paper_lines` by name."""
    return paper_lines(moments, a, b) if fit == "paper" else tls_lines(moments, a, b)


MIN_INCIDENCE_WEIGHT = 0.1
"""Floor of :class:`RunCost`'s weight ``cos^2`` of the incidence (72 deg): on a wall
seen closer to grazing, model errors, not range noise, dominate the residuals."""


class RunCost:
    """Fitting error of runs ``[a, b]``, optionally in units of their expected noise.

    Range noise moves a return along its beam; on a line at incidence ``beta``
    only ``cos(beta)`` of it shows as an orthogonal residual. With ``r`` given,
    each run's error is divided by the mean ``cos^2(beta_i) = (rho / r_i)^2`` of its
    points, so one radial noise level serves walls seen head-on and slanted
    alike. Without ``r`` it is the plain error of the fit.
    """

    __slots__ = ("fit", "moments", "sum_inv_r2")

    def __init__(self, moments: Moments, fit: str, r: np.ndarray | None = None) -> None:
        self.moments = moments
        self.fit = fit
        if r is None:
            self.sum_inv_r2 = None
        else:  # a micrometre floor keeps one absurd range from poisoning the running sum
            inverse = 1.0 / np.maximum(r, 1e-6) ** 2
            self.sum_inv_r2 = np.concatenate(([0.0], np.cumsum(inverse)))

    def many(self, *runs: tuple[np.ndarray, np.ndarray]) -> list[np.ndarray]:
        """The cost of several sets of runs in one call (one fit over all of them)."""
        sizes = [len(a) for a, _ in runs]
        joined = self(np.concatenate([a for a, _ in runs]), np.concatenate([b for _, b in runs]))
        return np.split(joined, np.cumsum(sizes)[:-1])

    def __call__(self, a: np.ndarray, b: np.ndarray) -> np.ndarray:
        lines = fit_runs(self.fit, self.moments, a, b)
        if self.sum_inv_r2 is None:
            return lines.sse
        mean_inv_r2 = (self.sum_inv_r2[b + 1] - self.sum_inv_r2[a]) / (b - a + 1)
        with np.errstate(invalid="ignore", over="ignore"):
            weight = np.clip(lines.rho * lines.rho * mean_inv_r2, MIN_INCIDENCE_WEIGHT, 1.0)
        return lines.sse / weight


def run_labels(a: np.ndarray, b: np.ndarray, n: int) -> tuple[np.ndarray, np.ndarray]:
    """Positions covered by runs ``[a, b]`` and the run number of each (runs may overlap)."""
    lengths = b - a + 1
    run = np.repeat(np.arange(a.shape[0]), lengths)
    start_of_run = np.repeat(np.cumsum(lengths) - lengths, lengths)
    position = np.repeat(a, lengths) + (np.arange(run.shape[0]) - start_of_run)
    return position, run


def point_residuals(
    x: np.ndarray,
    y: np.ndarray,
    rho: np.ndarray,
    alpha: np.ndarray,
    position: np.ndarray,
    run: np.ndarray,
) -> np.ndarray:
    """Signed orthogonal distance of each labelled point to its run's line."""
    a = alpha[run]
    return x[position] * np.cos(a) + y[position] * np.sin(a) - rho[run]


def line_covariances(
    x: np.ndarray,
    y: np.ndarray,
    r: np.ndarray,
    rho: np.ndarray,
    alpha: np.ndarray,
    position: np.ndarray,
    run: np.ndarray,
    range_sigma: float,
) -> np.ndarray:
    """Covariance of ``(rho, alpha)`` of each run, propagated from range noise.

    First-order propagation for the orthogonal fit: a range error ``e`` on a beam
    at incidence ``cos(theta - alpha) = rho / r`` moves the point ``e rho / r``
    off the line. With ``s`` the point's position along the line from the run's
    centroid ``t0``, ``d alpha = -sum s e' / sum s^2`` and
    ``d rho = mean(e') + t0 d alpha`` (after [2]_).
    """
    runs = rho.shape[0]
    if runs == 0:
        return np.zeros((0, 2, 2))
    # Degenerate runs (two points, a paper fit without slope) give inf/NaN, not errors.
    with np.errstate(all="ignore"):
        return _covariances(x, y, r, rho, alpha, position, run, range_sigma)


def _covariances(x, y, r, rho, alpha, position, run, range_sigma):
    runs = rho.shape[0]
    a = alpha[run]
    along = -x[position] * np.sin(a) + y[position] * np.cos(a)
    var = (range_sigma * rho[run] / r[position]) ** 2
    count = np.bincount(run, minlength=runs).astype(np.float64)
    t0 = np.bincount(run, along, minlength=runs) / np.maximum(count, 1.0)
    s = along - t0[run]
    s2 = np.bincount(run, s * s, minlength=runs)
    var_alpha = np.bincount(run, s * s * var, minlength=runs) / (s2 * s2)
    var_mean = np.bincount(run, var, minlength=runs) / (count * count)
    cov_mean_alpha = -np.bincount(run, s * var, minlength=runs) / (count * s2)
    var_rho = var_mean + t0 * t0 * var_alpha + 2.0 * t0 * cov_mean_alpha
    cov_rho_alpha = cov_mean_alpha + t0 * var_alpha
    out = np.empty((runs, 2, 2))
    out[:, 0, 0] = var_rho
    out[:, 0, 1] = out[:, 1, 0] = cov_rho_alpha
    out[:, 1, 1] = var_alpha
    return out
