"""The default extractor: the paper's adaptive-threshold method, changed to work on real logs.

The method of the Electronics 2022 paper [1]_ with the changes below, each a parameter.

What it does to each scan, in order (the kernel is C++, ``cpp/scanlines/methods/adaptive.cpp``,
``adaptive_scan``: one call per stack of scans, without the GIL):

1. the noise line every threshold uses (below): the ``noise_sigma`` override, else the
   sensor profile's or the scan's own (one constant with ``noise_model="constant"``);
2. denoising (:mod:`scanlines.steps.denoise`): spikes, single-return clusters and
   mixed pixels between two surfaces are dropped and reported as outliers;
3. clustering (:mod:`scanlines.steps.breakpoints`, :mod:`scanlines.steps.clusters`): a
   breakpoint where the next return is beyond the incidence-bounded distance plus a noise
   margin, unless the step continues the lines on both sides;
4. corner scores (:mod:`scanlines.steps.corners`): the turn angle between lines fitted to
   a window of returns on each side, and its peaks as candidates;
5. the threshold sweep (:mod:`scanlines.steps.select`): every distinct cut the candidates
   allow, the one with the best BIC (each run's error in noise variances), stopped where
   the choice is certain (``sweep_decided``), then chosen again with the noise scaled
   to the lines of the first choice (the median ``sqrt(cost / (n - 2))`` of their runs of
   8 points or more);
6. the segments: cut at the chosen corners, each cut moved by one position where that
   fits better, neighbours merged by the criterion and by a chi-square test of their
   lines, split where a return leaves the residual bound (``residual_tolerances``),
   kept when they hold ``min_points`` returns and are ``min_length`` long;
7. the corners and jumps between the kept segments
   (``junction_events``: two lines that do not meet near
   their ends are a jump; two whose turn is within the noise of their directions meet at
   no corner);
8. total-least-squares lines with covariances from the noise (:mod:`scanlines.steps.fit`).

The paper's method as printed is the ``paper`` method (:mod:`scanlines.methods.paper`);
``preset="paper"`` here is its alias, with exactly its features
(``tests/methods/test_paper.py``). Every step above that differs from the paper's is a
parameter whose other values include the paper's choice, so that each change is measured
alone. The evidence: the tests named in brackets, and ``docs/decisions/`` (300 simulated
scenes per sensor preset).

``breakpoints="abd"``, ``abd_lambda="auto"``, ``noise_k=3``, ``line_k=3``
    ``D = k rho dtheta`` is ``k`` times the spacing of returns on a surface
    facing the sensor; on a wall seen at incidence ``beta`` the spacing is
    ``rho dtheta / cos(beta)``, so ``k = 3`` cuts every wall beyond 70.5 deg.
    The default bounds the incidence instead (80 deg: Borges and Aldon's
    detector [2]_, the same range-proportional threshold made exact for slanted
    surfaces; on scans coarser than 0.67 deg the bound tightens so that it alone
    never bridges a step of more than 7.2 % of the range: 75 deg at 1 deg), adds
    ``noise_k`` standard deviations of a range difference (noise estimated from
    the scan; at 0.33 deg, 2 m and 1 cm noise ``3 rho dtheta`` is 3.5 cm and noise
    alone cuts about one pair in fifty), and does not cut a step that continues
    the lines on both sides (walls at grazing incidence; at a wall's end in open
    space or behind an edge, the one side there is).
    [test_adaptive.py::test_grazing_wall_stays_one_cluster,
    test_adaptive.py::test_grazing_wall_right_after_a_jump_keeps_its_first_returns,
    test_adaptive.py::test_auto_lambda_cuts_a_depth_step_that_10_deg_bridges_at_1_deg,
    docs/decisions/breakpoints.md]
``denoise="isolated"``, ``min_cluster_points=2``
    Step 2 as printed (``d_{i-1} > d_{i-2}`` and ``d_i > d_{i+1}``) flags any local
    bump of the neighbour distance: about a quarter of the points of a straight
    noisy wall. The default drops a point that the breakpoint test cuts from both
    neighbours while the neighbours stay continuous (a spike), single-return
    clusters (stray echoes, mixed pixels between two surfaces), and two-return
    clusters whose ranges lie between those of the clusters on either side (mixed
    pixels at a depth jump; a small object in front of both stays);
    dropped points are reported in ``Extraction.outliers``. No point is moved.
    [test_adaptive.py::test_spike_outlier_in_wall_is_dropped,
    test_adaptive.py::test_two_returns_between_two_surfaces,
    test_steps.py::test_literal_noise_rule_fires_on_ordinary_wall_points]
``corner_score="turn"``, ``slope_window="auto"``
    ``Dk`` from raw ranges is dominated by range noise at fine resolution (at
    0.33 deg and 1 cm noise one noisy pair gives ``|Dk|`` near 0.8), and with the
    printed absolute values a corner seen symmetrically scores zero. The default
    scores the turn angle between lines fitted to ``w`` points on each side,
    ``w = 3 + 6 sigma / spacing`` (3..15).
    [test_steps.py::test_dk_as_printed_misses_a_symmetric_corner]
``criterion="bic"``, ``penalty=4``, ``dkth_range="auto"``
    The smallest SSE always picks the lowest threshold (more cuts never raise a
    least-squares error). The default charges each segment ``penalty ln(n)``
    noise variances (BIC); each run's error is divided by the mean ``cos^2`` of
    its incidence, since range noise shows only partly as an orthogonal
    residual, and the noise is re-estimated from the runs of a first choice.
    ``(0, 0.052)`` is the range of ``|Dk|`` in the paper's own scan; the default
    tries every distinct cut the candidates allow (at most ``max_evaluations``).
    [test_steps.py::test_min_sse_picks_the_lowest_threshold]
``fit="tls"``
    ``y = kx + b`` cannot describe a wall parallel to the y axis (the paper fit
    returns NaN there) and its error is measured vertically; total least squares
    in Hesse form has neither fault. [test_adaptive.py::test_vertical_wall_paper_fit_has_no_slope]
``corner_split="refine"``, ``merge=True``, ``corner_check=True``, ``max_residual=0.1``
    The corner point goes to the side whose fit it suits (among the three beams
    around the peak), collinear neighbours that a global threshold cut apart are
    merged by the same criterion, two segments whose lines do not meet near
    their facing ends are a depth step (a breakpoint), not a corner, two whose lines
    turn by less than three standard deviations of the turn (from each segment's
    direction covariance) meet at no corner, since the noise hides the turn, and no point
    of a segment is farther than ``max_residual`` from its line, or than five noise
    sigmas at its range where that is more (a fixed 10 cm cut the walls of sensors
    with centimetres of noise at the noise: on the family's noisiest sensor, 137
    segments a scan against 41 now, and over the 28 family sensors the worst
    breakpoint F1 was 0.42 against 0.75 now; ``scanlines eval --family -n 30``).
    [test_adaptive.py::test_corner_check_turns_a_bridged_depth_step_into_a_breakpoint]

The range noise (all of the above) is a line ``sigma(r) = sigma0 + per_metre r``
    measured from the data (:mod:`scanlines.steps.noise`): from a
    :class:`~scanlines.sensor.profile.SensorProfile` of the whole log when the
    extractor has one (``scanlines run`` measures one, or takes ``--sensor-profile``),
    else from the scan itself (each return against a parabola through its seven
    neighbours' ranges; a slope only where it stands out of the noise). Every threshold
    takes its sigma from it at the range where it applies: the breakpoint margin and
    the line-continuation tolerance per pair, the criterion per run (each run's error
    over its returns' mean variance), the turn window and the corner check at the
    scan's median range. ``noise_sigma`` (one sigma, metres) and
    ``noise_model="constant"`` (the line's value at the median range) override it.
    [test_steps.py::test_scan_noise_follows_noise_proportional_to_range,
    test_sensor_profile.py::test_calibration_recovers_a_known_noise_curve_in_every_range_bin,
    test_adaptive.py::test_range_noise_model_keeps_far_noisy_walls_whole]
``merge_chi2=9.21``
    After the criterion's merge, neighbours whose ``(rho, alpha)`` agree within a
    chi-square of 9.21 (2 dof, 99 %) are joined, with covariances from the noise line,
    widened where a segment's own residuals are larger than the noise explains (as
    split-and-merge joins its segments).

Segment covariances come from the same noise line (``range_sigma`` overrides it) and
are scaled up by a segment's reduced chi-square when its residuals exceed the noise
(a rough or curved surface); each segment end says what ends it
(:data:`scanlines.extraction.END_KINDS`). Ranges and angles are taken at float32
precision, so a log gives the same features read directly or from a ROS bag.

Missing beams: one missing beam is bridged, two or more end a cluster; full-circle
scans join across the seam.

The method's own steps (those no other method uses) are in its kernel file, not in
:mod:`scanlines.steps`: ``abd_lambda="auto"`` (``auto_abd_lambda``), the noise scale
of a first choice, the early stop of the sweep (``sweep_decided``), the refined cuts,
the merge by the criterion and the split at the residual bound
(``residual_tolerances``); those the tests call are bound in
:mod:`scanlines._core` (checked there), the package calls none of them directly.

References
----------
.. [1] "An adaptive threshold line segment feature extraction algorithm for laser
   radar scanning environments", Electronics 11(11), 1759, 2022.
   doi:10.3390/electronics11111759
.. [2] G. A. Borges and M.-J. Aldon, "Line extraction in 2D range images for
   mobile robotics", J. Intelligent and Robotic Systems 40, 267-297, 2004.
"""

