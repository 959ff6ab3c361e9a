"""Breakpoints: where consecutive returns stop belonging to one surface.

Four rules for the largest distance ``D`` two consecutive returns may be apart
and still be one cluster (each compares the Cartesian neighbour distance
``d_i = |P_{i+1} - P_i|``, eq. 4/19 of [1]_, against ``D``):

``"adaptive"``  ``D = k rho_i dtheta + noise_k sqrt(2) sigma`` (eq. 6-7 and 21 of [1]_,
                ``k = 3``; the paper has no noise term, ``noise_k = 0``). Without it,
                at fine resolution the difference of two noisy ranges alone
                crosses ``k rho dtheta``: at 0.33 deg, 2 m and 1 cm noise, ``D`` is
                3.5 cm and about one pair in fifty of a plain wall is cut.
``"abd"``       the Adaptive Breakpoint Detector [2]_:
                ``D = rho_i sin(dtheta) / sin(lambda - dtheta) + noise_k sqrt(2) sigma``:
                the spacing of returns on a surface seen at the largest
                incidence ``90 deg - lambda`` (the paper's ``k rho dtheta`` is the
                spacing on a surface facing the sensor, times ``k``; ``k = 3``
                tolerates incidence up to 70.5 deg, ``lambda = 10 deg`` up to 80).
                Borges and Aldon add ``3 sigma_r``: ``noise_k = 2.12``.
``"pdbs"``      point-distance-based segmentation [3]_:
                ``D = C0 + C1 min(rho_i, rho_{i+1})``, ``C1 = sqrt(2 (1 - cos dtheta))``.
``"fixed"``     a constant jump distance.

Beams with no return follow the project convention: one missing beam between two
returns is bridged (``dtheta`` is doubled for that pair), a run of two or more
always ends a cluster. A breakpoint is reported at the last valid beam before
the gap.

References
----------
.. [1] "An adaptive threshold line segment feature extraction algorithm for laser
   radar scanning environments", Electronics 11(11), 1759, 2022.
   doi:10.3390/electronics11111759
.. [2] G. A. Borges and M.-J. Aldon, "Line extraction in 2D range images for
   mobile robotics", J. Intelligent and Robotic Systems 40, 267-297, 2004.
.. [3] C. Premebida and U. Nunes, "Segmentation and geometric primitives
   extraction from 2D laser range data for mobile robot applications",
   Robotica 2005, Coimbra.
"""

from __future__ import annotations

import math
from collections.abc import Callable
from dataclasses import dataclass
from typing import Any

import numpy as np

from scanlines.params import Param, choice, number
from scanlines.scan import is_full_circle
from scanlines.steps.points import Sequence, rotate

__all__ = [
    "BREAKPOINT_PARAMS",
    "MAX_BRIDGED_GAP",
    "BreakpointRule",
    "Clusters",
    "cluster",
    "cluster_scan",
    "neighbour_distances",
    "thresholds",
]

MAX_BRIDGED_GAP = 2
"""Largest beam gap between consecutive returns that may still be one cluster
(one missing beam in between)."""

RULES = ("adaptive", "abd", "pdbs", "fixed")

BREAKPOINT_PARAMS: dict[str, Param] = {
    "breakpoints": Param("abd", choice(*RULES), "clustering rule: " + ", ".join(RULES)),
    "k": Param(3.0, number(low=0.0, low_open=True), "adaptive rule: D = k rho dtheta (eq. 7)"),
    "noise_k": Param(
        3.0, number(low=0.0), "adaptive/abd: noise margin in sigmas of a range difference"
    ),
    "line_k": Param(
        3.0,
        number(low=0.0),
        "continuing a line bridges any step: tolerance in sigmas of an extrapolation (0: off)",
    ),
    "abd_lambda": Param(
        10.0, number(low=0.0, high=90.0, low_open=True), "ABD: worst incidence angle, degrees"
    ),
    "pdbs_c0": Param(0.1, number(low=0.0), "PDBS: constant C0 in metres"),
    "jump_distance": Param(
        0.3, number(low=0.0, low_open=True), "fixed rule: largest neighbour distance, metres"
    ),
}


