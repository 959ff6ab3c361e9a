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

from scanlines._jit import jit
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


ABD_LAMBDA_FLOOR = math.radians(10.0)
"""Borges and Aldon's ``lambda``: walls up to 80 deg incidence stay one cluster."""

MAX_BRIDGED_SHARE = math.sin(math.radians(1.0)) / math.sin(math.radians(14.0))
"""Largest step, as a share of the range, that the incidence bound alone bridges in
:func:`auto_abd_lambda` (7.2 %: ``lambda`` = 15 deg at 1 deg resolution)."""


@jit(inline=True)
def auto_abd_lambda(step: float) -> float:
    """ABD's ``lambda`` (radians) for beams ``step`` apart.

    10 deg, raised where it would bridge steps of more than :data:`MAX_BRIDGED_SHARE`
    of the range: on scans coarser than 0.67 deg (15 deg at 1 deg). There, returns on
    a wall near grazing incidence are many noise sigmas apart, so the line-continuation
    test keeps such walls whole, while the 10 deg bound would also bridge depth steps
    of 10 % of the range, which then pass for corners (``docs/decisions/breakpoints.md``).
    At most 90 deg (scans coarser than 4 deg cannot keep to the share).
    """
    step = abs(step)
    bridged = math.asin(min(math.sin(step) / MAX_BRIDGED_SHARE, 1.0))
    return min(max(ABD_LAMBDA_FLOOR, step + bridged), 0.5 * math.pi)


RULE_CODES = {name: code for code, name in enumerate(RULES)}
ADAPTIVE, ABD, PDBS, FIXED = range(4)
# Positions in the array form of a rule that the kernels take.
_KIND, _K, _MARGIN, _LINE_TOL, _LAMBDA, _C0, _JUMP, _FAR_MARGIN, _GROWTH, _FAR_RANGE = range(10)


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

    def as_array(self) -> np.ndarray:
        """The rule as the kernels take it (kind code first)."""
        return rule_array(
            RULE_CODES[self.name],
            self.k,
            self.noise_margin,
            self.line_tolerance,
            self.abd_lambda,
            self.pdbs_c0,
            self.jump_distance,
        )


@jit
def rule_array(
    kind: int,
    k: float,
    noise_margin: float,
    line_tolerance: float,
    abd_lambda: float,
    pdbs_c0: float,
    jump_distance: float,
) -> np.ndarray:
    """Array form of a :class:`BreakpointRule` (``kind`` one of ``ADAPTIVE ... FIXED``)."""
    rule = np.zeros(10)
    rule[_KIND] = kind
    rule[_K] = k
    rule[_MARGIN] = noise_margin
    rule[_LINE_TOL] = line_tolerance
    rule[_LAMBDA] = abd_lambda
    rule[_C0] = pdbs_c0
    rule[_JUMP] = jump_distance
    return rule


@jit
def noise_rule(kind, k, noise_k, line_k, abd_lambda_rad, pdbs_c0, jump_distance, sigma):
    """:func:`rule_array` with the noise terms in units of the range noise ``sigma``.

    The margin is ``noise_k`` standard deviations of a difference of two ranges
    (``sqrt(2) sigma``), the line tolerance ``line_k`` standard deviations of an
    extrapolation from two points (``sqrt(5) sigma``), as in
    :meth:`BreakpointRule.from_params`.
    """
    return rule_array(
        kind,
        k,
        noise_k * math.sqrt(2.0) * sigma,
        line_k * math.sqrt(5.0) * sigma,
        abd_lambda_rad,
        pdbs_c0,
        jump_distance,
    )


@jit
def with_margin_growth(rule: np.ndarray, far_margin: float, growth: float, far_range: float):
    """The rule with a noise margin that grows with range where the noise does.

    The margin at range ``r`` becomes ``max(noise_margin, far_margin + growth (r -
    far_range))``: sensors whose range noise is a share of the range (the
    URG-04LX: 1 % beyond 1 m) need a wider margin far away than near.
    """
    out = rule.copy()
    out[_FAR_MARGIN], out[_GROWTH], out[_FAR_RANGE] = far_margin, growth, far_range
    return out


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


@jit
def neighbour_steps(x: np.ndarray, y: np.ndarray) -> np.ndarray:
    """``d_i = |P_{i+1} - P_i|`` for consecutive points (eq. 4 / 19)."""
    d = np.empty(max(x.shape[0] - 1, 0))
    for p in range(d.shape[0]):
        dx, dy = x[p + 1] - x[p], y[p + 1] - y[p]
        d[p] = math.sqrt(dx * dx + dy * dy)
    return d