from __future__ import annotations

from dataclasses import replace
from typing import Any, ClassVar

import numpy as np

from scanlines import _core
from scanlines._core import adaptive_stack
from scanlines.methods.base import CompiledMethod
from scanlines.methods.paper import Paper
from scanlines.params import (
    MAX_COUNT,
    KernelField,
    Param,
    Settings,
    as_float,
    auto_or,
    choice,
    coded,
    flag,
    integer,
    number,
    optional,
    radians,
    with_default,
)
from scanlines.steps.assemble import output_settings
from scanlines.steps.breakpoints import CLUSTERING
from scanlines.steps.corners import SCORE_CODES, SCORES
from scanlines.steps.denoise import DENOISE_CODES
from scanlines.steps.fit import FIT_CODES, FITS
from scanlines.steps.select import CRITERIA, CRITERION_CODES, threshold_grid

__all__ = [
    "MAX_BRIDGED_SHARE",
    "SWEEP_CHUNK",
    "Adaptive",
]


PAPER = Paper.parameters
"""The paper method's parameters: adaptive's options of the paper's steps take their
domains from them, and its ``paper`` preset their defaults."""


def _count_or_zero(value: Any) -> int:
    """An integer, ``"auto"`` as 0 (its flag says so)."""
    return 0 if value == "auto" else int(value)


