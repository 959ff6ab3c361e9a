"""The adaptive-threshold line-segment extractor of the Electronics 2022 paper [1]_.

Steps (the paper's numbering, sec. 3):

1. points and neighbour distances ``d_i`` (eq. 3, 4/19);
2-3. denoising: isolated noise points (Step 2) and their replacement by a window
   mean (eq. 5/20) -- :mod:`scanlines.steps.denoise`;
4. adaptive nearest-neighbour breakpoints ``D = k rho dtheta`` (eq. 6-7/21) --
   :mod:`scanlines.steps.breakpoints`;
5. corner candidates from the slope difference ``Dk`` (eq. 12-13) with the peak
   and position rules, and the removal of corners with fewer than two points on a
   side -- :mod:`scanlines.steps.corners`;
6-7. the sweep of the corner threshold ``dkth`` over ``(a, b)``, keeping the cut
   with the best fitting-error criterion (eq. 14) -- :mod:`scanlines.steps.select`;
8. a line per part: five sub-set means and ordinary least squares (eq. 15-17) --
   :mod:`scanlines.steps.fit`.

``preset="paper"`` runs exactly that: window 10, ``k = 3``, ``Dk`` as printed,
``dkth`` in ``(0, 0.052)`` in steps of 0.01, ``W_i = 1``, the smallest SSE, the
5-point OLS fit, the corner point shared by both segments.

Deviations of the default, each a parameter. The evidence: the tests named in
brackets, and ``docs/decisions/`` (300 simulated scenes per sensor preset).

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
    their facing ends are a depth step (a breakpoint), not a corner, and no point
    of a segment is farther than ``max_residual`` from its line.
    [test_adaptive.py::test_corner_check_turns_a_bridged_depth_step_into_a_breakpoint]

``noise_model="constant"`` (option ``"range"``)
    One range-noise sigma per scan sets the breakpoint margin. ``"range"`` lets the margin
    grow with range where the scan's noise does (fitted from each return's distance to
    the chord of its neighbours): on the URG-04LX preset, whose error is 1 % of the
    range, breakpoint F1 0.919 -> 0.937; nearly neutral on the other presets.
    [test_adaptive.py::test_range_noise_model_keeps_far_noisy_walls_whole,
    test_steps.py::test_noise_growth_sees_constant_noise_at_1_deg,
    docs/decisions/noise-model.md]

Missing beams: one missing beam is bridged, two or more end a cluster; full-circle
scans join across the seam. The paper preset's window mean can replace three
returns by one point; runs of identical points have no paper-fit line (NaN).

References
----------
.. [1] "An adaptive threshold line segment feature extraction algorithm for laser
   radar scanning environments", Electronics 11(11), 1759, 2022.
   doi:10.3390/electronics11111759
.. [2] G. A. Borges and M.-J. Aldon, "Line extraction in 2D range images for
   mobile robotics", J. Intelligent and Robotic Systems 40, 267-297, 2004.
"""

from __future__ import annotations

import math
from collections.abc import Mapping
from typing import Any

import numpy as np

from scanlines._jit import jit
from scanlines.extraction import Extraction
from scanlines.params import (
    Param,
    auto_or,
    choice,
    float_pair,
    int_at_least,
    number,
    optional,
    segment_params,
)
from scanlines.steps.assemble import CompiledMethod, assemble_runs, empty_result
from scanlines.steps.breakpoints import (
    BREAKPOINT_PARAMS,
    RULE_CODES,
    auto_abd_lambda,
    break_beams,
    break_flags,
    cluster_bounds,
    neighbour_steps,
    noise_rule,
    seam_break,
    seam_rotation,
    with_margin_growth,
)
from scanlines.steps.corners import SCORES, peak_positions, ring_anchor, slope_scores, turn_scores
from scanlines.steps.denoise import (
    MIN_NOISE_SIGMA,
    in_between_clusters,
    isolated_noise_mask,
    literal_noise,
    noise_from_ranges,
    noise_growth,
    small_clusters,
    window_means,
)
from scanlines.steps.fit import (
    FIT_CODES,
    FITS,
    PAPER,
    fit_run,
    inverse_square_sums,
    line_intersection,
    prefix_moments,
    run_cost,
)
from scanlines.steps.merge import merge_runs, split_runs
from scanlines.steps.points import Sequence
from scanlines.steps.select import (
    BIC,
    CRITERIA,
    CRITERION_CODES,
    best_level,
    level_corners,
    sweep_levels,
    threshold_grid,
)

