"""Line regression: sliding-window fits grouped by the similarity of their lines.

Algorithm (Arras and Siegwart [1]_; the "Line-Regression" algorithm as
described by Nguyen et al. [2]_):

1. cluster the returns by a fixed jump distance (``breakpoints="fixed"``,
   ``jump_distance = 0.3`` m) -- :mod:`scanlines.steps.breakpoints`;
2. fit a total-least-squares line to every ``window`` (``N_f``) consecutive
   points of a cluster, with its ``(rho, alpha)`` covariance propagated from
   ``range_sigma`` (:func:`scanlines.steps.fit.run_covariances`);
3. line fidelity of each window: the sum of the Mahalanobis distances
   ``dL^T (P_i + P_j)^-1 dL`` (angle difference wrapped) between its line and
   the lines of the windows before and after it (at a cluster end, twice the one
   neighbour's);
4. consecutive windows whose fidelity is below ``fidelity`` form one segment
   (the agglomeration of Nguyen et al.'s step 4 reduced to runs of consecutive
   similar windows): it covers the points from the first window's first to the
   last window's last point;
5. overlapping segments (windows overlap by ``N_f - 1`` points) merge when their
   lines pass the same chi-square test with ``merge_chi2``; otherwise the
   overlap is divided where the two fits' summed squared error is smallest;
   every segment is refitted;
6. segments with fewer than ``min_points`` (5) points or shorter than
   ``min_length`` (0 m) are dropped; corners by the shared rule of
   ``segment_events``; breakpoints from step 1.

Defaults: ``window = 9``, ``fidelity = 4``, ``range_sigma = 0.02`` m,
``merge_chi2 = 6`` (the 95 % point of chi-square with 2 degrees of freedom).
The fidelity of overlapping windows is not chi-square distributed (adjacent
windows share ``N_f - 1`` points, so their lines differ far less than two
independent fits would, and a noisy point raises the fidelity of ``N_f``
windows at once): with ``range_sigma`` equal to the noise, a straight wall's
window fidelity has a median of 0.6 and a 99th percentile of 4 (1/3 deg, 2 cm,
``N_f = 9``). The pair (4, 0.02 m) gave the best segment TruePos of
``fidelity`` in {2, 4, 8} and ``range_sigma`` in {0.01, 0.02} on the simulated
TiM571 and LMS sets; the method is sensitive to both (the bound scales with
``range_sigma^2``).

A window of ``N_f`` points spans ``N_f`` beam spacings: its direction is
known only to about ``sigma / (spacing sqrt(N_f^3 / 12))``, so at fine angular
resolution the similarity test is weak and corners are found late.

References
----------
.. [1] K. O. Arras and R. Siegwart, "Feature extraction and scene interpretation
   for map-based navigation and map building", Proc. SPIE 3210, Mobile Robots
   XII, 42-53, 1997.
.. [2] V. Nguyen, A. Martinelli, N. Tomatis and R. Siegwart, "A comparison of
   line extraction algorithms using 2D laser rangefinder for indoor mobile
   robotics", IEEE/RSJ IROS 2005.
"""

from __future__ import annotations

import math
from typing import ClassVar

import numpy as np

from scanlines.methods.base import ClusteredMethod
from scanlines.params import Param, Settings, integer, number
from scanlines.steps.assemble import output_settings
from scanlines.steps.breakpoints import published_clustering
from scanlines.steps.events import EVENTS
from scanlines.steps.fit import TLS, Moments, fit_many, prefix_moments, run_covariances
from scanlines.steps.merge import pair_chi_squares
from scanlines.steps.noise import covariance_sigmas
from scanlines.steps.returns import Returns

_EMPTY = np.zeros(0, dtype=np.int64)


class LineRegression(ClusteredMethod):
    """Line regression (module docstring)."""

    name = "line_regression"
    settings: ClassVar[Settings] = Settings(
        clustering=published_clustering("fixed", "line regression: fixed jump distance"),
        segments={
            "window": Param(9, integer(2, 1000), "sliding window N_f: points per window fit"),
            "fidelity": Param(
                4.0,
                number(low=0.0, low_open=True),
                "largest fidelity (summed chi-square) of a window",
            ),
            "merge_chi2": Param(
                6.0,
                number(low=0.0),
                "overlapping segments merge below this chi-square of (rho, alpha)",
            ),
        },
        events=EVENTS,
        output=output_settings(5, range_sigma=0.02),
    )

    def find_runs(self, returns, gap, start, end):
        moments = prefix_moments(returns.x, returns.y)
        window, sigma = self.params["window"], self._sigmas(returns, gap)
        first, group = _window_starts(start, end, window)
        good = _similar_windows(
            returns, moments, first, group, window, sigma, self.params["fidelity"]
        )
        a, b, group = _window_runs(first[good], group[good], window)
        a, b, group = _resolve_overlaps(
            returns, moments, a, b, group, sigma, self.params["merge_chi2"]
        )
        return a, b, group, _EMPTY

    def _sigmas(self, returns: Returns, gap: np.ndarray) -> np.ndarray:
        """The range noise of each return: ``range_sigma``, or the noise model's."""
        given = self.params["range_sigma"]
        given = math.nan if given == "auto" else float(given)
        return covariance_sigmas(given, self.noise, returns, gap)


