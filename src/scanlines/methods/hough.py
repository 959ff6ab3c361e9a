"""Hough transform: the most-voted line, its inliers removed, until the peak is too low.

Algorithm (Hough [1]_ in the normal parametrisation of Duda and Hart [2]_; the
"Hough Transform" algorithm as described by Nguyen et al. [3]_):

1. by default on the whole scan (``breakpoints="none"``: the algorithm starts
   from the set of all points); with a clustering rule, on each cluster
   separately;
2. every point votes, for every angle ``alpha_j = j * angle_resolution`` in
   ``[0, pi)``, for the cell of ``rho = u cos alpha_j + v sin alpha_j`` rounded to
   ``rho_resolution`` (``u, v`` relative to the points' centroid, so the
   accumulator spans only the cluster); the accumulator is built once and votes
   are subtracted as points leave;
3. the cell with the most votes is the next line; below ``min_votes`` the search
   ends;
4. its inliers (free points within ``inlier_distance``) are refitted by total
   least squares and collected again, cut into runs contiguous in beam order
   (one return off the line bridged and dropped as an outlier; two or more
   missing beams, or inliers more than ``max_gap`` apart, end a run); runs with at
   least ``min_points`` inliers become segments and their points' votes are
   removed (a set without such a run is removed as a whole) --
   :mod:`scanlines.methods.consensus`;
5. segments shorter than ``min_length`` are dropped; corners and (on the whole
   scan) breakpoints between consecutive segments by the shared rule of
   ``segment_events``.

Defaults: ``angle_resolution = 1`` deg and ``rho_resolution = 0.02`` m (the cell
is about the width of the 1-2 cm range noise; a 1 deg error tilts a 2 m wall by
3.5 cm at its ends, within ``inlier_distance = 0.05`` m of the refitted line);
``min_votes = 5``, ``max_gap = 0.4`` m, ``min_points = 5``, ``min_length = 0``.
When the points span more than ``MAX_RHO_BINS`` cells (returns beyond about
40 m at 2 cm) the rho cells are widened to fit.

References
----------
.. [1] P. V. C. Hough, "Method and means for recognizing complex patterns",
   U.S. Patent 3,069,654, 1962.
.. [2] R. O. Duda and P. E. Hart, "Use of the Hough transformation to detect
   lines and curves in pictures", Communications of the ACM 15(1), 11-15, 1972.
.. [3] V. Nguyen, A. Martinelli, N. Tomatis and R. Siegwart, "A comparison of
   line extraction algorithms using 2D laser rangefinder for indoor mobile
   robotics", IEEE/RSJ IROS 2005.
"""

from __future__ import annotations

import math
from typing import Any, ClassVar

import numpy as np

from scanlines.methods.consensus import MAX_MISSES, WHOLE_SCAN, ConsensusMethod
from scanlines.params import MAX_COUNT, Param, Settings, integer, number
from scanlines.steps.assemble import output_settings
from scanlines.steps.breakpoints import published_clustering
from scanlines.steps.events import EVENTS
from scanlines.steps.returns import Returns

MAX_RHO_BINS = 4096
"""Most rho cells of an accumulator (the cells widen beyond)."""
MIN_RHO_RESOLUTION = 1e-6
"""Finest rho cell (m): the points' reach over it is a finite number of cells (a cell of
5e-324 m made that count infinite); far below any scanner's range noise."""
MAX_RHO_RESOLUTION = 1e3
"""Coarsest rho cell (m): every scan's points fall in a few cells."""
BLOCK_CELLS = 1 << 21
"""Votes computed at once (a block of points times the angles)."""


