"""Scans to and from ``sensor_msgs/LaserScan``, an extraction as the node's messages, and a
log's pose as ``/tf``."""

from __future__ import annotations

import math

import numpy as np

from scanlines.errors import ScanError
from scanlines.extraction import END_KINDS, END_X, END_Y, START_X, START_Y, Extraction
from scanlines.ros2 import messages as msg
from scanlines.scan import Scan

__all__ = [
    "beam_count_error",
    "features",
    "laser_scan",
    "line_marker",
    "line_segments",
    "markers",
    "scan_of",
    "stamp_of",
    "stamp_problem",
    "transform",
]

_COLORS = {
    "segments": (0.1, 0.8, 0.2, 1.0),
    "breakpoints": (0.9, 0.1, 0.1, 1.0),
    "corners": (0.1, 0.3, 1.0, 1.0),
}
_SCALES = {"segments": 0.03, "breakpoints": 0.08, "corners": 0.12}
#: laser_line_extraction's marker on ``line_markers``: its namespace, line width and colour.
LINE_MARKER_NS = "line_extraction"
LINE_MARKER_WIDTH = 0.1
LINE_MARKER_COLOR = (1.0, 0.0, 0.0, 1.0)
#: Largest ``builtin_interfaces/msg/Time.sec`` (an int32).
MAX_STAMP_SECONDS = 2**31 - 1


def _float32(values: np.ndarray) -> np.ndarray:
    """``values`` as the float32 a message carries: one beyond float32's range is an
    infinity (a covariance of 1e39 from ranges near float32's largest, say), as the cast
    makes it, without numpy's overflow warning on the node's stderr."""
    with np.errstate(over="ignore"):
        return values.astype(np.float32)


def stamp_problem(seconds: float) -> str | None:
    """Why ``seconds`` cannot be a ROS 2 time (``builtin_interfaces/Time``: an int32 of
    seconds, from 0 on), or ``None``."""
    if not math.isfinite(seconds) or not 0 <= seconds <= MAX_STAMP_SECONDS:
        return f"{seconds!r} s is not a ROS 2 time (0 .. 2**31 - 1 s)"
    return None


def stamp_of(seconds: float) -> msg.Time:
    """A ROS time of ``seconds`` (0 for none), nanoseconds rounded."""
    problem = stamp_problem(seconds)
    if problem is not None:
        raise ScanError(f"timestamp {problem}")
    sec, nanosec = divmod(round(seconds * 1e9), 1_000_000_000)
    return msg.Time(sec=int(sec), nanosec=int(nanosec))


def laser_scan(scan: Scan, frame_id: str, scan_time: float = 0.0) -> msg.LaserScan:
    """``scan`` as a LaserScan in frame ``frame_id``, stamped with its timestamp."""
    n = len(scan)
    intensities = [] if scan.intensities is None else _float32(scan.intensities).tolist()
    return msg.LaserScan(
        header=msg.Header(stamp=stamp_of(scan.timestamp or 0.0), frame_id=frame_id),
        angle_min=scan.angle_min,
        angle_max=scan.angle_min + (n - 1) * scan.angle_increment,
        angle_increment=scan.angle_increment,
        scan_time=scan_time,
        range_min=scan.range_min,
        range_max=min(scan.range_max, float(np.finfo(np.float32).max)),
        ranges=_float32(scan.ranges).tolist(),
        intensities=intensities,
    )


def beam_count_error(message: msg.LaserScan) -> str | None:
    """Why the ranges and the angles of ``message`` disagree, or ``None``: ROS 2 drivers give
    ``angle_max = angle_min + (n - 1) angle_increment``; one beam either way is tolerated."""
    step = message.angle_increment
    if not math.isfinite(step) or step == 0.0:
        return f"angle_increment must be finite and non-zero, got {step!r}"
    beams = (message.angle_max - message.angle_min) / step + 1.0
    if not math.isfinite(beams) or abs(beams - len(message.ranges)) > 1.5:
        return (
            f"ranges has {len(message.ranges)} values but angle_min {message.angle_min!r} to "
            f"angle_max {message.angle_max!r} by {step!r} makes {beams:.6g} beams"
        )
    return None


def scan_of(message: msg.LaserScan) -> Scan:
    """The scan of a LaserScan message; :class:`ScanError` when it is malformed."""
    problem = beam_count_error(message)
    if problem is not None:
        raise ScanError(problem)
    return Scan.from_laserscan(message)


def line_segments(extraction: Extraction, header: msg.Header) -> msg.LineSegmentList:
    """laser_line_extraction's message of the segments (radius, angle, covariance, ends)."""
    lines = _float32(extraction.lines)
    covariances = _float32(extraction.covariances).reshape(-1, 4).tolist()
    return msg.LineSegmentList(
        header=header,
        line_segments=[
            msg.LineSegment(
                radius=row[0],
                angle=row[1],
                covariance=cov,
                start=[row[START_X], row[START_Y]],
                end=[row[END_X], row[END_Y]],
            )
            for row, cov in zip(lines.tolist(), covariances, strict=True)
        ],
    )