NAME = "adaptive"

PARAMS: dict[str, Param] = {
    **segment_params(3),
    **BREAKPOINT_PARAMS,
    "denoise": Param(
        "isolated", choice("isolated", "paper", "none"), "noise rule: isolated | paper | none"
    ),
    "window": Param(10, int_at_least(1), "paper denoising: mean-filter window N (eq. 5)"),
    "corner_score": Param("turn", choice(*SCORES), "corner score: " + ", ".join(SCORES)),
    "slope_window": Param(
        "auto", auto_or(int_at_least(2)), "turn score: points fitted on each side, or auto"
    ),
    "dkth_range": Param(
        "auto", auto_or(float_pair()), "threshold range (a, b), or auto: the candidates' scores"
    ),
    "dkth_step": Param(0.01, number(low=0.0, low_open=True), "threshold step with a fixed range"),
    "max_evaluations": Param(100, int_at_least(1), "most thresholds tried"),
    "criterion": Param("bic", choice(*CRITERIA), "selection: bic | sse (smallest SSE)"),
    "penalty": Param(4.0, number(low=0.0), "bic: cost of a segment, in ln(n) noise variances"),
    "noise_sigma": Param(
        "auto", auto_or(number(low=0.0, low_open=True)), "bic noise (m), or auto: estimated"
    ),
    "fit": Param("tls", choice(*FITS), "line fit: tls | paper (5-point OLS, eq. 15-17)"),
    "corner_split": Param(
        "refine", choice("refine", "shared"), "corner point: refine (best side) | shared"
    ),
    "merge": Param(True, choice(True, False), "merge collinear neighbours"),
    "max_residual": Param(
        0.1, optional(number(low=0.0, low_open=True)), "largest point-to-line distance (m)"
    ),
    "corner_check": Param(
        True, choice(True, False), "lines that do not meet near their ends are a jump, not a corner"
    ),
    "abd_lambda": Param(
        "auto",
        auto_or(BREAKPOINT_PARAMS["abd_lambda"].check),
        "ABD: worst incidence angle, degrees, or auto: 10, more on scans coarser than 0.67 deg",
    ),
    "min_cluster_points": Param(
        2, int_at_least(1), "isolated denoising: smaller clusters are dropped as noise"
    ),
    "noise_model": Param(
        "constant",
        choice("constant", "range"),
        "breakpoint noise margin: constant, or growing with range as the scan's noise does",
    ),
}

PRESETS: dict[str, dict[str, Any]] = {
    "paper": {
        "breakpoints": "adaptive",
        "k": 3.0,
        "noise_k": 0.0,
        "line_k": 0.0,
        "denoise": "paper",
        "window": 10,
        "corner_score": "dk",
        "dkth_range": (0.0, 0.052),
        "dkth_step": 0.01,
        "max_evaluations": 100,
        "criterion": "sse",
        "fit": "paper",
        "corner_split": "shared",
        "merge": False,
        "corner_check": False,
        "max_residual": None,
        "min_points": 2,
        "min_cluster_points": 1,
        "min_length": 0.0,
    },
}

# --------------------------------------------------------------------------- settings
# The kernel takes the parameters as one float array; these name its slots.
(
    RULE_KIND, K, NOISE_K, LINE_K, ABD_LAMBDA, PDBS_C0, JUMP_DISTANCE,
    DENOISE, WINDOW, MIN_CLUSTER_POINTS, CORNER_SCORE, SLOPE_WINDOW, USE_GRID,
    MAX_EVALUATIONS, CRITERION, PENALTY, NOISE_SIGMA, FIT, SHARED, MERGE, MAX_RESIDUAL,
    CORNER_CHECK, MIN_POINTS, MIN_LENGTH, RANGE_SIGMA, RANGE_NOISE, N_SETTINGS,
) = range(27)  # fmt: skip
DENOISE_CODES = {"isolated": 0, "paper": 1, "none": 2}
ISOLATED, LITERAL, NO_DENOISE = 0, 1, 2
SCORE_CODES = {name: code for code, name in enumerate(SCORES)}
TURN, DK, DK_SIGNED = 0, 1, 2
AUTO = -1.0
"""``slope_window``, ``noise_sigma``, ``abd_lambda`` and ``max_residual`` slots: estimate / none."""


