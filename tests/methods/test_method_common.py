"""What the comparison methods share: the segment steps, the clustering rules, any input.

The helpers at the top (scenes with known answers, the seeded simulated set) are
imported by the ``test_method_<name>.py`` files.
"""

from __future__ import annotations

import math
from functools import cache

import numpy as np
import pytest
from hypothesis import HealthCheck, given, settings

from scanlines import Extraction, Extractor, Scan, extract, method_info
from scanlines.builtin_methods import BUILTIN_METHODS
from scanlines.evaluation.metrics import aggregate, score
from scanlines.evaluation.scores import Summary
from scanlines.methods.consensus import inlier_runs
from scanlines.sim import SimScan, random_scene
from scanlines.steps.fit import TLS, fit_many, prefix_moments
from scanlines.steps.merge import pair_chi_squares
from scanlines.steps.returns import Returns
from scanlines.steps.split import CHORD, REFERENCE_CODES
from scenes import beam_of, returns_of, scan_of, square_room
from step_kernels import (
    chord_distance,
    hesse_difference,
    merge_by_chi_square,
    segment_events,
    split_at_farthest,
)
from test_properties import check_order, scans

# adaptive and paper (its paper preset as a method, NaN lines and all): their own tests
METHODS = tuple(m for m in BUILTIN_METHODS if m not in ("adaptive", "paper"))
SIGMA = 0.01  # 1 cm Gaussian range noise in the hand-built scenes
SIM_PRESETS = ("tim571", "lms_1deg")
SIM_SEEDS = range(20)

# --------------------------------------------------------------------------- scenes


def room_scan(seed: int, *, full_circle: bool = False) -> Scan:
    """The 4 m square room from its centre: 340 deg (gap behind) or the full circle, 1/3 deg."""
    if full_circle:
        return scan_of(
            square_room(), fov_deg=360, step_deg=1 / 3, sigma=SIGMA, seed=seed, full_circle=True
        )
    return scan_of(
        square_room(), fov_deg=340, step_deg=1 / 3, sigma=SIGMA, seed=seed, start_deg=-170
    )


def room_corners(scan: Scan) -> list[int]:
    """Beams nearest the four room corners, ascending."""
    return sorted(beam_of(scan, math.radians(d)) for d in (-135, -45, 45, 135))


def angle_error(a: float, b: float) -> float:
    return abs(math.remainder(a - b, 2 * math.pi))


def assert_room_walls(result: Extraction, *, rho_tol: float = 0.01, deg_tol: float = 0.5) -> None:
    """Every segment lies on one of the four walls (rho 2 m, alpha 0, 90, 180, -90 deg)."""
    walls = [(2.0, 0.0), (2.0, math.pi / 2), (2.0, math.pi), (2.0, -math.pi / 2)]
    for segment in result.segments:
        rho, alpha = min(walls, key=lambda w: angle_error(segment.alpha, w[1]))
        assert abs(segment.rho - rho) < rho_tol
        assert angle_error(segment.alpha, alpha) < math.radians(deg_tol)


def door_scene() -> list:
    """Near wall at x = 3 m with a 1 m door, a far wall at x = 5 m behind it."""
    return [((3.0, -4.0), (3.0, -0.5)), ((3.0, 0.5), (3.0, 4.0)), ((5.0, -4.0), (5.0, 4.0))]


def door_scan(seed: int) -> Scan:
    return scan_of(door_scene(), fov_deg=100, step_deg=1 / 3, sigma=SIGMA, seed=seed)


def door_breakpoints(scan: Scan) -> list[int]:
    """The last near-wall beam before the door and the last far-wall beam seen through it."""
    near = np.abs(np.tan(scan.angles) * 3.0) > 0.5
    return [int(np.flatnonzero(near & (scan.angles < 0))[-1]), int(np.flatnonzero(~near)[-1])]


def vertical_wall_scan(seed: int) -> Scan:
    """A wall at x = 3 m, parallel to the sensor's y axis."""
    return scan_of([((3.0, -4.0), (3.0, 4.0))], fov_deg=100, step_deg=1 / 3, sigma=SIGMA, seed=seed)


@cache
def simulated_set(preset: str) -> tuple[SimScan, ...]:
    """The fixed seeded simulated set: 20 random scenes of one sensor."""
    return tuple(random_scene(seed, preset).scan(seed) for seed in SIM_SEEDS)


