"""What scenes are built with: distances, inside tests, doors in an outline, the layout."""

from __future__ import annotations

import math
from collections.abc import Callable, Sequence
from dataclasses import dataclass, field
from typing import NamedTuple

import numpy as np

from scanlines.sim.sensors import SensorSpec
from scanlines.sim.world import Shape, polygon, polyline

# Clearances in metres: obstacle to wall, obstacle to obstacle, sensor to anything.
_WALL_GAP, _OBSTACLE_GAP, _SENSOR_GAP = 0.15, 0.1, 0.4
# --------------------------------------------------------------------------- geometry


def _segment_distance(p0: np.ndarray, p1: np.ndarray, q0: np.ndarray, q1: np.ndarray) -> np.ndarray:
    """Distance between segments ``p0 p1`` (rows) and ``q0 q1`` (columns), 0 if they cross."""
    p0, p1 = p0[:, None, :], p1[:, None, :]
    q0, q1 = q0[None, :, :], q1[None, :, :]

    def point_to_segment(x: np.ndarray, a: np.ndarray, b: np.ndarray) -> np.ndarray:
        ab = b - a
        t = np.clip(((x - a) * ab).sum(-1) / np.maximum((ab * ab).sum(-1), 1e-300), 0.0, 1.0)
        return np.hypot(*np.moveaxis(x - (a + t[..., None] * ab), -1, 0))

    def orient(a: np.ndarray, b: np.ndarray, c: np.ndarray) -> np.ndarray:
        return np.sign(
            (b[..., 0] - a[..., 0]) * (c[..., 1] - a[..., 1])
            - (b[..., 1] - a[..., 1]) * (c[..., 0] - a[..., 0])
        )

    cross = (orient(p0, p1, q0) * orient(p0, p1, q1) < 0) & (
        orient(q0, q1, p0) * orient(q0, q1, p1) < 0
    )
    dist = np.minimum.reduce(
        [
            point_to_segment(p0, q0, q1),
            point_to_segment(p1, q0, q1),
            point_to_segment(q0, p0, p1),
            point_to_segment(q1, p0, p1),
        ]
    )
    return np.where(cross, 0.0, dist)


def _shape_distance(a: Shape, b: Shape) -> float:
    return float(_segment_distance(a.edge_start, a.edge_end, b.edge_start, b.edge_end).min())


def _point_distance(point: np.ndarray, shape: Shape) -> float:
    p = np.asarray(point, dtype=np.float64).reshape(1, 2)
    return float(_segment_distance(p, p, shape.edge_start, shape.edge_end).min())


def _inside(point: np.ndarray, shape: Shape) -> bool:
    """Point in a closed shape (even-odd rule); never inside an open one."""
    if not shape.closed:
        return False
    x, y = point
    a, b = shape.edge_start, shape.edge_end
    straddle = (a[:, 1] > y) != (b[:, 1] > y)
    with np.errstate(divide="ignore", invalid="ignore"):
        x_cross = a[:, 0] + (y - a[:, 1]) * (b[:, 0] - a[:, 0]) / (b[:, 1] - a[:, 1])
    return bool(np.count_nonzero(straddle & (x_cross > x)) % 2)


def _inset_inside(point: np.ndarray, convex_ccw: np.ndarray, margin: float) -> bool:
    """Point at least ``margin`` inside a counter-clockwise convex polygon."""
    a = convex_ccw
    d = np.roll(a, -1, axis=0) - a
    normal = np.column_stack((-d[:, 1], d[:, 0])) / np.hypot(d[:, 0], d[:, 1])[:, None]
    return bool(np.all(((np.asarray(point) - a) * normal).sum(1) >= margin))


def _transform(shape: Shape, angle: float, offset: np.ndarray) -> Shape:
    c, s = math.cos(angle), math.sin(angle)
    pts = shape.vertices @ np.array([[c, s], [-s, c]]) + offset
    return Shape(
        pts, closed=shape.closed, is_line=shape.is_line, kind=shape.kind, returns=shape.returns
    )


