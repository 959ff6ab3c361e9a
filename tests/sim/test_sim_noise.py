"""Each noise component does what it says (seeded, statistical checks)."""

from __future__ import annotations

import math
from dataclasses import replace

import numpy as np
import pytest

from scanlines.sim import (
    BeamStatus,
    NoiseModel,
    NoisyRanges,
    World,
    apply_noise,
    box,
    simulate,
    wall,
)

N = 20_000


def _noisy(
    true: np.ndarray,
    noise: NoiseModel,
    seed: int = 0,
    jump: np.ndarray | None = None,
    **limits: float,
) -> NoisyRanges:
    jump = np.zeros(len(true) - 1, bool) if jump is None else jump
    return apply_noise(true, jump, noise, np.random.default_rng(seed), **limits)


def test_exact_model_returns_true_ranges() -> None:
    true = np.linspace(0.5, 20.0, 300)
    out = _noisy(true, NoiseModel.exact())
    np.testing.assert_array_equal(out.ranges, true)
    assert np.all(out.status == BeamStatus.HIT)
    assert NoiseModel.exact().bias_at(np.array([3.0]), out.bias_scale)[0] == 0.0


def test_gaussian_noise_has_the_stated_sigma() -> None:
    true = np.full(N, 3.0)
    err = _noisy(true, NoiseModel(sigma=0.02), seed=1).ranges - true
    # sample std of 20000 normals: relative standard error 0.5 %
    assert abs(err.std() - 0.02) < 0.02 * 0.03
    assert abs(err.mean()) < 4 * 0.02 / math.sqrt(N)


def test_range_dependent_sigma_follows_max_of_floor_and_fraction() -> None:
    noise = NoiseModel(sigma=0.01, sigma_rel=0.01)
    for r, expected in ((0.5, 0.01), (1.0, 0.01), (4.0, 0.04)):
        err = _noisy(np.full(N, r), noise, seed=2).ranges - r
        assert abs(err.std() - expected) < expected * 0.03, r


def test_bias_is_one_value_per_scan_within_its_bounds() -> None:
    noise = NoiseModel(sigma=0.005, bias=0.06)
    biases = []
    for seed in range(200):
        out = _noisy(np.full(2000, 4.0), noise, seed=seed)
        b = float(noise.bias_at(np.array([4.0]), out.bias_scale)[0])
        assert -0.06 <= b <= 0.06
        # the whole scan is shifted by the drawn bias
        assert abs((out.ranges - 4.0).mean() - b) < 4 * 0.005 / math.sqrt(2000)
        biases.append(b)
    biases = np.array(biases)
    # uniform on +-6 cm: the extremes are reached and the spread matches 0.06 / sqrt(3)
    assert biases.min() < -0.05
    assert biases.max() > 0.05
    assert abs(biases.std() - 0.06 / math.sqrt(3)) < 0.006


def test_proportional_bias_scales_with_range() -> None:
    noise = NoiseModel(bias=0.02, bias_rel=0.02)
    out = _noisy(np.array([0.5, 1.0, 2.0, 4.0]), noise, seed=5)
    u = out.bias_scale
    assert u != 0.0
    assert abs(u) <= 1.0
    # u * max(2 cm, 2 % r): constant up to 1 m, proportional beyond
    np.testing.assert_allclose(
        out.ranges, [0.5, 1.0, 2.0, 4.0] + u * np.array([0.02, 0.02, 0.04, 0.08])
    )


@pytest.mark.parametrize("quantum", [0.01, 0.001])
def test_quantisation_rounds_to_the_resolution(quantum: float) -> None:
    true = np.random.default_rng(0).uniform(0.5, 10.0, 5000)
    out = _noisy(true, NoiseModel(quantum=quantum)).ranges
    steps = out / quantum
    np.testing.assert_allclose(steps, np.round(steps), atol=1e-6)
    assert np.abs(out - true).max() <= quantum / 2 + 1e-12


def test_ranges_beyond_the_limits_are_no_return() -> None:
    true = np.array([0.03, 0.06, 24.9, 25.1, np.inf])
    out = _noisy(true, NoiseModel(), range_min=0.05, range_max=25.0)
    assert out.ranges[1] == 0.06
    assert out.ranges[2] == 24.9
    assert np.isinf(out.ranges[[0, 3, 4]]).all()
    assert out.status.tolist() == [
        BeamStatus.OUT_OF_RANGE,
        BeamStatus.HIT,
        BeamStatus.HIT,
        BeamStatus.OUT_OF_RANGE,
        BeamStatus.NO_HIT,
    ]


def test_dropouts_remove_the_stated_share_of_returns() -> None:
    out = _noisy(np.full(N, 2.0), NoiseModel(dropout_prob=0.1), seed=3)
    dropped = out.status == BeamStatus.DROPOUT
    assert abs(dropped.mean() - 0.1) < 4 * math.sqrt(0.1 * 0.9 / N)
    assert np.isinf(out.ranges[dropped]).all()
    assert np.all(out.ranges[~dropped] == 2.0)