def features(extraction: Extraction, scan: Scan, header: msg.Header) -> msg.ScanFeatures:
    """The full result as the project's ``scanlines/msg/ScanFeatures`` (the breakpoints'
    and corners' returns as points of ``scan``)."""
    lines = _float32(extraction.lines).tolist()
    covariances = _float32(extraction.covariances).reshape(-1, 4).tolist()
    segments = [
        msg.Segment(
            first=int(a),
            last=int(b),
            n_points=int(n),
            radius=row[0],
            angle=row[1],
            covariance=cov,
            start=[row[START_X], row[START_Y]],
            end=[row[END_X], row[END_Y]],
            rms=row[6],
            start_kind=int(kinds[0]),
            end_kind=int(kinds[1]),
        )
        for a, b, n, row, cov, kinds in zip(
            extraction.first.tolist(),
            extraction.last.tolist(),
            extraction.n_points.tolist(),
            lines,
            covariances,
            extraction.end_kinds.tolist(),
            strict=True,
        )
    ]
    return msg.ScanFeatures(
        header=header,
        method=extraction.method,
        segments=segments,
        breakpoints=extraction.breakpoints.tolist(),
        corners=extraction.corners.tolist(),
        outliers=extraction.outliers.tolist(),
        breakpoint_points=_points(scan, extraction.breakpoints),
        corner_points=_points(scan, extraction.corners),
    )


def _points(scan: Scan, beams) -> list[msg.Point]:
    return [msg.Point(x, y, 0.0) for x, y in scan.points[beams].tolist()]


assert len(END_KINDS) < 256  # end kinds travel as uint8


def _segment_ends(extraction: Extraction) -> list[msg.Point]:
    ends = extraction.lines[:, [START_X, START_Y, END_X, END_Y]].reshape(-1, 2)
    return [msg.Point(x, y, 0.0) for x, y in ends.tolist()]


def line_marker(extraction: Extraction, header: msg.Header) -> msg.Marker:
    """The segments as laser_line_extraction draws them on ``line_markers``: one
    ``LINE_LIST`` marker (namespace ``line_extraction``, id 0, 0.1 m wide, red), each
    segment's start and end, which replaces the previous scan's in RViz."""
    return msg.Marker(
        header=header,
        ns=LINE_MARKER_NS,
        id=0,
        type=msg.Marker.LINE_LIST,
        action=msg.Marker.ADD,
        scale=msg.Vector3(LINE_MARKER_WIDTH, 0.0, 0.0),
        color=msg.ColorRGBA(*LINE_MARKER_COLOR),
        points=_segment_ends(extraction),
    )


def markers(extraction: Extraction, scan: Scan, header: msg.Header) -> msg.MarkerArray:
    """RViz / Foxglove markers: a DELETEALL, then segments (a line list), breakpoints and
    corners (sphere lists at their beams' points)."""
    points = scan.points
    ends = extraction.lines[:, [START_X, START_Y, END_X, END_Y]].reshape(-1, 2)
    groups = (
        ("segments", ends),
        ("breakpoints", points[extraction.breakpoints]),
        ("corners", points[extraction.corners]),
    )
    out = [msg.Marker(header=header, action=msg.Marker.DELETEALL)]
    for marker_id, (namespace, xy) in enumerate(groups, start=1):
        scale, color = _SCALES[namespace], _COLORS[namespace]
        kind = msg.Marker.LINE_LIST if namespace == "segments" else msg.Marker.SPHERE_LIST
        out.append(
            msg.Marker(
                header=header,
                ns=namespace,
                id=marker_id,
                type=kind,
                action=msg.Marker.ADD,
                scale=msg.Vector3(scale, scale, scale),
                color=msg.ColorRGBA(*color),
                points=[msg.Point(x, y, 0.0) for x, y in xy.tolist()],
            )
        )
    return msg.MarkerArray(markers=out)


def transform(
    pose: tuple[float, float, float], stamp: msg.Time, parent: str, child: str
) -> msg.TFMessage:
    """``/tf`` of a planar pose ``(x, y, theta)`` of frame ``child`` in frame ``parent``
    (``odom -> laser``), stamped ``stamp``."""
    x, y, theta = pose
    return msg.TFMessage(
        transforms=[
            msg.TransformStamped(
                header=msg.Header(stamp=stamp, frame_id=parent),
                child_frame_id=child,
                transform=msg.Transform(
                    translation=msg.Vector3(x, y, 0.0),
                    rotation=msg.Quaternion(0.0, 0.0, math.sin(theta / 2), math.cos(theta / 2)),
                ),
            )
        ]
    )