class Hough(ConsensusMethod):
    """Hough transform (module docstring)."""

    name = "hough"
    settings: ClassVar[Settings] = Settings(
        clustering=published_clustering(WHOLE_SCAN),
        segments={
            "max_misses": MAX_MISSES,
            "rho_resolution": Param(
                0.02,
                number(low=MIN_RHO_RESOLUTION, high=MAX_RHO_RESOLUTION),
                "accumulator cell size in rho (m)",
            ),
            "angle_resolution": Param(
                1.0, number(low=0.05, high=90.0), "accumulator cell size in alpha (deg)"
            ),
            "min_votes": Param(5, integer(1, MAX_COUNT), "fewest votes of an accumulator peak"),
            "inlier_distance": Param(
                0.05,
                number(low=0.0, low_open=True),
                "largest distance of an inlier from its line (m)",
            ),
            "max_gap": Param(
                0.4,
                number(low=0.0, low_open=True),
                "largest distance between consecutive inliers (m)",
            ),
        },
        events=EVENTS,
        output=output_settings(5),
    )

    def line_finder(self, returns: Returns, member: np.ndarray, search: Any) -> Accumulator:
        return Accumulator(
            returns,
            member,
            rho_resolution=self.params["rho_resolution"],
            angle_resolution=math.radians(self.params["angle_resolution"]),
            min_votes=self.params["min_votes"],
        )


class Accumulator:
    """The ``(alpha, rho)`` vote array of the points ``member`` (steps 2-3)."""

    def __init__(
        self,
        returns: Returns,
        member: np.ndarray,
        *,
        rho_resolution: float,
        angle_resolution: float,
        min_votes: int,
    ) -> None:
        points = np.flatnonzero(member)
        self.centre = (float(returns.x[points].mean()), float(returns.y[points].mean()))
        u, v = returns.x[points] - self.centre[0], returns.y[points] - self.centre[1]
        self.angles = np.arange(0.0, math.pi, angle_resolution)
        reach = float(np.max(np.hypot(u, v)))
        half = math.ceil(reach / rho_resolution)
        if 2 * half + 1 > MAX_RHO_BINS:
            half = (MAX_RHO_BINS - 1) // 2
            rho_resolution = max(reach / half, rho_resolution)
        self.resolution = rho_resolution
        self.half = half
        self.n_rho = 2 * half + 1
        self.u, self.v = u, v
        self.votes = np.zeros(self.angles.size * self.n_rho, dtype=np.int64)
        block = max(1, BLOCK_CELLS // self.angles.size)
        for start in range(0, points.size, block):
            self.votes += self._tally(np.arange(start, min(start + block, points.size)))
        self.row = np.full(returns.index.shape[0], -1, dtype=np.intp)
        self.row[points] = np.arange(points.size)
        self.min_votes = min_votes

    def _tally(self, rows: np.ndarray) -> np.ndarray:
        """The votes of the points ``rows`` (of the member points), one per angle. Cells
        are computed when needed, never stored: memory stays at about
        :data:`BLOCK_CELLS` cells whatever the number of points."""
        rho = np.outer(self.u[rows], np.cos(self.angles)) + np.outer(
            self.v[rows], np.sin(self.angles)
        )
        cell = np.clip(
            np.rint(rho / self.resolution).astype(np.intp) + self.half, 0, self.n_rho - 1
        )
        cell += np.arange(self.angles.size) * self.n_rho
        return np.bincount(cell.ravel(), minlength=self.votes.size)

    def best_line(self, free: np.ndarray) -> tuple[float, float] | None:
        """``(rho, alpha)`` of the most-voted cell in the scan's local frame, or ``None``."""
        peak = int(np.argmax(self.votes))
        if self.votes[peak] < self.min_votes:
            return None
        alpha = float(self.angles[peak // self.n_rho])
        rho = (peak % self.n_rho - self.half) * self.resolution
        rho += self.centre[0] * math.cos(alpha) + self.centre[1] * math.sin(alpha)
        return rho, alpha

    def remove(self, positions: np.ndarray) -> None:
        """Subtract the votes of the points at ``positions`` (each point once)."""
        rows = self.row[positions]
        rows = rows[rows >= 0]
        self.row[positions] = -1
        block = max(1, BLOCK_CELLS // self.angles.size)
        for start in range(0, rows.size, block):
            self.votes -= self._tally(rows[start : start + block])
