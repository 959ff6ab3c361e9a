"""Each step of the adaptive method on its own, against hand-computed values."""

from __future__ import annotations

import math

import numpy as np
import pytest

from scanlines import Scan, extract
from scanlines.evaluate import make_scene
from scanlines.steps.breakpoints import (
    MAX_BRIDGED_SHARE,
    BreakpointRule,
    Clusters,
    auto_abd_lambda,
    cluster,
    is_break,
    thresholds,
)
from scanlines.steps.corners import corner_side, peak_candidates, slope_difference, turn_angle
from scanlines.steps.denoise import (
    estimate_noise,
    in_between_clusters,
    isolated_noise,
    literal_noise,
    noise_growth,
    replace_by_window_mean,
)
from scanlines.steps.fit import (
    Moments,
    RunCost,
    line_covariances,
    paper_lines,
    run_labels,
    tls_lines,
)
from scanlines.steps.points import make_sequence
from scanlines.steps.select import sweep, threshold_grid
from scenes import cast, scan_of, square_room


def sequence_of(scan: Scan):
    local = scan.angle_increment * np.arange(len(scan))
    return make_sequence(
        scan.ranges, scan.valid, np.cos(local), np.sin(local), scan.angle_increment
    )


def one_cluster(n: int) -> Clusters:
    return Clusters(np.array([0]), np.array([n - 1]), np.zeros(0, dtype=np.intp))


# --- breakpoints (eq. 6-7) ---------------------------------------------------------------


def test_adaptive_threshold_is_k_rho_dtheta():
    rule = BreakpointRule(k=3.0)
    r = np.array([2.0, 4.0])
    limit = thresholds(rule, r, r, np.array([1, 2]), math.radians(1.0))
    np.testing.assert_allclose(limit, [3 * 2.0 * math.radians(1), 3 * 4.0 * 2 * math.radians(1)])


def test_abd_threshold_matches_borges_aldon():
    rule = BreakpointRule(name="abd", abd_lambda=math.radians(10), noise_margin=0.03)
    dphi = math.radians(1)
    expected = 2.0 * math.sin(dphi) / math.sin(math.radians(10) - dphi) + 0.03
    assert thresholds(rule, np.array([2.0]), np.array([5.0]), np.array([1]), dphi)[
        0
    ] == pytest.approx(expected)


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
    rule = BreakpointRule(name="pdbs", pdbs_c0=0.1)
    dphi = math.radians(1)
    expected = 0.1 + math.sqrt(2 * (1 - math.cos(dphi))) * 2.0
    assert thresholds(rule, np.array([5.0]), np.array([2.0]), np.array([1]), dphi)[
        0
    ] == pytest.approx(expected)


def test_breaks_at_jumps_and_long_gaps_only():
    ranges = np.array([2.0, 2.0, 2.0, 3.0, 3.0, np.nan, 3.0, 3.0, np.nan, np.nan, 3.0, 3.0])
    scan = Scan(ranges, 0.0, math.radians(1.0))
    seq = sequence_of(scan)
    breaks = is_break(seq, BreakpointRule(k=3.0))
    # pairs of valid beams: (0,1) (1,2) (2,3)* (3,4) (4,6) bridged (6,7) (7,10)* gap of two
    assert breaks.tolist() == [False, False, True, False, False, False, True, False]
    clusters = cluster(seq, breaks)
    assert clusters.breakpoints.tolist() == [2, 7]


# --- denoising (Step 2-3) -------------------------------------------------------------------


def test_literal_noise_rule_fires_on_ordinary_wall_points():
    scan = scan_of([((3.0, -4.0), (3.0, 4.0))], fov_deg=100, step_deg=1 / 3, sigma=0.01, seed=2)
    seq = sequence_of(scan)
    noise = literal_noise(np.hypot(np.diff(seq.x), np.diff(seq.y)))
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
    seq = sequence_of(Scan(ranges, scan.angle_min, scan.angle_increment))
    rule = BreakpointRule(k=3.0, noise_margin=0.04)
    noise = isolated_noise(seq, rule, is_break(seq, rule))
    assert np.flatnonzero(noise).tolist() == [100]