@cache
def simulated_summary(method: str, preset: str) -> Summary:
    """Pooled scores of ``method`` (defaults) on :func:`simulated_set`."""
    sims = simulated_set(preset)
    return aggregate(score(extract(s.scan, method), s.truth, s.scan) for s in sims)


def returns_from_points(x: np.ndarray, y: np.ndarray) -> Returns:
    """Returns at given points on consecutive beams (no beam missing)."""
    return Returns(np.arange(x.size), np.hypot(x, y), x, y)


def ones(n: int) -> np.ndarray:
    """Beam gaps of ``n`` returns on consecutive beams."""
    return np.ones(max(n - 1, 0), dtype=np.int64)


# --------------------------------------------------------------------------- hand-built scenes

# Known limits, from the literature, that the room tests tolerate:
# line tracking absorbs the first returns past a corner (the paper, sec. 1), so its
# corners land up to 3 beams late and its lines tilt towards the next wall; RANSAC's
# inlier band gives the first wall found the returns of the next one within 5 cm of it.
CORNER_BEAMS = {"line_tracking": 3, "ransac": 2}
WALL_TOLERANCE = {"line_tracking": (0.015, 1.0)}  # (rho m, alpha deg)
# The room has 1 cm noise; line regression's covariances default to 2 cm (its windows'
# similarity then misses one corner in seed 1): told the scene's noise, its fidelity
# bound has to rise with it (it scales with range_sigma^2, see the module docstring).
ROOM_PARAMS = {"line_regression": {"range_sigma": SIGMA, "fidelity": 8.0}}


def room_result(method: str, seed: int, *, full_circle: bool = False) -> Extraction:
    return extract(room_scan(seed, full_circle=full_circle), method, **ROOM_PARAMS.get(method, {}))


@pytest.mark.parametrize("method", METHODS)
@pytest.mark.parametrize("seed", range(5))
def test_square_room_340_degrees(method, seed):
    result = room_result(method, seed)
    assert len(result) == 5
    assert len(result.breakpoints) == 0
    found = result.corners
    assert found.size == 4
    assert np.all(np.abs(found - room_corners(room_scan(seed))) <= CORNER_BEAMS.get(method, 1))
    rho_tol, deg_tol = WALL_TOLERANCE.get(method, (0.01, 0.5))
    assert_room_walls(result, rho_tol=rho_tol, deg_tol=deg_tol)


@pytest.mark.parametrize("method", METHODS)
@pytest.mark.parametrize("seed", range(3))
def test_square_room_full_circle(method, seed):
    result = room_result(method, seed, full_circle=True)
    assert len(result) == 4
    assert len(result.breakpoints) == 0
    found = np.sort(result.corners)
    true = np.array(room_corners(room_scan(seed, full_circle=True)))
    assert found.size == 4
    assert np.all(np.abs(found - true) <= CORNER_BEAMS.get(method, 1))
    # the wall ahead (beam 0 looks at its middle) crosses the seam and is listed last
    assert result.first[-1] > result.last[-1]
    rho_tol, deg_tol = WALL_TOLERANCE.get(method, (0.01, 0.5))
    assert_room_walls(result, rho_tol=rho_tol, deg_tol=deg_tol)


@pytest.mark.parametrize("method", METHODS)
@pytest.mark.parametrize(
    ("missing", "breakpoint"), [(np.r_[1075:1080, 0:6], 1074), (np.r_[500:510], 499)]
)
def test_full_circle_with_a_gap(method, missing, breakpoint):
    """Beams with no return across the seam, or on the wall opposite it."""
    scan = room_scan(0, full_circle=True)
    ranges = scan.ranges.copy()
    ranges[missing] = np.inf
    result = extract(Scan(ranges, scan.angle_min, scan.angle_increment), method)
    assert result.breakpoints.tolist() == [breakpoint]
    assert len(result) == 5
    found = np.sort(result.corners)
    assert np.all(np.abs(found - room_corners(scan)) <= CORNER_BEAMS.get(method, 1))
    assert not np.any(np.isin(missing, result.first) | np.isin(missing, result.last))


@pytest.mark.parametrize("method", METHODS)
@pytest.mark.parametrize("seed", range(3))
def test_door_gap_gives_two_breakpoints(method, seed):
    scan = door_scan(seed)
    result = extract(scan, method)
    first, second = door_breakpoints(scan)
    assert result.breakpoints.tolist() == [first, second]
    assert result.first.tolist() == [0, first + 1, second + 1]
    assert result.last.tolist() == [first, second, len(scan) - 1]
    assert len(result.corners) == 0


