"""2D worlds: polylines and polygons whose edges a simulated laser beam can hit.

A :class:`World` is an immutable collection of :class:`Shape` objects. Each shape is
a polyline (open) or a polygon (closed) with a ``kind`` tag (``"wall"``, ``"box"``,
``"round pillar"``, ...) and an ``is_line`` flag: shapes with ``is_line=False`` are
many-sided approximations of curved surfaces (round pillars), whose edges are not
true line segments and whose vertices are not true corners.

The world flattens its shapes into edge arrays (one row per edge) that the ray caster
and the ground truth use: ``edge_start``, ``edge_end``, ``edge_shape``,
``edge_is_line``, ``next_edge`` and ``prev_edge`` (the neighbouring edge of the same
shape sharing the end / start vertex, ``-1`` when there is none).
"""

from __future__ import annotations

import math
from collections.abc import Iterable, Sequence
from dataclasses import dataclass, field

import numpy as np

from scanlines.sim.raycast import RayHits, cast_rays

__all__ = [
    "Shape",
    "World",
    "box",
    "polygon",
    "polyline",
    "regular_polygon",
    "round_pillar",
    "wall",
]

# Turns smaller than this (|sin| of the angle between consecutive edges) are straight.
_COLLINEAR_SIN = 1e-9


def _readonly(values: np.ndarray) -> np.ndarray:
    values.setflags(write=False)
    return values


def _drop_redundant_vertices(vertices: np.ndarray, closed: bool) -> np.ndarray:
    """Remove repeated vertices and vertices where the outline runs straight on."""
    pts = vertices[np.r_[True, np.any(np.diff(vertices, axis=0) != 0, axis=1)]]
    if closed and len(pts) > 1 and np.array_equal(pts[0], pts[-1]):
        pts = pts[:-1]
    if len(pts) < 3:
        return pts
    d_in = pts - np.roll(pts, 1, axis=0)
    d_out = np.roll(pts, -1, axis=0) - pts
    cross = d_in[:, 0] * d_out[:, 1] - d_in[:, 1] * d_out[:, 0]
    dot = np.einsum("ij,ij->i", d_in, d_out)
    scale = np.hypot(*d_in.T) * np.hypot(*d_out.T)
    straight = (np.abs(cross) <= _COLLINEAR_SIN * scale) & (dot > 0)
    if not closed:
        straight[[0, -1]] = False
    return pts[~straight]


@dataclass(frozen=True, eq=False)
class Shape:
    """One polyline or polygon of a world.

    Parameters
    ----------
    vertices:
        ``K x 2`` vertex coordinates in metres, world frame. Repeated vertices and
        vertices where the outline runs straight on are dropped, so that every
        remaining vertex is a real corner.
    closed:
        ``True`` for a polygon (an edge joins the last vertex back to the first).
    is_line:
        ``False`` for a polygonal approximation of a curved surface: its edges are
        not true segments and its vertices are not true corners.
    kind:
        A free tag naming what the shape stands for (``"wall"``, ``"box"``, ...);
        the scene generator uses it to report which features a scene contains.
    returns:
        ``False`` for a surface that stops a beam but sends nothing back (a glass
        pane, as the simulator models it): a beam hitting it has no return, and what
        lies behind it is not seen.
    """

    vertices: np.ndarray
    closed: bool = False
    is_line: bool = True
    kind: str = "wall"
    returns: bool = True
    _edges: tuple[np.ndarray, np.ndarray] = field(init=False, repr=False)

    def __post_init__(self) -> None:
        pts = np.array(self.vertices, dtype=np.float64, copy=True)
        if pts.ndim != 2 or pts.shape[1] != 2 or not np.all(np.isfinite(pts)):
            raise ValueError(f"vertices must be a finite K x 2 array, got shape {pts.shape}")
        pts = _drop_redundant_vertices(pts, self.closed)
        minimum = 3 if self.closed else 2
        if len(pts) < minimum:
            raise ValueError(
                f"a {'polygon' if self.closed else 'polyline'} needs at least {minimum} "
                f"distinct vertices, got {len(pts)}"
            )
        object.__setattr__(self, "vertices", _readonly(pts))
        starts = pts if self.closed else pts[:-1]
        ends = np.roll(pts, -1, axis=0) if self.closed else pts[1:]
        object.__setattr__(self, "_edges", (_readonly(starts.copy()), _readonly(ends.copy())))

    @property
    def n_edges(self) -> int:
        """Number of edges (``K`` for a polygon, ``K - 1`` for a polyline)."""
        return len(self._edges[0])

    @property
    def edge_start(self) -> np.ndarray:
        """``n_edges x 2`` start vertex of each edge."""
        return self._edges[0]

    @property
    def edge_end(self) -> np.ndarray:
        """``n_edges x 2`` end vertex of each edge."""
        return self._edges[1]