def settings(params: Mapping[str, Any]) -> tuple[np.ndarray, np.ndarray]:
    """The kernel's form of resolved ``params``: the settings array and the threshold grid."""
    s = np.zeros(N_SETTINGS)
    s[RULE_KIND] = RULE_CODES[params["breakpoints"]]
    s[K], s[NOISE_K], s[LINE_K] = params["k"], params["noise_k"], params["line_k"]
    lam = params["abd_lambda"]
    s[ABD_LAMBDA] = AUTO if lam == "auto" else math.radians(lam)
    s[PDBS_C0], s[JUMP_DISTANCE] = params["pdbs_c0"], params["jump_distance"]
    s[DENOISE] = DENOISE_CODES[params["denoise"]]
    s[WINDOW], s[MIN_CLUSTER_POINTS] = params["window"], params["min_cluster_points"]
    s[CORNER_SCORE] = SCORE_CODES[params["corner_score"]]
    s[SLOPE_WINDOW] = AUTO if params["slope_window"] == "auto" else params["slope_window"]
    s[MAX_EVALUATIONS] = params["max_evaluations"]
    s[CRITERION], s[PENALTY] = CRITERION_CODES[params["criterion"]], params["penalty"]
    s[NOISE_SIGMA] = AUTO if params["noise_sigma"] == "auto" else params["noise_sigma"]
    s[FIT] = FIT_CODES[params["fit"]]
    s[SHARED] = params["corner_split"] == "shared"
    s[MERGE], s[CORNER_CHECK] = params["merge"], params["corner_check"]
    s[MAX_RESIDUAL] = AUTO if params["max_residual"] is None else params["max_residual"]
    s[MIN_POINTS], s[MIN_LENGTH] = params["min_points"], params["min_length"]
    s[RANGE_SIGMA] = params["range_sigma"]
    s[RANGE_NOISE] = params["noise_model"] == "range"
    grid = np.zeros(0)
    if params["dkth_range"] != "auto":
        low, high = params["dkth_range"]
        grid = threshold_grid(low, high, params["dkth_step"], params["max_evaluations"])
        s[USE_GRID] = 1.0
    return s, grid


# --------------------------------------------------------------------------- entry points


def run(seq: Sequence, angle_min: float, params: Mapping[str, Any]) -> Extraction:
    """Extract features from the valid returns ``seq`` of one scan (its own points)."""
    return Compiled(params).sequence(seq, angle_min)


class Compiled(CompiledMethod):
    """The method in kernel form (see :class:`~scanlines.steps.assemble.CompiledMethod`)."""

    __slots__ = ()
    name = NAME

    def arguments(self, params: Mapping[str, Any]) -> tuple[np.ndarray, np.ndarray]:
        return settings(params)

    @staticmethod
    def scan_kernel(*args):
        return extract_scan(*args)

    @staticmethod
    def returns_kernel(*args):
        return extract_points(*args)


# --------------------------------------------------------------------------- the kernel


@jit
def extract_scan(ranges, valid, cos, sin, step, full_circle, angle_min, s, grid):
    """The whole method on one scan; arrays of the result.

    ``valid`` marks the beams with a return, ``cos, sin`` are the bearing tables
    relative to beam 0. Returns ``first, last, n_points, lines, covariances,
    breakpoints, corners, outliers`` as :func:`~scanlines.steps.assemble.from_arrays`
    takes them.
    """
    index = np.flatnonzero(valid)
    r = ranges[index]
    x, y = r * cos[index], r * sin[index]
    n_beams = ranges.shape[0]
    return _points_pipeline(index, r, x, y, n_beams, step, full_circle, angle_min, s, grid)