@pytest.mark.parametrize("method", METHODS)
def test_vertical_wall_rho_and_alpha(method):
    for seed in range(3):
        (segment,) = extract(vertical_wall_scan(seed), method).segments
        assert abs(segment.rho - 3.0) < 0.005
        assert angle_error(segment.alpha, 0.0) < math.radians(0.2)
        assert segment.covariance[0, 0] > 0.0


# --------------------------------------------------------------------------- any input

any_scan = settings(max_examples=75, deadline=None, suppress_health_check=[HealthCheck.too_slow])


@pytest.mark.parametrize("method", METHODS)
@any_scan
@given(scan=scans(max_beams=1000))
def test_any_scan_gives_ordered_segments_in_range(method, scan):
    result = extract(scan, method)
    check_order(result, len(scan), scan.full_circle)
    assert np.all(result.n_points >= result.params["min_points"])
    assert np.all(result.lines[:, 0] >= 0.0)


@pytest.mark.parametrize("method", METHODS)
def test_empty_and_tiny_scans_give_nothing(method):
    for ranges in ([], [np.nan], [1.0, 1.0], [np.inf] * 5, [0.0, -1.0, np.nan]):
        result = extract(Scan(np.array(ranges, dtype=float), 0.0, 0.01), method)
        assert len(result) == 0
        assert result.corners.size == 0


@pytest.mark.parametrize("method", METHODS)
def test_negative_increment_mirrors_the_beams(method):
    scan = door_scan(0)
    mirrored = Scan(scan.ranges, -scan.angle_min, -scan.angle_increment)
    a, b = extract(scan, method), extract(mirrored, method)
    assert a.breakpoints.tolist() == b.breakpoints.tolist()
    assert a.first.tolist() == b.first.tolist()
    np.testing.assert_allclose(b.lines[:, 0], a.lines[:, 0], atol=1e-9)
    np.testing.assert_allclose(np.abs(b.lines[:, 1]), np.abs(a.lines[:, 1]), atol=1e-9)


@pytest.mark.parametrize("method", ["adaptive", "iepf", "pdbs", "split_merge"])
@pytest.mark.parametrize("full_circle", [False, True])
@pytest.mark.parametrize("clockwise", [False, True])
def test_batch_is_the_single_call_on_full_circles_and_clockwise_scans(
    method, full_circle, clockwise
):
    scan = room_scan(0, full_circle=full_circle)
    if clockwise:  # a negative increment: the points are mirrored, not the ranges
        scan = Scan(scan.ranges, -scan.angle_min, -scan.angle_increment)
    extractor = Extractor(method)
    direct = extractor(scan)
    (batched,) = extractor.batch(scan.ranges[None, :], scan.angle_min, scan.angle_increment)
    for name in ("first", "last", "breakpoints", "corners", "outliers"):
        assert getattr(batched, name).tolist() == getattr(direct, name).tolist()
    np.testing.assert_array_equal(batched.lines, direct.lines)


# --------------------------------------------------------------------------- clustering rules


@pytest.mark.parametrize("rule", ["paper", "abd", "pdbs", "fixed"])
@pytest.mark.parametrize("seed", range(3))
def test_every_clustering_rule_cuts_the_door(rule, seed):
    scan = door_scan(seed)
    result = extract(scan, "iepf", breakpoints=rule)
    assert result.breakpoints.tolist() == door_breakpoints(scan)
    assert len(result) == 3


@pytest.mark.parametrize("method", ["ransac", "hough"])
@pytest.mark.parametrize("rule", ["none", "fixed"])
def test_consensus_methods_find_the_door_with_and_without_clusters(method, rule):
    scan = door_scan(1)
    result = extract(scan, method, breakpoints=rule)
    assert result.breakpoints.tolist() == door_breakpoints(scan)
    assert len(result) == 3


def test_published_rules_have_no_line_bridge():
    clustered = [m for m in METHODS if "breakpoints" in method_info(m)["params"]]
    assert "partition" not in clustered  # it has no clustering rule to publish
    for method in clustered:
        assert method_info(method)["params"]["line_k"][0] == 0.0


# --------------------------------------------------------------------------- splitting


def l_shape(n_side: int = 40) -> tuple[np.ndarray, np.ndarray]:
    """Noise-free points along x = 2 then y = 2 (corner at position n_side - 1)."""
    t = np.linspace(-1.0, 2.0, n_side)
    x = np.r_[np.full(n_side, 2.0), 2.0 - np.linspace(0.05, 2.0, n_side)]
    y = np.r_[t + 0.0, np.full(n_side, 2.0)]
    return x, y