def test_window_mean_never_crosses_a_jump():
    ranges = np.r_[np.full(10, 2.0), np.full(10, 4.0)]
    scan = Scan(ranges, 0.0, math.radians(1.0))
    seq = sequence_of(scan)
    rule = BreakpointRule(k=3.0)
    breaks = is_break(seq, rule)
    noise = np.zeros(len(seq), dtype=bool)
    noise[9] = True  # last point before the jump
    smoothed = replace_by_window_mean(seq, noise, 10, breaks)
    assert np.all(smoothed.r[10:] == seq.r[10:])  # the far side is untouched
    assert np.all(np.abs(smoothed.r[:10] - 2.0) < 0.01)  # the mean stays on the near surface


def test_noise_estimate_recovers_sigma():
    scan = scan_of([((3.0, -4.0), (3.0, 4.0))], fov_deg=60, step_deg=0.25, sigma=0.02, seed=5)
    seq = sequence_of(scan)
    assert estimate_noise(seq, np.array([0]), np.array([len(seq) - 1])) == pytest.approx(
        0.02, rel=0.15
    )


# --- corners (eq. 12-13) -----------------------------------------------------------------------


def test_slope_difference_matches_eq_13():
    ranges = np.array([2.0, 2.1, 2.3, 2.2])
    step = math.radians(1.0)
    seq = sequence_of(Scan(ranges, 0.0, step))
    dk = slope_difference(seq, one_cluster(4))
    expected_1 = abs(2.1 - 2.0) / (2.0 * step) - abs(2.3 - 2.1) / (2.1 * step)
    expected_2 = abs(2.3 - 2.1) / (2.1 * step) - abs(2.2 - 2.3) / (2.3 * step)
    np.testing.assert_allclose(dk, [0.0, expected_1, expected_2, 0.0])


def test_dk_as_printed_misses_a_symmetric_corner():
    """Seen from inside a room, range rises into a corner and falls after it: |Dk| ~ 0."""
    scan = scan_of(square_room(), fov_deg=60, step_deg=1 / 3, start_deg=15)
    seq = sequence_of(scan)
    corner = int(np.argmax(seq.r))  # the 45 deg corner
    literal = slope_difference(seq, one_cluster(len(seq)))
    signed = slope_difference(seq, one_cluster(len(seq)), signed=True)
    turn = turn_angle(seq, one_cluster(len(seq)), 5, Moments(seq.x, seq.y))
    assert abs(literal[corner]) < 0.01
    assert abs(signed[corner]) > 1.0
    assert turn[corner] == pytest.approx(math.pi / 2, abs=0.01)


def test_peak_rule_and_position_rule():
    score = np.array([0.0, 0.1, 0.5, 0.9, 0.7, 0.1, 0.0])
    peaks = peak_candidates(score, one_cluster(7))
    assert peaks.tolist() == [3]
    # |0.9 - 0.5| = 0.4 > |0.9 - 0.7| = 0.2: the corner lies between 3 and 4.
    assert corner_side(score, peaks).tolist() == [1]
    assert corner_side(np.array([0.0, 0.8, 0.9, 0.2, 0.0]), np.array([2])).tolist() == [-1]


# --- threshold sweep (Step 5-7) ------------------------------------------------------------------


def noisy_room_sweep(seed: int):
    scan = scan_of(
        square_room(), fov_deg=340, step_deg=1 / 3, sigma=0.01, seed=seed, start_deg=-170
    )
    seq = sequence_of(scan)
    moments = Moments(seq.x, seq.y)
    clusters = one_cluster(len(seq))
    score = turn_angle(seq, clusters, 5, moments)
    candidates = peak_candidates(score, clusters)
    return sweep(
        RunCost(moments, "tls"),
        clusters,
        candidates,
        score[candidates],
        grid=None,
        max_evaluations=100,
        shared=False,
    )


def test_min_sse_picks_the_lowest_threshold():
    cuts = noisy_room_sweep(0)
    chosen = cuts.choose("sse", 0.01, 4.0)
    assert chosen.threshold == cuts.thresholds.min()
    assert len(chosen.corners) > 20  # every noise peak becomes a corner


