"""Split-and-merge with a chi-square merge, after laser_line_extraction.

Algorithm (Pavlidis and Horowitz [1]_, as described by Nguyen et al. [2]_; the
parameters and their meaning as documented by the ROS package
laser_line_extraction [3]_):

1. outlier filter: a return whose range differs by more than ``outlier_distance``
   from both neighbours' and that lies farther than ``split_distance`` from the
   line through them is dropped (reported as an outlier); at the ends of the
   scan the two neighbours on one side are used;
2. clustering by a fixed jump distance: ``breakpoints="fixed"`` with
   ``jump_distance = 0.4`` m, the package's ``max_line_gap`` (points of one line
   are never farther apart);
3. split: fit a total-least-squares line to each run, split at the interior
   point farthest from it while that distance exceeds ``split_distance``
   (0.05 m, the package's ``min_split_dist``)
   (``split_at_farthest``, reference ``LINE``); the split
   point joins the part whose line it is nearer, so no point is lost;
4. filter: runs with fewer than ``min_points`` (9, ``min_line_points``) points or
   shorter than ``min_length`` (0.5 m, ``min_line_length``) are dropped, as the
   package does before merging (the line of a fragment of a few returns is
   mostly noise, and its first-order covariance understates that, so a fragment
   left between two halves of a wall would keep them apart);
5. merge: neighbouring runs of one cluster whose ``(rho, alpha)`` agree,
   ``dL^T (P_1 + P_2)^-1 dL < merge_chi2`` (3, the package's bound), with
   covariances propagated from ``range_sigma`` (0.02 m, the package's
   ``range_std_dev``) and the angle difference wrapped to ``(-pi, pi]``; the most
   similar pair first, refitted over everything from the first's start to the
   second's end (returns of a dropped fragment between them included), until
   none passes (``merge_by_chi_square``);
6. corners by the shared rule of ``segment_events``,
   breakpoints from step 2.

Differences from the package, on purpose: its split drops the point before the
split and the last point of every part (no point is lost here, and a merged
line takes the returns between its parts); its merge compares angles without
wrapping, so two halves of a wall seen at ``alpha`` near ``+-pi`` never merge
(wrapped here); it merges across gaps (here only within a cluster, which keeps
the breakpoints consistent with the segments); it merges left to right (here
the most similar pair first); its lines come from Pfister et al.'s weighted fit
with bearing noise (total least squares and range noise only, here); its
``min_range`` is the scan's ``range_min``.

References
----------
.. [1] T. Pavlidis and S. L. Horowitz, "Segmentation of plane curves", IEEE
   Trans. Computers C-23(8), 860-870, 1974.
.. [2] V. Nguyen, A. Martinelli, N. Tomatis and R. Siegwart, "A comparison of
   line extraction algorithms using 2D laser rangefinder for indoor mobile
   robotics", IEEE/RSJ IROS 2005.
.. [3] M. Gallant, laser_line_extraction (ROS package),
   https://github.com/kam3k/laser_line_extraction, README "Parameters".
"""

from __future__ import annotations

from dataclasses import replace
from typing import ClassVar

from scanlines._core import split_merge_stack
from scanlines.methods.iepf import SplitMethod
from scanlines.params import Param, Settings, number
from scanlines.steps.assemble import output_settings
from scanlines.steps.breakpoints import CLUSTERING, published_clustering
from scanlines.steps.events import EVENTS


class SplitMerge(SplitMethod):
    """Split-and-merge with a chi-square merge (module docstring)."""

    name = "split_merge"
    settings: ClassVar[Settings] = Settings(
        clustering={
            **published_clustering("fixed", "split-and-merge: fixed, max_line_gap"),
            "jump_distance": replace(
                CLUSTERING["jump_distance"],
                default=0.4,
                doc="fixed rule: largest neighbour distance, metres (laser_line_extraction "
                "max_line_gap)",
            ),
            "outlier_distance": Param(
                0.05,
                number(low=0.0, low_open=True),
                "outlier: range difference to both neighbours (m; outlier_dist)",
            ),
        },
        segments={
            "split_distance": Param(
                0.05,
                number(low=0.0, low_open=True),
                "split where a point is this far from the run's fitted line (m; min_split_dist)",
            ),
            "merge_chi2": Param(
                3.0,
                number(low=0.0),
                "merge neighbours while chi-square of (rho, alpha) is below this",
            ),
        },
        events=EVENTS,
        output=output_settings(9, min_length=0.5, range_sigma=0.02),
    )

    reference = "line"

    @staticmethod
    def kernel(*arguments):
        return split_merge_stack(*arguments)
