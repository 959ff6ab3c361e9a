"""The building blocks of :mod:`scanlines.steps`, each against its definition."""

from __future__ import annotations

import math

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from scanlines import Scan, extract
from scanlines.evaluation.scenes import make_scene
from scanlines.methods.adaptive import MAX_BRIDGED_SHARE
from scanlines.steps.breakpoints import RULE_CODES, BreakpointRule
from scanlines.steps.fit import PAPER, TLS, RunCost, prefix_moments, run_covariances
from scanlines.steps.noise import NoiseLine, noise_at, scan_noise
from scanlines.steps.returns import Returns, beam_gaps
from scanlines.steps.select import BIC, SSE, threshold_grid
from scenes import cast, returns_of, scan_of, square_room
from step_kernels import (
    auto_abd_lambda,
    best_level,
    break_beams,
    break_flags,
    cluster_bounds,
    extend_sweep,
    fit_run,
    in_between_clusters,
    isolated_noise,
    level_corners,
    literal_noise,
    offset_power_sums,
    parabola_at_centre,
    peak_positions,
    slope_scores,
    start_sweep,
    sweep_decided,
    sweep_levels,
    threshold,
    turn_scores,
    window_means,
)


def rule_of(name="paper", *, k=3.0, noise_margin=0.0, abd_lambda=10.0, pdbs_c0=0.1):
    """A breakpoint rule with its margin in metres and ``abd_lambda`` in degrees."""
    lam = math.radians(abd_lambda)
    sigmas = 1.0 if noise_margin else 0.0
    noise = NoiseLine(noise_margin, 0.0)
    return BreakpointRule(RULE_CODES[name], k, sigmas, 0.0, noise, lam, pdbs_c0, 0.3)


def whole(n: int) -> tuple[np.ndarray, np.ndarray]:
    """``start, end`` of one cluster over ``n`` positions."""
    return np.array([0]), np.array([n - 1])


def gaps(returns) -> np.ndarray:
    return beam_gaps(returns.index, int(returns.index[-1]) + 1)


# --- breakpoints (eq. 6-7) ---------------------------------------------------------------


def test_adaptive_threshold_is_k_rho_dtheta():
    rule = rule_of(k=3.0)
    dphi = math.radians(1.0)
    limit = [threshold(rule, 2.0, 2.0, 1, dphi), threshold(rule, 4.0, 4.0, 2, dphi)]
    np.testing.assert_allclose(limit, [3 * 2.0 * dphi, 3 * 4.0 * 2 * dphi])


def test_abd_threshold_matches_borges_aldon():
    rule = rule_of("abd", abd_lambda=10.0, noise_margin=0.03)
    dphi = math.radians(1)
    expected = 2.0 * math.sin(dphi) / math.sin(math.radians(10) - dphi) + 0.03
    assert threshold(rule, 2.0, 5.0, 1, dphi) == pytest.approx(expected)


@pytest.mark.parametrize(
    ("step_deg", "lambda_deg"), [(0.25, 10.0), (0.33, 10.0), (0.5, 10.0), (1.0, 15.0), (-1.0, 15.0)]
)
def test_auto_abd_lambda_is_10_deg_unless_the_scan_is_coarse(step_deg, lambda_deg):
    assert math.degrees(auto_abd_lambda(math.radians(step_deg))) == pytest.approx(lambda_deg)


@pytest.mark.parametrize("step_deg", [0.7, 1.0, 2.0, 4.0])
def test_auto_abd_lambda_bridges_at_most_its_share_of_the_range(step_deg):
    dphi = math.radians(step_deg)
    lam = auto_abd_lambda(dphi)
    assert lam > math.radians(10.0)
    assert math.sin(dphi) / math.sin(lam - dphi) == pytest.approx(MAX_BRIDGED_SHARE)


def test_auto_abd_lambda_stops_at_90_deg():
    assert auto_abd_lambda(math.radians(10.0)) == pytest.approx(math.pi / 2)


def test_pdbs_threshold_uses_the_nearer_range():
    rule = rule_of("pdbs", pdbs_c0=0.1)
    dphi = math.radians(1)
    expected = 0.1 + math.sqrt(2 * (1 - math.cos(dphi))) * 2.0
    assert threshold(rule, 5.0, 2.0, 1, dphi) == pytest.approx(expected)


