"""The random scene generator: reproducible, and it contains the hard cases."""

from __future__ import annotations

import math

import numpy as np
import pytest

from scanlines.sim import SENSORS, NoiseModel, Scene, random_scene

SEEDS = range(8)


def _scene_fingerprint(scene: Scene) -> tuple[object, ...]:
    return (
        scene.kind,
        scene.pose,
        [(s.kind, s.closed, s.vertices.tolist()) for s in scene.world.shapes],
    )


@pytest.mark.parametrize("sensor", sorted(SENSORS))
def test_same_seed_same_scene_and_scan(sensor: str) -> None:
    a, b = random_scene(5, sensor), random_scene(5, sensor)
    assert _scene_fingerprint(a) == _scene_fingerprint(b)
    np.testing.assert_array_equal(a.scan(9).scan.ranges, b.scan(9).scan.ranges)
    assert _scene_fingerprint(random_scene(6, sensor)) != _scene_fingerprint(a)


def test_a_generator_can_be_passed_instead_of_a_seed() -> None:
    rng = np.random.default_rng(5)
    assert _scene_fingerprint(random_scene(rng)) == _scene_fingerprint(random_scene(5))


@pytest.mark.parametrize("sensor", sorted(SENSORS))
def test_every_scene_has_a_visible_grazing_wall_and_short_wall(sensor: str) -> None:
    for seed in SEEDS:
        scene = random_scene(seed, sensor)
        truth = scene.scan(noise=NoiseModel()).truth
        seen = truth.true_return & ~truth.on_curve
        grazing = seen & (truth.incidence >= math.radians(70))
        _, per_edge = np.unique(truth.edge[grazing], return_counts=True)
        assert per_edge.max() >= 5, seed
        kinds = np.array([s.kind for s in scene.world.shapes])
        shape_kind = kinds[scene.world.edge_shape[truth.edge[seen]]]
        assert np.count_nonzero(shape_kind == "short wall") >= 2, seed


@pytest.mark.parametrize("kind", ["room", "corridor"])
def test_scenes_contain_the_listed_obstacles_and_doors(kind: str) -> None:
    for seed in SEEDS:
        scene = random_scene(seed, "tim571", kind=kind)
        assert scene.kind == kind
        kinds = scene.shape_kinds
        assert {"round pillar", "box", "outer wall", "short wall"} <= kinds, seed
        walls = [s for s in scene.world.shapes if s.kind in ("room wall", "corridor wall")]
        # at least one door opening: the outline is cut into open polylines
        assert walls, seed
        assert not any(s.closed for s in walls), seed
        round_pillars = [s for s in scene.world.shapes if s.kind == "round pillar"]
        assert all(not s.is_line and s.n_edges >= 24 for s in round_pillars)
        if kind == "room":
            assert "partition" in kinds, seed


def test_partitions_are_thin_and_some_walls_meet_at_odd_angles() -> None:
    odd_angles = 0
    for seed in range(12):
        scene = random_scene(seed, "lms_1deg", kind="room")
        for shape in scene.world.shapes:
            if shape.kind == "partition":
                sides = np.hypot(*(shape.edge_end - shape.edge_start).T)
                assert sides.min() <= 0.06
            if shape.kind == "room wall":
                d = shape.edge_end - shape.edge_start
                heading = np.degrees(np.arctan2(d[:, 1], d[:, 0]))
                turn = np.abs((np.diff(heading) + 180.0) % 360.0 - 180.0)
                odd_angles += np.count_nonzero(np.abs(turn - 90.0) > 5.0)
    assert odd_angles >= 3  # chamfered corners: walls at arbitrary angles


@pytest.mark.parametrize("sensor", sorted(SENSORS))
def test_sensor_is_in_free_space(sensor: str) -> None:
    for seed in SEEDS:
        scene = random_scene(seed, sensor)
        truth = scene.scan(noise=NoiseModel()).truth
        hit = np.isfinite(truth.true_ranges)
        assert truth.true_ranges[hit].min() > 0.3, seed
        # at least a quarter of the beams see something within the sensor's range
        assert np.mean(truth.true_ranges <= scene.sensor.range_max) > 0.25, seed


@pytest.mark.parametrize("sensor", sorted(SENSORS))
def test_noisy_scans_of_scenes_have_outliers_mixed_pixels_and_dropouts(sensor: str) -> None:
    counts = np.zeros(3, int)
    for seed in SEEDS:
        truth = random_scene(seed, sensor).scan(seed).truth
        counts += [len(truth.outliers), len(truth.mixed_pixels), len(truth.dropouts)]
        assert len(truth.breakpoints) >= 2, seed
    assert np.all(counts >= 4), counts


def test_scenes_have_corners_and_breakpoints_in_number() -> None:
    n_bp = n_c = 0
    for seed in range(10):
        truth = random_scene(seed, "lms_1deg").scan(seed).truth
        n_bp += len(truth.breakpoints)
        n_c += len(truth.corners)
    # the paper's Intel frames have 4-20 breakpoints and 4-13 corners each
    assert n_bp >= 40
    assert n_c >= 10


def test_unknown_kind_is_rejected() -> None:
    with pytest.raises(ValueError, match="corridor"):
        random_scene(0, kind="garage")
