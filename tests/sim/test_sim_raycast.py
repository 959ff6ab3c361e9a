"""The ray caster against hand-computed hits."""

from __future__ import annotations

import math

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from scanlines.sim import World, box, cast_rays, polygon, wall
from scanlines.sim import raycast as raycast_module


def _edges(
    *segments: tuple[tuple[float, float], tuple[float, float]],
) -> tuple[np.ndarray, np.ndarray]:
    starts = np.array([s[0] for s in segments], dtype=float)
    ends = np.array([s[1] for s in segments], dtype=float)
    return starts, ends


def test_wall_at_x2_is_hit_at_2_over_cos() -> None:
    angles = np.radians(np.arange(-80.0, 81.0, 1.0))
    hits = cast_rays((0, 0), angles, *_edges(((2.0, -100.0), (2.0, 100.0))))
    np.testing.assert_allclose(hits.ranges, 2.0 / np.cos(angles), rtol=1e-12)
    assert np.all(hits.edge == 0)


def test_square_room_from_its_centre() -> None:
    room = World([polygon([(-1, -1), (1, -1), (1, 1), (-1, 1)])])
    angles = np.radians(np.arange(0.0, 360.0, 7.3))
    hits = room.cast((0, 0), angles)
    expected = 1.0 / np.maximum(np.abs(np.cos(angles)), np.abs(np.sin(angles)))
    np.testing.assert_allclose(hits.ranges, expected, rtol=1e-12)
    # edges in vertex order: 0 bottom (y=-1), 1 right (x=1), 2 top, 3 left
    assert hits.edge[0] == 1
    assert room.cast((0, 0), [math.pi / 2]).edge[0] == 2


def test_beam_through_a_shared_vertex_does_not_leak() -> None:
    room = World([polygon([(-1, -1), (1, -1), (1, 1), (-1, 1)])])
    hits = room.cast((0, 0), np.radians([45.0, 135.0, -135.0, -45.0]))
    np.testing.assert_allclose(hits.ranges, math.sqrt(2.0), rtol=1e-12)
    assert np.all(hits.edge >= 0)


def test_beam_missing_everything_has_no_return() -> None:
    hits = cast_rays((0, 0), [math.pi, math.pi / 2], *_edges(((2.0, -1.0), (2.0, 1.0))))
    assert np.all(np.isinf(hits.ranges))
    assert np.all(hits.edge == -1)


def test_nearest_of_two_surfaces_wins_in_any_edge_order() -> None:
    near, far = ((2.0, -1.0), (2.0, 1.0)), ((3.0, -1.0), (3.0, 1.0))
    for order, near_id in (((near, far), 0), ((far, near), 1)):
        hits = cast_rays((0, 0), [0.0, 0.2], *_edges(*order))
        np.testing.assert_allclose(hits.ranges, 2.0 / np.cos([0.0, 0.2]))
        assert np.all(hits.edge == near_id)


def test_ray_behind_the_origin_and_edge_on_rays_do_not_hit() -> None:
    # the wall is behind the ray; and a ray running along a zero-thickness wall sees nothing
    hits = cast_rays((0, 0), [math.pi, 0.0], *_edges(((2.0, -1.0), (2.0, 1.0))))
    assert math.isinf(hits.ranges[0])
    along = cast_rays((0, 0), [0.0], *_edges(((1.0, 0.0), (2.0, 0.0))))
    assert math.isinf(along.ranges[0])


def test_max_range_turns_far_hits_into_no_return() -> None:
    hits = cast_rays((0, 0), [0.0], *_edges(((6.0, -1.0), (6.0, 1.0))), max_range=5.6)
    assert math.isinf(hits.ranges[0])
    assert hits.edge[0] == -1


def test_origin_and_angles_in_world_frame() -> None:
    world = World([wall((5, -10), (5, 10)), box((3, 2), 1.0, 1.0)])
    hits = world.cast((1.0, 2.0), [0.0, math.pi / 2])
    # straight ahead: box front face at x = 2.5, seen from x = 1
    np.testing.assert_allclose(hits.ranges[0], 1.5)
    assert world.edge_shape[hits.edge[0]] == 1
    assert math.isinf(hits.ranges[1])


def test_chunked_casting_equals_one_chunk(monkeypatch: pytest.MonkeyPatch) -> None:
    rng = np.random.default_rng(3)
    starts, ends = rng.uniform(-5, 5, (40, 2)), rng.uniform(-5, 5, (40, 2))
    angles = np.linspace(-math.pi, math.pi, 500)
    whole = cast_rays((0.1, -0.2), angles, starts, ends)
    monkeypatch.setattr(raycast_module, "_CHUNK_PAIRS", 97)
    chunked = cast_rays((0.1, -0.2), angles, starts, ends)
    np.testing.assert_array_equal(whole.ranges, chunked.ranges)
    np.testing.assert_array_equal(whole.edge, chunked.edge)


@settings(max_examples=60, deadline=None)
@given(
    ax=st.floats(-5, 5),
    ay=st.floats(-5, 5),
    bx=st.floats(-5, 5),
    by=st.floats(-5, 5),
)
def test_hits_lie_on_the_segment_and_the_ray(ax: float, ay: float, bx: float, by: float) -> None:
    a, b = np.array([ax, ay]), np.array([bx, by])
    d = b - a
    if np.hypot(*d) < 1e-3 or abs(a[0] * d[1] - a[1] * d[0]) < 1e-3 * np.hypot(*d):
        return  # too short, or its line passes through the sensor
    angles = np.linspace(-math.pi, math.pi, 361)
    hits = cast_rays((0, 0), angles, a[None], b[None])
    hit = np.isfinite(hits.ranges)
    pts = hits.ranges[hit, None] * np.column_stack((np.cos(angles[hit]), np.sin(angles[hit])))
    cross = d[0] * (pts[:, 1] - a[1]) - d[1] * (pts[:, 0] - a[0])
    np.testing.assert_allclose(cross / np.hypot(*d), 0.0, atol=1e-9)
    t = ((pts - a) @ d) / (d @ d)
    assert np.all((t > -1e-6) & (t < 1 + 1e-6))
    # a beam aimed at the segment's midpoint hits it (unless it runs along the segment)
    mid = (a + b) / 2
    if np.hypot(*mid) > 1e-3 and abs(mid[0] * d[1] - mid[1] * d[0]) > 1e-6 * np.hypot(
        *mid
    ) * np.hypot(*d):
        aimed = cast_rays((0, 0), [math.atan2(mid[1], mid[0])], a[None], b[None])
        np.testing.assert_allclose(aimed.ranges[0], np.hypot(*mid), rtol=1e-7)