def test_bic_picks_the_four_corners():
    for seed in range(3):
        chosen = noisy_room_sweep(seed).choose("bic", 0.01, 4.0)
        assert len(chosen.corners) == 4


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
    lines = tls_lines(Moments(x, y), np.array([0]), np.array([39]))
    assert lines.rho[0] == pytest.approx(rho)
    assert abs(math.remainder(lines.alpha[0] - alpha, 2 * math.pi)) < 1e-9
    assert lines.sse[0] == pytest.approx(0.0, abs=1e-9)


def test_paper_fit_on_five_means_is_ols():
    rng = np.random.default_rng(3)
    x = np.linspace(0.5, 4.0, 50)
    y = 0.4 * x + 1.0 + rng.normal(0, 0.01, 50)
    lines = paper_lines(Moments(x, y), np.array([0]), np.array([49]))
    means_x = [x[i * 10 : (i + 1) * 10].mean() for i in range(5)]
    means_y = [y[i * 10 : (i + 1) * 10].mean() for i in range(5)]
    k, b = np.polyfit(means_x, means_y, 1)
    norm = math.hypot(k, 1)
    assert lines.rho[0] == pytest.approx(abs(b) / norm)
    assert math.tan(lines.alpha[0] + math.pi / 2) == pytest.approx(k)
    assert lines.sse[0] == pytest.approx(np.sum((y - (k * x + b)) ** 2))


def test_covariance_of_a_wall_facing_the_sensor():
    # Wall x = 2 seen head-on: rho ~ mean of perpendicular offsets, alpha ~ slope.
    step = math.radians(1.0)
    angles = np.radians(np.arange(-20, 21))
    r = 2.0 / np.cos(angles)
    x, y = r * np.cos(angles), r * np.sin(angles)
    rho, alpha = np.array([2.0]), np.array([0.0])
    position, run = run_labels(np.array([0]), np.array([40]), 41)
    cov = line_covariances(x, y, r, rho, alpha, position, run, 0.01)[0]
    weights = (2.0 / r) ** 2 * 0.01**2
    s = y - y.mean()
    assert cov[1, 1] == pytest.approx(np.sum(s * s * weights) / np.sum(s * s) ** 2)
    assert cov[0, 0] == pytest.approx(np.sum(weights) / 41**2)
    assert step > 0


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
    x = np.arange(12, dtype=float)
    moments = Moments(x, np.zeros(12))
    clusters = Clusters(np.array([0]), np.array([11]), np.zeros(0, dtype=np.intp))
    cuts = sweep(
        RunCost(moments, "tls"),
        clusters,
        np.array([1, 5, 10]),
        np.array([3.0, 2.0, 1.0]),
        grid=None,
        max_evaluations=10,
        shared=shared,
    )
    assert cuts.accepted.tolist() == expected


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


def _growth_on_scenes(sensor: str, n: int = 20) -> np.ndarray:
    """``(sigma_far, slope, far_range)`` of :func:`noise_growth` on ``n`` simulated scans."""
    out = []
    for index in range(n):
        seq = sequence_of(make_scene(sensor, index, seed=3).scan)
        ends = (np.zeros(1, np.int64), np.full(1, len(seq) - 1, np.int64))
        out.append(noise_growth(seq.x, seq.y, seq.r, seq.gap, *ends))
    return np.array(out)


def test_noise_growth_sees_constant_noise_at_1_deg():
    # lms_1deg: 1 cm noise and 1 cm quantisation at every range (sigma 1.04 cm). At 1 deg the
    # range second differences of slanted walls far away hold their geometry; chords do not.
    sigma_far, slope, _ = np.median(_growth_on_scenes("lms_1deg"), axis=0)
    assert sigma_far == pytest.approx(math.hypot(0.01, 0.01 / math.sqrt(12)), rel=0.2)
    assert slope < 0.001


def test_noise_growth_follows_noise_proportional_to_range():
    # urg04lx: 1 cm plus 1 % of the range
    growth = _growth_on_scenes("urg04lx")
    assert np.all(growth[:, 1] > 0.002)
    sigma_far, _, far_range = np.median(growth, axis=0)
    assert sigma_far == pytest.approx(math.hypot(0.01, 0.01 * far_range), rel=0.25)
