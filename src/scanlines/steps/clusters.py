"""Clusters: runs of consecutive returns that belong to one surface.

A cluster is an inclusive run ``[start[c], end[c]]`` of positions; a breakpoint is
reported at the last beam of every cluster but the last. :func:`cluster_returns` is
the one clustering of every method: it cuts where the rule's
:func:`~scanlines.steps.breakpoints.break_flags` say, and joins the seam of a
full-circle scan:

* a full circle whose seam fails the breakpoint test is clustered as it is;
* one whose seam passes is rotated to start right after its first break, so that
  the cluster across the seam is one run of positions;
* one without any break is a closed ring: it is rotated to start at its strongest
  corner (:func:`~scanlines.steps.corners.ring_anchor`), where the cut the ring
  needs falls where the scan turns anyway.
"""

from __future__ import annotations

import numpy as np

from scanlines._jit import kernel
from scanlines.steps.breakpoints import break_flags, seam_break
from scanlines.steps.corners import ring_anchor
from scanlines.steps.returns import beam_gaps, rotated

__all__ = ["break_beams", "cluster_bounds", "cluster_ids", "cluster_returns", "seam_rotation"]


@kernel
def cluster_bounds(breaks):
    """Inclusive ``start, end`` positions of the runs between ``breaks`` (flags per pair)."""
    n = breaks.shape[0] + 1
    count = 1
    for flag in breaks:
        count += flag
    start = np.empty(count, dtype=np.int64)
    end = np.empty(count, dtype=np.int64)
    start[0] = 0
    c = 0
    for p in range(n - 1):
        if breaks[p]:
            end[c] = p
            c += 1
            start[c] = p + 1
    end[c] = n - 1
    return start, end


@kernel
def cluster_ids(breaks):
    """Cluster number of every position, given the break flags between positions."""
    ids = np.zeros(breaks.shape[0] + 1, dtype=np.int64)
    for p in range(breaks.shape[0]):
        ids[p + 1] = ids[p] + breaks[p]
    return ids


@kernel
def break_beams(index, end, at_seam):
    """Breakpoint beams: the last beam of each cluster but the last (and it too when
    ``at_seam``, a full circle whose seam is a break)."""
    count = end.shape[0] if at_seam else end.shape[0] - 1
    return np.sort(index[end[:count]])


@kernel
def seam_rotation(returns, gap, n_beams, step, rule):
    """How a full circle is clustered: ``(rotate_to, seam_is_break, ring)``."""
    if seam_break(returns, n_beams, step, rule):
        return 0, True, False
    breaks = break_flags(returns, gap, step, rule)
    for p in range(breaks.shape[0]):
        if breaks[p]:
            return p + 1, True, False
    return 0, False, True


@kernel
def cluster_returns(returns, n_beams, step, full_circle, rule, ring_window, known_breaks):
    """Clusters of one scan's returns, the seam of a full circle joined (module docstring).

    ``known_breaks`` are the break flags of ``returns`` if already computed (else an
    empty array); ``ring_window`` the points fitted on each side when a ring is
    anchored.

    Returns ``(returns, start, end, breakpoints, ring)``: the returns (rotated for a
    full circle), the clusters' inclusive bounds, the breakpoint beams and whether
    the scan is one closed ring.
    """
    n = returns.index.shape[0]
    none = np.zeros(0, dtype=np.int64)
    if n == 0:
        return returns, none, none.copy(), none.copy(), False
    ring = False
    at_seam = False
    if full_circle and n >= 3:
        shift, at_seam, ring = seam_rotation(
            returns, beam_gaps(returns.index, n_beams), n_beams, step, rule
        )
        if ring:
            shift = ring_anchor(returns.x, returns.y, ring_window)
        if shift:
            returns = rotated(returns, shift)
        known_breaks = np.zeros(0, dtype=np.bool_)
    if ring:
        return returns, np.zeros(1, np.int64), np.full(1, n - 1, np.int64), none, True
    breaks = known_breaks
    if breaks.shape[0] != n - 1:
        breaks = break_flags(returns, beam_gaps(returns.index, n_beams), step, rule)
    start, end = cluster_bounds(breaks)
    return returns, start, end, break_beams(returns.index, end, at_seam), False