def neighbour_distances(x: np.ndarray, y: np.ndarray) -> np.ndarray:
    """``d_i = |P_{i+1} - P_i|`` for consecutive points (eq. 4 / 19)."""
    return neighbour_steps(np.asarray(x, dtype=np.float64), np.asarray(y, dtype=np.float64))


@jit(inline=True)
def gap_factor(rule: np.ndarray, gap: int, step: float) -> float:
    """The part of the threshold that depends on the beam gap only (see :func:`threshold`)."""
    kind = rule[_KIND]
    dphi = gap * step
    if kind == ADAPTIVE:
        return rule[_K] * dphi
    if kind == ABD:
        margin = rule[_LAMBDA] - dphi
        return math.sin(dphi) / math.sin(margin) if margin > 0.0 else math.inf
    if kind == PDBS:
        return math.sqrt(2.0 * (1.0 - math.cos(dphi)))
    return 0.0


@jit(inline=True)
def scaled_threshold(rule: np.ndarray, factor: float, r_from: float, r_to: float) -> float:
    """The threshold from :func:`gap_factor` and the two ranges."""
    kind = rule[_KIND]
    if kind in (ADAPTIVE, ABD):
        far = rule[_FAR_MARGIN] + rule[_GROWTH] * (r_from - rule[_FAR_RANGE])
        return factor * r_from + max(rule[_MARGIN], far)
    if kind == PDBS:
        return rule[_C0] + factor * min(r_from, r_to)
    return rule[_JUMP]


@jit(inline=True)
def threshold(rule: np.ndarray, r_from: float, r_to: float, gap: int, step: float) -> float:
    """Largest distance ``D`` between returns ``r_from`` and ``r_to``, ``gap`` beams apart."""
    return scaled_threshold(rule, gap_factor(rule, gap, step), r_from, r_to)


@jit
def _thresholds(rule, r_from, r_to, gap, step):
    out = np.empty(r_from.shape[0])
    for i in range(r_from.shape[0]):
        out[i] = threshold(rule, r_from[i], r_to[i], gap[i], step)
    return out


def thresholds(
    rule: BreakpointRule, r_from: np.ndarray, r_to: np.ndarray, gap: np.ndarray, step: float
) -> np.ndarray:
    """:func:`threshold` for arrays of pairs."""
    r_from, r_to, gap = np.broadcast_arrays(
        np.asarray(r_from, dtype=np.float64), np.asarray(r_to, dtype=np.float64), np.asarray(gap)
    )
    flat = _thresholds(
        rule.as_array(),
        np.ascontiguousarray(r_from.ravel()),
        np.ascontiguousarray(r_to.ravel()),
        np.ascontiguousarray(gap.ravel(), dtype=np.int64),
        float(step),
    )
    return flat.reshape(r_from.shape)


@jit(inline=True)
def _distance_to_line(ax, ay, bx, by, px, py) -> float:
    """Distance of ``P`` from the line through ``A`` and ``B`` (inf when ``A == B``)."""
    ux, uy = bx - ax, by - ay
    length = math.hypot(ux, uy)
    if length == 0.0:
        return math.inf
    return abs(ux * (py - ay) - uy * (px - ax)) / length


@jit(inline=True)
def continues_line_at(x, y, gap, d, p: int, tolerance: float) -> bool:
    """Pair ``(p, p+1)`` continues the line of the pair before and of the pair after.

    ``P_{p+1}`` lies within ``tolerance`` of the line through ``P_{p-1}, P_p``, ``P_p``
    within ``tolerance`` of the line through ``P_{p+1}, P_{p+2}``, both neighbouring
    steps are longer than ``tolerance`` (shorter ones give a line direction that is
    mostly noise), and ``d_p`` is at most :data:`MAX_STEP_GROWTH` times the
    shorter neighbouring step. Returns on a wall seen at grazing incidence are far
    apart but collinear and evenly spaced, so a distance threshold alone cuts the
    wall; a depth jump or a spike is neither. Where one neighbouring pair does not
    exist (the scan's ends, two or more missing beams) or is itself a jump (more than
    :data:`MAX_STEP_GROWTH` times ``d_p``), the other decides alone: the first and
    last returns of a wall that starts behind an edge or ends in open space.
    """
    n = x.shape[0]
    jump = MAX_STEP_GROWTH * d[p]
    has_before = p >= 1 and gap[p - 1] <= MAX_BRIDGED_GAP and d[p - 1] <= jump
    has_after = p + 2 < n and gap[p + 1] <= MAX_BRIDGED_GAP and d[p + 1] <= jump
    if not (has_before or has_after):
        return False
    shorter = math.inf
    if has_before:
        shorter = d[p - 1]
    if has_after:
        shorter = min(shorter, d[p + 1])
    if not (d[p] <= MAX_STEP_GROWTH * shorter and shorter > tolerance):
        return False
    if has_before:
        before = _distance_to_line(x[p - 1], y[p - 1], x[p], y[p], x[p + 1], y[p + 1])
        if not before < tolerance:
            return False
    if has_after:
        after = _distance_to_line(x[p + 2], y[p + 2], x[p + 1], y[p + 1], x[p], y[p])
        if not after < tolerance:
            return False
    return True


