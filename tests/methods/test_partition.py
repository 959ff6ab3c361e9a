"""The penalised-likelihood partition: optimality, walls, corners, frames, precision."""

from __future__ import annotations

import math
from pathlib import Path

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from scanlines import Extractor, Scan, extract
from scanlines._core import partition_optimal_runs
from scanlines.data import sample
from scanlines.io import open_log

PENALTY, CLUTTER, MIN_POINTS = 6.0, 4.0, 3


def _chi2(x, y, sigma, a, b):
    """The weighted residual of points ``a..b`` along the beams: the depth along their mean
    bearing regressed on the lateral position, by weighted least squares (computed here with
    numpy, apart from the kernel)."""
    w = 1.0 / sigma[a : b + 1] ** 2
    points = np.stack((x[a : b + 1], y[a : b + 1]), axis=1)
    mean = (w[:, None] * points).sum(axis=0) / w.sum()
    bearing = mean / np.hypot(*mean)
    depth = points @ bearing
    lateral = points @ np.array([-bearing[1], bearing[0]])
    design = np.stack((np.ones_like(lateral), lateral), axis=1) * np.sqrt(w)[:, None]
    fitted, *_ = np.linalg.lstsq(design, depth * np.sqrt(w), rcond=None)
    residual = depth * np.sqrt(w) - design @ fitted
    return float(residual @ residual)


def _cost(points, runs, n):
    """The objective of a partition: runs ``(a, b)``, every other position left out."""
    total, held = 0.0, 0
    for a, b in runs:
        total += 0.5 * _chi2(*points, a, b) + PENALTY
        held += b - a + 1
    return total + CLUTTER * (n - held)


def _brute_force(points, n, opens):
    """The least cost over every partition of ``n`` positions, by enumeration."""

    def best(p):
        if p == n:
            return 0.0
        value = CLUTTER + best(p + 1)
        for q in range(p + MIN_POINTS - 1, n):
            if any(opens[p + 1 : q + 1]):
                break
            value = min(value, _cost(points, [(p, q)], q - p + 1) + best(q + 1))
        return value

    return best(0)


@settings(max_examples=60, deadline=None)
@given(
    n=st.integers(1, 12),
    seed=st.integers(0, 2**32 - 1),
    noise=st.sampled_from([0.002, 0.02, 0.2]),
)
def test_partition_is_optimal_on_small_scans(n, seed, noise):
    rng = np.random.default_rng(seed)
    bearing = np.sort(rng.uniform(-1.0, 1.0, n))
    r = rng.uniform(1.0, 3.0) / np.maximum(np.cos(bearing - rng.uniform(-0.5, 0.5)), 0.3)
    r = np.where(rng.random(n) < 0.3, r * rng.uniform(0.5, 1.5, n), r)
    x, y = r * np.cos(bearing) + rng.normal(0, noise, n), r * np.sin(bearing)
    sigma = np.full(n, 0.01)
    opens = np.zeros(n, dtype=bool)
    opens[0] = True
    opens[rng.integers(0, n)] = True
    a, b = partition_optimal_runs(x, y, sigma, 0.0, opens, PENALTY, CLUTTER, MIN_POINTS)
    assert all(not opens[p + 1 : q + 1].any() for p, q in zip(a, b, strict=True))
    points = (x, y, sigma)
    assert _cost(points, list(zip(a, b, strict=True)), n) == pytest.approx(
        _brute_force(points, n, opens), rel=1e-9, abs=1e-7
    )


def _wall_scan(rng, sigma_of_range, increment_deg=0.5, distance=3.0, turn=0.3):
    """A straight wall ``distance`` from the sensor, its normal ``turn`` rad off the x axis."""
    bearings = np.radians(np.arange(-60.0, 60.0, increment_deg))
    ranges = distance / np.cos(bearings - turn)
    ranges = ranges + rng.normal(0.0, 1.0, ranges.shape) * sigma_of_range(ranges)
    return Scan(ranges, bearings[0], math.radians(increment_deg), range_max=30.0)


@pytest.mark.parametrize(
    "sigma_of_range",
    [lambda r: 0.001 + 0 * r, lambda r: 0.01 + 0 * r, lambda r: 0.03 + 0.03 * r],
    ids=["1mm", "1cm", "3cm+3%"],
)
@pytest.mark.parametrize("seed", range(4))
def test_a_noisy_flat_wall_is_one_segment(sigma_of_range, seed):
    scan = _wall_scan(np.random.default_rng(seed), sigma_of_range)
    result = extract(scan, "partition")
    assert len(result) == 1
    assert result.n_points[0] >= 0.95 * np.count_nonzero(scan.valid)


