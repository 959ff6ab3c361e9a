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
  needs falls where the scan turns anyway (the largest turn angle of lines fitted to
  ``ring_window`` points on each side, scored cyclically).
"""

from __future__ import annotations

import numpy as np

from scanlines import _core
from scanlines.steps.arrays import bools
from scanlines.steps.breakpoints import BreakpointRule
from scanlines.steps.returns import Returns

__all__ = ["break_beams", "cluster_bounds", "cluster_returns"]


def cluster_bounds(breaks: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Inclusive ``start, end`` positions of the runs between ``breaks`` (flags per pair)."""
    cut = np.flatnonzero(breaks)
    return np.r_[0, cut + 1].astype(np.int64), np.r_[cut, len(breaks)].astype(np.int64)


def break_beams(index: np.ndarray, end: np.ndarray, at_seam: bool) -> np.ndarray:
    """Breakpoint beams: the last beam of each cluster but the last (and it too when
    ``at_seam``, a full circle whose seam is a break)."""
    count = len(end) if at_seam else len(end) - 1
    return np.sort(index[end[:count]])


def cluster_returns(
    returns: Returns,
    n_beams: int,
    step: float,
    full_circle: bool,
    rule: BreakpointRule,
    ring_window: int,
    known_breaks: np.ndarray,
):
    """Clusters of one scan's returns, the seam of a full circle joined (module docstring).

    ``known_breaks`` are the break flags of ``returns`` if already computed (else an
    empty array); ``ring_window`` the points fitted on each side when a ring is
    anchored.

    Returns ``(returns, start, end, breakpoints, ring)``: the returns (rotated for a
    full circle), the clusters' inclusive bounds, the breakpoint beams and whether
    the scan is one closed ring.
    """
    rotated, start, end, breakpoints, ring = _core.cluster_returns(
        *returns, int(n_beams), float(step), bool(full_circle), rule, int(ring_window),
        bools(known_breaks),
    )  # fmt: skip
    return Returns(*rotated), start, end, breakpoints, ring
