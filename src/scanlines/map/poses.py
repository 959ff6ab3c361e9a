"""Where each scan stood: the log's own poses, a TUM trajectory file, or scan registration."""

from __future__ import annotations

import math
from pathlib import Path

import numpy as np

from scanlines.errors import ScanlinesError
from scanlines.geometry.poses import IDENTITY, Pose, compose, relative_pose
from scanlines.geometry.registration import icp, line_target
from scanlines.map.frame import MapError, check_pose
from scanlines.scan import Scan

__all__ = [
    "LogPoses",
    "PoseError",
    "RegistrationOdometry",
    "TrajectoryPoses",
    "choose_poses",
    "read_tum",
]


class PoseError(ScanlinesError, ValueError):
    """A trajectory file that cannot be read, or a log whose scans carry no pose."""


class LogPoses:
    """The pose each scan carries (CARMEN ``FLASER``/``ROBOTLASER``: the laser's pose).

    A log cannot say whether its poses were corrected (by SLAM) or are raw odometry, which
    drifts: a map of raw odometry draws each wall several times, a fan of copies. ``note``
    says so, for the summary and the map's metadata."""

    name = "the log's poses"
    note = (
        "the map uses the log's poses as recorded, unaligned; a log cannot say whether they "
        "are corrected, and raw odometry drifts (each wall drawn several times): give "
        "corrected poses with --poses FILE (TUM)"
    )

    def __call__(self, index: int, scan: Scan) -> Pose | None:
        return scan.pose


class TrajectoryPoses:
    """Poses of a trajectory (``times``, ``N x 3`` poses), interpolated at each scan's time.

    A scan without a time, or more than ``tolerance`` seconds outside the trajectory, has
    no pose (it is counted, not mapped).
    """

    def __init__(self, times: np.ndarray, poses: np.ndarray, source: str, tolerance: float = 0.05):
        order = np.argsort(times, kind="stable")
        self.times = np.asarray(times, dtype=np.float64)[order]
        self.poses = np.asarray(poses, dtype=np.float64)[order]
        self.name = f"the trajectory {source}"
        self.tolerance = tolerance

    def __call__(self, index: int, scan: Scan) -> Pose | None:
        t = scan.timestamp
        times = self.times
        if t is None or not len(times) or t < times[0] - self.tolerance:
            return None
        if t > times[-1] + self.tolerance:
            return None
        k = int(np.clip(np.searchsorted(times, t), 1, max(len(times) - 1, 1)))
        if len(times) == 1:
            return tuple(float(v) for v in self.poses[0])  # type: ignore[return-value]
        t0, t1 = times[k - 1], times[k]
        w = 0.0 if t1 == t0 else float(np.clip((t - t0) / (t1 - t0), 0.0, 1.0))
        a, b = self.poses[k - 1], self.poses[k]
        turn = math.remainder(b[2] - a[2], 2 * math.pi)
        return (
            float(a[0] + w * (b[0] - a[0])),
            float(a[1] + w * (b[1] - a[1])),
            float(math.remainder(a[2] + w * turn, 2 * math.pi)),
        )


def read_tum(path: str | Path) -> TrajectoryPoses:
    """A TUM trajectory file (``timestamp tx ty tz qx qy qz qw`` per line, ``#`` comments;
    the format evo reads and writes): planar poses, yaw from the quaternion.

    Two lines with the same timestamp must give the same planar pose (within
    :data:`DUPLICATE_TOLERANCE`; a writer that repeats a pose is harmless, and the line is
    kept once); two different poses at one time are refused, naming both lines. So is a
    position beyond the map's limit (:data:`~scanlines.map.frame.MAX_COORDINATE`)."""
    path = Path(path)
    times, poses, numbers = [], [], []
    try:
        text = path.read_text(encoding="utf-8")
    except UnicodeDecodeError as error:
        raise PoseError(f"{path}: not a text file ({error.reason})") from None
    for number, line in enumerate(text.splitlines(), 1):
        fields = line.split()
        if not fields or fields[0].startswith("#"):
            continue
        if len(fields) != 8:
            raise PoseError(
                f"{path}: line {number}: a TUM pose has 8 fields "
                f"(timestamp tx ty tz qx qy qz qw), got {len(fields)}"
            )
        try:
            t, x, y, _, qx, qy, qz, qw = (float(v) for v in fields)
        except ValueError:
            raise PoseError(f"{path}: line {number}: a field is not a number: {line!r}") from None
        names = ("timestamp", "tx", "ty", "tz", "qx", "qy", "qz", "qw")
        for name, value in zip(names, fields, strict=True):
            if not math.isfinite(float(value)):
                raise PoseError(f"{path}: line {number}: field {name} is not finite: {value}")
        norm = math.sqrt(qx * qx + qy * qy + qz * qz + qw * qw)
        if norm < 1e-6:
            raise PoseError(f"{path}: line {number}: the quaternion (qx..qw) is zero")
        qx, qy, qz, qw = qx / norm, qy / norm, qz / norm, qw / norm
        try:
            check_pose((x, y, 0.0), f"{path}: line {number}")
        except MapError as error:
            raise PoseError(str(error)) from None
        times.append(t)
        poses.append((x, y, math.atan2(2 * (qw * qz + qx * qy), 1 - 2 * (qy * qy + qz * qz))))
        numbers.append(number)
    if not times:
        raise PoseError(f"{path}: no pose in the file")
    keep = _unique_times(np.array(times), np.array(poses), np.array(numbers), path)
    return TrajectoryPoses(np.array(times)[keep], np.array(poses)[keep], source=path.name)