@dataclass(frozen=True, slots=True)
class BreakpointRule:
    """A clustering rule and its constants (see the module docstring)."""

    name: str = "adaptive"
    k: float = 3.0
    noise_margin: float = 0.0
    line_tolerance: float = 0.0
    abd_lambda: float = math.radians(10.0)
    pdbs_c0: float = 0.1
    jump_distance: float = 0.3

    @classmethod
    def from_params(cls, params: dict[str, Any], sigma: float = 0.0) -> BreakpointRule:
        """Build the rule from a method's resolved parameters and the range noise ``sigma``."""
        return cls(
            name=params["breakpoints"],
            k=params["k"],
            noise_margin=params.get("noise_k", 0.0) * math.sqrt(2.0) * sigma,
            line_tolerance=params.get("line_k", 0.0) * math.sqrt(5.0) * sigma,
            abd_lambda=math.radians(params["abd_lambda"]),
            pdbs_c0=params["pdbs_c0"],
            jump_distance=params["jump_distance"],
        )


@dataclass(frozen=True, slots=True)
class Clusters:
    """Runs of sequence positions that belong to one surface.

    ``start[c]`` and ``end[c]`` are inclusive positions; ``breakpoints`` are beam
    indices (the last valid beam before each gap), sorted.
    """

    start: np.ndarray
    end: np.ndarray
    breakpoints: np.ndarray

    def __len__(self) -> int:
        return int(self.start.shape[0])


def neighbour_distances(x: np.ndarray, y: np.ndarray) -> np.ndarray:
    """``d_i = |P_{i+1} - P_i|`` for consecutive points (eq. 4 / 19)."""
    return np.hypot(np.diff(x), np.diff(y))


def thresholds(
    rule: BreakpointRule, r_from: np.ndarray, r_to: np.ndarray, gap: np.ndarray, step: float
) -> np.ndarray:
    """Largest distance ``D`` between returns ``r_from`` and ``r_to``, ``gap`` beams apart."""
    dphi = gap * step
    if rule.name == "adaptive":
        return rule.k * r_from * dphi + rule.noise_margin
    if rule.name == "abd":
        margin = rule.abd_lambda - dphi
        with np.errstate(divide="ignore", invalid="ignore"):
            reach = np.where(margin > 0.0, r_from * np.sin(dphi) / np.sin(margin), np.inf)
        return reach + rule.noise_margin
    if rule.name == "pdbs":
        return rule.pdbs_c0 + np.sqrt(2.0 * (1.0 - np.cos(dphi))) * np.minimum(r_from, r_to)
    return np.full(np.shape(r_from), rule.jump_distance)


def is_break(seq: Sequence, rule: BreakpointRule) -> np.ndarray:
    """For each pair of consecutive positions, True where a cluster ends."""
    d = neighbour_distances(seq.x, seq.y)
    limit = thresholds(rule, seq.r[:-1], seq.r[1:], seq.gap, seq.step)
    apart = ~(d < limit)
    if rule.line_tolerance > 0.0:
        apart &= ~continues_line(seq, d, rule.line_tolerance)
    return (seq.gap > MAX_BRIDGED_GAP) | apart


def continues_line(seq: Sequence, d: np.ndarray, tolerance: float) -> np.ndarray:
    """Pairs ``(p, p+1)`` that continue the line of the pair before *and* of the pair after.

    ``P_{p+1}`` lies within ``tolerance`` of the line through ``P_{p-1}, P_p``, ``P_p``
    within ``tolerance`` of the line through ``P_{p+1}, P_{p+2}``, both neighbouring
    steps are longer than ``tolerance`` (shorter ones give a line direction that is
    mostly noise), and ``d_p`` is at most :data:`MAX_STEP_GROWTH` times the
    shorter neighbouring step. Returns on a wall seen at grazing incidence are far
    apart but collinear and evenly spaced, so a distance threshold alone cuts the
    wall; a depth jump or a spike is neither.
    """
    n = len(seq)
    out = np.zeros(max(n - 1, 0), dtype=bool)
    if n < 4:
        return out
    p = np.arange(1, n - 2)
    x, y = seq.x, seq.y
    before = _distance_to_line(x[p - 1], y[p - 1], x[p], y[p], x[p + 1], y[p + 1])
    after = _distance_to_line(x[p + 2], y[p + 2], x[p + 1], y[p + 1], x[p], y[p])
    neighbours_close = (seq.gap[p - 1] <= MAX_BRIDGED_GAP) & (seq.gap[p + 1] <= MAX_BRIDGED_GAP)
    shorter = np.minimum(d[p - 1], d[p + 1])
    steady = (d[p] <= MAX_STEP_GROWTH * shorter) & (shorter > tolerance)
    out[p] = (before < tolerance) & (after < tolerance) & neighbours_close & steady
    return out


