"""Splitting runs of points: at the point farthest from the chord, and at the corners a
sweep chose.

``split_at_farthest``  the recursive split of iterative end-point fit [1]_ [2]_
                       (``reference`` :data:`CHORD`: a run is split while a point is
                       farther than the threshold from the chord from its first to its
                       last point) and of split-and-merge [3]_ (:data:`LINE`: ... from
                       the run's total-least-squares line). Either way the cut is at the
                       interior point farthest from the chord, runs are split depth
                       first, and the split point joins the part whose line (fitted
                       without it) it is nearer, so no point is lost.
``cut_at``             the runs of clusters cut at chosen corners (the adaptive and
                       paper methods).

The adaptive method's own splits (each cut moved by one position where that fits better,
the residual bound) are in its files (:mod:`scanlines.methods.adaptive`).

References
----------
.. [1] R. O. Duda and P. E. Hart, *Pattern Classification and Scene Analysis*,
   Wiley, 1973 (iterative end-point fit).
.. [2] T. Pavlidis and S. L. Horowitz, "Segmentation of plane curves", IEEE Trans.
   Computers C-23(8), 860-870, 1974 (split-and-merge).
.. [3] V. Nguyen, A. Martinelli, N. Tomatis and R. Siegwart, "A comparison of line
   extraction algorithms using 2D laser rangefinder for indoor mobile robotics",
   IEEE/RSJ IROS 2005, 1929-1934.
"""

from __future__ import annotations

__all__ = [
    "CHORD",
    "LINE",
    "REFERENCE_CODES",
]

CHORD, LINE = 0, 1
REFERENCE_CODES = {"chord": CHORD, "line": LINE}
