"""Line tracking (incremental): grow a line point by point, start anew when a point leaves it.

Algorithm (Siadat et al. [1]_; the "Incremental" algorithm as described by
Nguyen et al. [2]_):

1. cluster the returns by a fixed jump distance (``breakpoints="fixed"``,
   ``jump_distance = 0.3`` m) -- :mod:`scanlines.steps.breakpoints`;
2. in each cluster, start a line with its first two points;
3. take the next point: if it lies within ``track_distance`` of the current
   line (the total-least-squares line of the points so far), add it and refit;
   otherwise the current segment ends before it, and a new line starts with it
   and the point after it;
4. segments with fewer than ``min_points`` (5) points or shorter than
   ``min_length`` (0 m) are dropped; corners between consecutive segments of one
   cluster by the shared rule of ``segment_events``;
   breakpoints from step 1.

Default ``track_distance = 0.1`` m: with 1-2 cm range noise a point of a
straight wall is practically never that far from the line fitted so far (more
than 5 standard deviations; the line itself is uncertain where it starts, two
points give only a direction of noise).

Known limits (the paper [3]_, sec. 1): the test only sees
the distance of the *next* point, so a segment absorbs the first points past a
corner until they drift ``track_distance`` off the line (at a right angle, about
``track_distance`` of the next wall); and there is no merging, so a wall cut
by one noisy point stays cut.

Implementation: the refit after each point costs O(1) with prefix sums
(:class:`scanlines.steps.fit.Moments`); the lines of all candidate end points of
one segment are evaluated at once, so Python loops once per *segment*, not per
point (in chunks that double in length: O(n) work per scan).

References
----------
.. [1] A. Siadat, A. Kaske, S. Klausmann, M. Dufaut and R. Husson, "An optimized
   segmentation method for a 2D laser-scanner applied to mobile robot
   navigation", IFAC Symposium on Intelligent Components and Instruments for
   Control Applications, 1997.
.. [2] V. Nguyen, A. Martinelli, N. Tomatis and R. Siegwart, "A comparison of
   line extraction algorithms using 2D laser rangefinder for indoor mobile
   robotics", IEEE/RSJ IROS 2005.
.. [3] "An adaptive threshold line segment feature extraction algorithm for laser
   radar scanning environments", Electronics 11(11), 1759, 2022.
   doi:10.3390/electronics11111759
"""

from __future__ import annotations

from typing import ClassVar

import numpy as np

from scanlines.methods.base import ClusteredMethod
from scanlines.params import Param, Settings, number
from scanlines.steps.assemble import output_settings
from scanlines.steps.breakpoints import published_clustering
from scanlines.steps.events import EVENTS
from scanlines.steps.fit import TLS, Moments, fit_many, prefix_moments
from scanlines.steps.returns import Returns

_FIRST_CHUNK = 32


class LineTracking(ClusteredMethod):
    """Line tracking (module docstring)."""

    name = "line_tracking"
    settings: ClassVar[Settings] = Settings(
        clustering=published_clustering("fixed", "line tracking: fixed jump distance"),
        segments={
            "track_distance": Param(
                0.1,
                number(low=0.0, low_open=True),
                "a point farther than this from the current line starts a new one (m)",
            ),
        },
        events=EVENTS,
        output=output_settings(5),
    )

    def find_runs(self, returns, gap, start, end):
        moments = prefix_moments(returns.x, returns.y)
        threshold = self.params["track_distance"]
        runs = [
            (a, b, c)
            for c, (first, last) in enumerate(zip(start.tolist(), end.tolist(), strict=True))
            for a, b in _track(returns, moments, first, last, threshold)
        ]
        a, b, group = np.array(runs, dtype=np.int64).reshape(-1, 3).T
        return a, b, group, np.zeros(0, dtype=np.int64)


def _track(returns: Returns, moments: Moments, first: int, last: int, threshold: float):
    """Segments ``(a, b)`` of the cluster ``[first, last]``, in order."""
    runs = []
    start = first
    while start <= last:
        end = _segment_end(returns, moments, start, last, threshold)
        runs.append((start, end))
        start = end + 1
    return runs


def _segment_end(
    returns: Returns, moments: Moments, start: int, last: int, threshold: float
) -> int:
    """Last point of the segment that starts at ``start``.

    The line of ``[start, e]`` (``e >= start + 1``) is tested against point
    ``e + 1``; the first point that fails ends the segment at ``e``.
    """
    low, chunk = start + 1, _FIRST_CHUNK
    while low < last:
        end = np.arange(low, min(low + chunk, last), dtype=np.int64)
        rho, alpha, _ = fit_many(TLS, moments, np.full(end.size, start, dtype=np.int64), end)
        following = end + 1
        off = np.abs(
            returns.x[following] * np.cos(alpha) + returns.y[following] * np.sin(alpha) - rho
        )
        fails = np.flatnonzero(~(off <= threshold))
        if fails.size:
            return int(end[fails[0]])
        low, chunk = low + chunk, 2 * chunk
    return last