def wall(
    start: Sequence[float], end: Sequence[float], kind: str = "wall", *, returns: bool = True
) -> Shape:
    """A single straight wall of zero thickness from ``start`` to ``end``.

    ``returns=False`` makes it a glass pane: it stops beams and returns nothing.
    """
    return Shape(np.array([start, end], dtype=np.float64), closed=False, kind=kind, returns=returns)


def polyline(
    points: Sequence[Sequence[float]] | np.ndarray, kind: str = "wall", *, is_line: bool = True
) -> Shape:
    """An open chain of straight walls through ``points``.

    ``is_line=False`` for a curved wall drawn as a fine polyline (an arc): its edges are
    not true segments and its vertices not true corners, like a round pillar's.
    """
    return Shape(np.asarray(points, dtype=np.float64), closed=False, is_line=is_line, kind=kind)


def polygon(points: Sequence[Sequence[float]] | np.ndarray, kind: str = "polygon") -> Shape:
    """A closed polygon through ``points`` (the last joins back to the first)."""
    return Shape(np.asarray(points, dtype=np.float64), closed=True, kind=kind)


def _rotation(angle: float) -> np.ndarray:
    c, s = math.cos(angle), math.sin(angle)
    return np.array([[c, -s], [s, c]])


def box(
    center: Sequence[float],
    width: float,
    height: float,
    angle: float = 0.0,
    kind: str = "box",
) -> Shape:
    """A rectangle of ``width`` (along its x axis) by ``height``, turned by ``angle``."""
    if width <= 0 or height <= 0:
        raise ValueError(f"box sides must be positive, got {width} x {height}")
    half = np.array([[-width, -height], [width, -height], [width, height], [-width, height]]) / 2
    pts = half @ _rotation(angle).T + np.asarray(center, dtype=np.float64)
    return Shape(pts, closed=True, kind=kind)


def regular_polygon(
    center: Sequence[float],
    radius: float,
    sides: int,
    angle: float = 0.0,
    *,
    is_line: bool = True,
    kind: str = "pillar",
) -> Shape:
    """A regular ``sides``-gon with circumradius ``radius``, first vertex at ``angle``."""
    if sides < 3 or radius <= 0:
        raise ValueError(f"need sides >= 3 and radius > 0, got {sides}, {radius}")
    phi = angle + 2.0 * math.pi * np.arange(sides) / sides
    pts = np.asarray(center, dtype=np.float64) + radius * np.column_stack(
        (np.cos(phi), np.sin(phi))
    )
    return Shape(pts, closed=True, is_line=is_line, kind=kind)


def round_pillar(
    center: Sequence[float], radius: float, sides: int = 32, kind: str = "round pillar"
) -> Shape:
    """A round pillar: a ``sides``-gon marked ``is_line=False`` (no true segments or corners)."""
    return regular_polygon(center, radius, sides, is_line=False, kind=kind)


