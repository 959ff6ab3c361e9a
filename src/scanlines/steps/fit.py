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

from typing import NamedTuple

import numpy as np

from scanlines import _core
from scanlines.steps.arrays import float64s, int64s

__all__ = [
    "FITS",
    "FIT_CODES",
    "PAPER",
    "TLS",
    "Moments",
    "RunCost",
    "fit_many",
    "prefix_moments",
    "run_covariances",
    "run_labels",
    "tls_run",
]

FITS = ("tls", "paper")
FIT_CODES = {"tls": 0, "paper": 1}
TLS, PAPER = 0, 1


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


MIN_INCIDENCE_WEIGHT = 0.1
"""Floor of :func:`run_cost`'s weight ``cos^2`` of the incidence (72 deg): on a wall
seen closer to grazing, model errors, not range noise, dominate the residuals."""


def prefix_moments(x: np.ndarray, y: np.ndarray) -> Moments:
    """:class:`Moments` of the points ``x, y``."""
    return Moments(*_core.prefix_moments(x, y))


def tls_run(moments: Moments, a: int, b: int) -> tuple[float, float, float]:
    """Total-least-squares line ``(rho, alpha, sse)`` of run ``[a, b]``."""
    return _core.tls_run(*moments, a, b)


def fit_many(fit: int, moments: Moments, a: np.ndarray, b: np.ndarray):
    """``fit_run`` over runs ``[a[k], b[k]]``: arrays ``rho, alpha, sse``."""
    return _core.fit_many(fit, *moments, int64s(a), int64s(b))


def run_labels(a: np.ndarray, b: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Positions covered by runs ``[a, b]`` and the run number of each (runs may overlap)."""
    lengths = np.maximum(np.asarray(b) - np.asarray(a) + 1, 0)
    run = np.repeat(np.arange(len(lengths), dtype=np.int64), lengths)
    first = np.repeat(np.asarray(a, dtype=np.int64), lengths)
    offset = np.arange(run.size, dtype=np.int64) - np.repeat(np.cumsum(lengths) - lengths, lengths)
    return first + offset, run


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
    return _core.run_covariances(
        r,
        x,
        y,
        float64s(rho),
        float64s(alpha),
        int64s(a),
        int64s(b),
        float64s(sigma),
        bool(inflate),
    )
