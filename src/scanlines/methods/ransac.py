"""Sequential RANSAC: the line with the most inliers, removed, until too few points remain.

Algorithm (Fischler and Bolles [1]_; the "RANSAC" algorithm as
described by Nguyen et al. [2]_):

1. by default on the whole scan (``breakpoints="none"``: the algorithm starts
   from the set of all points); with a clustering rule, on each cluster
   separately;
2. draw ``trials`` pairs of free points uniformly at random; each pair defines a
   line; the line with the most free points within ``inlier_distance`` wins (with
   more than :data:`SCORED_POINTS` free points, the lines are scored on a random
   sample of that many, so a huge scan costs linear time);
3. refit the winner's inliers by total least squares and collect the inliers of
   the refitted line;
4. cut the consensus set into runs contiguous in beam order
   (:func:`scanlines.methods.consensus.inlier_runs`: one return off the line is
   bridged and dropped as an outlier; a gap of two or more missing beams, or
   consecutive inliers more than ``max_gap`` apart, end a run); runs with at
   least ``min_points`` inliers become segments and leave the set (a set without
   such a run leaves as a whole) -- :mod:`scanlines.methods.consensus`;
5. repeat from 2 until fewer than ``min_points`` points remain, the best line
   has fewer inliers, or ``max_misses`` lines in a row made no segment;
6. segments shorter than ``min_length`` are dropped; corners and (on the whole
   scan) breakpoints between consecutive segments by the shared rule of
   ``segment_events``.

The draws come from ``numpy.random.default_rng(seed)``, created anew for every
scan: one seed gives the same result for the same scan.

Defaults: ``inlier_distance = 0.05`` m (about 3 standard deviations of the 1-2 cm
range noise of the simulated sensors, quantisation included); ``trials = 200``:
with uniform pairs a wall holding a fraction ``w`` of the points is drawn with
probability ``1 - (1 - w^2)^trials``, 99.97 % for ``w = 0.2`` (the wall found
first is the largest; smaller ones are searched among the remaining points);
``max_gap = 0.4`` m (as laser_line_extraction's ``max_line_gap``);
``min_points = 5``, ``min_length = 0``, ``seed = 0``.

The pairs are drawn from the whole scan, as in the literature: a line through
two far-apart points of different walls can collect more inliers than a short
wall; such a consensus set is broken into short runs and discarded.

References
----------
.. [1] M. A. Fischler and R. C. Bolles, "Random sample consensus: a paradigm for
   model fitting with applications to image analysis and automated
   cartography", Communications of the ACM 24(6), 381-395, 1981.
.. [2] V. Nguyen, A. Martinelli, N. Tomatis and R. Siegwart, "A comparison of
   line extraction algorithms using 2D laser rangefinder for indoor mobile
   robotics", IEEE/RSJ IROS 2005.
"""

from __future__ import annotations

import math
from typing import Any, ClassVar

import numpy as np

from scanlines.methods.consensus import MAX_MISSES, WHOLE_SCAN, ConsensusMethod
from scanlines.params import Param, Settings, integer, number
from scanlines.steps.assemble import output_settings
from scanlines.steps.breakpoints import published_clustering
from scanlines.steps.events import EVENTS
from scanlines.steps.returns import Returns

#: Most random pairs drawn per line (the cost grows with trials times the points).
MAX_TRIALS = 10_000
#: Most free points each drawn line is scored on: beyond this, a random sample of them
#: (scans of real 2D lasers have fewer returns, and are scored on all of them).
SCORED_POINTS = 4096
#: Distances computed at once while scoring (8 bytes each).
BLOCK_CELLS = 1 << 21


class Ransac(ConsensusMethod):
    """Sequential RANSAC (module docstring)."""

    name = "ransac"
    settings: ClassVar[Settings] = Settings(
        clustering=published_clustering(WHOLE_SCAN),
        segments={
            "max_misses": MAX_MISSES,
            "inlier_distance": Param(
                0.05,
                number(low=0.0, low_open=True),
                "largest distance of an inlier from its line (m)",
            ),
            "trials": Param(200, integer(1, MAX_TRIALS), "random point pairs drawn per line"),
            "max_gap": Param(
                0.4,
                number(low=0.0, low_open=True),
                "largest distance between consecutive inliers (m)",
            ),
            "seed": Param(0, integer(0, 2**63 - 1), "seed of the random draws (per scan)"),
        },
        events=EVENTS,
        output=output_settings(5),
    )

    def new_search(self) -> np.random.Generator:
        return np.random.default_rng(self.params["seed"])

    def line_finder(self, returns: Returns, member: np.ndarray, search: Any) -> RandomSampler:
        return RandomSampler(returns, search, self.params["trials"], self.params["inlier_distance"])


class RandomSampler:
    """Line proposals from random pairs of free points (step 2)."""

    def __init__(
        self, returns: Returns, rng: np.random.Generator, trials: int, inlier_distance: float
    ) -> None:
        self.returns = returns
        self.rng = rng
        self.trials = trials
        self.inlier_distance = inlier_distance

    def best_line(self, free: np.ndarray) -> tuple[float, float] | None:
        """The line through the drawn pair with the most free points near it."""
        points = np.flatnonzero(free)
        m = points.size
        if m < 2:
            return None
        first = self.rng.integers(0, m, self.trials)
        second = self.rng.integers(0, m - 1, self.trials)
        second = second + (second >= first)
        x, y = self.returns.x[points], self.returns.y[points]
        dx, dy = x[second] - x[first], y[second] - y[first]
        length = np.hypot(dx, dy)
        usable = length > 0.0
        if not usable.any():
            return None
        nx, ny = -dy[usable] / length[usable], dx[usable] / length[usable]
        rho = nx * x[first[usable]] + ny * y[first[usable]]
        if m > SCORED_POINTS:  # score the lines on a random sample of the free points
            sample = self.rng.choice(m, SCORED_POINTS, replace=False)
            x, y = x[sample], y[sample]
        best = int(np.argmax(self._inlier_counts(nx, ny, rho, x, y)))
        return float(rho[best]), math.atan2(float(ny[best]), float(nx[best]))

    def _inlier_counts(self, nx, ny, rho, x, y) -> np.ndarray:
        """Points of ``x, y`` within ``inlier_distance`` of each line, in blocks of lines
        (memory stays at about :data:`BLOCK_CELLS` distances)."""
        counts = np.empty(nx.size, dtype=np.int64)
        block = max(1, BLOCK_CELLS // max(x.size, 1))
        for start in range(0, nx.size, block):
            part = slice(start, start + block)
            distance = np.outer(nx[part], x) + np.outer(ny[part], y) - rho[part, None]
            counts[part] = np.count_nonzero(np.abs(distance) <= self.inlier_distance, axis=1)
        return counts

    def remove(self, positions: np.ndarray) -> None:
        """Nothing to forget: every draw looks at the free points only."""
