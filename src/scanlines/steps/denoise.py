"""Denoising before breakpoint detection (Steps 2-3, eq. 5 and 20 of [1]_).

Two readings of the paper's isolated-noise rule:

``literal_noise``  Step 2 as written: point ``i`` is noise when ``d_{i-1} > d_{i-2}``
                   and ``d_i > d_{i+1}``. On real scans this fires on a large share
                   of ordinary points (any local bump of the neighbour distance).
``isolated_noise`` the tighter reading used by default: point ``i`` is noise when
                   the breakpoint test separates it from *both* neighbours while
                   those two neighbours pass the test with each other (a spike
                   that would otherwise form a one-point cluster).

Step 3 replaces a noise point and its two neighbours by the mean of a window of
``N`` points centred on it (``window_means``). The window never
spans a pair of returns that the raw breakpoint test separates, so smoothing
cannot move a breakpoint. The default instead drops an isolated point (it then
counts as one missing beam, which clustering bridges): no point is invented. It
also drops single-return clusters and two-return clusters that lie in depth between
their neighbours (mixed pixels); ``denoise`` is the whole stage.

The rules in detail:

* the literal rule works on the neighbour distances ``d_i = |P_{i+1} - P_i|`` and never
  flags the first or last two points;
* the isolated rule flags point ``i`` when the breakpoint test cuts it from both
  neighbours, the neighbours are at most two beams apart (no beam missing on either
  side of ``i``) and the test between them, ``|P_{i+1} - P_{i-1}|`` against its threshold at that
  gap, keeps them together;
* the window of Step 3, ``[i - N//2, i - N//2 + N - 1]``, is clipped to the raw cluster of
  ``i``, and neighbours across a raw break are left alone; where two windows overlap, a
  point takes the mean of the noise point to its left (left neighbours are moved first,
  then the points, then the right neighbours). The moved points take the range of their
  new position;
* after the isolated points, clusters of fewer than ``min_cluster_points`` returns (the
  breakpoint test redone without the isolated points) are dropped, the first and last
  clusters of a full circle whose seam is continuous counting as one: a cluster of one or
  two returns between two jumps is, far more often than a real object, a mixed pixel (a
  return between two surfaces) or a spurious echo;
* with ``min_cluster_points == 2`` also two-return clusters whose ranges lie between the
  facing returns of the clusters on either side, within ``margin`` (the breakpoint margin),
  are dropped: two mixed pixels, or one with the last return of the near surface cut off by
  the jump. A small object in front of a wall is nearer than both sides and stays. Only
  clusters whose neighbours are at most one missing beam away, and are not small
  themselves, are judged.

The stage returns the cleaned returns, the beams dropped as noise (``Extraction.outliers``)
and, when nothing moved or was dropped, the break flags already computed.

The kernels are C++ (``cpp/scanlines/steps/denoise.cpp``), called by the adaptive
method's kernel; ``scanlines._core`` binds ``literal_noise``, ``isolated_noise``,
``window_means``, ``small_clusters`` and ``in_between_clusters`` for the tests.

References
----------
.. [1] Electronics 11(11), 1759, 2022 (doi:10.3390/electronics11111759), sec. 2.1 and sec. 3.
"""

from __future__ import annotations

__all__ = ["DENOISE", "DENOISE_CODES", "ISOLATED", "LITERAL", "NO_DENOISE"]

DENOISE = ("isolated", "paper", "none")
DENOISE_CODES = {name: code for code, name in enumerate(DENOISE)}
ISOLATED, LITERAL, NO_DENOISE = range(3)