MAX_STEP_GROWTH = 2.5
"""Largest ratio of a step to its neighbours' on a continued line (grazing walls
grow their spacing smoothly; a jump does not)."""


@jit
def break_flags(x, y, r, gap, step: float, rule: np.ndarray) -> np.ndarray:
    """For each pair of consecutive positions, True where a cluster ends."""
    n = x.shape[0]
    out = np.zeros(max(n - 1, 0), dtype=np.bool_)
    if n < 2:
        return out
    d = neighbour_steps(x, y)
    tolerance = rule[_LINE_TOL]
    factors = np.array([gap_factor(rule, g, step) for g in range(MAX_BRIDGED_GAP + 1)])
    for p in range(n - 1):
        if gap[p] > MAX_BRIDGED_GAP:
            out[p] = True
        elif not d[p] < scaled_threshold(rule, factors[gap[p]], r[p], r[p + 1]):
            out[p] = not (tolerance > 0.0 and continues_line_at(x, y, gap, d, p, tolerance))
    return out


def is_break(seq: Sequence, rule: BreakpointRule) -> np.ndarray:
    """For each pair of consecutive positions, True where a cluster ends."""
    return break_flags(seq.x, seq.y, seq.r, seq.gap, seq.step, rule.as_array())


@jit
def seam_break(x, y, r, index, n_beams: int, step: float, rule: np.ndarray) -> bool:
    """The breakpoint test between the last and the first position of a full circle."""
    gap = index[0] + n_beams - index[-1]
    if gap > MAX_BRIDGED_GAP:
        return True
    d = math.hypot(x[0] - x[-1], y[0] - y[-1])
    return not d < threshold(rule, r[-1], r[0], gap, step)


def seam_is_break(seq: Sequence, rule: BreakpointRule) -> bool:
    """The same test between the last and the first position of a full circle."""
    return bool(seam_break(seq.x, seq.y, seq.r, seq.index, seq.n_beams, seq.step, rule.as_array()))


@jit
def cluster_bounds(breaks: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
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


@jit
def break_beams(index: np.ndarray, end: np.ndarray, seam_break: bool) -> np.ndarray:
    """Breakpoint beams: the last beam of each cluster but the last (and it too at a seam)."""
    count = end.shape[0] if seam_break else end.shape[0] - 1
    return np.sort(index[end[:count]])


def cluster(seq: Sequence, breaks: np.ndarray, *, seam_break: bool = False) -> Clusters:
    """Cut the sequence at ``breaks`` (one flag per consecutive pair).

    ``seam_break`` adds the breakpoint of a full-circle scan whose last and first
    returns are not continuous; with a rotated sequence the caller passes the
    break that the rotation put at the end.
    """
    if len(seq) == 0:
        empty = np.zeros(0, dtype=np.intp)
        return Clusters(empty, empty, empty)
    start, end = cluster_bounds(np.asarray(breaks, dtype=np.bool_))
    return Clusters(start, end, break_beams(seq.index, end, seam_break))


@jit
def seam_rotation(x, y, r, index, gap, n_beams: int, step: float, rule) -> tuple[int, bool, bool]:
    """How a full circle is clustered: ``(rotate_to, seam_break, ring)``.

    A full circle whose seam fails the test is clustered as it is (with the seam
    break). One whose seam passes is rotated to start right after its first
    gap, so that the cluster across the seam is one run of positions. One
    without any gap is a closed ring: the caller picks where to cut it.
    """
    if seam_break(x, y, r, index, n_beams, step, rule):
        return 0, True, False
    breaks = break_flags(x, y, r, gap, step, rule)
    for p in range(breaks.shape[0]):
        if breaks[p]:
            return p + 1, True, False
    return 0, False, True


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
    if not is_full_circle(seq.n_beams, seq.step) or len(seq) < 3:
        return seq, cluster(seq, is_break(seq, rule)), False
    rotate_to, seam, ring = seam_rotation(
        seq.x, seq.y, seq.r, seq.index, seq.gap, seq.n_beams, seq.step, rule.as_array()
    )
    if ring:
        seq = rotate(seq, ring_anchor(seq))
        return seq, cluster(seq, np.zeros(len(seq) - 1, dtype=bool)), True
    if rotate_to:
        seq = rotate(seq, rotate_to)
    return seq, cluster(seq, is_break(seq, rule), seam_break=seam), False