class _Door(NamedTuple):
    """A door on edge ``edge`` between the fractions ``t0 < t1`` of its length.

    ``depth == 0``: an opening. ``depth > 0``: a closed door in a niche that deep.
    """

    edge: int
    t0: float
    t1: float
    depth: float = 0.0


def _outline_with_doors(vertices: np.ndarray, doors: Sequence[_Door], kind: str) -> list[Shape]:
    """The outline of a counter-clockwise polygon as polylines, doors cut or recessed.

    Doors on one edge must not overlap. Niches go outwards.
    """
    k = len(vertices)
    chains: list[np.ndarray] = []
    current = [vertices[0]]
    for e in range(k):
        a, b = vertices[e], vertices[(e + 1) % k]
        outward = np.array([b[1] - a[1], a[0] - b[0]]) / np.hypot(*(b - a))
        for door in sorted(d for d in doors if d.edge == e):
            p0 = a if door.t0 == 0.0 else a + door.t0 * (b - a)
            p1 = b if door.t1 == 1.0 else a + door.t1 * (b - a)
            if door.depth > 0:
                current.extend([p0, p0 + door.depth * outward, p1 + door.depth * outward, p1])
            else:
                chains.append(np.array([*current, p0]))
                current = [p1]
        current.append(b)
    if not chains:
        return [polygon(np.array(current[:-1]), kind=kind)]
    # the last chain ends at vertex 0, where the first one starts: join them
    chains[0] = np.vstack([np.array(current[:-1]), chains[0]])
    return [polyline(c, kind=kind) for c in chains]


@dataclass
class _Layout:
    """A scene under construction, in its local frame."""

    rng: np.random.Generator
    sensor: SensorSpec
    reach: float
    free: np.ndarray  # convex CCW polygon the sensor and obstacles must stay inside
    walls: list[Shape]
    pose: tuple[float, float, float] = (0.0, 0.0, 0.0)
    obstacles: list[Shape] = field(default_factory=list)

    def uniform(self, low: float, high: float) -> float:
        return float(self.rng.uniform(low, high))

    def bearing(self) -> float:
        """A bearing well inside the field of view (sensor frame)."""
        lo, hi = sorted((self.sensor.angle_min, self.sensor.angle_max))
        span = hi - lo
        return self.uniform(lo + 0.12 * span, hi - 0.12 * span)

    def fits(self, shape: Shape, wall_gap: float = _WALL_GAP) -> bool:
        """Inside the free area, clear of the walls, the other obstacles and the sensor."""
        centre = shape.vertices.mean(axis=0)
        sensor = np.array(self.pose[:2])
        return (
            _inset_inside(centre, self.free, 0.0)
            and all(_shape_distance(shape, w) >= wall_gap for w in self.walls)
            and all(_shape_distance(shape, o) >= _OBSTACLE_GAP for o in self.obstacles)
            and _point_distance(sensor, shape) >= _SENSOR_GAP
            and not _inside(sensor, shape)
        )

    def place(self, make: Callable[[], Shape], tries: int = 40) -> bool:
        """Draw shapes from ``make`` until one fits; keep it. False when none did."""
        for _ in range(tries):
            shape = make()
            if self.fits(shape):
                self.obstacles.append(shape)
                return True
        return False

    def place_group(self, make: Callable[[], list[Shape]], tries: int = 40) -> bool:
        """Like :meth:`place` for a group (chair legs, a person's legs): all or none.

        The group's members are spaced by construction; each must fit the rest.
        """
        for _ in range(tries):
            group = make()
            if all(self.fits(shape) for shape in group):
                self.obstacles.extend(group)
                return True
        return False

    def random_point(self, margin: float) -> np.ndarray:
        lo, hi = self.free.min(axis=0), self.free.max(axis=0)
        for _ in range(200):
            p = self.rng.uniform(lo, hi)
            if _inset_inside(p, self.free, margin):
                return p
        return self.free.mean(axis=0)

    def ray_point(self, bearing: float, distance: float) -> np.ndarray:
        x, y, theta = self.pose
        return np.array(
            [x + distance * math.cos(theta + bearing), y + distance * math.sin(theta + bearing)]
        )