def test_outliers_are_spurious_short_returns() -> None:
    true = np.full(N, 5.0)
    true[:1000] = np.inf  # beams that hit nothing can also return an outlier
    noise = NoiseModel(outlier_prob=0.05, outlier_far=3.0)
    out = _noisy(true, noise, seed=4, range_min=0.1)
    outlier = out.status == BeamStatus.OUTLIER
    assert abs(outlier.mean() - 0.05) < 4 * math.sqrt(0.05 * 0.95 / N)
    hit_outliers = out.ranges[outlier & np.isfinite(true)]
    assert hit_outliers.min() >= 0.1
    assert hit_outliers.max() < 0.9 * 5.0
    # uniform between range_min and 0.9 r: mean near the middle
    assert abs(hit_outliers.mean() - (0.1 + 4.5) / 2) < 0.15
    far = out.ranges[outlier & np.isinf(true)]
    assert len(far) > 20
    assert far.max() < 3.0
    assert np.all(out.ranges[~outlier & np.isfinite(true)] == 5.0)


def test_mixed_pixels_appear_only_at_marked_depth_jumps_and_lie_between() -> None:
    # pairs (k, k+1) alternate between 2 m and 4 m; mark every 4th pair as a jump
    true = np.where(np.arange(4000) % 2 == 0, 2.0, 4.0)
    jump = np.zeros(3999, bool)
    jump[::4] = True
    out = _noisy(true, NoiseModel(mixed_pixel_prob=1.0), seed=6, jump=jump)
    mixed = np.flatnonzero(out.status == BeamStatus.MIXED)
    assert len(mixed) == jump.sum()  # one beam per discontinuity
    pairs = np.flatnonzero(jump)
    assert np.all(np.isin(mixed, np.concatenate((pairs, pairs + 1))))
    assert np.all((out.ranges[mixed] > 2.0) & (out.ranges[mixed] < 4.0))
    # both sides of the edge are chosen about equally often
    left_share = np.isin(mixed, pairs).mean()
    assert 0.45 < left_share < 0.55


def test_mixed_pixel_probability_and_minimum_jump() -> None:
    true = np.where(np.arange(8000) % 2 == 0, 2.0, 4.0)
    jump = np.ones(7999, bool)
    out = _noisy(true, NoiseModel(mixed_pixel_prob=0.3), seed=7, jump=jump)
    # every beam is in two pairs, each picking it with probability 0.3 / 2:
    # P(mixed) = 1 - 0.85^2 = 0.2775 (4 standard errors: +-0.02)
    assert abs((out.status == BeamStatus.MIXED).mean() - 0.2775) < 0.02
    small = np.where(np.arange(1000) % 2 == 0, 2.0, 2.05)
    quiet = _noisy(
        small, NoiseModel(mixed_pixel_prob=1.0, mixed_pixel_min_jump=0.1), jump=jump[:999]
    )
    assert not np.any(quiet.status == BeamStatus.MIXED)


def test_same_seed_same_scan_and_components_draw_independently() -> None:
    noise = NoiseModel(sigma=0.01, dropout_prob=0.05, outlier_prob=0.02)
    true = np.full(3000, 3.0)
    a, b = _noisy(true, noise, seed=11), _noisy(true, noise, seed=11)
    np.testing.assert_array_equal(a.ranges, b.ranges)
    assert not np.array_equal(a.ranges, _noisy(true, noise, seed=12).ranges)
    # switching dropouts off leaves every other beam's Gaussian noise unchanged
    no_drop = _noisy(true, replace(noise, dropout_prob=0.0), seed=11)
    kept = a.status == BeamStatus.HIT
    np.testing.assert_array_equal(a.ranges[kept], no_drop.ranges[kept])


def test_simulated_scan_has_mixed_pixels_at_a_box_edge() -> None:
    world = World([wall((5, -10), (5, 10)), box((3, 0), 1.0, 1.0)])
    noise = NoiseModel(mixed_pixel_prob=1.0)
    sim = simulate(world, "lms_1deg", seed=0, noise=noise)
    # the two depth jumps are the pairs (78, 79) and (101, 102)
    assert len(sim.truth.mixed_pixels) == 2
    assert sorted(sim.truth.mixed_pixels.tolist())[0] in (78, 79)
    assert sorted(sim.truth.mixed_pixels.tolist())[1] in (101, 102)
    for beam in sim.truth.mixed_pixels:
        assert 2.5 / math.cos(math.radians(beam - 90)) - 0.01 < sim.scan.ranges[beam]
        assert sim.scan.ranges[beam] < 5.0 / math.cos(math.radians(beam - 90)) + 0.01
    # the truth still has its two breakpoints, next to the mixed pixels
    assert len(sim.truth.breakpoints) == 2


def test_noise_model_rejects_bad_values() -> None:
    with pytest.raises(ValueError, match="sigma"):
        NoiseModel(sigma=-0.01)
    with pytest.raises(ValueError, match="dropout_prob"):
        NoiseModel(dropout_prob=1.5)
