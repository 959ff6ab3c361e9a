"""The map's local frame, and the limit of the coordinates a map takes.

A line ``(rho, alpha)`` far from its frame's origin is ill-conditioned: 10^7 m away (a
UTM northing), ``rho`` is about 10^7 m and a thousandth of a degree of ``alpha`` moves the
line by 170 m, so the covariances of association swamp every gate. A map is therefore
built in a *local frame*: the world less an ``origin``, the first pose's position rounded
to the metre. Every stage (poses, association, fusion, the spatial index, alignment,
scoring) works in it; the writers add the origin back to the coordinates they write and
say where it is. A whole number of metres is subtracted exactly, so the same trajectory
shifted by any whole number of metres (up to the limit) gives the same local frame and
the same map.

The limits: a pose (the log's, a trajectory file's) with ``|x|`` or ``|y|`` above
:data:`MAX_COORDINATE` (10^9 m) is refused: no place on Earth needs more than 10^7 m, and
at 10^9 m a double still resolves 10^-7 m. So is a pose or a segment farther than
:data:`MAX_EXTENT` (10^5 m) from the map's origin in ``x`` or ``y``: even in the local
frame, a line that far is too ill-conditioned to fuse (a room 10^6 m from the origin
already maps one wall as two lines, 10^7 m away as twice as many lines as walls).
"""

from __future__ import annotations

import math
from collections.abc import Sequence
from typing import NamedTuple

import numpy as np

from scanlines.errors import ScanlinesError

__all__ = [
    "MAX_COORDINATE",
    "MAX_EXTENT",
    "LocalFrame",
    "MapError",
    "check_extent",
    "check_pose",
    "check_segments",
    "frame_at",
]

#: The largest ``|x|``, ``|y|`` (metres) of a pose in the world a map takes.
MAX_COORDINATE = 1e9
#: The largest ``|x|``, ``|y|`` (metres) of a pose or a segment in the map's local frame.
MAX_EXTENT = 1e5


class MapError(ScanlinesError, ValueError):
    """A map that cannot be built from what it was given (coordinates beyond
    :data:`MAX_COORDINATE`, a pose that is not finite)."""


class LocalFrame(NamedTuple):
    """The world less ``origin`` (``x0, y0``, whole metres): where a map is built."""

    x0: float = 0.0
    y0: float = 0.0

    @property
    def origin(self) -> tuple[float, float]:
        return (self.x0, self.y0)

    def pose(self, pose: Sequence[float]) -> tuple[float, float, float]:
        """A world pose in this frame."""
        x, y, theta = (float(v) for v in pose)
        return (x - self.x0, y - self.y0, theta)

    def world_pose(self, pose: Sequence[float]) -> tuple[float, float, float]:
        """A pose of this frame in the world."""
        x, y, theta = (float(v) for v in pose)
        return (x + self.x0, y + self.y0, theta)

    def world(self, points: np.ndarray) -> np.ndarray:
        """``... x 2`` points of this frame in the world."""
        return np.asarray(points, dtype=np.float64) + np.array([self.x0, self.y0])


def frame_at(pose: Sequence[float]) -> LocalFrame:
    """The local frame of a map whose first pose is ``pose``: its position rounded to
    the metre (``-0.0`` as ``0.0``)."""
    x, y = float(pose[0]), float(pose[1])
    return LocalFrame(float(round(x)) + 0.0, float(round(y)) + 0.0)


def check_pose(pose: Sequence[float], where: str) -> None:
    """Raise a :class:`MapError` naming ``where`` if the world ``pose`` is not finite or
    beyond :data:`MAX_COORDINATE`."""
    names = ("x", "y", "theta")
    for name, value in zip(names, pose, strict=True):
        if not math.isfinite(value):
            raise MapError(f"{where}: the pose's {name} is not finite ({value})")
    for name, value in zip(names[:2], pose[:2], strict=False):
        if abs(value) > MAX_COORDINATE:
            raise MapError(
                f"{where}: the pose's {name} = {value!r} m is beyond the map's limit "
                f"|{name}| <= 1e9 m"
            )


def check_extent(pose: Sequence[float], frame: LocalFrame, where: str) -> None:
    """Raise a :class:`MapError` naming ``where`` if the local ``pose`` is farther than
    :data:`MAX_EXTENT` from the map's origin."""
    far = max(abs(float(pose[0])), abs(float(pose[1])))
    if far > MAX_EXTENT:
        raise MapError(
            f"{where}: the pose is {far:.6g} m from the map's origin (the first pose, at "
            f"{frame.x0!r}, {frame.y0!r}), beyond the map's limit of 1e5 m"
        )


def check_segments(ends: np.ndarray, where: str) -> None:
    """Raise a :class:`MapError` naming ``where`` if a segment's ends (``... x 2``, local
    frame) are not finite or farther than :data:`MAX_EXTENT` from the map's origin."""
    ends = np.asarray(ends, dtype=np.float64)
    if not ends.size:
        return
    if not np.isfinite(ends).all():
        raise MapError(f"{where}: a segment's end is not finite")
    far = float(np.abs(ends).max())
    if far > MAX_EXTENT:
        raise MapError(
            f"{where}: a segment ends {far:.6g} m from the map's origin, beyond the map's "
            "limit of 1e5 m"
        )
