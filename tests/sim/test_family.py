"""The sensor family: deterministic draws, the stated ranges, the corner sensors, names."""

from __future__ import annotations

import math

import numpy as np
import pytest

from scanlines.errors import ParameterError
from scanlines.sim import SENSORS, NoiseModel, get_sensor
from scanlines.sim.family import (
    BIAS_FACTOR,
    CORNER_NAMES,
    DROPOUT,
    FOV_DEG,
    MAX_BEAMS,
    MIXED_PIXEL,
    NOISE_A,
    NOISE_B,
    OUTLIER,
    RANGE_MAX,
    RANGE_MIN,
    RESOLUTION_DEG,
    SLOPE_REACH,
    corner_sensors,
    family_names,
    family_sensors,
    random_sensor,
)

EPS = 1e-9


def _step_deg(spec) -> float:
    return math.degrees(abs(spec.angle_increment))


def _fov_deg(spec) -> float:
    return 360.0 if spec.full_circle else _step_deg(spec) * (spec.n_beams - 1)


def test_draws_are_deterministic_for_a_seed() -> None:
    a = random_sensor(np.random.default_rng(5))
    assert a == random_sensor(np.random.default_rng(5))
    assert a != random_sensor(np.random.default_rng(6))
    assert family_sensors(24, 0) == family_sensors(24, 0)
    assert family_sensors(24, 0) != family_sensors(24, 1)
    # member k does not depend on how many members are drawn
    assert family_sensors(3)[:3] == family_sensors(24)[:3]


def test_the_family_is_24_named_members_and_the_4_corners() -> None:
    names = family_names()
    assert names == (*(f"family-{k:02d}" for k in range(24)), *CORNER_NAMES)
    assert [s.name for s in family_sensors()] == list(names)
    assert family_names(2, 3) == ("family-s3-00", "family-s3-01", *CORNER_NAMES)
    assert len(set(names) & set(SENSORS)) == 0


def test_family_names_resolve_through_get_sensor() -> None:
    members = family_sensors(24)
    assert get_sensor("family-07") == members[7]
    assert get_sensor("corner-fine-noisy") == corner_sensors()[1]
    assert get_sensor("family-s3-01") == family_sensors(2, 3)[1]
    for bad in ("family-7", "family-s0-07", "corner-fine", "family-", "nope"):
        with pytest.raises(ParameterError, match="unknown sensor"):
            get_sensor(bad)


def _check_ranges(spec) -> None:
    n = spec.noise
    a, b = n.sigma, n.sigma_slope
    assert NOISE_A[0] - EPS <= a <= NOISE_A[1] + EPS
    assert NOISE_B[0] <= b <= NOISE_B[1] + EPS
    assert n.sigma_rel == 0.0
    np.testing.assert_allclose(n.sigma_at(np.array([0.0, 1.0, 10.0])), a + b * np.array([0, 1, 10]))
    assert 0.0 <= n.bias <= BIAS_FACTOR[1] * a + EPS
    assert 0.0 <= n.bias_rel <= BIAS_FACTOR[1] * b + EPS
    assert RESOLUTION_DEG[0] - 1e-3 <= _step_deg(spec) <= RESOLUTION_DEG[1] + 1e-3
    assert spec.n_beams <= MAX_BEAMS
    if not spec.full_circle:
        assert FOV_DEG[0] - RESOLUTION_DEG[1] <= _fov_deg(spec) <= FOV_DEG[1] + EPS
        # centred on the front
        assert spec.angle_min == pytest.approx(-spec.angle_max)
    assert RANGE_MIN[0] <= spec.range_min <= RANGE_MIN[1]
    assert RANGE_MAX[0] <= spec.range_max <= RANGE_MAX[1]
    assert spec.range_max == RANGE_MAX[0] or b * spec.range_max <= SLOPE_REACH + EPS
    assert DROPOUT[0] <= n.dropout_prob <= DROPOUT[1]
    assert OUTLIER[0] <= n.outlier_prob <= OUTLIER[1]
    assert MIXED_PIXEL[0] <= n.mixed_pixel_prob <= MIXED_PIXEL[1]
    assert n.quantum == 0.001


def test_every_drawn_sensor_is_within_the_stated_ranges() -> None:
    rng = np.random.default_rng(0)
    drawn = [random_sensor(rng) for _ in range(300)]
    for spec in [*drawn, *family_sensors(24)]:
        _check_ranges(spec)
    # the draws cover the ranges (not stuck at one end)
    a = np.array([s.noise.sigma for s in drawn])
    b = np.array([s.noise.sigma_slope for s in drawn])
    step = np.array([_step_deg(s) for s in drawn])
    assert a.min() < 0.004
    assert a.max() > 0.025
    assert b.min() < 0.002
    assert b.max() > 0.028
    assert step.min() < 0.12
    assert step.max() > 0.9
    full = np.array([s.full_circle for s in drawn])
    assert 0.15 < full.mean() < 0.35


def test_corner_sensors_are_the_extremes() -> None:
    corners = dict(zip(CORNER_NAMES, corner_sensors(), strict=True))
    for spec in corners.values():
        _check_ranges(spec)
        assert spec.full_circle
    drawn = [random_sensor(np.random.default_rng(k)) for k in range(100)]
    for name, spec in corners.items():
        _, resolution, level = name.split("-")
        n = spec.noise
        if level == "quiet":
            assert (n.sigma, n.sigma_slope) == (NOISE_A[0], NOISE_B[0])
            assert n.dropout_prob == n.outlier_prob == n.bias == 0.0
            assert all(n.sigma_at(5.0) <= d.noise.sigma_at(5.0) + EPS for d in drawn)
        else:
            assert (n.sigma, n.sigma_slope) == (NOISE_A[1], NOISE_B[1])
            assert all(n.sigma_at(5.0) >= d.noise.sigma_at(5.0) - EPS for d in drawn)
        step = _step_deg(spec)
        if resolution == "fine":
            assert step == pytest.approx(RESOLUTION_DEG[0])
            assert spec.n_beams == 3600
            assert all(step <= _step_deg(d) + 1e-3 for d in drawn)
        else:
            assert step == pytest.approx(RESOLUTION_DEG[1])
            assert spec.n_beams == 360
            assert all(step >= _step_deg(d) - 1e-3 for d in drawn)


def test_the_additive_noise_term_leaves_the_presets_alone() -> None:
    urg = SENSORS["urg04lx"].noise
    assert urg.sigma_slope == 0.0
    np.testing.assert_allclose(urg.sigma_at(np.array([0.5, 3.0])), [0.010, 0.030])
    both = NoiseModel(sigma=0.01, sigma_rel=0.01, sigma_slope=0.02)
    np.testing.assert_allclose(both.sigma_at(np.array([0.5, 3.0])), [0.02, 0.09])
    quantised = NoiseModel(sigma=0.003, quantum=0.01)
    assert quantised.effective_sigma(np.array([1.0]))[0] == pytest.approx(
        math.sqrt(0.003**2 + 0.01**2 / 12)
    )
    with pytest.raises(ValueError, match="sigma_slope"):
        NoiseModel(sigma_slope=-0.1)
