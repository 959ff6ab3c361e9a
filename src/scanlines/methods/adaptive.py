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

``breakpoints="abd"``, ``noise_k=3``, ``line_k=3``
    ``D = k rho dtheta`` is ``k`` times the spacing of returns on a surface
    facing the sensor; on a wall seen at incidence ``beta`` the spacing is
    ``rho dtheta / cos(beta)``, so ``k = 3`` cuts every wall beyond 70.5 deg.
    The default bounds the incidence instead (80 deg: Borges and Aldon's
    detector [2]_, the same range-proportional threshold made exact for slanted
    surfaces), adds ``noise_k`` standard deviations of a range difference (noise
    estimated from the scan; at 0.33 deg, 2 m and 1 cm noise ``3 rho dtheta`` is
    3.5 cm and noise alone cuts about one pair in fifty), and does not cut a step
    that continues the lines on both sides (walls at grazing incidence).
    [test_adaptive.py::test_grazing_wall_stays_one_cluster, docs/decisions/breakpoints.md]
``denoise="isolated"``, ``min_cluster_points=2``
    Step 2 as printed (``d_{i-1} > d_{i-2}`` and ``d_i > d_{i+1}``) flags any local
    bump of the neighbour distance: about a quarter of the points of a straight
    noisy wall. The default drops a point that the breakpoint test cuts from both
    neighbours while the neighbours stay continuous (a spike), and single-return
    clusters (stray echoes, mixed pixels between two surfaces);
    dropped points are reported in ``Extraction.outliers``. No point is moved.
    [test_adaptive.py::test_spike_outlier_in_wall_is_dropped,
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
from scanlines.scan import is_full_circle
from scanlines.steps.assemble import assemble, empty_extraction
from scanlines.steps.breakpoints import (
    BREAKPOINT_PARAMS,
    BreakpointRule,
    Clusters,
    cluster_scan,
    is_break,
    seam_is_break,
)
from scanlines.steps.corners import (
    SCORES,
    peak_candidates,
    slope_difference,
    strongest_turn,
    turn_angle,
)
from scanlines.steps.denoise import (
    MIN_NOISE_SIGMA,
    estimate_noise,
    isolated_noise,
    literal_noise,
    replace_by_window_mean,
    small_clusters,
)
from scanlines.steps.fit import FITS, Moments, RunCost, fit_runs
from scanlines.steps.merge import merge_collinear, split_by_residual
from scanlines.steps.points import Sequence
from scanlines.steps.segments import line_intersections
from scanlines.steps.select import CRITERIA, sweep, threshold_grid

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
    "min_cluster_points": Param(
        2, int_at_least(1), "isolated denoising: smaller clusters are dropped as noise"
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


def run(seq: Sequence, angle_min: float, params: Mapping[str, Any]) -> Extraction:
    """Extract features from the valid returns ``seq`` of one scan."""
    if len(seq) == 0:
        return empty_extraction(NAME, params)
    if params["fit"] == "paper":
        # y = kx + b depends on the frame: fit in the sensor frame, as the paper does.
        seq, angle_min = seq.turned(angle_min), 0.0
    sigma = _noise_sigma(seq, params)
    rule = BreakpointRule.from_params(dict(params), sigma)
    seq, outliers = _denoise(seq, rule, params)  # Steps 1-3
    if len(seq) == 0:
        return empty_extraction(NAME, params, outliers=outliers)
    window = _slope_window(seq, sigma, params["slope_window"])
    seq, clusters, ring = cluster_scan(seq, rule, lambda ring: strongest_turn(ring, window))
    moments = Moments(seq.x, seq.y)
    cost = RunCost(moments, params["fit"], seq.r if params["criterion"] == "bic" else None)
    corners, sigma = _choose_corners(seq, clusters, moments, cost, window, sigma, params)
    a, b, owner = _segments(seq, clusters, corners, moments, cost, sigma, params)
    shared = params["corner_split"] == "shared"
    check_sigma = sigma if params["corner_check"] else None
    corners, jumps = _corner_beams(
        seq, moments, params["fit"], a, b, owner, shared, ring, check_sigma
    )
    return assemble(
        seq,
        a,
        b,
        fit=params["fit"],
        moments=moments,
        corners=corners,
        breakpoints=np.union1d(clusters.breakpoints, jumps).astype(np.intp),
        outliers=outliers,
        angle_min=angle_min,
        range_sigma=params["range_sigma"],
        method=NAME,
        params=params,
    )


def _choose_corners(
    seq: Sequence,
    clusters: Clusters,
    moments: Moments,
    cost: RunCost,
    window: int,
    sigma: float,
    params: Mapping[str, Any],
) -> tuple[np.ndarray, float]:
    """Steps 5-7: corner candidates and the threshold sweep; returns corners and the noise."""
    shared = params["corner_split"] == "shared"
    scores = _scores(seq, clusters, moments, params, window)
    candidates = peak_candidates(scores, clusters)
    grid = None
    if params["dkth_range"] != "auto":
        low, high = params["dkth_range"]
        grid = threshold_grid(low, high, params["dkth_step"], params["max_evaluations"])
    cuts = sweep(
        cost,
        clusters,
        candidates,
        scores[candidates],
        grid=grid,
        max_evaluations=params["max_evaluations"],
        shared=shared,
    )
    selection = cuts.choose(params["criterion"], sigma, params["penalty"])
    if params["noise_sigma"] == "auto" and params["criterion"] == "bic":
        # Second pass with the noise measured on the lines of the first choice.
        a, b, _ = _cut(clusters, selection.corners, shared)
        sigma = _residual_sigma(cost, a, b, sigma)
        selection = cuts.choose(params["criterion"], sigma, params["penalty"])
    return selection.corners, sigma


def _segments(
    seq: Sequence,
    clusters: Clusters,
    corners: np.ndarray,
    moments: Moments,
    cost: RunCost,
    sigma: float,
    params: Mapping[str, Any],
) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Runs ``[a, b]`` (and cluster of each) after cutting, refining, merging and bounding."""
    shared = params["corner_split"] == "shared"
    a, b, owner = _cut(clusters, corners, shared)
    if not shared:
        b, a = _refine_splits(cost, a, b, owner)
    if params["merge"]:
        a, b, owner = merge_collinear(
            cost, a, b, owner, sigma=sigma, penalty=params["penalty"], n_points=len(seq)
        )
    if params["max_residual"] is not None:
        a, b, owner = split_by_residual(
            seq.x,
            seq.y,
            moments,
            params["fit"],
            a,
            b,
            owner,
            max_residual=params["max_residual"],
            min_points=params["min_points"],
        )
    return _drop_small(seq, a, b, owner, params)


def _noise_sigma(seq: Sequence, params: Mapping[str, Any]) -> float:
    """The range noise: given, or estimated from the raw returns."""
    if params["noise_sigma"] != "auto":
        return params["noise_sigma"]
    return estimate_noise(seq, np.array([0]), np.array([len(seq) - 1]))


def _residual_sigma(cost: RunCost, a: np.ndarray, b: np.ndarray, fallback: float) -> float:
    """Range noise from the fits of the runs ``[a, b]``: the median of ``sqrt(cost / (n - 2))``.

    Only runs of :data:`MIN_RUN_FOR_NOISE` points or more count (short runs fit
    their own noise); the median ignores the few runs that still hide a corner.
    """
    long_enough = b - a + 1 >= MIN_RUN_FOR_NOISE
    if not long_enough.any():
        return fallback
    a, b = a[long_enough], b[long_enough]
    per_run = np.sqrt(cost(a, b) / (b - a - 1))
    per_run = per_run[np.isfinite(per_run)]
    if per_run.size == 0:
        return fallback
    return max(float(np.median(per_run)), MIN_NOISE_SIGMA)


MIN_RUN_FOR_NOISE = 8


def _denoise(
    seq: Sequence, rule: BreakpointRule, params: Mapping[str, Any]
) -> tuple[Sequence, np.ndarray]:
    """Steps 2-3; returns the cleaned sequence and the beams dropped as noise."""
    none = np.zeros(0, dtype=np.intp)
    if params["denoise"] == "none" or len(seq) < 3:
        return seq, none
    raw_breaks = is_break(seq, rule)
    if params["denoise"] == "paper":
        d = np.hypot(np.diff(seq.x), np.diff(seq.y))
        noise = literal_noise(d)
        return replace_by_window_mean(seq, noise, params["window"], raw_breaks), none
    noise = isolated_noise(seq, rule, raw_breaks)
    if params["min_cluster_points"] > 1:
        kept = seq.subset(~noise)
        joined = (
            is_full_circle(seq.n_beams, seq.step)
            and len(kept) >= 3
            and not seam_is_break(kept, rule)
        )
        small = small_clusters(
            is_break(kept, rule), params["min_cluster_points"], seam_joined=joined
        )
        noise[np.flatnonzero(~noise)[small]] = True
    if not noise.any():
        return seq, none
    return seq.subset(~noise), seq.index[noise]


def _scores(
    seq: Sequence, clusters: Clusters, moments: Moments, params: Mapping[str, Any], window: int
) -> np.ndarray:
    kind = params["corner_score"]
    if kind == "turn":
        return turn_angle(seq, clusters, window, moments)
    return slope_difference(seq, clusters, signed=kind == "dk_signed")


def _slope_window(seq: Sequence, sigma: float, setting: Any) -> int:
    """Points fitted on each side for the turn score: given, or grown with the noise.

    A line through ``w`` points ``h`` apart with noise ``sigma`` has a direction
    error near ``sigma / (h w^1.5 / sqrt(12))``; ``auto`` takes
    ``w = 3 + 6 sigma / h`` (``h`` the median spacing, ``w`` in 3..15), so that at
    1 deg and 1 cm noise a short wall still has a corner score, and at 0.33 deg
    and 2 cm the score is not noise.
    """
    if setting != "auto":
        return int(setting)
    steps = np.hypot(np.diff(seq.x), np.diff(seq.y))[seq.gap == 1]
    if steps.size == 0:
        return 3
    spacing = float(np.median(steps))
    wanted = 3 + 6 * sigma / spacing if spacing > 0.0 else math.inf
    return round(min(max(wanted, 3), SLOPE_WINDOW_MAX))


SLOPE_WINDOW_MAX = 15


def _cut(
    clusters: Clusters, corners: np.ndarray, shared: bool
) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Runs ``[a, b]`` and their cluster number after cutting the clusters at ``corners``."""
    a = np.sort(np.r_[clusters.start, corners + (0 if shared else 1)]).astype(np.intp)
    b = np.sort(np.r_[corners, clusters.end]).astype(np.intp)
    owner = np.searchsorted(clusters.start, a, side="right") - 1
    return a, b, owner


def _refine_splits(
    cost: RunCost, a: np.ndarray, b: np.ndarray, owner: np.ndarray
) -> tuple[np.ndarray, np.ndarray]:
    """Move each cut (end ``b[k]`` / start ``a[k+1]``) by one position where that fits better."""
    b, a = b.copy(), a.copy()
    k = np.flatnonzero(owner[:-1] == owner[1:])
    if k.size == 0:
        return b, a
    best_cost = np.full(k.size, np.inf)
    best_shift = np.zeros(k.size, dtype=np.intp)
    shifts = (0, -1, 1)
    ends = [b[k] + shift for shift in shifts]
    # The three shifts' parts, fitted in one call; a shift that empties a part costs inf.
    safe = [np.clip(end, a[k], b[k + 1] - 1) for end in ends]
    parts = cost.many(*[(a[k], e) for e in safe], *[(e + 1, b[k + 1]) for e in safe])
    for j, (shift, end) in enumerate(zip(shifts, ends, strict=True)):
        ok = (end - a[k] >= 1) & (b[k + 1] - end - 1 >= 1)
        total = parts[j] + parts[j + len(shifts)]
        total = np.where(ok & ~np.isnan(total), total, np.inf)
        better = total < best_cost - 1e-15
        best_cost = np.where(better, total, best_cost)
        best_shift = np.where(better, shift, best_shift)
    # Two cuts moving towards each other could leave a run of one point: keep those still.
    new_b = b.copy()
    new_b[k] += best_shift
    new_a = a.copy()
    new_a[k + 1] = new_b[k] + 1
    too_short = new_b - new_a < 1
    if too_short.any():
        bad = np.flatnonzero(too_short)
        frozen = np.isin(k, bad) | np.isin(k + 1, bad)
        new_b[k[frozen]] = b[k[frozen]]
        new_a[k[frozen] + 1] = a[k[frozen] + 1]
    return new_b, new_a


def _drop_small(
    seq: Sequence, a: np.ndarray, b: np.ndarray, owner: np.ndarray, params: Mapping[str, Any]
) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    length = np.hypot(seq.x[b] - seq.x[a], seq.y[b] - seq.y[a])
    keep = (b - a + 1 >= params["min_points"]) & (length >= params["min_length"])
    return a[keep], b[keep], owner[keep]


def _corner_beams(
    seq: Sequence,
    moments: Moments,
    fit: str,
    a: np.ndarray,
    b: np.ndarray,
    owner: np.ndarray,
    shared: bool,
    ring: bool,
    sigma: float | None,
) -> tuple[np.ndarray, np.ndarray]:
    """Beams of the corners where two kept segments of one cluster meet, and of jumps.

    A shared corner is its shared point; otherwise the point nearer the two
    lines' intersection among those between the segments. With ``sigma`` given,
    two segments whose lines do not meet near their facing ends (farther than
    :data:`CORNER_REACH` times the local spacing plus three ``sigma``) are two
    surfaces at different depths joined by a mixed pixel or a small step: the
    junction is reported as a breakpoint (the last beam of the first segment).
    """
    none = np.zeros(0, dtype=np.intp)
    if a.size == 0:
        return none, none
    left = np.flatnonzero((owner[:-1] == owner[1:]) & (a[1:] - b[:-1] <= 2))
    ends, starts = b[left], a[left + 1]
    if ring and a.size >= 2 and a[0] == 0 and b[-1] == len(seq) - 1:
        left = np.r_[left, a.size - 1]
        ends, starts = np.r_[ends, b[-1]], np.r_[starts, a[0]]
    if shared:
        return seq.index[starts], none
    lines = fit_runs(fit, moments, a, b)
    right = (left + 1) % a.size
    corner_x, corner_y = line_intersections(lines, left, right)
    before_dist = np.hypot(seq.x[ends] - corner_x, seq.y[ends] - corner_y)
    after_dist = np.hypot(seq.x[starts] - corner_x, seq.y[starts] - corner_y)
    pick = np.where(after_dist < before_dist, starts, ends)
    if sigma is None:
        return seq.index[pick], none
    spacing = np.hypot(seq.x[starts] - seq.x[ends], seq.y[starts] - seq.y[ends])
    reach = CORNER_REACH * spacing + 3.0 * sigma
    meets = np.maximum(before_dist, after_dist) <= reach  # NaN (parallel) is not a corner
    return seq.index[pick[meets]], seq.index[ends[~meets]]


CORNER_REACH = 2.0
"""A corner's lines meet within this many spacings (plus noise) of the facing ends."""
