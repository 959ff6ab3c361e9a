"""Breakpoints: where consecutive returns stop belonging to one surface.

Four rules for the largest distance ``D`` two consecutive returns may be apart
and still be one cluster (each compares the Cartesian neighbour distance
``d_i = |P_{i+1} - P_i|``, eq. 4/19 of [1]_, against ``D``):

``"paper"``     ``D = k rho_i dtheta + noise_k sqrt(2) sigma`` (eq. 6-7 and 21 of [1]_,
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
from typing import NamedTuple

import numpy as np

from scanlines._jit import kernel
from scanlines.params import Param, choice, coded, number, radians
from scanlines.steps.noise import NoiseLine, noise_at, resolve_noise
from scanlines.steps.returns import MAX_BRIDGED_GAP

__all__ = [
    "ABD",
    "ADAPTIVE",
    "BREAKPOINT_PARAMS",
    "FIXED",
    "LITERAL_CLUSTERING",
    "NO_RULE",
    "PDBS",
    "RULES",
    "RULE_CODES",
    "BreakpointRule",
    "RuleSpec",
    "auto_abd_lambda",
    "break_flags",
    "make_rule",
    "neighbour_steps",
    "scan_rule",
    "seam_break",
    "threshold",
]

RULES = ("paper", "abd", "pdbs", "fixed")
RULE_CODES = {name: code for code, name in enumerate(RULES)}
ADAPTIVE, ABD, PDBS, FIXED = range(4)

BREAKPOINT_PARAMS: dict[str, Param] = {
    "breakpoints": Param(
        "abd", choice(*RULES), "clustering rule: " + ", ".join(RULES), (coded(RULE_CODES),)
    ),
    "k": Param(3.0, number(low=0.0, low_open=True), "paper rule: D = k rho dtheta (eq. 7)"),
    "noise_k": Param(
        3.0, number(low=0.0), "paper/abd: noise margin in sigmas of a range difference"
    ),
    "line_k": Param(
        3.0,
        number(low=0.0),
        "continuing a line bridges any step: tolerance in sigmas of an extrapolation (0: off)",
    ),
    "abd_lambda": Param(
        10.0,
        number(low=0.0, high=90.0, low_open=True),
        "ABD: worst incidence angle, degrees",
        (radians(),),
    ),
    "pdbs_c0": Param(0.1, number(low=0.0), "PDBS: constant C0 in metres"),
    "jump_distance": Param(
        0.3, number(low=0.0, low_open=True), "fixed rule: largest neighbour distance, metres"
    ),
}
"""The parameters of a clustering rule, shared by every method that clusters."""

LITERAL_CLUSTERING: dict[str, Param] = {
    "line_k": Param(
        0.0, BREAKPOINT_PARAMS["line_k"].check, BREAKPOINT_PARAMS["line_k"].doc + "; off here"
    )
}
"""Overrides of :data:`BREAKPOINT_PARAMS` for the comparison methods: the published
clustering rules have no line-continuation bridge."""


class BreakpointRule(NamedTuple):
    """A clustering rule and its constants (see the module docstring).

    ``kind`` is one of :data:`ADAPTIVE`, :data:`ABD`, :data:`PDBS`, :data:`FIXED`;
    ``abd_lambda`` in radians. The noise margin of a pair is ``margin_sigmas`` and the
    line tolerance ``tolerance_sigmas`` times the range noise ``noise`` (a
    :class:`~scanlines.steps.noise.NoiseLine`) at the pair's range.
    """

    kind: int
    k: float
    margin_sigmas: float
    tolerance_sigmas: float
    noise: NoiseLine
    abd_lambda: float
    pdbs_c0: float
    jump_distance: float


class RuleSpec(NamedTuple):
    """A clustering rule as a method's parameters give it: the noise terms in sigmas
    (``noise_k``, ``line_k``), ``abd_lambda`` in radians, ``breakpoints`` a rule code or
    :data:`NO_RULE` (the fields of the parameters of :data:`BREAKPOINT_PARAMS`)."""

    breakpoints: int
    k: float
    noise_k: float
    line_k: float
    abd_lambda: float
    pdbs_c0: float
    jump_distance: float


NO_RULE = -1
"""The ``breakpoints`` code of a method that works on the whole scan: cuts at missing beams only."""

ABD_LAMBDA_FLOOR = math.radians(10.0)
"""Borges and Aldon's ``lambda``: walls up to 80 deg incidence stay one cluster."""