def test_breaks_at_jumps_and_long_gaps_only():
    ranges = np.array([2.0, 2.0, 2.0, 3.0, 3.0, np.nan, 3.0, 3.0, np.nan, np.nan, 3.0, 3.0])
    scan = Scan(ranges, 0.0, math.radians(1.0))
    returns = returns_of(scan)
    breaks = break_flags(returns, gaps(returns), scan.angle_increment, rule_of(k=3.0))
    # pairs of valid beams: (0,1) (1,2) (2,3)* (3,4) (4,6) bridged (6,7) (7,10)* gap of two
    assert breaks.tolist() == [False, False, True, False, False, False, True, False]
    _, end = cluster_bounds(breaks)
    assert break_beams(returns.index, end, False).tolist() == [2, 7]


# --- denoising (Step 2-3) -------------------------------------------------------------------


def test_literal_noise_rule_fires_on_ordinary_wall_points():
    scan = scan_of([((3.0, -4.0), (3.0, 4.0))], fov_deg=100, step_deg=1 / 3, sigma=0.01, seed=2)
    returns = returns_of(scan)
    noise = literal_noise(np.hypot(np.diff(returns.x), np.diff(returns.y)))
    share = noise.mean()
    assert 0.15 < share < 0.35  # a plain wall, yet about a quarter of its points are "noise"


def test_literal_noise_rule_matches_its_definition():
    d = np.array([1.0, 2.0, 3.0, 1.0, 1.0, 5.0, 2.0])
    # i = 2: d1 > d0 and d2 > d3 -> noise; i = 5: d4 > d3? no.
    assert np.flatnonzero(literal_noise(d)).tolist() == [2]


def test_isolated_rule_finds_a_spike_and_nothing_else():
    scan = scan_of([((3.0, -4.0), (3.0, 4.0))], fov_deg=100, step_deg=1 / 3, sigma=0.01, seed=2)
    ranges = scan.ranges.copy()
    ranges[100] += 0.8
    returns = returns_of(Scan(ranges, scan.angle_min, scan.angle_increment))
    rule = rule_of(k=3.0, noise_margin=0.04)
    step = scan.angle_increment
    breaks = break_flags(returns, gaps(returns), step, rule)
    noise = isolated_noise(returns, gaps(returns), step, rule, breaks)
    assert np.flatnonzero(noise).tolist() == [100]


def test_window_mean_never_crosses_a_jump():
    ranges = np.r_[np.full(10, 2.0), np.full(10, 4.0)]
    scan = Scan(ranges, 0.0, math.radians(1.0))
    returns = returns_of(scan)
    breaks = break_flags(returns, gaps(returns), scan.angle_increment, rule_of(k=3.0))
    noise = np.zeros(20, dtype=bool)
    noise[9] = True  # last point before the jump
    x, y = window_means(returns.x, returns.y, noise, 10, breaks)
    smoothed = np.hypot(x, y)
    assert np.all(smoothed[10:] == returns.r[10:])  # the far side is untouched
    assert np.all(np.abs(smoothed[:10] - 2.0) < 0.01)  # the mean stays on the near surface


def test_noise_estimate_recovers_sigma():
    scan = scan_of([((3.0, -4.0), (3.0, 4.0))], fov_deg=60, step_deg=0.25, sigma=0.02, seed=5)
    returns = returns_of(scan)
    noise = scan_noise(returns, gaps(returns))
    assert noise_at(noise, np.median(returns.r)) == pytest.approx(0.02, rel=0.15)


def test_noise_estimate_sees_through_repeated_ranges():
    # Drivers that repeat one reading over three beams make second differences read zero.
    scan = scan_of([((3.0, -4.0), (3.0, 4.0))], fov_deg=60, step_deg=0.25, sigma=0.02, seed=5)
    ranges = np.repeat(scan.ranges[::3], 3)[: len(scan)]
    returns = returns_of(Scan(ranges, scan.angle_min, scan.angle_increment))
    noise = scan_noise(returns, gaps(returns))
    assert noise_at(noise, np.median(returns.r)) > 0.012


# --- corners (eq. 12-13) -----------------------------------------------------------------------


def test_slope_difference_matches_eq_13():
    ranges = np.array([2.0, 2.1, 2.3, 2.2])
    step = math.radians(1.0)
    returns = returns_of(Scan(ranges, 0.0, step))
    dk = slope_scores(returns.r, gaps(returns), step, *whole(4), False)
    expected_1 = abs(2.1 - 2.0) / (2.0 * step) - abs(2.3 - 2.1) / (2.1 * step)
    expected_2 = abs(2.3 - 2.1) / (2.1 * step) - abs(2.2 - 2.3) / (2.3 * step)
    np.testing.assert_allclose(dk, [0.0, expected_1, expected_2, 0.0])


