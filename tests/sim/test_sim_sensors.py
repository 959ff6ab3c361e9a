"""Sensor presets carry the real sensors' numbers."""

from __future__ import annotations

import math

import numpy as np
import pytest

from scanlines.errors import ParameterError
from scanlines.sim import SENSORS, NoiseModel, SensorSpec, World, get_sensor, simulate, wall


def test_lms_1deg_is_the_intel_log_layout() -> None:
    s = get_sensor("lms_1deg")
    assert s.n_beams == 180
    np.testing.assert_allclose(np.degrees([s.angle_min, s.angle_max]), [-90.0, 89.0])
    assert s.range_max == 80.0
    assert (s.noise.sigma, s.noise.bias, s.noise.quantum) == (0.01, 0.015, 0.01)


def test_lms_05deg_has_360_beams_over_180_deg() -> None:
    s = get_sensor("lms_05deg")
    assert s.n_beams == 360
    np.testing.assert_allclose(math.degrees(s.angle_increment), 0.5)
    np.testing.assert_allclose(np.degrees([s.angle_min, s.angle_max]), [-90.0, 89.5])


def test_tim571_spans_160_deg_symmetric_about_the_front() -> None:
    s = get_sensor("tim571")
    assert s.n_beams == 481
    np.testing.assert_allclose(math.degrees(s.angle_max - s.angle_min), 160.0)
    np.testing.assert_allclose(s.angle_min, -s.angle_max)
    # the paper's 10..170 deg, shifted by -90 deg so that 0 is straight ahead
    np.testing.assert_allclose(np.degrees([s.angle_min, s.angle_max]) + 90.0, [10.0, 170.0])
    assert (s.range_min, s.range_max) == (0.05, 25.0)
    assert (s.noise.sigma, s.noise.bias, s.noise.quantum) == (0.02, 0.06, 0.001)


def test_urg04lx_layout_and_range_dependent_noise() -> None:
    s = get_sensor("urg04lx")
    assert s.n_beams == 683
    np.testing.assert_allclose(s.angle_increment, 2 * math.pi / 1024)
    assert 239.0 < math.degrees(s.angle_max - s.angle_min) <= 240.0
    assert (s.range_min, s.range_max) == (0.02, 5.6)
    np.testing.assert_allclose(s.noise.sigma_at(np.array([0.5, 1.0, 4.0])), [0.01, 0.01, 0.04])
    # statistical 1 sigma + largest bias equals the datasheet's accuracy bound
    r = np.array([0.1, 0.5, 1.0, 3.0, 5.5])
    worst = s.noise.sigma_at(r) + np.abs(s.noise.bias_at(r, 1.0))
    np.testing.assert_allclose(worst, np.maximum(0.03, 0.03 * r))


def test_presets_are_partial_scans_and_a_ring_is_full() -> None:
    assert not any(s.full_circle for s in SENSORS.values())
    ring = SensorSpec("ring", 360, 0.0, math.radians(1.0), 0.0, 10.0)
    assert ring.full_circle


def test_unknown_preset_names_the_known_ones() -> None:
    with pytest.raises(ParameterError, match="lms_1deg"):
        get_sensor("lms_2deg")


def test_with_noise_overrides_single_fields() -> None:
    s = get_sensor("tim571").with_noise(dropout_prob=0.2)
    assert s.noise.dropout_prob == 0.2
    assert s.noise.sigma == 0.02
    assert get_sensor("tim571").noise.dropout_prob == 0.01


@pytest.mark.parametrize(("name", "quantum"), [("lms_1deg", 0.01), ("tim571", 0.001)])
def test_simulated_ranges_are_quantised_like_the_sensor(name: str, quantum: float) -> None:
    sim = simulate(World([wall((3, -20), (3, 20))]), name, seed=3)
    r = sim.scan.ranges[sim.scan.valid]
    np.testing.assert_allclose(r / quantum, np.round(r / quantum), atol=1e-6)
    assert sim.scan.range_max == get_sensor(name).range_max


def test_urg_does_not_see_beyond_5_6_m() -> None:
    sim = simulate(World([wall((6, -20), (6, 20))]), "urg04lx", seed=0, noise=NoiseModel())
    assert not sim.scan.valid[341]  # the 0 deg beam: 6 m away
    assert sim.scan.valid.sum() == 0
