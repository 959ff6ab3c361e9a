"""Planar poses from ROS 2 messages: odometry kept by stamp and interpolated, static frames."""

from __future__ import annotations

import bisect
import math

from scanlines.geometry.poses import Pose, compose

__all__ = [
    "OdometryBuffer",
    "StaticFrames",
    "pose_of",
    "seconds_of",
    "strip_frame",
    "yaw_of",
]

#: Seconds of odometry kept before the newest sample.
KEEP = 10.0


def seconds_of(stamp) -> float:
    """A ``builtin_interfaces/Time`` as seconds."""
    return stamp.sec + stamp.nanosec * 1e-9


def yaw_of(q) -> float:
    """The rotation about z of a quaternion (``x, y, z, w``)."""
    return math.atan2(2.0 * (q.w * q.z + q.x * q.y), 1.0 - 2.0 * (q.y * q.y + q.z * q.z))


def pose_of(position, orientation) -> Pose:
    """The planar pose of a position (``x, y``) and a quaternion."""
    return (float(position.x), float(position.y), yaw_of(orientation))


def strip_frame(name: str) -> str:
    """A frame's name as tf2 compares them: without a leading ``/``."""
    return name.lstrip("/")


def _between(a: Pose, b: Pose, w: float) -> Pose:
    """``a`` moved a fraction ``w`` of the way to ``b`` (the heading the short way)."""
    turn = math.remainder(b[2] - a[2], math.tau)
    return (
        a[0] + w * (b[0] - a[0]),
        a[1] + w * (b[1] - a[1]),
        math.remainder(a[2] + w * turn, math.tau),
    )


class OdometryBuffer:
    """Stamped odometry poses (seconds, ``x, y, yaw``) kept in stamp order for
    :data:`KEEP` seconds, interpolated at a scan's stamp as tf2 does (linearly; the heading
    the short way). A sample of a stamp already held replaces it."""

    def __init__(self, keep: float = KEEP) -> None:
        self.keep = keep
        self.times: list[float] = []
        self.poses: list[Pose] = []

    def add(self, t: float, pose: Pose) -> None:
        k = bisect.bisect_left(self.times, t)
        if k < len(self.times) and self.times[k] == t:
            self.poses[k] = pose
        else:
            self.times.insert(k, t)
            self.poses.insert(k, pose)
        cut = bisect.bisect_left(self.times, self.times[-1] - self.keep)
        if cut:
            del self.times[:cut], self.poses[:cut]

    @property
    def newest(self) -> float | None:
        return self.times[-1] if self.times else None

    def at(self, t: float) -> Pose | None:
        """The pose at ``t``: a sample of that stamp, else interpolated between the two
        around it; ``None`` outside the samples held."""
        times = self.times
        if not times or t < times[0] or t > times[-1]:
            return None
        k = bisect.bisect_left(times, t)
        if times[k] == t:
            return self.poses[k]
        t0, t1 = times[k - 1], times[k]
        return _between(self.poses[k - 1], self.poses[k], (t - t0) / (t1 - t0))


class StaticFrames:
    """The planar transforms of ``/tf_static`` by child frame: ``(parent, pose)``."""

    def __init__(self) -> None:
        self.parents: dict[str, tuple[str, Pose]] = {}

    def add(self, parent: str, child: str, pose: Pose) -> None:
        self.parents[strip_frame(child)] = (strip_frame(parent), pose)

    def lookup(self, parent: str, child: str) -> Pose | None:
        """The pose of ``child`` in ``parent`` through the static transforms (up the
        tree from ``child``), or ``None`` when they do not connect them."""
        parent, frame = strip_frame(parent), strip_frame(child)
        chain: list[Pose] = []
        seen: set[str] = set()
        while frame != parent:
            if frame in seen or frame not in self.parents:
                return None
            seen.add(frame)
            frame, pose = self.parents[frame]
            chain.append(pose)
        pose: Pose = (0.0, 0.0, 0.0)
        for step in reversed(chain):
            pose = compose(pose, step)
        return pose
