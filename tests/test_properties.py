"""Properties of every extraction, for any input (hypothesis)."""

from __future__ import annotations

import math

import numpy as np
import pytest
from hypothesis import HealthCheck, given, settings
from hypothesis import strategies as st
from hypothesis.extra.numpy import arrays

from scanlines import Extraction, Extractor, Scan

SPECIAL = [math.nan, math.inf, -math.inf, 0.0, -1.0, 1e-9, 1e6]

range_values = st.one_of(
    st.floats(min_value=0.0, max_value=60.0, allow_nan=False),
    st.sampled_from(SPECIAL),
)


@st.composite
def scans(draw, max_beams: int = 2000) -> Scan:
    """Arbitrary ranges, or piecewise-smooth ones (so that segments actually form)."""
    n = draw(st.integers(min_value=0, max_value=max_beams))
    if draw(st.booleans()):
        ranges = draw(arrays(np.float64, n, elements=range_values))
    else:
        seed = draw(st.integers(0, 2**32 - 1))
        rng = np.random.default_rng(seed)
        pieces = max(1, n // max(1, rng.integers(5, 200)))
        base = np.repeat(rng.uniform(0.2, 20.0, pieces), math.ceil(n / pieces))[:n]
        ranges = base + np.cumsum(rng.normal(0, 0.02, n)) + rng.normal(0, 0.01, n)
        drop = rng.random(n) < rng.uniform(0, 0.3)
        ranges[drop] = rng.choice(SPECIAL, drop.sum())
    turn = 2 * math.pi / max(n, 1)  # a scan spans at most one turn
    step = draw(st.one_of(st.floats(min_value=1e-4, max_value=0.1).map(lambda s: min(s, turn))))
    increment = draw(st.sampled_from([step, -step, turn, -turn]))
    angle_min = draw(st.floats(min_value=-math.pi, max_value=math.pi))
    return Scan(ranges, angle_min, increment, range_max=draw(st.sampled_from([math.inf, 30.0])))


def check_order(result: Extraction, n: int, full_circle: bool) -> None:
    first, last = result.first, result.last
    assert np.all((first >= 0) & (first < n) & (last >= 0) & (last < n))
    crossing = first > last
    if crossing.any():
        assert full_circle
        assert crossing.sum() == 1
        assert crossing[-1]
    straight = ~crossing
    assert np.all(result.last[straight][:-1] <= result.first[straight][1:])
    if crossing.any() and len(first) > 1:
        assert result.last[-1] <= result.first[0]
    for events in (result.breakpoints, result.corners, result.outliers):
        assert np.all((events >= 0) & (events < n))
        assert np.all(np.diff(events) > 0)


def assigned_beams(result: Extraction, k: int, n: int) -> np.ndarray:
    first, last = int(result.first[k]), int(result.last[k])
    beams = np.arange(first, last + 1) if first <= last else np.r_[first:n, 0 : last + 1]
    return beams[~np.isin(beams, result.outliers)]


default = Extractor()
CONFIGURATIONS = {
    "default": default,
    "paper preset": Extractor(preset="paper"),
    "noise_model=range": Extractor(noise_model="range"),
}
settings_fast = settings(
    max_examples=150, deadline=None, suppress_health_check=[HealthCheck.too_slow]
)


@pytest.mark.parametrize("configuration", CONFIGURATIONS)
@settings_fast
@given(scan=scans())
def test_never_fails_and_orders_segments(configuration, scan):
    result = CONFIGURATIONS[configuration](scan)
    check_order(result, len(scan), scan.full_circle)


@settings_fast
@given(scans())
def test_every_point_of_a_segment_is_near_its_line(scan):
    from scanlines.sensor.profile import scan_noise_line
    from step_kernels import residual_tolerances

    result = default(scan)
    bound = default.params["max_residual"]
    noise = scan_noise_line(scan)  # the bound grows to 5 noise sigmas where that is more
    points = scan.points
    for k, segment in enumerate(result.segments):
        beams = assigned_beams(result, k, len(scan))
        # the extractor sees the ranges at float32 precision (6e-8 relative; 1e-48 is 0)
        beams = beams[scan.valid[beams] & (scan.ranges[beams].astype(np.float32) > 0)]
        x, y = points[beams, 0], points[beams, 1]
        distance = np.abs(x * math.cos(segment.alpha) + y * math.sin(segment.alpha) - segment.rho)
        tolerance = residual_tolerances(scan.ranges[beams], noise, bound)
        assert np.all(distance <= tolerance * (1 + 1e-6) + 1e-7 * scan.ranges[beams] + 1e-9)
        assert segment.rho >= 0.0
        assert -math.pi < segment.alpha <= math.pi


@settings_fast
@given(scans(max_beams=800), st.floats(min_value=-3.0, max_value=3.0))
def test_rotating_the_scan_rotates_every_line(scan, turn):
    rotated = Scan(
        scan.ranges, scan.angle_min + turn, scan.angle_increment, scan.range_min, scan.range_max
    )
    a, b = default(scan), default(rotated)
    assert a.first.tolist() == b.first.tolist()
    assert a.last.tolist() == b.last.tolist()
    assert a.corners.tolist() == b.corners.tolist()
    assert a.breakpoints.tolist() == b.breakpoints.tolist()
    np.testing.assert_allclose(a.lines[:, 0], b.lines[:, 0], atol=1e-9)
    turned = np.angle(np.exp(1j * (b.lines[:, 1] - a.lines[:, 1] - turn)))
    # angle_min is taken at float32 precision: the turn seen is off by up to 3e-7 rad
    np.testing.assert_allclose(turned, 0.0, atol=1e-6)