MAX_BRIDGED_SHARE = math.sin(math.radians(1.0)) / math.sin(math.radians(14.0))
"""Largest step, as a share of the range, that the incidence bound alone bridges in
:func:`auto_abd_lambda` (7.2 %: ``lambda`` = 15 deg at 1 deg resolution)."""

MAX_STEP_GROWTH = 2.5
"""Largest ratio of a step to its neighbours' on a continued line (grazing walls
grow their spacing smoothly; a jump does not)."""


@kernel
def auto_abd_lambda(step):
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


@kernel
def make_rule(kind, k, noise_k, line_k, abd_lambda, pdbs_c0, jump_distance, noise):
    """The :class:`BreakpointRule` with its noise terms in units of the range noise
    ``noise`` (a :class:`~scanlines.steps.noise.NoiseLine`).

    The margin is ``noise_k`` standard deviations of a difference of two ranges
    (``sqrt(2) sigma``), the line tolerance ``line_k`` standard deviations of an
    extrapolation from two points (``sqrt(5) sigma``).
    """
    return BreakpointRule(
        kind,
        k,
        noise_k * math.sqrt(2.0),
        line_k * math.sqrt(5.0),
        noise,
        abd_lambda,
        pdbs_c0,
        jump_distance,
    )


@kernel
def scan_rule(spec, returns, gap, noise):
    """The rule of the :class:`RuleSpec` ``spec``, its noise ``noise`` (a sensor
    profile's :class:`~scanlines.steps.noise.NoiseLine`, or NaN: measured from the scan,
    only when the rule uses it). :data:`NO_RULE` gives a rule that cuts at missing
    beams only.
    """
    if spec.breakpoints == NO_RULE:
        fixed = np.int64(FIXED)  # not a literal: one compiled make_rule for every caller
        quiet = NoiseLine(0.0, 0.0)
        return make_rule(fixed, spec.k, 0.0, 0.0, spec.abd_lambda, spec.pdbs_c0, math.inf, quiet)
    noisy_rule = spec.breakpoints in (ADAPTIVE, ABD) and spec.noise_k > 0.0
    if noisy_rule or spec.line_k > 0.0:
        noise = resolve_noise(noise, returns, gap)
    else:
        noise = NoiseLine(0.0, 0.0)
    return make_rule(
        spec.breakpoints, spec.k, spec.noise_k, spec.line_k, spec.abd_lambda, spec.pdbs_c0,
        spec.jump_distance, noise,
    )  # fmt: skip


@kernel
def neighbour_steps(x, y):
    """``d_i = |P_{i+1} - P_i|`` for consecutive points (eq. 4 / 19)."""
    d = np.empty(max(x.shape[0] - 1, 0))
    for p in range(d.shape[0]):
        dx, dy = x[p + 1] - x[p], y[p + 1] - y[p]
        d[p] = math.sqrt(dx * dx + dy * dy)
    return d


@kernel
def gap_factor(rule, gap, step):
    """The part of the threshold that depends on the beam gap only (see :func:`threshold`)."""
    kind = rule.kind
    dphi = gap * step
    if kind == ADAPTIVE:
        return rule.k * dphi
    if kind == ABD:
        margin = rule.abd_lambda - dphi
        return math.sin(dphi) / math.sin(margin) if margin > 0.0 else math.inf
    if kind == PDBS:
        return math.sqrt(2.0 * (1.0 - math.cos(dphi)))
    return 0.0


@kernel
def scaled_threshold(rule, factor, r_from, r_to):
    """The threshold from :func:`gap_factor` and the two ranges."""
    kind = rule.kind
    if kind in (ADAPTIVE, ABD):
        margin = rule.margin_sigmas * noise_at(rule.noise, r_from) if rule.margin_sigmas else 0.0
        return factor * r_from + margin
    if kind == PDBS:
        return rule.pdbs_c0 + factor * min(r_from, r_to)
    return rule.jump_distance


@kernel
def threshold(rule, r_from, r_to, gap, step):
    """Largest distance ``D`` between returns ``r_from`` and ``r_to``, ``gap`` beams apart."""
    return scaled_threshold(rule, gap_factor(rule, gap, step), r_from, r_to)