def test_dk_as_printed_misses_a_symmetric_corner():
    """Seen from inside a room, range rises into a corner and falls after it: |Dk| ~ 0."""
    scan = scan_of(square_room(), fov_deg=60, step_deg=1 / 3, start_deg=15)
    returns = returns_of(scan)
    n, step, gap = len(returns.r), scan.angle_increment, gaps(returns)
    corner = int(np.argmax(returns.r))  # the 45 deg corner
    literal = slope_scores(returns.r, gap, step, *whole(n), False)
    signed = slope_scores(returns.r, gap, step, *whole(n), True)
    moments = prefix_moments(returns.x, returns.y)
    turn = turn_scores(returns.x, returns.y, moments, *whole(n), 5)
    assert abs(literal[corner]) < 0.01
    assert abs(signed[corner]) > 1.0
    assert turn[corner] == pytest.approx(math.pi / 2, abs=0.01)


def test_peak_rule():
    score = np.array([0.0, 0.1, 0.5, 0.9, 0.7, 0.1, 0.0])
    assert peak_positions(score, *whole(7)).tolist() == [3]
    assert peak_positions(-score, *whole(7)).tolist() == [3]  # by magnitude
    assert peak_positions(score, np.array([0, 4]), np.array([3, 6])).tolist() == []


# --- threshold sweep (Step 5-7) ------------------------------------------------------------------


def room_sweep_inputs(seed: int, noise: float):
    """A noisy room scan's candidates and the sweep over them (a plain SSE cost):
    ``(cost, start, end, candidates, scores, n_points, full sweep)``."""
    scan = scan_of(
        square_room(), fov_deg=340, step_deg=1 / 3, sigma=noise, seed=seed, start_deg=-170
    )
    returns = returns_of(scan)
    start, end = whole(len(returns.r))
    moments = prefix_moments(returns.x, returns.y)
    score = turn_scores(returns.x, returns.y, moments, start, end, 5)
    candidates = peak_positions(score, start, end)
    cost = RunCost(TLS, moments, np.zeros(0), np.zeros(0))
    scores = score[candidates]
    swept = sweep_levels(cost, start, end, candidates, scores, np.zeros(0), False, 100, False)
    return cost, start, end, candidates, scores, len(returns.r), swept


def room_sweep_choice(seed: int, criterion: int) -> tuple[np.ndarray, float, np.ndarray]:
    """The corners and threshold the sweep chooses on a noisy room, and every threshold."""
    *_, n_points, swept = room_sweep_inputs(seed, 0.01)
    ranked, accepted, sse, segments, thresholds, levels = swept
    best, _ = best_level(criterion, sse, segments, levels, n_points, 0.01, 4.0)
    return level_corners(ranked, accepted, levels[best]), thresholds[best], thresholds


def test_min_sse_picks_the_lowest_threshold():
    corners, chosen, thresholds = room_sweep_choice(0, SSE)
    assert chosen == thresholds.min()
    assert len(corners) > 20  # every noise peak becomes a corner


def test_bic_picks_the_four_corners():
    for seed in range(3):
        corners, _, _ = room_sweep_choice(seed, BIC)
        assert len(corners) == 4


