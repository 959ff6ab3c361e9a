"""The input type: one 2D range scan."""

from __future__ import annotations

import math
from collections.abc import Sequence
from typing import Any

import numpy as np

from scanlines.errors import ScanError, describe

__all__ = ["Scan", "as_array", "is_full_circle", "valid_returns"]

FloatArray = np.ndarray
#: Largest magnitude of ``angle_min``, radians (two turns either way).
MAX_ANGLE_MIN = 4.0 * math.pi
#: Largest angle from the first beam to the last (one turn, and a little for rounding).
MAX_SPAN = 2.0 * math.pi * (1.0 + 1e-4)


def _as_float(name: str, value: Any, *, finite: bool = False, allow_inf: bool = True) -> float:
    if isinstance(value, float):  # float and np.float64, checked first: the common case
        out = float(value)
    elif isinstance(value, bool) or not isinstance(value, (int, np.integer, np.floating)):
        raise ScanError(f"{name} must be a real number, got {value!r}")
    else:
        out = float(value)
    if (
        math.isnan(out)
        or (finite and not math.isfinite(out))
        or (not allow_inf and math.isinf(out))
    ):
        raise ScanError(f"{name} must be finite, got {value!r}")
    return out


def as_array(values: Any, name: str) -> np.ndarray:
    """``np.asarray(values)``, a ragged or otherwise unusable input being a
    :class:`ScanError` naming ``name``."""
    try:
        return np.asarray(values)
    except (ValueError, TypeError) as exc:
        raise ScanError(
            f"{name} must be an array of numbers, got {_preview(values)} ({describe(exc)})"
        ) from None


def _as_vector(name: str, values: Any, *, length: int | None = None) -> FloatArray:
    arr = as_array(values, name)
    if arr.dtype.kind not in "fiu":  # not bool ("b") either
        raise ScanError(
            f"{name} must hold real numbers, got dtype {arr.dtype} ({_preview(values)})"
        )
    if arr.ndim != 1:
        raise ScanError(f"{name} must be 1-D, got shape {arr.shape}")
    if length is not None and arr.shape[0] != length:
        raise ScanError(f"{name} has {arr.shape[0]} values but ranges has {length}")
    out = np.array(arr, dtype=np.float64, copy=True)
    out.setflags(write=False)
    return out


def _stamp_seconds(stamp: Any) -> float:
    """A ROS time in seconds: ROS 2 and rosbags (``sec``, ``nanosec``), ROS 1 (``secs``,
    ``nsecs``)."""
    if hasattr(stamp, "sec"):
        return stamp.sec + stamp.nanosec * 1e-9
    try:
        return stamp.secs + stamp.nsecs * 1e-9
    except AttributeError:
        raise ScanError(f"header.stamp is not a ROS time: {stamp!r}") from None


def _preview(values: Any) -> str:
    text = repr(values)
    return text if len(text) <= 60 else text[:57] + "..."


def valid_returns(ranges: np.ndarray, range_min: float, range_max: float) -> np.ndarray:
    """Mask of beams with a return: finite, > 0 and within ``[range_min, range_max]``.

    Works on one scan or a stack of scans (any shape).
    """
    # Comparisons with NaN are False (and quiet), so two comparisons cover every rule.
    lower = (ranges > 0.0) if range_min <= 0.0 else (ranges >= range_min)
    upper = (ranges < math.inf) if range_max == math.inf else (ranges <= range_max)
    return np.logical_and(lower, upper, out=lower)


def is_full_circle(n_beams: int, angle_increment: float) -> bool:
    """True when ``n_beams`` beams at ``angle_increment`` close the circle.

    The rule is ``N |dtheta| >= 2 pi - |dtheta| / 2``: the gap between the last
    and first beam is no wider than one and a half increments.
    """
    step = abs(angle_increment)
    return n_beams >= 3 and n_beams * step >= 2.0 * math.pi - step / 2.0