@kernel
def distance_to_line(ax, ay, bx, by, px, py):
    """Distance of ``P`` from the line through ``A`` and ``B`` (inf when ``A == B``)."""
    ux, uy = bx - ax, by - ay
    length = math.hypot(ux, uy)
    if length == 0.0:
        return math.inf
    return abs(ux * (py - ay) - uy * (px - ax)) / length


@kernel
def continues_line_at(x, y, gap, d, p, tolerance):
    """Pair ``(p, p+1)`` continues the line of the pair before and of the pair after.

    ``P_{p+1}`` lies within ``tolerance`` of the line through ``P_{p-1}, P_p``, ``P_p``
    within ``tolerance`` of the line through ``P_{p+1}, P_{p+2}`` (each tolerance grown
    by :func:`extrapolation_growth` for the step ``d_p`` beyond), both neighbouring
    steps are longer than ``tolerance`` (shorter ones give a line direction that is
    mostly noise), and ``d_p`` is at most :data:`MAX_STEP_GROWTH` times the shorter
    neighbouring step plus ``tolerance`` (near grazing incidence, range noise moves
    returns along the wall and makes neighbouring steps unequal). Returns on a wall seen
    at grazing incidence are far apart but collinear and evenly spaced, so a distance
    threshold alone cuts the wall; a depth jump or a spike is neither. Where one
    neighbouring pair does not exist (the scan's ends, two or more missing beams) or is
    itself a jump (more than :data:`MAX_STEP_GROWTH` times ``d_p``), the other decides
    alone: the first and last returns of a wall that starts behind an edge or ends in
    open space.
    """
    n = x.shape[0]
    jump = MAX_STEP_GROWTH * d[p] + tolerance
    has_before = p >= 1 and gap[p - 1] <= MAX_BRIDGED_GAP and d[p - 1] <= jump
    has_after = p + 2 < n and gap[p + 1] <= MAX_BRIDGED_GAP and d[p + 1] <= jump
    if not (has_before or has_after):
        return False
    shorter = math.inf
    if has_before:
        shorter = d[p - 1]
    if has_after:
        shorter = min(shorter, d[p + 1])
    if not (d[p] <= MAX_STEP_GROWTH * shorter + tolerance and shorter > tolerance):
        return False
    if has_before:
        before = distance_to_line(x[p - 1], y[p - 1], x[p], y[p], x[p + 1], y[p + 1])
        if not before < tolerance * extrapolation_growth(d[p] / d[p - 1]):
            return False
    if has_after:
        after = distance_to_line(x[p + 2], y[p + 2], x[p + 1], y[p + 1], x[p], y[p])
        if not after < tolerance * extrapolation_growth(d[p] / d[p + 1]):
            return False
    return True


@kernel
def extrapolation_growth(t):
    """How much farther off a line through two points a third lies by noise alone when it
    is ``t`` times their distance beyond them, relative to ``t = 1`` (the ``sqrt(5)`` of
    :func:`make_rule`): ``sqrt((1 + t)^2 + t^2) / sqrt(5)``."""
    return math.sqrt((1.0 + t) ** 2 + t * t) / math.sqrt(5.0)


@kernel
def break_flags(returns, gap, step, rule):
    """For each pair of consecutive positions, True where a cluster ends."""
    _, r, x, y = returns
    n = x.shape[0]
    out = np.zeros(max(n - 1, 0), dtype=np.bool_)
    if n < 2:
        return out
    d = neighbour_steps(x, y)
    line_test = rule.tolerance_sigmas > 0.0
    factors = np.array([gap_factor(rule, g, step) for g in range(MAX_BRIDGED_GAP + 1)])
    for p in range(n - 1):
        if gap[p] > MAX_BRIDGED_GAP:
            out[p] = True
        elif not d[p] < scaled_threshold(rule, factors[gap[p]], r[p], r[p + 1]):
            if line_test:
                tolerance = rule.tolerance_sigmas * noise_at(rule.noise, r[p])
                out[p] = not continues_line_at(x, y, gap, d, p, tolerance)
            else:
                out[p] = True
    return out


@kernel
def seam_break(returns, n_beams, step, rule):
    """The breakpoint test between the last and the first position of a full circle."""
    index, r, x, y = returns
    gap = index[0] + n_beams - index[-1]
    if gap > MAX_BRIDGED_GAP:
        return True
    d = math.hypot(x[0] - x[-1], y[0] - y[-1])
    return not d < threshold(rule, r[-1], r[0], gap, step)