def _fixed_range(value: Any) -> bool:
    """Whether a fixed threshold range (the kernel's ``grid``) replaces the candidates'
    own scores."""
    return value != "auto"


NOISE: dict[str, Param] = {
    "noise_sigma": Param(
        "auto",
        auto_or(number(low=0.0, low_open=True)),
        "bic noise (m), or auto: estimated",
        (as_float(), flag("estimate_noise", "auto")),
    ),
    "noise_model": Param(
        "range",
        choice("range", "constant"),
        "noise: growing with range as measured (sensor profile or scan), or one constant",
        (flag("constant_noise", "constant"),),
    ),
}

CLUSTERS: dict[str, Param] = {
    **CLUSTERING,
    "abd_lambda": Param(
        "auto",
        auto_or(CLUSTERING["abd_lambda"].check),
        "ABD: worst incidence angle, degrees, or auto: 10, more on scans coarser than 0.67 deg",
        (radians(), flag("auto_abd_lambda", "auto")),
        applies=CLUSTERING["abd_lambda"].applies,
    ),
    "denoise": Param(
        "isolated",
        choice("isolated", "paper", "none"),
        "noise rule: isolated | paper | none",
        (coded(DENOISE_CODES),),
    ),
    "window": replace(
        with_default(PAPER["window"], 10, "with denoise=paper"),
        applies=("denoise", ("paper",), True),
    ),
    "min_cluster_points": Param(
        2,
        integer(1, MAX_COUNT),
        "isolated denoising: smaller clusters are dropped as noise",
        applies=("denoise", ("isolated",), True),
    ),
}

