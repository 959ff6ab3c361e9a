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

from typing import NamedTuple

from scanlines.params import Param, choice, coded, number, radians, with_default
from scanlines.steps.noise import NoiseLine

__all__ = [
    "ABD",
    "ADAPTIVE",
    "CLUSTERING",
    "FIXED",
    "NO_RULE",
    "PDBS",
    "RULES",
    "RULE_CODES",
    "BreakpointRule",
    "RuleSpec",
    "published_clustering",
]

RULES = ("paper", "abd", "pdbs", "fixed")
RULE_CODES = {name: code for code, name in enumerate(RULES)}
ADAPTIVE, ABD, PDBS, FIXED = range(4)

CLUSTERING: dict[str, Param] = {
    "breakpoints": Param(
        "abd", choice(*RULES), "clustering rule: " + ", ".join(RULES), (coded(RULE_CODES),)
    ),
    "k": Param(
        3.0,
        number(low=0.0, low_open=True),
        "paper rule: D = k rho dtheta (eq. 7)",
        applies=("breakpoints", ("paper",), True),
    ),
    "noise_k": Param(
        3.0,
        number(low=0.0),
        "paper/abd: noise margin in sigmas of a range difference",
        applies=("breakpoints", ("paper", "abd"), True),
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
        applies=("breakpoints", ("abd",), True),
    ),
    "pdbs_c0": Param(
        0.1,
        number(low=0.0),
        "PDBS: constant C0 in metres",
        applies=("breakpoints", ("pdbs",), True),
    ),
    "jump_distance": Param(
        0.3,
        number(low=0.0, low_open=True),
        "fixed rule: largest neighbour distance, metres",
        applies=("breakpoints", ("fixed",), True),
    ),
}
"""The parameters of a clustering rule, shared by every method that clusters."""


def published_clustering(rule: str | Param, note: str = "") -> dict[str, Param]:
    """The clustering settings of a comparison method: :data:`CLUSTERING` with the method's
    default rule (a rule's name, ``note`` added to its doc, or a ``breakpoints`` parameter
    of the method's own) and no line-continuation bridge (the published rules have none)."""
    breakpoints = (
        rule if isinstance(rule, Param) else with_default(CLUSTERING["breakpoints"], rule, note)
    )
    line_k = CLUSTERING["line_k"]
    return {
        **CLUSTERING,
        "breakpoints": breakpoints,
        "line_k": Param(0.0, line_k.check, line_k.doc + "; off here"),
    }


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
    :data:`NO_RULE` (the fields of the parameters of :data:`CLUSTERING`)."""

    breakpoints: int
    k: float
    noise_k: float
    line_k: float
    abd_lambda: float
    pdbs_c0: float
    jump_distance: float


NO_RULE = -1
"""The ``breakpoints`` code of a method that works on the whole scan: cuts at missing beams only."""
