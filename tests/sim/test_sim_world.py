"""World construction: shapes, edge arrays, adjacency."""

from __future__ import annotations

import math
from collections.abc import Callable

import numpy as np
import pytest

from scanlines.sim import Shape, World, box, polygon, polyline, regular_polygon, round_pillar, wall


def test_edges_are_numbered_shape_by_shape_with_neighbours() -> None:
    world = World([polyline([(0, 0), (1, 0), (1, 1)]), polygon([(3, 0), (4, 0), (4, 1)])])
    assert world.n_edges == 5
    np.testing.assert_array_equal(world.edge_shape, [0, 0, 1, 1, 1])
    # open polyline: no neighbour past its ends; closed polygon wraps around
    np.testing.assert_array_equal(world.next_edge, [1, -1, 3, 4, 2])
    np.testing.assert_array_equal(world.prev_edge, [-1, 0, 4, 2, 3])
    assert world.adjacent(np.array([0, 0, 1, 2, 4]), np.array([1, 2, 2, 4, 4])).tolist() == [
        True,
        False,
        False,
        True,
        False,
    ]


def test_shared_vertex_of_adjacent_edges() -> None:
    world = World([polygon([(0, 0), (2, 0), (2, 1), (0, 1)])])
    np.testing.assert_array_equal(world.shared_vertex([0, 1], [1, 0]), [[2, 0], [2, 0]])
    np.testing.assert_array_equal(world.shared_vertex([0], [3]), [[0, 0]])
    assert np.isnan(world.shared_vertex([0], [2])).all()


def test_straight_through_and_repeated_vertices_are_dropped() -> None:
    shape = polyline([(0, 0), (1, 0), (1, 0), (2, 0), (2, 1)])
    np.testing.assert_array_equal(shape.vertices, [(0, 0), (2, 0), (2, 1)])
    square = polygon([(0, 0), (1, 0), (2, 0), (2, 2), (0, 2), (0, 1)])
    assert len(square.vertices) == 4


def test_round_pillar_is_a_curved_surface() -> None:
    world = World([wall((5, -5), (5, 5)), round_pillar((2, 0), 0.3, sides=24)])
    assert world.n_edges == 25
    assert world.edge_is_line.tolist() == [True] + [False] * 24
    keys = world.surface_key(np.arange(world.n_edges))
    assert keys[0] == 0
    assert len(set(keys[1:].tolist())) == 1
    assert keys[1] != 0
    assert world.surface_key(np.array([-1]))[0] == -1


def test_box_and_regular_polygon_geometry() -> None:
    b = box((1, 2), 2.0, 1.0, angle=math.pi / 2)
    np.testing.assert_allclose(np.sort(b.vertices[:, 0]), [0.5, 0.5, 1.5, 1.5], atol=1e-12)
    np.testing.assert_allclose(np.sort(b.vertices[:, 1]), [1, 1, 3, 3], atol=1e-12)
    hexagon = regular_polygon((0, 0), 2.0, 6)
    np.testing.assert_allclose(np.hypot(*hexagon.vertices.T), 2.0)
    assert hexagon.is_line


@pytest.mark.parametrize(
    "make",
    [
        lambda: polyline([(0, 0)]),
        lambda: polygon([(0, 0), (1, 0)]),
        lambda: box((0, 0), 0.0, 1.0),
        lambda: polyline([(0, 0), (math.nan, 1)]),
    ],
)
def test_degenerate_shapes_are_rejected(make: Callable[[], Shape]) -> None:
    with pytest.raises(ValueError, match=r"vertices|box|sides|distinct"):
        make()


def test_vertices_are_read_only() -> None:
    shape = wall((0, 0), (1, 0))
    with pytest.raises(ValueError, match="read-only"):
        shape.vertices[0, 0] = 5.0