SEGMENTS: dict[str, Param] = {
    "corner_score": Param(
        "turn", choice(*SCORES), "corner score: " + ", ".join(SCORES), (coded(SCORE_CODES),)
    ),
    "slope_window": Param(
        "auto",
        auto_or(integer(2, 1000)),
        "turn score: points fitted on each side, or auto",
        (KernelField("", _count_or_zero), flag("auto_slope_window", "auto")),
        applies=("corner_score", ("turn",), True),
    ),
    "dkth_range": Param(
        "auto",
        auto_or(PAPER["dkth_range"].check),
        "threshold range (a, b), or auto: the candidates' scores",
        (KernelField("use_grid", _fixed_range),),  # the thresholds: the kernel's grid
    ),
    "dkth_step": replace(
        with_default(PAPER["dkth_step"], 0.01, "with a fixed dkth_range"),
        applies=("dkth_range", ("auto",), False),
    ),
    "max_evaluations": replace(PAPER["max_evaluations"], kernel=None),  # the sweep reads it
    "criterion": Param(
        "bic",
        choice(*CRITERIA),
        "selection: bic | sse (smallest SSE)",
        (coded(CRITERION_CODES),),
    ),
    "penalty": Param(4.0, number(low=0.0), "bic: cost of a segment, in ln(n) noise variances"),
    "fit": Param(
        "tls",
        choice(*FITS),
        "line fit: tls | paper (5-point OLS, eq. 15-17)",
        (coded(FIT_CODES),),
    ),
    "corner_split": Param(
        "refine",
        choice("refine", "shared"),
        "corner point: refine (best side) | shared",
        (flag("shared_corner", "shared"),),
    ),
    "merge": Param(True, choice(True, False), "merge collinear neighbours"),
    "merge_chi2": Param(
        9.21,
        number(low=0.0),
        "merge neighbours whose (rho, alpha) agree within this chi-square (2 dof; covariances "
        "from the noise model and the residuals; 0: off)",
        applies=("merge", (True,), True),
    ),
    "max_residual": Param(
        0.1,
        optional(number(low=0.0, low_open=True)),
        "largest point-to-line distance (m), or 5 noise sigmas at the point's range where "
        "that is more",
    ),
}

EVENTS: dict[str, Param] = {
    "corner_check": Param(
        True, choice(True, False), "lines that do not meet near their ends are a jump, not a corner"
    ),
}

PRESETS: dict[str, dict[str, Any]] = {
    # The paper's method (its own parameters' defaults), each step switched to its choice.
    "paper": {
        **{name: param.default for name, param in PAPER.items()},
        "breakpoints": "paper",
        "noise_k": 0.0,
        "line_k": 0.0,
        "denoise": "paper",
        "min_cluster_points": 1,
        "corner_score": "dk",
        "criterion": "sse",
        "fit": "paper",
        "corner_split": "shared",
        "merge": False,
        "max_residual": None,
        "corner_check": False,
    },
}


class Adaptive(CompiledMethod):
    """The adaptive-threshold extractor (module docstring)."""

    name = "adaptive"
    settings: ClassVar[Settings] = Settings(
        noise=NOISE,
        clustering=CLUSTERS,
        segments=SEGMENTS,
        events=EVENTS,
        output=output_settings(3),
    )
    presets: ClassVar[dict[str, dict[str, Any]]] = PRESETS

    def kernel_arguments(self) -> tuple[dict[str, Any], np.ndarray]:
        """The settings and the thresholds of a fixed ``dkth_range`` (else empty)."""
        grid = np.zeros(0)
        if self.params["dkth_range"] != "auto":
            low, high = self.params["dkth_range"]
            step, most = self.params["dkth_step"], self.params["max_evaluations"]
            grid = threshold_grid(low, high, step, most)
        return self.record, grid

    @staticmethod
    def kernel(*arguments):
        return adaptive_stack(*arguments)


# The method's own steps, bound for the tests (cpp/scanlines/methods/adaptive.hpp).

MAX_BRIDGED_SHARE: float = _core.MAX_BRIDGED_SHARE
"""Largest step, as a share of the range, that the incidence bound alone bridges in
``auto_abd_lambda`` (``sin 1 deg / sin 14 deg``, 7.2 %: ``lambda`` = 15 deg at 1 deg
resolution)."""


#: Candidates ``sweep_decided`` inserts between two checks of its bound.
SWEEP_CHUNK = 8
