"""CARMEN messages: their names, their field layouts, and taking a record line apart."""

from __future__ import annotations

import math
import re
from collections.abc import Sequence
from pathlib import Path
from typing import Any

import numpy as np

from scanlines.errors import LogFormatError, ParameterError
from scanlines.geometry.poses import relative_pose
from scanlines.io.numbers import INTEGER, NumberFields
from scanlines.io.text import parse_int

#: Laser message names, in the order of preference used to choose one.
LASER_MESSAGES = (
    "ROBOTLASER1",
    "FLASER",
    "RAWLASER1",
    "ROBOTLASER2",
    "RLASER",
    "RAWLASER2",
    "RAWLASER3",
    "RAWLASER4",
)
#: Other message names a CARMEN logger writes (never read as scans).
KNOWN_MESSAGES = frozenset(
    {
        *LASER_MESSAGES,
        "ODOM",
        "PARAM",
        "TRUEPOS",
        "SYNC",
        "NMEAGGA",
        "NMEARMC",
        "GPSNMEA",
        "SONAR",
        "BUMPER",
        "IMU",
        "BASEVELOCITY",
        "ROBOTVELOCITY",
        "VECTORMOVE",
        "FOLLOWTRAJECTORY",
        "ARM",
        "LASER3",
        "LASER4",
        "POSITIONLASER",
        "SCANMARK",
    }
)
_DETECT_WINDOW_LINES = 50
_MESSAGE_NAME = re.compile(r"[A-Z][A-Z0-9_]{0,39}")
_SIDE = {"FLASER": "front", "RLASER": "rear"}
_NUMERIC_PARAMS = {
    "robot_front_laser_max",
    "robot_rear_laser_max",
    "laser_front_laser_fov",
    "laser_rear_laser_fov",
    "laser_front_laser_resolution",
    "laser_rear_laser_resolution",
}
_LASER_HEADER = (
    "laser_type",
    "start_angle",
    "fov",
    "angular_resolution",
    "maximum_range",
    "accuracy",
    "remission_mode",
)
_ROBOTLASER_TAIL = (
    "laser_x",
    "laser_y",
    "laser_theta",
    "robot_x",
    "robot_y",
    "robot_theta",
    "tv",
    "rv",
    "forward_safety_dist",
    "side_safety_dist",
    "turn_axis",
)
_FLASER_TAIL = ("x", "y", "theta", "odom_x", "odom_y", "odom_theta")
_ODOM_FIELDS = ("x", "y", "theta", "tv", "rv", "accel")
_ODOM_ALL_FIELDS = (*_ODOM_FIELDS, "ipc_timestamp", "ipc_hostname", "logger_timestamp")
_STAMPS = (("ipc_timestamp", None), ("logger_timestamp", None))


def looks_like_carmen(head: bytes) -> bool:
    """True when the first record line of ``head`` starts with a CARMEN-style message name.

    CARMEN message names are upper-case identifiers (``PARAM``, ``ODOM``,
    ``FLASER``, ``ROBOTLASER1``, ``NEFF``, ``VERTEX_SE2`` ...).
    """
    for raw in head.decode("utf-8", errors="replace").splitlines():
        line = raw.strip()
        if not line:
            continue
        if line.startswith("#"):
            continue
        name = line.split(None, 1)[0]
        return name[0].isalpha() and name.isupper() and name.replace("_", "").isalnum()
    text = head.decode("utf-8", errors="replace")
    return "CARMEN" in text or any(name in text for name in LASER_MESSAGES)


def _record_name(line: str) -> str:
    """The first token of a line (its message name), without splitting the whole line."""
    parts = line.split(None, 1)
    return parts[0] if parts else ""


def _split_first(parse: Any) -> Any:
    """``parse`` (which takes a record's tokens) taking the record's line."""
    return lambda line, line_number: parse(line.split(), line_number)


def _skip_kind(name: str) -> str:
    """The ``skipped`` key of a line: its message name, or a bounded set of catch-alls.

    Only CARMEN-like names (upper-case identifiers) get their own key, so a
    file of junk cannot grow the counter without bound.
    """
    if not name:
        return "blank"
    if name.startswith("#"):
        return "comment"
    if _MESSAGE_NAME.fullmatch(name):
        return name
    return "other"


def _count_field(fields: NumberFields, at: int) -> int | None:
    """The count at position ``at`` of a record read by
    :func:`~scanlines.io.numbers.number_fields`, or ``None`` when it is not one (missing,
    not digits, negative: the slow path reports it)."""
    if len(fields) <= at or fields.kinds[at] != INTEGER or fields.values[at] < 0:
        return None
    return int(fields.values[at])


def _count(tokens: list[str], at: int, field: str, path: Path, line_number: int) -> int:
    if len(tokens) <= at:
        raise LogFormatError(
            f"{tokens[0]} record ends before its {field} field ({len(tokens)} fields)",
            path=path,
            record=line_number,
            field=field,
        )
    return parse_int(tokens[at], field, path=path, record=line_number)


def _expect_length(
    tokens: list[str], expected: int, path: Path, line_number: int, name: str, field: str, n: int
) -> None:
    if len(tokens) != expected:
        raise LogFormatError(
            f"{name} says {field} = {n}, so the record has {expected} fields, but it has "
            f"{len(tokens)}",
            path=path,
            record=line_number,
            field=field,
        )


def _check_choice(option: str, value: Any, choices: tuple[Any, ...]) -> None:
    if value not in choices:
        shown = ", ".join(repr(c) for c in choices)
        raise ParameterError(f"{option} must be one of {shown}; got {value!r}")


def _as_mounting(mounting: Sequence[float]) -> tuple[float, float, float]:
    try:
        values = tuple(float(v) for v in mounting)
    except (TypeError, ValueError):
        raise ParameterError(f"mounting must be (x, y, theta), got {mounting!r}") from None
    if len(values) != 3 or not all(map(math.isfinite, values)):
        raise ParameterError(f"mounting must be three finite numbers (x, y, theta): {mounting!r}")
    return values  # type: ignore[return-value]


def _mounting_between(laser: np.ndarray, robot: np.ndarray) -> tuple[float, float, float] | None:
    """The laser's pose in the robot's frame, or ``None`` when a pose is not finite."""
    if not (np.isfinite(laser).all() and np.isfinite(robot).all()):
        return None
    return relative_pose(robot, laser)
