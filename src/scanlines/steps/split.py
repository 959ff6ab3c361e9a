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

from scanlines import _core
from scanlines.steps.arrays import float64s, int64s
from scanlines.steps.fit import Moments

__all__ = [
    "CHORD",
    "LINE",
    "REFERENCE_CODES",
    "chord_distance",
    "split_at_farthest",
]

CHORD, LINE = 0, 1
REFERENCE_CODES = {"chord": CHORD, "line": LINE}


def chord_distance(x, y, a: int, b: int, p: int) -> float:
    """Distance of point ``p`` to the chord from point ``a`` to point ``b``.

    The chord is the segment between the two points: a point whose foot lies beyond an
    end is measured to that end. For a cluster that nearly closes on itself (a room seen
    all round) the chord is short and its line points anywhere; measured to the segment,
    the farthest point is the far corner, not an arbitrary point of the side opposite the
    chord.
    """
    return _core.chord_distance(float64s(x), float64s(y), a, b, p)


def split_at_farthest(x, y, moments: Moments, a, b, group, threshold: float, reference: int):
    """Each run ``[a, b]`` (of ``group``) split recursively, depth first (module docstring).

    Returns ``a, b, group`` of the final runs, each input run's parts in order
    (so sequence order for disjoint runs given in order).
    """
    return _core.split_at_farthest(
        float64s(x), float64s(y), *moments, int64s(a), int64s(b), int64s(group), float(threshold),
        int(reference),
    )  # fmt: skip