@pytest.mark.parametrize("reference", ["chord", "line"])
def test_split_cuts_an_l_at_its_corner_and_keeps_every_point(reference):
    x, y = l_shape()
    a, b, group = split_at_farthest(
        x, y, prefix_moments(x, y), np.array([0]), np.array([x.size - 1]), np.array([7]),
        0.05, REFERENCE_CODES[reference],
    )  # fmt: skip
    # the corner return (position 39) lies on both lines: either side may take it
    assert b[0] in (38, 39)
    assert a.tolist() == [0, b[0] + 1]
    assert b[1] == 79
    assert group.tolist() == [7, 7]


def test_split_leaves_a_straight_run_whole():
    x = np.full(50, 3.0)
    y = np.linspace(-1, 1, 50) + 0.0
    one = np.array([0])
    a, b, _ = split_at_farthest(x, y, prefix_moments(x, y), one, np.array([49]), one, 0.01, CHORD)
    assert (a.tolist(), b.tolist()) == ([0], [49])


def test_chord_distance_beyond_the_ends_is_to_the_end_point():
    x = np.array([0.0, 1.0, 3.0])
    y = np.array([0.0, 0.0, 1.0])
    d = [chord_distance(x, y, 0, 1, p) for p in range(3)]
    np.testing.assert_allclose(d, [0.0, 0.0, math.hypot(2.0, 1.0)])


# --------------------------------------------------------------------------- inlier runs


def test_inlier_runs_bridge_one_return_and_no_more():
    returns = returns_from_points(np.full(20, 3.0), np.linspace(-1, 1, 20))
    inlier = np.ones(20, dtype=bool)
    inlier[[5, 12, 13]] = False  # one return off the line, then two
    free = np.ones(20, dtype=bool)
    a, b, bridged = inlier_runs(returns, ones(20), inlier, free, max_gap=1.0)
    assert list(zip(a.tolist(), b.tolist(), strict=True)) == [(0, 11), (14, 19)]
    assert bridged.tolist() == [5]


def test_inlier_runs_do_not_bridge_taken_returns_or_missing_beams():
    returns = returns_from_points(np.full(20, 3.0), np.linspace(-1, 1, 20))
    inlier = np.ones(20, dtype=bool)
    inlier[5] = False
    free = np.ones(20, dtype=bool)
    free[5] = False  # already a point of another segment
    a, _, _ = inlier_runs(returns, ones(20), inlier, free, max_gap=1.0)
    assert a.tolist() == [0, 6]
    gap = ones(20)
    gap[9] = 3  # two beams missing between positions 9 and 10
    a, _, _ = inlier_runs(returns, gap, np.ones(20, dtype=bool), np.ones(20, bool), max_gap=1)
    assert a.tolist() == [0, 10]


def test_inlier_runs_end_at_a_spatial_gap():
    y = np.r_[np.linspace(-1, 0, 10), np.linspace(0.6, 1.6, 10)]
    returns = returns_from_points(np.full(20, 3.0), y)
    a, b, _ = inlier_runs(returns, ones(20), np.ones(20, bool), np.ones(20, bool), max_gap=0.4)
    assert list(zip(a.tolist(), b.tolist(), strict=True)) == [(0, 9), (10, 19)]


# --------------------------------------------------------------------------- chi-square merge


def bent_wall_at_pi(delta: float, n: int = 160) -> tuple[np.ndarray, np.ndarray]:
    """A wall near x = -3 (normal along -x, alpha = pi) bent by 2 delta at y = 0.

    The lower half has ``alpha = pi - delta``, the upper ``alpha = -pi + delta``: the
    same line up to noise, on both sides of the +-pi wrap.
    """
    y = np.linspace(-1.5, 1.5, n)
    sign = np.where(y < 0, 1.0, -1.0)
    x = (sign * y * math.sin(delta) - 3.0) / math.cos(delta)
    return x, y


def test_chi_square_merge_joins_two_halves_across_the_pi_wrap():
    x, y = bent_wall_at_pi(0.002)
    returns = returns_from_points(x, y)
    moments = prefix_moments(x, y)
    a, b = np.array([0, 80]), np.array([79, 159])
    _, alpha, _ = fit_many(TLS, moments, a, b)
    # on both sides of the wrap: the raw difference is nearly 2 pi
    assert alpha[0] > 3.1
    assert alpha[1] < -3.1
    sigma = np.full(returns.r.size, 0.01)
    merged = merge_by_chi_square(returns, moments, a, b, np.zeros(2, np.int64), sigma, 3.0, False)
    assert (merged[0].tolist(), merged[1].tolist()) == ([0], [159])


