"""The line-segment extractor of the Electronics 2022 paper, as printed.

One choice per step, the paper's [1]_ (sec. 2-3; the equation numbers are the paper's):

1. Step 1: the points ``x_i = rho_i cos theta_i``, ``y_i = rho_i sin theta_i`` in the
   sensor frame (eq. 2-3) and the neighbour distances ``d_i = |P_{i+1} - P_i|`` (eq. 4/19).
2. Steps 2-3, denoising (eq. 5/20): point ``i`` is a noise point when
   ``d_{i-1} > d_{i-2}`` and ``d_i > d_{i+1}``; it and its two neighbours are replaced by
   the mean of the ``window`` points centred on it (``N = 10``), the window kept inside
   the clusters of the raw points so that no mean spans a jump. No point is dropped
   (:mod:`scanlines.steps.denoise`, ``"paper"``).
3. Step 4, adaptive nearest-neighbour breakpoints (eq. 6-7/21): consecutive returns
   belong to one cluster while ``d_i < D = k rho_i dtheta`` (``k = 3``); one missing beam
   is bridged with the spacing doubled, two or more end a cluster
   (:mod:`scanlines.steps.breakpoints`, ``"paper"`` with no noise term).
4. Step 5, corner candidates (eq. 12-13): the slope difference
   ``Dk(i) = |rho_i - rho_{i-1}| / (rho_{i-1} dtheta) - |rho_{i+1} - rho_i| / (rho_i dtheta)``
   of the ranges, a candidate where ``|Dk(i)|`` exceeds both neighbours' inside a
   cluster; a corner that leaves fewer than two points on a side is not cut
   (:mod:`scanlines.steps.corners`, ``"dk"``).
5. Steps 6-7, the threshold (eq. 14): ``dkth`` swept over ``dkth_range`` = ``(0, 0.052)``
   in steps of ``dkth_step`` = 0.01 (at most ``max_evaluations``); each cut of the
   clusters at the candidates with ``|Dk| > dkth`` is fitted, and the one with the
   smallest sum of squared fitting errors (SSE, ``W_i = 1``) is kept
   (:mod:`scanlines.steps.select`, ``"sse"``).
6. Step 8, the lines (eq. 15-17/22): each part between breakpoints and corners, the corner
   point shared by the parts on both sides, is divided into five sub-sets; a line
   ``y = kx + b`` is fitted by ordinary least squares to the five sub-set means, and the
   segment's ends are its first and last points projected onto it (:mod:`scanlines.steps.fit`,
   ``"paper"``).

Parts of at least ``min_points`` returns and ``min_length`` metres are reported; the events
between them are the clusters' breakpoints and the corners where two kept parts of one
cluster meet (the shared corner point's beam). The paper has no noise model: the range
noise (the sensor profile's noise line, else the scan's own, :mod:`scanlines.steps.noise`)
is used only for the segments' covariances (``range_sigma`` overrides it) and, on a
full-circle scan that is one closed ring, for the window that places the ring's start.

Known consequences of the literal method:

* Step 2 fires on any local bump of the neighbour distance: about a quarter of the points
  of a straight noisy wall are moved.
* At fine resolution ``|Dk|`` is dominated by range noise (at 0.33 deg and 1 cm noise one
  noisy pair gives ``|Dk|`` near 0.8), so nearly every peak exceeds every ``dkth`` of
  ``(0, 0.052)``; and since more cuts never raise a least-squares error, the smallest SSE
  always picks the lowest threshold, i.e. every candidate.
* ``D = k rho dtheta`` with ``k = 3`` cuts every wall seen beyond 70.5 deg of incidence.
* ``y = kx + b`` has no line parallel to the y axis (NaN there).
* NaN lines: Step 3 replaces a noise point and its two neighbours by one window mean, so
  the three become one point; the sweep then often cuts exactly those three into a run of
  their own, which has no ``y = kx + b`` line. On the first 100 scans of the Freiburg
  excerpt 1,473 of 9,647 segments (15 %) are NaN, 1,394 of them 3-point runs (most of the
  rest 4-point runs holding such a triple). It is the paper as printed; the ``adaptive``
  method's default neither moves points nor fits ``y = kx + b``.

It gives the features of ``Extractor("adaptive", preset="paper")`` bit for bit (tested);
the ``adaptive`` method documents its deviations from the paper and why.

The kernel is C++ (``cpp/scanlines/methods/paper.cpp``, ``paper_scan``): one call per stack
of scans, without the GIL, the steps above in order.

References
----------
.. [1] "An adaptive threshold line segment feature extraction algorithm for laser
   radar scanning environments", Electronics 11(11), 1759, 2022.
   doi:10.3390/electronics11111759
"""

from __future__ import annotations

from typing import Any, ClassVar

import numpy as np

from scanlines._core import paper_stack
from scanlines.methods.base import CompiledMethod
from scanlines.params import MAX_METRES, Param, Settings, float_pair, integer, number
from scanlines.steps.assemble import output_settings
from scanlines.steps.breakpoints import CLUSTERING
from scanlines.steps.select import threshold_grid

__all__ = ["Paper"]


class Paper(CompiledMethod):
    """The paper's extractor as printed (module docstring)."""

    name = "paper"
    #: The paper's parameters with its values (sec. 4: ``N = 10``, ``k = 3``, ``dkth`` in
    #: ``(0, 0.052)``) and the output ones every method has. The thresholds are the
    #: kernel's grid, not settings. The adaptive method takes its options of the paper's
    #: steps from here.
    settings: ClassVar[Settings] = Settings(
        clustering={
            "window": Param(10, integer(1, 1000), "denoising: mean-filter window N (eq. 5)"),
            "k": CLUSTERING["k"],
        },
        segments={
            "dkth_range": Param(
                (0.0, 0.052),
                float_pair(high=MAX_METRES),
                "threshold range (a, b) of dkth (Steps 6-7)",
                (),
            ),
            "dkth_step": Param(
                0.01, number(low=1e-9, high=MAX_METRES), "threshold step (Steps 6-7)", ()
            ),
            "max_evaluations": Param(100, integer(1, 10_000), "most thresholds tried", ()),
        },
        output=output_settings(2),
    )

    def kernel_arguments(self) -> tuple[dict[str, Any], np.ndarray]:
        """The settings and the thresholds ``dkth`` tried."""
        low, high = self.params["dkth_range"]
        step, most = self.params["dkth_step"], self.params["max_evaluations"]
        return self.record, threshold_grid(low, high, step, most)

    @staticmethod
    def kernel(*arguments):
        return paper_stack(*arguments)