#: Two poses of one timestamp closer than this (metres, radians) are the same pose.
DUPLICATE_TOLERANCE = 1e-9


def _unique_times(times: np.ndarray, poses: np.ndarray, numbers: np.ndarray, path: Path):
    """Indices of the poses to keep: the first of each timestamp; a :class:`PoseError`
    naming both lines where one timestamp has two different poses."""
    order = np.argsort(times, kind="stable")
    same = np.flatnonzero(times[order][1:] == times[order][:-1])
    for k in same:
        a, b = order[k], order[k + 1]
        step = np.abs(poses[b] - poses[a])
        step[2] = abs(math.remainder(poses[b, 2] - poses[a, 2], 2 * math.pi))
        if (step > DUPLICATE_TOLERANCE).any():
            first, second = sorted((int(numbers[a]), int(numbers[b])))
            raise PoseError(
                f"{path}: lines {first} and {second}: two different poses at the same "
                f"timestamp {float(times[a])!r}"
            )
    drop = np.zeros(len(times), dtype=bool)
    drop[order[same + 1]] = True
    return np.flatnonzero(~drop)


def write_tum(path: str | Path, stamped: list[tuple[float, Pose]]) -> None:
    """``stamped`` ``(time, pose)`` as a TUM trajectory file (z 0, yaw as a quaternion)."""
    lines = ["# timestamp tx ty tz qx qy qz qw"]
    for t, (x, y, theta) in stamped:
        lines.append(
            f"{t:.6f} {x:.6f} {y:.6f} 0 0 0 {math.sin(theta / 2):.9f} {math.cos(theta / 2):.9f}"
        )
    Path(path).write_text("\n".join(lines) + "\n", encoding="utf-8")


class RegistrationOdometry:
    """Poses chained from scan-to-scan registration (the point-to-line ICP of
    :mod:`scanlines.geometry.registration`), starting at the origin. The relative pose of
    the log's own odometry, where scans carry one, is the first guess."""

    name = "scan registration (scan to scan ICP) as odometry"

    def __init__(self) -> None:
        self._previous: Scan | None = None
        self._pose: Pose = IDENTITY

    def __call__(self, index: int, scan: Scan) -> Pose | None:
        previous, self._previous = self._previous, scan
        if previous is None:
            return self._pose
        guess = IDENTITY
        if previous.pose is not None and scan.pose is not None:
            guess = relative_pose(previous.pose, scan.pose)
        fit = icp(scan.points[scan.valid], line_target(previous), guess)
        step = fit.pose if fit.inlier_fraction >= 0.3 else guess
        self._pose = compose(self._pose, step)
        return self._pose


def choose_poses(first_scans, trajectory: str | Path | None = None):
    """The pose source of a map: the ``trajectory`` file (TUM) where one is given, else the
    log's own poses where its first scans (an iterable of :class:`Scan`, looked at up to
    the first 10) carry them, else scan registration as odometry."""
    if trajectory is not None:
        return read_tum(trajectory)
    for k, scan in enumerate(first_scans):
        if scan.pose is not None:
            return LogPoses()
        if k >= 9:
            break
    return RegistrationOdometry()
