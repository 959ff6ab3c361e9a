"""Events between consecutive segments: corners, and the jumps that become breakpoints.

``segment_events`` is the one rule every comparison method uses. Of two consecutive
segments, with facing end points ``P_e`` (last of the first) and ``P_s`` (first of the
second), at most ``corner_beams`` beams apart:

* they make a **corner** when their lines turn by at least ``corner_angle``
  and the lines' intersection ``X`` is within ``corner_distance`` metres of
  both ``P_e`` and ``P_s``; the corner is reported at the return nearest ``X``
  among those from ``corner_beams`` positions before ``P_e`` to
  ``corner_beams`` after ``P_s`` (a split one or two returns off the true
  corner, as noise makes it, does not move the corner);
* they **continue** one surface (no event) when they turn by less than
  ``corner_angle`` and each facing end is within ``corner_distance`` of the
  other segment's line: one wall cut in two;
* otherwise, and always when the facing ends are farther apart in beams, the
  pair is a **jump**.

A method with its own clustering tests only segments of one cluster and takes
its breakpoints from the clustering. A method without (RANSAC and Hough on
the whole scan) reports a **breakpoint** at the last beam of the first
segment of every jump. In a full-circle scan the last segment is followed by
the first, across the seam.

Defaults: ``corner_beams = 2`` tolerates one return between the segments (a
corner return left to neither side). ``corner_distance = 0.2`` m: the true
corner lies within one beam spacing of the facing returns, and the spacing is
``rho dtheta / cos(incidence)``: 0.17 m for a 1 deg scanner at 5 m and 60 deg
incidence, the coarsest case of the simulated sensors' typical geometry.
``corner_angle = 10`` deg: two total-least-squares fits to halves of one wall
differ in angle by the fits' noise, about 2 deg (one standard deviation) for
0.5 m halves with 2 cm range noise at 1/3 deg; a turn of 10 deg is well beyond
that, while real corners of indoor walls turn by far more.

``junction_events`` is the adaptive method's own rule between the segments of one
cluster: the corner beam nearer the lines' intersection, or a breakpoint where the
lines do not meet near their facing ends, or no event where their turn is within the
noise of their directions.
"""

from __future__ import annotations

from scanlines import _core
from scanlines.extraction import END_KINDS
from scanlines.params import Param, integer, number, radians

__all__ = [
    "CORNER_SIGMAS",
    "END_KINDS",
    "EVENTS",
]

EVENTS: dict[str, Param] = {
    "corner_beams": Param(
        2, integer(1, 1000), "corner: most beams between the facing ends of two segments"
    ),
    "corner_distance": Param(
        0.2,
        number(low=0.0, low_open=True),
        "corner: largest distance (m) of a facing end from the two lines' intersection",
    ),
    "corner_angle": Param(
        10.0,
        number(low=0.0, high=90.0),
        "corner: smallest turn between the two lines (deg)",
        (radians(),),
    ),
}
"""Parameters of the shared corner/breakpoint rule (``segment_events``)."""

CORNER_SIGMAS: float = _core.CORNER_SIGMAS
"""Standard deviations of the turn by which two segments' lines must turn to meet at a
corner (``junction_events``)."""
