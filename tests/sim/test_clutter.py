"""Clutter scenes: legs, people, glass, curved walls, long corridors; truth stays honest."""

from __future__ import annotations

import math

import numpy as np
import pytest

from scanlines.sim import (
    CLUTTER_KINDS,
    SCENE_KINDS,
    BeamStatus,
    NoiseModel,
    World,
    polyline,
    random_scene,
    simulate,
    wall,
)

CLUTTER = {"leg", "person leg", "glass", "curved wall"}
SEEDS = range(5)


def _fingerprint(scene) -> tuple[object, ...]:
    return (
        scene.kind,
        scene.pose,
        [(s.kind, s.closed, s.is_line, s.returns, s.vertices.tolist()) for s in scene.world.shapes],
    )


@pytest.mark.parametrize("sensor", ["lms_1deg", "urg04lx"])
def test_default_scenes_draw_no_clutter(sensor: str) -> None:
    for seed in range(4):
        scene = random_scene(seed, sensor)
        assert _fingerprint(scene) == _fingerprint(random_scene(seed, sensor, clutter=False))
        assert scene.kind in SCENE_KINDS
        assert not scene.shape_kinds & CLUTTER
        assert all(s.returns for s in scene.world.shapes)


@pytest.mark.parametrize("kind", CLUTTER_KINDS)
@pytest.mark.parametrize("sensor", ["tim571", "family-05", "corner-coarse-noisy"])
def test_clutter_scenes_have_legs_people_glass_and_curves(sensor: str, kind: str) -> None:
    for seed in SEEDS:
        scene = random_scene(seed, sensor, kind=kind)
        assert scene.kind == kind
        assert scene.shape_kinds >= CLUTTER, (seed, scene.shape_kinds)
        assert _fingerprint(scene) == _fingerprint(random_scene(seed, sensor, kind=kind))
        for shape in scene.world.shapes:
            extent = shape.vertices.max(axis=0) - shape.vertices.min(axis=0)
            if shape.kind == "glass":
                assert not shape.returns
                assert shape.is_line
            elif shape.kind == "curved wall":
                assert not shape.is_line
                assert not shape.closed
                assert shape.n_edges >= 23
            elif shape.kind == "leg" and shape.is_line:  # a square leg
                sides = np.hypot(*(shape.edge_end - shape.edge_start).T)
                assert 0.02 - 1e-9 <= sides.min() <= sides.max() <= 0.05 + 1e-9
            elif shape.kind == "leg":  # a round leg
                assert 0.02 * math.cos(math.pi / 12) - 1e-9 <= max(extent) <= 0.05 + 1e-9
            elif shape.kind == "person leg":
                assert not shape.is_line
                assert 0.08 - 1e-9 <= max(extent) <= 0.15 + 1e-9
        legs = [s for s in scene.world.shapes if s.kind == "leg"]
        people = [s for s in scene.world.shapes if s.kind == "person leg"]
        assert len(legs) % 4 == 0
        assert len(people) % 2 == 0
        assert legs
        assert people
        if kind == "long corridor":
            walls = np.vstack([s.vertices for s in scene.world.shapes if s.kind == "corridor wall"])
            span = max(np.hypot(*(walls - p).T).max() for p in walls)
            assert 20.0 <= span <= 41.0


def test_clutter_is_picked_at_random_among_the_clutter_kinds() -> None:
    kinds = {random_scene(seed, "lms_05deg", clutter=True).kind for seed in range(8)}
    assert kinds == set(CLUTTER_KINDS)


def test_glass_stops_the_beam_and_returns_nothing() -> None:
    behind = wall((4, -3), (4, 3))
    pane = wall((2, -0.5), (2, 0.5), kind="glass", returns=False)
    sim = simulate(World([behind, pane]), "lms_1deg", noise=NoiseModel())
    truth = sim.truth
    through = math.degrees(math.atan2(0.5, 2.0))
    bearings = np.arange(-90.0, 90.0)
    on_glass = np.abs(bearings) < through
    assert on_glass.sum() >= 20
    assert np.all(truth.status[on_glass] == BeamStatus.NO_HIT)
    assert np.all(truth.edge[on_glass] == -1)
    assert not sim.scan.valid[on_glass].any()
    # the wall behind is seen beside the pane; the gap is one breakpoint, before it
    assert sim.scan.valid[(np.abs(bearings) > through + 2) & (np.abs(bearings) < 30)].all()
    assert truth.breakpoints.tolist() == [np.flatnonzero(on_glass)[0] - 1]
    assert not truth.breakpoint_dont_care.any()


def test_a_straight_wall_running_into_a_curved_one_is_a_dont_care_junction() -> None:
    straight = polyline([(3, -3), (3, 0)], kind="room wall")
    t = np.linspace(0, math.pi / 2, 30)
    arc = polyline(np.column_stack((4 - np.cos(t), np.sin(t))), is_line=False)
    truth = simulate(World([straight, arc]), "lms_05deg", noise=NoiseModel()).truth
    assert len(truth.breakpoints) == 1
    assert truth.breakpoint_dont_care.tolist() == [True]
    assert len(truth.corners) == 0
    # the only segment is the straight wall; the arc gives none
    assert len(truth.segments) == 1
    assert truth.segments.edge.tolist() == [0]


@pytest.mark.parametrize("sensor", ["family-02", "corner-fine-noisy"])
def test_clutter_truth_claims_no_segment_or_corner_on_a_curve(sensor: str) -> None:
    for seed in range(3):
        scene = random_scene(seed, sensor, clutter=True)
        truth = scene.scan(seed).truth
        world = scene.world
        assert world.edge_is_line[truth.segments.edge].all()
        assert world.edge_is_line[truth.edge[truth.corners]].all()
        glass = np.array([not world.shapes[k].returns for k in world.edge_shape])
        assert not glass[truth.segments.edge].any()
        returned = truth.true_return
        assert np.all(truth.edge[returned] >= 0)
        assert not glass[truth.edge[returned]].any()