def points_pipeline(index, r, x, y, n_beams, step, full_circle, angle_min, s, grid):
    """The whole method on the valid returns (beam ``index``, range, point) of one scan."""
    outliers = np.zeros(0, dtype=np.int64)
    if index.shape[0] == 0:
        return empty_result(outliers, outliers)
    fit = int(s[FIT])
    if fit == PAPER:
        # y = kx + b depends on the frame: fit in the sensor frame, as the paper does.
        c, si = math.cos(angle_min), math.sin(angle_min)
        x, y = c * x - si * y, si * x + c * y
        angle_min = 0.0
    gap = _gaps(index, n_beams)
    sigma = s[NOISE_SIGMA]
    if sigma == AUTO:
        sigma = noise_from_ranges(r, gap, np.zeros(1, np.int64), np.full(1, r.shape[0] - 1))
    rule = _rule(s, sigma, step)
    if s[RANGE_NOISE]:
        far_sigma, growth, far_range = noise_growth(
            x, y, r, gap, np.zeros(1, np.int64), np.full(1, r.shape[0] - 1)
        )
        margin = s[NOISE_K] * math.sqrt(2.0)
        rule = with_margin_growth(rule, margin * far_sigma, margin * growth, far_range)
    index, r, x, y, outliers, breaks = _denoise(
        index, r, x, y, n_beams, step, full_circle, rule, sigma, s
    )
    if index.shape[0] == 0:
        return empty_result(outliers, outliers)
    window = _slope_window(x, y, index, sigma, s[SLOPE_WINDOW])
    index, r, x, y, start, end, breakpoints, ring = _cluster_scan(
        index, r, x, y, n_beams, step, full_circle, rule, window, breaks
    )
    table, ox, oy = prefix_moments(x, y)
    inv_r2 = inverse_square_sums(r) if s[CRITERION] == BIC else np.zeros(0)
    scores = _scores(x, y, r, index, n_beams, step, table, start, end, window, s)
    corners, sigma = _choose_corners(table, ox, oy, inv_r2, start, end, scores, sigma, s, grid)
    a, b, owner = _segments(x, y, table, ox, oy, inv_r2, start, end, corners, sigma, s)
    check_sigma = sigma if s[CORNER_CHECK] else -1.0
    corner_beams, jumps = _corner_beams(
        x, y, index, table, ox, oy, fit, a, b, owner, s[SHARED] != 0.0, ring, check_sigma
    )
    return assemble_runs(
        index, x, y, r, a, b, fit, table, ox, oy, angle_min, s[RANGE_SIGMA],
        sorted_union(breakpoints, jumps), corner_beams, outliers,
    )  # fmt: skip


# One implementation, two entries: inlined into extract_scan (one compiled layer
# less), and on its own for run(), which starts from a sequence's points.
_points_pipeline = jit(inline=True)(points_pipeline)
extract_points = jit(points_pipeline)


@jit
def _rule(s, sigma, step):
    lam = auto_abd_lambda(step) if s[ABD_LAMBDA] == AUTO else s[ABD_LAMBDA]
    return noise_rule(
        int(s[RULE_KIND]), s[K], s[NOISE_K], s[LINE_K], lam, s[PDBS_C0], s[JUMP_DISTANCE], sigma
    )