class Scan:
    """One 2D laser scan, immutable.

    Parameters
    ----------
    ranges:
        1-D ranges in metres, one per beam, in beam order. Beams with no return
        (0, negative, ``inf``, ``NaN``, or outside ``[range_min, range_max]``) are
        normal data: they are kept and reported as not :attr:`valid`.
    angle_min:
        Bearing of beam 0 in radians, in the sensor frame (REP 103: x forward,
        y left, counter-clockwise positive).
    angle_increment:
        Bearing step between beams in radians; negative for clockwise scanners.
    range_min, range_max:
        The sensor's valid range interval in metres.
    timestamp:
        Seconds, or ``None`` when the log has none. Kept as given.
    intensities:
        Optional 1-D array of the same length as ``ranges``.
    pose:
        The sensor's ``(x, y, theta)`` in the log's world frame, when known.

    Raises
    ------
    ScanError
        When a field has the wrong shape or type, or the increment is zero or
        not finite. The message names the field and the bad value.

    Notes
    -----
    The arrays are copied on construction and made read-only, so neither the
    caller's arrays nor the scan can change afterwards.
    """

    __slots__ = (
        "_angles",
        "_points",
        "_valid",
        "angle_increment",
        "angle_min",
        "intensities",
        "pose",
        "range_max",
        "range_min",
        "ranges",
        "timestamp",
    )

    ranges: FloatArray
    angle_min: float
    angle_increment: float
    range_min: float
    range_max: float
    timestamp: float | None
    intensities: FloatArray | None
    pose: tuple[float, float, float] | None

    def __init__(
        self,
        ranges: Sequence[float] | FloatArray,
        angle_min: float,
        angle_increment: float,
        range_min: float = 0.0,
        range_max: float = math.inf,
        timestamp: float | None = None,
        intensities: Sequence[float] | FloatArray | None = None,
        pose: Sequence[float] | None = None,
    ) -> None:
        set_ = object.__setattr__
        ranges_arr = _as_vector("ranges", ranges)
        set_(self, "ranges", ranges_arr)
        first_bearing = _as_float("angle_min", angle_min, finite=True)
        if abs(first_bearing) > MAX_ANGLE_MIN:
            raise ScanError(
                f"angle_min must be within [-4 pi, 4 pi] radians, got {angle_min!r} "
                "(degrees given as radians?)"
            )
        set_(self, "angle_min", first_bearing)
        increment = _as_float("angle_increment", angle_increment, finite=True)
        if increment == 0.0:
            raise ScanError("angle_increment must be non-zero, got 0.0")
        if abs(increment) < 1e-30 and np.float32(increment) == 0.0:  # (no cast of a huge one)
            raise ScanError(
                f"angle_increment {increment!r} rad rounds to 0 in float32, the precision "
                "features are computed in (and LaserScan carries): beams would coincide"
            )
        span = abs(increment) * max(ranges_arr.shape[0] - 1, 1)
        if span > MAX_SPAN:
            raise ScanError(
                f"angle_increment {increment!r} rad over {ranges_arr.shape[0]} beams spans "
                f"{span:.6g} rad, more than one turn (2 pi): beams would overlap"
            )
        set_(self, "angle_increment", increment)
        rmin = _as_float("range_min", range_min)
        rmax = _as_float("range_max", range_max)
        if rmin > rmax:
            raise ScanError(f"range_min ({rmin}) is larger than range_max ({rmax})")
        set_(self, "range_min", rmin)
        set_(self, "range_max", rmax)
        stamp = None if timestamp is None else _as_float("timestamp", timestamp)
        set_(self, "timestamp", stamp)
        set_(
            self,
            "intensities",
            None
            if intensities is None
            else _as_vector("intensities", intensities, length=ranges_arr.shape[0]),
        )
        set_(self, "pose", None if pose is None else _as_pose(pose))
        set_(self, "_angles", None)
        set_(self, "_points", None)
        set_(self, "_valid", None)

    def __setattr__(self, name: str, value: object) -> None:
        raise AttributeError(f"Scan is immutable: cannot set {name!r}")

    def __len__(self) -> int:
        return int(self.ranges.shape[0])

    @classmethod
    def from_laserscan(
        cls,
        message: Any,
        *,
        fallback_time: float | None = None,
        pose: Sequence[float] | None = None,
    ) -> Scan:
        """A scan from a ``sensor_msgs/LaserScan`` message object: rosbags', rclpy's
        (``stamp.sec``, ``stamp.nanosec``) or rospy's (``stamp.secs``, ``stamp.nsecs``).

        Ranges and intensities are taken as they are (REP 117's ``-inf``, ``NaN`` and
        ``+inf`` are beams without a return); intensities are kept when there is one per
        beam. The timestamp is the header stamp in seconds, or ``fallback_time`` when the
        stamp is zero (a driver that does not stamp).

        Raises
        ------
        ScanError
            When ``message`` lacks a LaserScan field or holds invalid values.
        """
        try:
            with np.errstate(invalid="ignore"):  # a signaling NaN is still a NaN
                ranges = np.asarray(message.ranges, dtype=np.float64)
                intensities = np.asarray(message.intensities, dtype=np.float64)
            geometry = (message.angle_min, message.angle_increment)
            limits = (message.range_min, message.range_max)
            stamp = message.header.stamp
        except AttributeError as exc:
            raise ScanError(
                f"not a sensor_msgs/LaserScan message ({type(message).__name__} has no "
                f"field {exc.name!r})"
            ) from None
        except (TypeError, ValueError) as exc:
            raise ScanError(f"ranges or intensities are not numbers ({describe(exc)})") from None
        seconds = _stamp_seconds(stamp)
        return cls(
            ranges,
            *(float(value) for value in geometry),
            *(float(value) for value in limits),
            timestamp=seconds if seconds else fallback_time,
            intensities=intensities if intensities.shape == ranges.shape else None,
            pose=pose,
        )

    def __reduce__(self) -> tuple:
        # Pickle by the constructor's arguments (for multiprocessing); caches are rebuilt.
        return (
            Scan,
            (
                self.ranges,
                self.angle_min,
                self.angle_increment,
                self.range_min,
                self.range_max,
                self.timestamp,
                self.intensities,
                self.pose,
            ),
        )

    def __repr__(self) -> str:
        return (
            f"Scan({len(self)} beams, angle_min={self.angle_min:.6g}, "
            f"angle_increment={self.angle_increment:.6g}, valid={int(self.valid.sum())}, "
            f"timestamp={self.timestamp!r})"
        )

    @property
    def angles(self) -> FloatArray:
        """Bearing of every beam in radians (read-only)."""
        if self._angles is None:
            angles = self.angle_min + self.angle_increment * np.arange(len(self), dtype=np.float64)
            angles.setflags(write=False)
            object.__setattr__(self, "_angles", angles)
        return self._angles  # type: ignore[return-value]

    @property
    def valid(self) -> np.ndarray:
        """Boolean mask of beams with a return: finite, > 0 and within the range limits."""
        if self._valid is None:
            mask = valid_returns(self.ranges, self.range_min, self.range_max)
            mask.setflags(write=False)
            object.__setattr__(self, "_valid", mask)
        return self._valid  # type: ignore[return-value]

    @property
    def points(self) -> FloatArray:
        """N x 2 Cartesian points in the sensor frame; NaN rows for beams with no return."""
        if self._points is None:
            r = np.where(self.valid, self.ranges, np.nan)
            pts = np.column_stack((r * np.cos(self.angles), r * np.sin(self.angles)))
            pts.setflags(write=False)
            object.__setattr__(self, "_points", pts)
        return self._points  # type: ignore[return-value]

    @property
    def full_circle(self) -> bool:
        """True when the beams cover the whole circle (see :func:`is_full_circle`)."""
        return is_full_circle(len(self), self.angle_increment)


def _as_pose(pose: Sequence[float]) -> tuple[float, float, float]:
    try:
        values = tuple(pose)
    except TypeError:
        raise ScanError(f"pose must be (x, y, theta), got {pose!r}") from None
    if len(values) != 3:
        raise ScanError(f"pose must be (x, y, theta), got {len(values)} values: {pose!r}")
    checked = [_as_float(name, v, finite=True) for name, v in zip(_POSE_NAMES, values, strict=True)]
    return tuple(checked)  # type: ignore[return-value]


_POSE_NAMES = ("pose[0]", "pose[1]", "pose[2]")