def test_a_20_degree_corner_at_1_degree_resolution_is_found():
    bearings = np.radians(np.arange(-60.0, 61.0, 1.0))
    # Two walls meeting at (3, 0): normals 90 deg and 70 deg apart, a turn of 20 deg.
    corner = np.array([3.0, 0.0])
    ranges = np.empty(bearings.shape)
    for k, bearing in enumerate(bearings):
        u = np.array([math.cos(bearing), math.sin(bearing)])
        normal = np.radians(-10.0 if bearing < 0 else 10.0)
        n = np.array([math.cos(normal), math.sin(normal)])
        ranges[k] = corner @ n / (u @ n)
    ranges += np.random.default_rng(0).normal(0.0, 0.005, ranges.shape)
    scan = Scan(ranges, bearings[0], math.radians(1.0), range_max=30.0)
    result = extract(scan, "partition")
    assert len(result) == 2
    assert len(result.corners) == 1
    assert abs(result.corners[0] - 60) <= 2


@pytest.mark.parametrize("turn", [0.7, -2.1, math.pi])
def test_segments_do_not_depend_on_the_frame(turn):
    scans = list(open_log(sample("intel")))[:20]
    extractor = Extractor("partition", noise_sigma=0.01)
    for scan in scans:
        turned = Scan(scan.ranges, scan.angle_min + turn, scan.angle_increment, range_max=30.0)
        here, there = extractor(Scan(scan.ranges, scan.angle_min, scan.angle_increment,
                                     range_max=30.0)), extractor(turned)  # fmt: skip
        assert here.first.tolist() == there.first.tolist()
        assert here.last.tolist() == there.last.tolist()
        np.testing.assert_allclose(here.lines[:, 0], there.lines[:, 0], atol=1e-9)
        change = np.angle(np.exp(1j * (there.lines[:, 1] - here.lines[:, 1] - turn)))
        np.testing.assert_allclose(change, 0.0, atol=1e-6)  # angles are float32


def test_float32_and_float64_agree_on_the_shipped_scans():
    agree = total = 0
    for name in ("intel", "freiburg", "urg"):
        scans = list(open_log(sample(name)))
        extractor = Extractor("partition")
        for scan in scans:
            wide = Scan(scan.ranges.astype(np.float64), scan.angle_min, scan.angle_increment,
                        scan.range_min, scan.range_max)  # fmt: skip
            narrow = Scan(scan.ranges.astype(np.float32), scan.angle_min, scan.angle_increment,
                          scan.range_min, scan.range_max)  # fmt: skip
            one, other = extractor(wide), extractor(narrow)
            agree += one.first.tolist() == other.first.tolist() and (
                one.last.tolist() == other.last.tolist()
            )
            total += 1
    assert agree >= 0.995 * total


def test_repeatable_keeps_only_well_determined_lines():
    scans = list(open_log(sample("freiburg")))[:30]
    every, repeatable = Extractor("partition"), Extractor("partition", preset="repeatable")
    for scan in scans:
        kept = repeatable(scan)
        assert len(kept) <= len(every(scan))
        assert np.all(np.sqrt(kept.covariances[:, 0, 0]) <= 0.02 * (1 + 1e-9))
    assert sum(len(every(s)) - len(repeatable(s)) for s in scans) > 0


def test_a_run_left_with_too_few_returns_in_its_fit_is_not_a_segment():
    """A scan found by the property test: a run of four returns lost two of them as
    outliers and was reported as a 2-point segment (min_points 4)."""
    ranges = np.load(Path(__file__).parent / "fixtures" / "partition_outliers_in_a_short_run.npy")
    result = extract(Scan(ranges, 0.0, 0.0140879), "partition")
    assert len(result) > 20
    assert np.all(result.n_points >= result.params["min_points"])


@pytest.mark.parametrize(
    "beams", [100_000, 300_000, pytest.param(1_000_000, marks=pytest.mark.slow)]
)
def test_a_densely_sampled_square_room_is_four_walls(beams):
    """The reliability issue's room, 5 m from the sensor, 1 cm range noise, one full turn:
    with the residual across the line, pieces of a wall sampled denser than its noise turned
    their lines towards the beams (1,018 segments at 3x10^5 beams, 1,961 at 10^6), and at
    10^6 one pass of joining the look-back's pieces left a wall in two."""
    step = 2.0 * math.pi / beams
    bearings = -math.pi + step * np.arange(beams)
    facing = np.round(bearings / (math.pi / 2)) * (math.pi / 2)
    ranges = 5.0 / np.cos(bearings - facing)
    ranges += np.random.default_rng(3).normal(0.0, 0.01, beams)
    scan = Scan(ranges, -math.pi, step, range_max=30.0)
    for preset in (None, "repeatable"):
        result = extract(scan, "partition", preset)
        assert len(result) == 4
        assert result.corners.size == 4