@jit
def _denoise(index, r, x, y, n_beams, step, full_circle, rule, sigma, s):
    """Steps 2-3; returns the cleaned returns, the beams dropped as noise and the
    break flags of the cleaned returns when known (empty otherwise)."""
    none = np.zeros(0, dtype=np.int64)
    unknown = np.zeros(0, dtype=np.bool_)
    kind = s[DENOISE]
    if kind == NO_DENOISE or index.shape[0] < 3:
        return index, r, x, y, none, unknown
    gap = _gaps(index, n_beams)
    raw_breaks = break_flags(x, y, r, gap, step, rule)
    if kind == LITERAL:
        noise = literal_noise(np.hypot(x[1:] - x[:-1], y[1:] - y[:-1]))
        if not noise.any():
            return index, r, x, y, none, raw_breaks
        x, y = window_means(x, y, noise, int(s[WINDOW]), raw_breaks)
        return index, np.hypot(x, y), x, y, none, unknown
    noise = isolated_noise_mask(x, y, r, gap, step, rule, raw_breaks)
    kept_breaks = raw_breaks
    if s[MIN_CLUSTER_POINTS] > 1:
        kept = np.flatnonzero(~noise)
        kx, ky, kr, ki = x[kept], y[kept], r[kept], index[kept]
        kept_gap = _gaps(ki, n_beams)
        joined = (
            full_circle
            and kept.shape[0] >= 3
            and not seam_break(kx, ky, kr, ki, n_beams, step, rule)
        )
        if noise.any():  # else the kept returns are all returns: same breaks
            kept_breaks = break_flags(kx, ky, kr, kept_gap, step, rule)
        small = small_clusters(kept_breaks, int(s[MIN_CLUSTER_POINTS]), joined)
        if s[MIN_CLUSTER_POINTS] == 2:
            margin = s[NOISE_K] * math.sqrt(2.0) * sigma
            small |= in_between_clusters(kr, kept_gap, kept_breaks, small, margin)
        noise[kept[small]] = True
    if not noise.any():
        return index, r, x, y, none, raw_breaks
    keep = ~noise
    return index[keep], r[keep], x[keep], y[keep], index[noise], unknown


@jit
def _gaps(index, n_beams):
    """Beams between consecutive positions (a rotated full circle wraps once)."""
    gap = np.empty(max(index.shape[0] - 1, 0), dtype=np.int64)
    for p in range(gap.shape[0]):
        gap[p] = (index[p + 1] - index[p]) % n_beams
    return gap


@jit
def sorted_union(first, second):
    """Sorted distinct values of two integer arrays."""
    both = np.sort(np.concatenate((first, second)))
    keep = np.ones(both.shape[0], dtype=np.bool_)
    for i in range(1, both.shape[0]):
        keep[i] = both[i] != both[i - 1]
    return both[keep]


@jit
def _slope_window(x, y, index, sigma, setting):
    """Points fitted on each side for the turn score: given, or grown with the noise.

    A line through ``w`` points ``h`` apart with noise ``sigma`` has a direction
    error near ``sigma / (h w^1.5 / sqrt(12))``; ``auto`` takes
    ``w = 3 + 6 sigma / h`` (``h`` the median spacing, ``w`` in 3..15), so that at
    1 deg and 1 cm noise a short wall still has a corner score, and at 0.33 deg
    and 2 cm the score is not noise.
    """
    if setting != AUTO:
        return int(setting)
    steps = neighbour_steps(x, y)
    adjacent = np.empty(steps.shape[0], dtype=np.bool_)
    for p in range(steps.shape[0]):
        adjacent[p] = index[p + 1] - index[p] == 1
    if not adjacent.any():
        return 3
    spacing = np.median(steps[adjacent])
    wanted = 3 + 6 * sigma / spacing if spacing > 0.0 else math.inf
    return int(round(min(max(wanted, 3.0), SLOPE_WINDOW_MAX)))  # noqa: RUF046 (int for numba)


SLOPE_WINDOW_MAX = 15


@jit
def _cluster_scan(index, r, x, y, n_beams, step, full_circle, rule, window, breaks):
    """Clusters, with the seam of a full circle joined (see ``steps.breakpoints.cluster_scan``).

    ``breaks`` are the break flags of the returns if already known (else empty).
    Returns the (possibly rotated) returns, cluster bounds, breakpoint beams and
    whether the scan is one closed ring.
    """
    n = index.shape[0]
    if not full_circle or n < 3:
        if breaks.shape[0] != n - 1:
            breaks = break_flags(x, y, r, _gaps(index, n_beams), step, rule)
        start, end = cluster_bounds(breaks)
        return index, r, x, y, start, end, break_beams(index, end, False), False
    gap = _gaps(index, n_beams)
    rotate_to, seam, ring = seam_rotation(x, y, r, index, gap, n_beams, step, rule)
    if ring:
        rotate_to = ring_anchor(x, y, window)
    if rotate_to:
        order = np.concatenate((np.arange(rotate_to, n), np.arange(0, rotate_to)))
        index, r, x, y = index[order], r[order], x[order], y[order]
    if ring:
        start, end = np.zeros(1, np.int64), np.full(1, n - 1, np.int64)
        return index, r, x, y, start, end, np.zeros(0, np.int64), True
    start, end = cluster_bounds(break_flags(x, y, r, _gaps(index, n_beams), step, rule))
    return index, r, x, y, start, end, break_beams(index, end, seam), False