class World:
    """An immutable set of shapes, flattened into edge arrays for ray casting.

    Parameters
    ----------
    shapes:
        The shapes; edge ids number the edges of ``shapes[0]`` first, then
        ``shapes[1]``, and so on, each in vertex order.

    Attributes
    ----------
    shapes:
        The shapes as a tuple.
    edge_start, edge_end:
        ``E x 2`` end points of every edge.
    edge_shape:
        Index of the shape each edge belongs to.
    edge_is_line:
        ``False`` for edges of curved shapes.
    edge_returns:
        ``False`` for edges of shapes that return nothing (glass).
    next_edge, prev_edge:
        Edge of the same shape that shares this edge's end (start) vertex, or ``-1``.
    """

    __slots__ = (
        "edge_end",
        "edge_is_line",
        "edge_returns",
        "edge_shape",
        "edge_start",
        "next_edge",
        "prev_edge",
        "shapes",
    )

    def __init__(self, shapes: Iterable[Shape]) -> None:
        self.shapes: tuple[Shape, ...] = tuple(shapes)
        for s in self.shapes:
            if not isinstance(s, Shape):
                raise TypeError(f"World takes Shape objects, got {type(s).__name__}")
        counts = [s.n_edges for s in self.shapes]
        offsets = np.concatenate(([0], np.cumsum(counts))).astype(np.intp)
        total = int(offsets[-1])
        starts = [s.edge_start for s in self.shapes] or [np.empty((0, 2))]
        ends = [s.edge_end for s in self.shapes] or [np.empty((0, 2))]
        self.edge_start = _readonly(np.concatenate(starts).reshape(total, 2))
        self.edge_end = _readonly(np.concatenate(ends).reshape(total, 2))
        self.edge_shape = _readonly(np.repeat(np.arange(len(self.shapes)), counts).astype(np.intp))
        self.edge_is_line = _readonly(
            np.repeat([s.is_line for s in self.shapes], counts).astype(bool).reshape(total)
        )
        self.edge_returns = _readonly(
            np.repeat([s.returns for s in self.shapes], counts).astype(bool).reshape(total)
        )
        nxt = np.full(total, -1, dtype=np.intp)
        prv = np.full(total, -1, dtype=np.intp)
        for shape, lo, count in zip(self.shapes, offsets[:-1], counts, strict=True):
            ids = np.arange(lo, lo + count)
            nxt[ids[:-1]] = ids[1:]
            prv[ids[1:]] = ids[:-1]
            if shape.closed:
                nxt[ids[-1]] = ids[0]
                prv[ids[0]] = ids[-1]
        self.next_edge = _readonly(nxt)
        self.prev_edge = _readonly(prv)

    def __len__(self) -> int:
        return len(self.shapes)

    def __repr__(self) -> str:
        return f"World({len(self.shapes)} shapes, {self.n_edges} edges)"

    @property
    def n_edges(self) -> int:
        """Total number of edges."""
        return len(self.edge_start)

    def adjacent(self, edge_a: np.ndarray, edge_b: np.ndarray) -> np.ndarray:
        """Element-wise: do the edges share a vertex as neighbours in one shape?

        ``-1`` (no edge) is adjacent to nothing; an edge is not adjacent to itself.
        """
        a = np.asarray(edge_a, dtype=np.intp)
        b = np.asarray(edge_b, dtype=np.intp)
        ok = (a >= 0) & (b >= 0) & (a != b)
        sa, sb = np.where(ok, a, 0), np.where(ok, b, 0)
        if self.n_edges == 0:
            return np.zeros(np.broadcast(a, b).shape, dtype=bool)
        return ok & ((self.next_edge[sa] == sb) | (self.prev_edge[sa] == sb))

    def shared_vertex(self, edge_a: np.ndarray, edge_b: np.ndarray) -> np.ndarray:
        """``K x 2`` vertex shared by each pair of adjacent edges (NaN where not adjacent)."""
        a = np.atleast_1d(np.asarray(edge_a, dtype=np.intp))
        b = np.atleast_1d(np.asarray(edge_b, dtype=np.intp))
        out = np.full((len(a), 2), np.nan)
        adjacent = self.adjacent(a, b)
        a_then_b = adjacent & (self.next_edge[np.where(adjacent, a, 0)] == b)
        b_then_a = adjacent & ~a_then_b
        out[a_then_b] = self.edge_end[a[a_then_b]]
        out[b_then_a] = self.edge_start[a[b_then_a]]
        return out

    def surface_key(self, edge: np.ndarray) -> np.ndarray:
        """One id per continuous surface: the edge id for line edges, ``E + shape`` for curves.

        Beams with the same key lie on one continuous surface; ``-1`` stays ``-1``.
        """
        e = np.asarray(edge, dtype=np.intp)
        if self.n_edges == 0:
            return np.full(e.shape, -1, dtype=np.intp)
        safe = np.where(e >= 0, e, 0)
        key = np.where(self.edge_is_line[safe], e, self.n_edges + self.edge_shape[safe])
        return np.where(e >= 0, key, -1)

    def cast(
        self, origin: Sequence[float], angles: np.ndarray, max_range: float = math.inf
    ) -> RayHits:
        """Cast rays from ``origin`` at world-frame ``angles`` (see :func:`cast_rays`)."""
        return cast_rays(origin, angles, self.edge_start, self.edge_end, max_range=max_range)

    def edge_normals(self) -> np.ndarray:
        """``E x 2`` unit normal of every edge (left of the edge direction)."""
        d = self.edge_end - self.edge_start
        length = np.hypot(d[:, 0], d[:, 1])
        return np.column_stack((-d[:, 1], d[:, 0])) / length[:, None]
