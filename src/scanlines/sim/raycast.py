"""Vectorised 2D ray casting against line segments.

Every beam is tested against every edge at once (numpy broadcasting), in chunks of
beams so that memory stays bounded for large worlds. There is no per-beam Python loop.

A ray ``p + t d`` (``t > 0``, ``d`` a unit vector) meets the segment
``a + s (b - a)`` (``0 <= s <= 1``) where

    t = ((a - p) x e) / (d x e),    s = ((a - p) x d) / (d x e),    e = b - a,

with ``x`` the 2D cross product. Rays parallel to a segment (``d x e = 0``) never hit
it. The nearest hit over all edges wins.
"""

from __future__ import annotations

import math
from collections.abc import Sequence
from dataclasses import dataclass

import numpy as np

__all__ = ["RayHits", "cast_rays"]

# Segment parameter slack, so that a beam through a shared vertex cannot slip between
# the two edges meeting there because of rounding.
_S_SLACK = 1e-9
# Hits closer than this to the ray origin are ignored (the origin lies on the edge).
_T_MIN = 1e-9
# Beam-edge pairs evaluated per chunk.
_CHUNK_PAIRS = 1 << 20


@dataclass(frozen=True, eq=False)
class RayHits:
    """Nearest hit of each ray.

    Attributes
    ----------
    ranges:
        Distance from the origin to the hit, ``inf`` when the ray hits nothing
        within ``max_range``.
    edge:
        Index of the edge hit, ``-1`` when none.
    """

    ranges: np.ndarray
    edge: np.ndarray


def _cross(ax: np.ndarray, ay: np.ndarray, bx: np.ndarray, by: np.ndarray) -> np.ndarray:
    return ax * by - ay * bx


def _cast_chunk(
    dx: np.ndarray, dy: np.ndarray, rel_a: np.ndarray, e: np.ndarray
) -> tuple[np.ndarray, np.ndarray]:
    """Nearest hit of rays with unit directions ``(dx, dy)`` (origin moved to 0)."""
    dx, dy = dx[:, None], dy[:, None]
    ax, ay = rel_a[None, :, 0], rel_a[None, :, 1]
    ex, ey = e[None, :, 0], e[None, :, 1]
    denom = _cross(dx, dy, ex, ey)
    with np.errstate(divide="ignore", invalid="ignore"):
        t = _cross(ax, ay, ex, ey) / denom
        s = _cross(ax, ay, dx, dy) / denom
    hit = (denom != 0.0) & (t > _T_MIN) & (s >= -_S_SLACK) & (s <= 1.0 + _S_SLACK)
    t = np.where(hit, t, np.inf)
    nearest = np.argmin(t, axis=1)
    ranges = t[np.arange(len(t)), nearest]
    return ranges, np.where(np.isfinite(ranges), nearest, -1)


def cast_rays(
    origin: Sequence[float] | np.ndarray,
    angles: Sequence[float] | np.ndarray,
    edge_start: np.ndarray,
    edge_end: np.ndarray,
    *,
    max_range: float = math.inf,
) -> RayHits:
    """Cast rays from one origin and return the nearest edge each ray hits.

    Parameters
    ----------
    origin:
        ``(x, y)`` of the ray origin.
    angles:
        Ray bearings in radians, in the same frame as the edges.
    edge_start, edge_end:
        ``E x 2`` end points of the edges.
    max_range:
        Hits farther than this count as no hit.

    Returns
    -------
    RayHits
        ``ranges`` (``inf`` for no hit) and ``edge`` (``-1`` for no hit). When a ray
        passes exactly through a vertex shared by two edges at the same distance, the
        lower edge id is reported.

    Examples
    --------
    >>> hits = cast_rays((0, 0), [0.0], np.array([[2.0, -1.0]]), np.array([[2.0, 1.0]]))
    >>> float(hits.ranges[0]), int(hits.edge[0])
    (2.0, 0)
    """
    p = np.asarray(origin, dtype=np.float64).reshape(2)
    theta = np.atleast_1d(np.asarray(angles, dtype=np.float64))
    a = np.asarray(edge_start, dtype=np.float64).reshape(-1, 2)
    b = np.asarray(edge_end, dtype=np.float64).reshape(-1, 2)
    n = len(theta)
    ranges = np.full(n, np.inf)
    edge = np.full(n, -1, dtype=np.intp)
    if len(a) == 0 or n == 0:
        return RayHits(ranges, edge)
    rel_a, e = a - p, b - a
    dx, dy = np.cos(theta), np.sin(theta)
    step = max(1, _CHUNK_PAIRS // len(a))
    for lo in range(0, n, step):
        hi = min(n, lo + step)
        ranges[lo:hi], edge[lo:hi] = _cast_chunk(dx[lo:hi], dy[lo:hi], rel_a, e)
    too_far = ranges > max_range
    ranges[too_far] = np.inf
    edge[too_far] = -1
    return RayHits(ranges, edge)