@jit
def _scores(x, y, r, index, n_beams, step, table, start, end, window, s):
    kind = s[CORNER_SCORE]
    if kind == TURN:
        return turn_scores(x, y, table, start, end, window)
    return slope_scores(r, _gaps(index, n_beams), step, start, end, kind == DK_SIGNED)


@jit
def _choose_corners(table, ox, oy, inv_r2, start, end, scores, sigma, s, grid):
    """Steps 5-7: corner candidates and the threshold sweep; returns corners and the noise."""
    fit, shared = int(s[FIT]), s[SHARED] != 0.0
    n = table.shape[1] - 1
    candidates = peak_positions(scores, start, end)
    ranked, accepted, sse, segments, _, levels = sweep_levels(
        fit, table, ox, oy, inv_r2, start, end, n, candidates, scores[candidates], grid,
        s[USE_GRID] != 0.0, int(s[MAX_EVALUATIONS]), shared,
    )  # fmt: skip
    n_points = int(np.sum(end - start + 1))
    criterion, penalty = int(s[CRITERION]), s[PENALTY]
    best, _ = best_level(criterion, sse, segments, levels, n_points, sigma, penalty)
    corners = level_corners(ranked, accepted, levels[best])
    if s[NOISE_SIGMA] == AUTO and criterion == BIC:
        # Second pass with the noise measured on the lines of the first choice.
        a, b, _ = _cut(start, end, corners, shared)
        sigma = _residual_sigma(fit, table, ox, oy, inv_r2, a, b, sigma)
        best, _ = best_level(criterion, sse, segments, levels, n_points, sigma, penalty)
        corners = level_corners(ranked, accepted, levels[best])
    return corners, sigma


@jit
def _segments(x, y, table, ox, oy, inv_r2, start, end, corners, sigma, s):
    """Runs ``[a, b]`` (and cluster of each) after cutting, refining, merging and bounding."""
    fit, shared = int(s[FIT]), s[SHARED] != 0.0
    a, b, owner = _cut(start, end, corners, shared)
    if not shared:
        a, b = _refine_splits(fit, table, ox, oy, inv_r2, a, b, owner)
    if s[MERGE]:
        segment_cost = s[PENALTY] * math.log(max(x.shape[0], 2)) * sigma * sigma
        a, b, owner = merge_runs(fit, table, ox, oy, inv_r2, a, b, owner, segment_cost)
    if s[MAX_RESIDUAL] != AUTO:
        a, b, owner = split_runs(
            x, y, fit, table, ox, oy, a, b, owner, s[MAX_RESIDUAL], int(s[MIN_POINTS])
        )
    keep = np.empty(a.shape[0], dtype=np.bool_)
    for k in range(a.shape[0]):
        length = math.sqrt((x[b[k]] - x[a[k]]) ** 2 + (y[b[k]] - y[a[k]]) ** 2)
        keep[k] = b[k] - a[k] + 1 >= s[MIN_POINTS] and length >= s[MIN_LENGTH]
    return a[keep], b[keep], owner[keep]


@jit
def _residual_sigma(fit, table, ox, oy, inv_r2, a, b, fallback):
    """Range noise from the fits of the runs ``[a, b]``: the median of ``sqrt(cost / (n - 2))``.

    Only runs of :data:`MIN_RUN_FOR_NOISE` points or more count (short runs fit
    their own noise); the median ignores the few runs that still hide a corner.
    """
    per_run = np.empty(a.shape[0])
    count = 0
    for k in range(a.shape[0]):
        if b[k] - a[k] + 1 >= MIN_RUN_FOR_NOISE:
            value = math.sqrt(run_cost(fit, table, ox, oy, inv_r2, a[k], b[k]) / (b[k] - a[k] - 1))
            if math.isfinite(value):
                per_run[count] = value
                count += 1
    if count == 0:
        return fallback
    return max(np.median(per_run[:count]), MIN_NOISE_SIGMA)