MAX_STEP_GROWTH = 2.5
"""Largest ratio of a step to its neighbours' on a continued line (grazing walls
grow their spacing smoothly; a jump does not)."""


def _distance_to_line(ax, ay, bx, by, px, py):
    """Distance of ``P`` from the line through ``A`` and ``B`` (inf when ``A == B``)."""
    ux, uy = bx - ax, by - ay
    length = np.hypot(ux, uy)
    with np.errstate(divide="ignore", invalid="ignore"):
        distance = np.abs(ux * (py - ay) - uy * (px - ax)) / length
    return np.where(length > 0.0, distance, np.inf)


def seam_is_break(seq: Sequence, rule: BreakpointRule) -> bool:
    """The same test between the last and the first position of a full circle."""
    gap = seq.seam_gap()
    if gap > MAX_BRIDGED_GAP:
        return True
    d = math.hypot(seq.x[0] - seq.x[-1], seq.y[0] - seq.y[-1])
    limit = thresholds(rule, seq.r[-1:], seq.r[:1], np.array([gap]), seq.step)[0]
    return not d < limit


def cluster(seq: Sequence, breaks: np.ndarray, *, seam_break: bool = False) -> Clusters:
    """Cut the sequence at ``breaks`` (one flag per consecutive pair).

    ``seam_break`` adds the breakpoint of a full-circle scan whose last and first
    returns are not continuous; with a rotated sequence the caller passes the
    break that the rotation put at the end.
    """
    n = len(seq)
    if n == 0:
        empty = np.zeros(0, dtype=np.intp)
        return Clusters(empty, empty, empty)
    cut = np.flatnonzero(breaks)
    start = np.r_[0, cut + 1].astype(np.intp)
    end = np.r_[cut, n - 1].astype(np.intp)
    bp_positions = np.r_[cut, n - 1] if seam_break else cut
    return Clusters(start, end, np.sort(seq.index[bp_positions]).astype(np.intp))


def cluster_scan(
    seq: Sequence, rule: BreakpointRule, ring_anchor: Callable[[Sequence], int]
) -> tuple[Sequence, Clusters, bool]:
    """Clusters of a whole scan, with the seam of a full circle joined when continuous.

    A full circle whose seam passes the test is rotated to start right after its
    first gap, so that the cluster across the seam is one run of positions. A
    full circle without any gap (a room seen all round) is one closed ring: it is
    rotated to start at ``ring_anchor(seq)`` (a strong corner, so that the cut the
    ring needs falls where the scan turns anyway).

    Returns the (possibly rotated) sequence, its clusters and whether it is a ring.
    """
    breaks = is_break(seq, rule)
    if not is_full_circle(seq.n_beams, seq.step) or len(seq) < 3:
        return seq, cluster(seq, breaks), False
    if seam_is_break(seq, rule):
        return seq, cluster(seq, breaks, seam_break=True), False
    cut = np.flatnonzero(breaks)
    if cut.size:
        seq = rotate(seq, int(cut[0]) + 1)
        return seq, cluster(seq, is_break(seq, rule), seam_break=True), False
    seq = rotate(seq, ring_anchor(seq))
    return seq, cluster(seq, np.zeros(len(seq) - 1, dtype=bool)), True