@given(
    seed=st.integers(0, 10_000),
    noise=st.sampled_from([0.002, 0.01, 0.03]),
    sigma=st.floats(0.002, 0.05),
    penalty=st.floats(0.0, 20.0),
    chunked=st.booleans(),
)
@settings(max_examples=60, deadline=None)
def test_a_sweep_stopped_when_decided_chooses_what_the_full_sweep_chooses(
    seed, noise, sigma, penalty, chunked
):
    cost, start, end, candidates, scores, n_points, swept = room_sweep_inputs(seed, noise)
    ranked, accepted, sse, segments, _, levels = swept
    full, _ = best_level(BIC, sse, segments, levels, n_points, sigma, penalty)
    sweep = start_sweep(cost, start, end, candidates, scores, np.zeros(0), False, 100)
    done = 0
    if chunked:  # a sweep already extended by an earlier choice
        done = extend_sweep(sweep, cost, False, 0, sweep.useful // 3)
    best, inserted = sweep_decided(sweep, cost, False, done, n_points, sigma, penalty)
    assert best == levels[full]
    assert inserted <= sweep.useful
    np.testing.assert_array_equal(sweep.sse[: inserted + 1], sse[: inserted + 1])
    np.testing.assert_array_equal(
        level_corners(sweep.ranked, sweep.accepted, best),
        level_corners(ranked, accepted, levels[full]),
    )


def test_paper_threshold_grid():
    np.testing.assert_allclose(
        threshold_grid(0.0, 0.052, 0.01, 100), [0, 0.01, 0.02, 0.03, 0.04, 0.05]
    )
    assert len(threshold_grid(0.0, 10.0, 0.01, 100)) == 100


# --- fitting (eq. 15-17, TLS) ---------------------------------------------------------------


@pytest.mark.parametrize("alpha", [0.0, 0.3, math.pi / 2, 2.5, -2.0, math.pi])
def test_tls_recovers_exact_lines(alpha):
    rho = 1.7
    t = np.linspace(-2, 3, 40)
    x = rho * math.cos(alpha) - t * math.sin(alpha)
    y = rho * math.sin(alpha) + t * math.cos(alpha)
    fitted_rho, fitted_alpha, sse = fit_run(TLS, prefix_moments(x, y), 0, 39)
    assert fitted_rho == pytest.approx(rho)
    assert abs(math.remainder(fitted_alpha - alpha, 2 * math.pi)) < 1e-9
    assert sse == pytest.approx(0.0, abs=1e-9)


def test_paper_fit_on_five_means_is_ols():
    rng = np.random.default_rng(3)
    x = np.linspace(0.5, 4.0, 50)
    y = 0.4 * x + 1.0 + rng.normal(0, 0.01, 50)
    rho, alpha, sse = fit_run(PAPER, prefix_moments(x, y), 0, 49)
    means_x = [x[i * 10 : (i + 1) * 10].mean() for i in range(5)]
    means_y = [y[i * 10 : (i + 1) * 10].mean() for i in range(5)]
    k, b = np.polyfit(means_x, means_y, 1)
    norm = math.hypot(k, 1)
    assert rho == pytest.approx(abs(b) / norm)
    assert math.tan(alpha + math.pi / 2) == pytest.approx(k)
    assert sse == pytest.approx(np.sum((y - (k * x + b)) ** 2))


def test_covariance_of_a_wall_facing_the_sensor():
    # Wall x = 2 seen head-on: rho ~ mean of perpendicular offsets, alpha ~ slope.
    angles = np.radians(np.arange(-20, 21))
    r = 2.0 / np.cos(angles)
    returns = Returns(np.arange(41), r, r * np.cos(angles), r * np.sin(angles))
    rho, alpha = np.array([2.0]), np.array([0.0])
    sigma = np.full(41, 0.01)
    cov = run_covariances(returns, rho, alpha, np.array([0]), np.array([40]), sigma, False)[0]
    weights = (2.0 / r) ** 2 * 0.01**2
    s = returns.y - returns.y.mean()
    assert cov[1, 1] == pytest.approx(np.sum(s * s * weights) / np.sum(s * s) ** 2)
    assert cov[0, 0] == pytest.approx(np.sum(weights) / 41**2)


def test_paper_preset_runs_the_literal_method_on_a_room():
    scan = scan_of(square_room(), fov_deg=340, step_deg=1 / 3, sigma=0.01, seed=0, start_deg=-170)
    literal = extract(scan, preset="paper")
    # min-SSE over (0, 0.052) keeps every |Dk| peak: far more corners than the room has.
    assert len(literal.corners) > 50
    assert literal.params["fit"] == "paper"


def test_cast_helper_hits_a_wall():
    assert cast(
        [((2.0, -1.0), (2.0, 1.0))], np.array([0.0, math.atan(0.5)])
    ).tolist() == pytest.approx([2.0, math.hypot(2.0, 1.0)])


@pytest.mark.parametrize(
    ("shared", "expected"),
    [
        (False, [True, True, False]),  # split after 10 leaves one point after it
        (True, [False, True, False]),  # [0, 1] and [10, 11] hold one point besides the corner
    ],
)
def test_corner_removal_rule_needs_two_points_on_each_side(shared, expected):
    """Step 5: a corner whose part before or after would have fewer than 2 points is dropped."""
    cost = RunCost(TLS, prefix_moments(np.arange(12.0), np.zeros(12)), np.zeros(0), np.zeros(0))
    candidates, scores = np.array([1, 5, 10]), np.array([3.0, 2.0, 1.0])
    _, accepted, *_ = sweep_levels(
        cost, *whole(12), candidates, scores, np.zeros(0), False, 10, shared
    )
    assert accepted.tolist() == expected


def test_in_between_clusters_judges_only_pairs_between_near_neighbours():
    r = np.array([2.0, 2.0, 2.9, 3.0, 4.0, 4.0, 3.5, 3.6, 1.0, 1.0])
    breaks = np.array([0, 1, 0, 1, 0, 1, 0, 1, 0], dtype=bool)  # clusters of two
    gap = np.ones(9, dtype=np.int64)
    none = np.zeros(10, dtype=bool)
    # (2.9, 3.0) lies between 2.0 and 4.0; (4.0, 4.0) does not lie between 3.0 and 3.5;
    # (3.5, 3.6) lies between 4.0 and 1.0
    expected = [False, False, True, True, False, False, True, True, False, False]
    assert in_between_clusters(r, gap, breaks, none, 0.05).tolist() == expected
    far = gap.copy()
    far[1] = 3  # two missing beams before the first pair: not judged
    assert not in_between_clusters(r, far, breaks, none, 0.05)[2]
    noisy_neighbour = none.copy()
    noisy_neighbour[5] = True
    assert not in_between_clusters(r, gap, breaks, noisy_neighbour, 0.05)[6]


def _noise_on_scenes(sensor: str, n: int = 20) -> np.ndarray:
    """``(sigma0, per_metre)`` of :func:`scan_noise` on ``n`` simulated scans."""
    out = []
    for index in range(n):
        scan = make_scene(sensor, index, seed=3).scan
        returns = returns_of(scan)
        out.append(scan_noise(returns, beam_gaps(returns.index, len(scan))))
    return np.array(out)


def test_scan_noise_sees_constant_noise_at_1_deg():
    # lms_1deg: 1 cm noise and 1 cm quantisation at every range (sigma 1.04 cm). At 1 deg the
    # range second differences of slanted walls far away hold their geometry; fitted lines do not.
    noise = np.median(_noise_on_scenes("lms_1deg"), axis=0)
    for r in (1.0, 4.0):
        assert noise_at(NoiseLine(*noise), r) == pytest.approx(0.0104, rel=0.2)


def test_scan_noise_follows_noise_proportional_to_range():
    # urg04lx: max(1 cm, 1 % of the range)
    line = NoiseLine(*np.median(_noise_on_scenes("urg04lx"), axis=0))
    assert line.per_metre > 0.004
    assert noise_at(line, 3.0) == pytest.approx(0.03, rel=0.25)


@settings(max_examples=80, deadline=None)
@given(
    st.lists(st.integers(1, 2), min_size=6, max_size=6),
    st.lists(st.floats(0.5, 30.0), min_size=7, max_size=7),
)
def test_parabola_at_centre_is_the_least_squares_parabola(steps, ranges):
    # beam offsets with one missing beam here and there, as the noise windows have them
    index = np.concatenate(([0], np.cumsum(steps)))
    r = np.array(ranges)
    t = (index - index[3]).astype(float)
    residual, leverage, slope = parabola_at_centre(
        index, r, 0, 6, 3, offset_power_sums(index, 0, 6, 3)
    )
    design = np.column_stack((np.ones(7), t, t * t))
    coefficients = np.linalg.lstsq(design, r, rcond=None)[0]
    hat = design @ np.linalg.inv(design.T @ design) @ design.T
    assert residual == pytest.approx(r[3] - coefficients[0], abs=1e-9)
    assert slope == pytest.approx(coefficients[1], abs=1e-9)
    assert leverage == pytest.approx(hat[3, 3], abs=1e-12)


def test_contiguous_power_sums_are_the_small_integers():
    assert offset_power_sums(np.arange(7), 0, 6, 3) == (7.0, 0.0, 28.0, 0.0, 196.0)
    shifted = np.arange(100, 107)
    assert offset_power_sums(shifted, 0, 6, 3) == offset_power_sums(np.arange(7), 0, 6, 3)


@pytest.mark.parametrize(("turn_sigma", "corners"), [(0.005, 1), (0.05, 0)])
def test_a_junction_turning_within_the_noise_of_its_lines_is_no_corner(turn_sigma, corners):
    from scanlines.steps.events import CORNER_SIGMAS
    from step_kernels import junction_events

    # two 1 m pieces of wall meeting at a 4 deg turn, 3 m ahead
    turn = math.radians(4.0)
    along = np.linspace(-1.0, 1.0, 41)
    bent = np.where(along < 0.0, along * math.cos(turn), along)
    side = np.where(along < 0.0, -along * math.sin(turn), 0.0)
    x, y = np.full(41, 3.0) + side, bent
    returns = Returns(np.arange(41), np.hypot(x, y), x, y)
    a, b, owner = np.array([0, 21]), np.array([20, 40]), np.zeros(2, dtype=np.int64)
    args = (returns, TLS, prefix_moments(x, y), a, b, owner, False, False, 0.01)
    found, jumps = junction_events(*args, np.full(2, turn_sigma))
    assert (turn >= CORNER_SIGMAS * math.sqrt(2) * turn_sigma) == bool(corners)
    assert len(found) == corners
    assert len(jumps) == 0
    assert len(junction_events(*args, np.zeros(0))[0]) == 1  # without the test: a corner