MIN_RUN_FOR_NOISE = 8


@jit
def _cut(start, end, corners, shared):
    """Runs ``[a, b]`` and their cluster number after cutting the clusters at ``corners``."""
    a = np.sort(np.concatenate((start, corners + (0 if shared else 1))))
    b = np.sort(np.concatenate((corners, end)))
    owner = np.searchsorted(start, a, side="right") - 1
    return a, b, owner


@jit
def _refine_splits(fit, table, ox, oy, inv_r2, a, b, owner):
    """Move each cut (end ``b[k]`` / start ``a[k+1]``) by one position where that fits better.

    Every cut is judged against the original neighbours; two cuts moving
    towards each other that would leave a run of one point both stay put.
    """
    m = a.shape[0]
    new_a, new_b = a.copy(), b.copy()
    for k in range(m - 1):
        if owner[k] != owner[k + 1]:
            continue
        best_cost, best_shift = math.inf, 0
        for shift in (0, -1, 1):
            cut = b[k] + shift
            if cut - a[k] < 1 or b[k + 1] - cut - 1 < 1:
                continue
            total = run_cost(fit, table, ox, oy, inv_r2, a[k], cut) + run_cost(
                fit, table, ox, oy, inv_r2, cut + 1, b[k + 1]
            )
            if total < best_cost - 1e-15:  # NaN never wins
                best_cost, best_shift = total, shift
        new_b[k] = b[k] + best_shift
        new_a[k + 1] = new_b[k] + 1
    too_short = new_b - new_a < 1
    for k in range(m - 1):
        if owner[k] == owner[k + 1] and (too_short[k] or too_short[k + 1]):
            new_b[k], new_a[k + 1] = b[k], a[k + 1]
    return new_a, new_b


@jit
def _corner_beams(x, y, index, table, ox, oy, fit, a, b, owner, shared, ring, sigma):
    """Beams of the corners where two kept segments of one cluster meet, and of jumps.

    A shared corner is its shared point; otherwise the point nearer the two
    lines' intersection among those between the segments. With ``sigma >= 0``,
    two segments whose lines do not meet near their facing ends (farther than
    :data:`CORNER_REACH` times the local spacing plus three ``sigma``) are two
    surfaces at different depths joined by a mixed pixel or a small step: the
    junction is reported as a breakpoint (the last beam of the first segment).
    """
    m = a.shape[0]
    corners = np.zeros(m, dtype=np.int64)
    jumps = np.zeros(m, dtype=np.int64)
    n_corners = n_jumps = 0
    for k in range(m):
        right = k + 1
        if right == m:
            if not (ring and m >= 2 and a[0] == 0 and b[-1] == x.shape[0] - 1):
                break
            right = 0
        elif owner[k] != owner[right] or a[right] - b[k] > 2:
            continue
        end, start = b[k], a[right]
        if shared:
            corners[n_corners] = index[start]
            n_corners += 1
            continue
        rho_i, alpha_i, _ = fit_run(fit, table, ox, oy, a[k], b[k])
        rho_j, alpha_j, _ = fit_run(fit, table, ox, oy, a[right], b[right])
        cx, cy = line_intersection(rho_i, alpha_i, rho_j, alpha_j)
        before = math.hypot(x[end] - cx, y[end] - cy)
        after = math.hypot(x[start] - cx, y[start] - cy)
        pick = start if after < before else end
        if sigma >= 0.0:
            reach = CORNER_REACH * math.hypot(x[start] - x[end], y[start] - y[end]) + 3.0 * sigma
            if not max(before, after) <= reach:  # NaN (parallel lines) is not a corner
                jumps[n_jumps] = index[end]
                n_jumps += 1
                continue
        corners[n_corners] = index[pick]
        n_corners += 1
    return corners[:n_corners], jumps[:n_jumps]


CORNER_REACH = 2.0
"""A corner's lines meet within this many spacings (plus noise) of the facing ends."""
