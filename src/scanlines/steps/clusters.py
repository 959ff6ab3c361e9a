"""Clusters: runs of consecutive returns that belong to one surface.

A cluster is an inclusive run ``[start[c], end[c]]`` of positions; a breakpoint is
reported at the last beam of every cluster but the last. ``cluster_returns`` is
the one clustering of every method: it cuts where the rule's
``break_flags`` say, and joins the seam of a
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

__all__: list[str] = []