def _window_starts(
    start: np.ndarray, end: np.ndarray, window: int
) -> tuple[np.ndarray, np.ndarray]:
    """First position and cluster of every window that fits inside a cluster."""
    count = np.maximum(end - start + 2 - window, 0)
    group = np.repeat(np.arange(start.shape[0]), count)
    offset = np.arange(group.size) - np.repeat(np.cumsum(count) - count, count)
    return (start[group] + offset).astype(np.int64), group.astype(np.int64)


def _lines_and_covariances(
    returns: Returns, moments: Moments, a: np.ndarray, b: np.ndarray, sigma: np.ndarray
) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    a = np.ascontiguousarray(a, dtype=np.int64)
    b = np.ascontiguousarray(b, dtype=np.int64)
    rho, alpha, _ = fit_many(TLS, moments, a, b)
    return rho, alpha, run_covariances(returns, rho, alpha, a, b, sigma, np.bool_(False))


def _similar_windows(
    returns: Returns,
    moments: Moments,
    start: np.ndarray,
    group: np.ndarray,
    window: int,
    sigma: np.ndarray,
    threshold: float,
) -> np.ndarray:
    """Steps 2-3: mask of windows whose fidelity is below ``threshold``."""
    if start.size == 0:
        return np.zeros(0, dtype=bool)
    rho, alpha, covariance = _lines_and_covariances(
        returns, moments, start, start + window - 1, sigma
    )
    k = np.arange(start.size - 1, dtype=np.int64)
    same = group[k] == group[k + 1]
    distance = np.where(same, pair_chi_squares(rho, alpha, covariance, k, k + 1), np.nan)
    distance = np.where(np.isnan(distance) & same, np.inf, distance)
    before = np.r_[np.nan, distance]
    after = np.r_[distance, np.nan]
    fidelity = np.where(
        np.isnan(before), 2.0 * after, np.where(np.isnan(after), 2.0 * before, before + after)
    )
    return fidelity < threshold


def _window_runs(
    start: np.ndarray, group: np.ndarray, window: int
) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Step 4: runs of consecutive similar windows as segments ``[a, b]``."""
    if start.size == 0:
        return _EMPTY, _EMPTY, _EMPTY
    new = np.r_[True, (np.diff(start) != 1) | (np.diff(group) != 0)]
    first = np.flatnonzero(new)
    last = np.r_[first[1:] - 1, start.size - 1]
    return start[first], start[last] + window - 1, group[first]


def _resolve_overlaps(
    returns: Returns,
    moments: Moments,
    a: np.ndarray,
    b: np.ndarray,
    group: np.ndarray,
    sigma: np.ndarray,
    merge_chi2: float,
) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Step 5: merge or divide overlapping neighbours, left to right.

    The runs kept are compacted in place (``kept`` is the last one), so a merge costs no
    copy of the arrays: linear in the runs, not quadratic."""
    a, b, group = a.copy(), b.copy(), group.copy()
    if a.size == 0:
        return a, b, group
    kept = 0
    for following in range(1, a.size):
        if group[kept] == group[following] and b[kept] >= a[following]:
            pair = np.array([kept, following])
            rho, alpha, covariance = _lines_and_covariances(
                returns, moments, a[pair], b[pair], sigma
            )
            if pair_chi_squares(rho, alpha, covariance, _FIRST, _SECOND)[0] < merge_chi2:
                b[kept] = max(b[kept], b[following])
                continue
            b[kept], a[following] = _best_cut(moments, a[kept], b[kept], a[following], b[following])
        kept += 1
        a[kept], b[kept], group[kept] = a[following], b[following], group[following]
    return a[: kept + 1], b[: kept + 1], group[: kept + 1]


def _best_cut(moments: Moments, a1: int, b1: int, a2: int, b2: int) -> tuple[int, int]:
    """End of the first and start of the second run, cut where the summed SSE is least."""
    end = np.arange(max(a2 - 1, a1 + 1), min(b1, b2 - 2) + 1, dtype=np.int64)
    if end.size == 0:
        return b1, b1 + 1
    sse = fit_many(TLS, moments, np.full(end.size, a1, dtype=np.int64), end)[2]
    sse = sse + fit_many(TLS, moments, end + 1, np.full(end.size, b2, dtype=np.int64))[2]
    best = int(end[np.argmin(sse)])
    return best, best + 1


_FIRST, _SECOND = np.array([0]), np.array([1])
