"""Planar poses: ``(x, y, theta)`` maps a point ``p`` of its frame to ``R(theta) p + (x, y)``.

The algebra the readers (a laser's mounting on its robot), the writers (features in the
world frame) and the evaluation (scan-to-scan registration) share.
"""

from __future__ import annotations

import math
from collections.abc import Sequence

__all__ = ["IDENTITY", "Pose", "compose", "invert", "relative_pose"]

Pose = tuple[float, float, float]
"""``(x, y, theta)``: maps a point ``p`` of its frame to ``R(theta) p + (x, y)``."""

IDENTITY: Pose = (0.0, 0.0, 0.0)


def _wrap(angle: float) -> float:
    return float(math.remainder(angle, 2.0 * math.pi))


def compose(a: Sequence[float], b: Sequence[float]) -> Pose:
    """``a o b``: the pose that maps a point by ``b``, then by ``a``."""
    ax, ay, at = (float(v) for v in a)
    bx, by, bt = (float(v) for v in b)
    c, s = math.cos(at), math.sin(at)
    return (ax + c * bx - s * by, ay + s * bx + c * by, _wrap(at + bt))


def invert(a: Sequence[float]) -> Pose:
    """The inverse of pose ``a``."""
    x, y, t = (float(v) for v in a)
    c, s = math.cos(t), math.sin(t)
    return (-(c * x + s * y), -(-s * x + c * y), _wrap(-t))


def relative_pose(pose_i: Sequence[float], pose_j: Sequence[float]) -> Pose:
    """Frame ``j`` in frame ``i``: ``inverse(pose_i) o pose_j`` (both in one world frame)."""
    return compose(invert(pose_i), pose_j)