def test_chi_square_merge_keeps_a_real_corner():
    x, y = l_shape()
    merged = merge_by_chi_square(
        returns_from_points(x, y), prefix_moments(x, y), np.array([0, 40]), np.array([39, 79]),
        np.zeros(2, np.int64), np.full(x.size, 0.01), 3.0, False,
    )  # fmt: skip
    assert merged[0].tolist() == [0, 40]


def test_hesse_difference_wraps_angles_and_resolves_the_hesse_flip():
    d_rho, d_alpha = hesse_difference(3.0, math.pi - 0.001, 3.0, -math.pi + 0.001)
    assert (d_rho, d_alpha) == pytest.approx((0.0, -0.002), abs=1e-12)
    # x = 0.01 and -x = 0.01 are parallel lines 2 cm apart
    assert hesse_difference(0.01, 0.0, 0.01, math.pi) == pytest.approx((0.02, 0.0), abs=1e-12)


def test_pair_chi_square_is_zero_for_equal_lines_and_nan_when_singular():
    x, y = bent_wall_at_pi(0.0)
    rho, alpha, _ = fit_many(TLS, prefix_moments(x, y), np.array([0, 0]), np.array([159, 159]))
    covariance = np.stack([np.eye(2) * 1e-4, np.zeros((2, 2))])
    value = pair_chi_squares(rho, alpha, covariance, np.array([0, 1]), np.array([0, 1]))
    assert value[0] == pytest.approx(0.0)
    assert math.isnan(value[1])


# ----------------------------------------------------------------------- corners and breakpoints


def events(returns: Returns, a, b, *, group=None, wrap=False, n_beams=None):
    a, b = np.array(a), np.array(b)
    clustered = group is not None
    group = np.array(group) if clustered else a
    n_beams = returns.index.shape[0] if n_beams is None else n_beams
    moments = prefix_moments(returns.x, returns.y)
    bounds = (2, 0.2, math.radians(10.0))
    return segment_events(returns, n_beams, moments, a, b, group, clustered, wrap, bounds)


def test_segments_meeting_at_an_l_make_a_corner_at_the_nearest_return():
    x, y = l_shape()
    returns = returns_from_points(x, y)
    corners, breakpoints = events(returns, [0, 40], [39, 79])
    assert corners.tolist() == [39]
    assert breakpoints.size == 0
    # a split two returns off the corner reports the corner all the same
    corners, _ = events(returns, [0, 42], [41, 79])
    assert corners.tolist() == [39]


def test_collinear_neighbours_continue_without_an_event():
    returns = returns_from_points(np.full(60, 3.0), np.linspace(-1, 1, 60))
    corners, breakpoints = events(returns, [0, 30], [29, 59])
    assert corners.size == 0
    assert breakpoints.size == 0


def test_a_jump_is_a_breakpoint_without_clusters_and_nothing_with():
    scan = door_scan(0)
    returns = returns_of(scan)
    first, second = door_breakpoints(scan)
    a, b = [0, first + 1, second + 1], [first, second, len(returns.r) - 1]
    corners, breakpoints = events(returns, a, b, n_beams=len(scan))
    assert corners.size == 0
    assert breakpoints.tolist() == [first, second]
    corners, breakpoints = events(returns, a, b, group=[0, 1, 2], n_beams=len(scan))
    assert corners.size == 0
    assert breakpoints.size == 0


def test_segments_of_different_clusters_never_make_a_corner():
    x, y = l_shape()
    corners, _ = events(returns_from_points(x, y), [0, 40], [39, 79], group=[0, 1])
    assert corners.size == 0


def test_the_corner_across_the_seam_of_a_ring():
    x, y = l_shape()
    # rotate so that the corner pair is (last segment, first segment)
    order = np.r_[40:80, 0:40]
    returns = returns_from_points(x[order], y[order])
    corners, _ = events(returns, [0, 40], [39, 79], group=[0, 0], wrap=True)
    assert corners.tolist() == [79]
    corners, _ = events(returns, [0, 40], [39, 79], group=[0, 0], wrap=False)
    assert corners.size == 0
