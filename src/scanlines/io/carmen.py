"""CARMEN text logs (``.log``, ``.clf``, plain or gzip-compressed): one message per line, one
:class:`~scanlines.Scan` per laser record of one message type; every field as read is in
``docs/FORMATS.md``."""

from __future__ import annotations

import math
from collections.abc import Iterator, Sequence
from pathlib import Path
from typing import Any, Literal

import numpy as np

from scanlines.errors import LogFormatError, ParameterError
from scanlines.geometry.poses import compose
from scanlines.io.base import (
    DEFAULT_MAX_BEAMS,
    DEFAULT_MAX_RECORD_BYTES,
    ErrorPolicy,
    LogReader,
)
from scanlines.io.carmen_messages import (
    _DETECT_WINDOW_LINES,
    _FLASER_TAIL,
    _LASER_HEADER,
    _MESSAGE_NAME,
    _NUMERIC_PARAMS,
    _ODOM_ALL_FIELDS,
    _ODOM_FIELDS,
    _ROBOTLASER_TAIL,
    _SIDE,
    _STAMPS,
    KNOWN_MESSAGES,
    LASER_MESSAGES,
    _as_mounting,
    _check_choice,
    _count,
    _count_field,
    _expect_length,
    _mounting_between,
    _record_name,
    _skip_kind,
    _split_first,
    looks_like_carmen,
)
from scanlines.io.fields import FieldLayout
from scanlines.io.numbers import NumberFields, number_fields
from scanlines.io.text import iter_lines, parse_floats
from scanlines.scan import Scan
from scanlines.untrusted import quote

__all__ = [
    "DEFAULT_FOV_DEG",
    "DEFAULT_SICK_MAX_RANGE",
    "LASER_MESSAGES",
    "CarmenReader",
    "looks_like_carmen",
]

AngleConvention = Literal["step", "linspace"]
PoseSource = Literal["laser", "robot"]
TimestampSource = Literal["logger", "ipc"]

#: Field of view assumed for ``FLASER``/``RLASER`` when neither option nor PARAM gives one.
DEFAULT_FOV_DEG = 180.0
#: ``range_max`` for ``FLASER``/``RLASER`` without option or PARAM: the SICK LMS maximum.
DEFAULT_SICK_MAX_RANGE = 80.0


class CarmenReader(LogReader):
    """Stream the laser scans of a CARMEN log (see the module docstring for the rules).

    Parameters
    ----------
    path:
        ``.log``/``.clf`` file, plain or gzip.
    message:
        Laser message to read (``"FLASER"``, ``"ROBOTLASER1"``, ...); ``None``
        chooses one (see the module docstring).
    fov:
        Field of view in degrees for ``FLASER``/``RLASER``; ``None``: PARAM or 180.
    angle_convention:
        ``"step"`` or ``"linspace"`` for ``FLASER``/``RLASER`` beam angles.
    max_range, range_max:
        ``Scan.range_max`` in metres (two names of one option); ``None``: PARAM, the
        record's value, or 80.
    range_min:
        ``Scan.range_min`` in metres.
    pose:
        ``"laser"`` (default) or ``"robot"`` pose triple of the record.
    mounting:
        The laser's ``(x, y, theta)`` on the robot (metres, radians): ``RAWLASER``
        records, whose only pose is the robot's (from ``ODOM``), get the laser's pose
        from it. ``None``: they keep the robot's pose.
    timestamp:
        ``"logger"`` (default) or ``"ipc"`` timestamp field.
    on_error:
        ``"fail"`` or ``"skip"`` malformed records.
    max_beams, max_record_bytes:
        Limits of one record (:mod:`scanlines.io.base`).

    Attributes
    ----------
    params : dict
        ``PARAM`` name -> value (text) of the last iteration.
    """

    format_name = "carmen"

    def __init__(
        self,
        path: str | Path,
        *,
        message: str | None = None,
        fov: float | None = None,
        angle_convention: AngleConvention = "step",
        max_range: float | None = None,
        range_max: float | None = None,
        range_min: float = 0.0,
        pose: PoseSource = "laser",
        mounting: Sequence[float] | None = None,
        timestamp: TimestampSource = "logger",
        on_error: ErrorPolicy = "fail",
        max_beams: int = DEFAULT_MAX_BEAMS,
        max_record_bytes: int = DEFAULT_MAX_RECORD_BYTES,
    ) -> None:
        super().__init__(
            path, on_error=on_error, max_beams=max_beams, max_record_bytes=max_record_bytes
        )
        _check_choice("message", message, (*LASER_MESSAGES, None))
        _check_choice("angle_convention", angle_convention, ("step", "linspace"))
        _check_choice("pose", pose, ("laser", "robot"))
        _check_choice("timestamp", timestamp, ("logger", "ipc"))
        if fov is not None and not 0.0 < fov <= 360.0:
            raise ParameterError(f"fov must be in (0, 360] degrees, got {fov!r}")
        if range_max is not None:  # the name every other reader uses
            if max_range is not None and max_range != range_max:
                raise ParameterError(
                    f"max_range {max_range!r} and range_max {range_max!r} differ; give one"
                )
            max_range = range_max
        if max_range is not None and not max_range > 0.0:
            raise ParameterError(f"max_range must be positive, got {max_range!r}")
        self._message = message
        self.fov = fov
        self.angle_convention: AngleConvention = angle_convention
        self.max_range = max_range
        self.range_min = float(range_min)
        self.pose_source: PoseSource = pose
        self.mounting = None if mounting is None else _as_mounting(mounting)
        self.timestamp_source: TimestampSource = timestamp
        self.params: dict[str, str] = {}
        self._numeric_params: dict[str, float] = {}
        self._odom_pose: tuple[float, float, float] | None = None
        self._pose_pair: tuple[np.ndarray, np.ndarray] | None = None  # of the last record

    # -- public metadata ------------------------------------------------------------------

    @property
    def message(self) -> str:
        """The laser message type read (detected on first use when not given)."""
        if self._message is None:
            self._message = self._detect_message()
        return self._message

    @property
    def recorded_mounting(self) -> tuple[float, float, float] | None:
        """The laser's pose on the robot from the record just read (laser and robot pose
        both finite), else ``None``."""
        if self._pose_pair is None:
            return None
        return _mounting_between(*self._pose_pair)

    @property
    def moves_robot_poses(self) -> bool:
        """Whether scans get the laser's pose from the robot's and ``mounting``
        (``RAWLASER`` records with the ``mounting`` option)."""
        return self.mounting is not None and self.message.startswith("RAWLASER")

    def options(self) -> dict[str, Any]:
        """Resolved options (the message type is detected if needed)."""
        return {
            **super().options(),
            "message": self.message,
            "fov": self.fov,
            "angle_convention": self.angle_convention,
            "max_range": self.max_range,
            "range_min": self.range_min,
            "pose": self.pose_source,
            "mounting": None if self.mounting is None else list(self.mounting),
            "timestamp": self.timestamp_source,
        }

    def info(self) -> dict[str, Any]:
        """Reader metadata plus ``message`` and the PARAM lines of the last iteration."""
        return {**super().info(), "message": self.message, "params": dict(self.params)}

    # -- streaming ------------------------------------------------------------------------

    def _detect_message(self) -> str:
        seen: set[str] = set()
        first_line: int | None = None
        for line_number, line in iter_lines(self.path, self.max_record_bytes):
            parts = line.split(None, 1)
            if parts and parts[0] in LASER_MESSAGES:
                seen.add(parts[0])
                first_line = first_line or line_number
            if first_line is not None and line_number - first_line >= _DETECT_WINDOW_LINES:
                break
        if not seen:
            raise LogFormatError(
                f"no laser records ({', '.join(LASER_MESSAGES)}) in this CARMEN log", path=self.path
            )
        return min(seen, key=LASER_MESSAGES.index)

    def _scans(self) -> Iterator[tuple[int, Scan]]:
        self.message  # noqa: B018 - detect the laser message before reading
        self.params = {}
        self._numeric_params = {}
        self._odom_pose = None
        self._pose_pair = None
        index = 0
        for line_number, line in iter_lines(self.path, self.max_record_bytes):
            name = _record_name(line)
            kind = self._record_kind(name, line, line_number)
            if kind == "scan":
                record_index = index
                index += 1
                scan = self._read_or_skip(self._parse_laser_line, line, line_number)
                if scan is not None:
                    self.counts[name] += 1
                    yield record_index, scan
            elif kind == "damaged scan":
                index += 1  # keeps its place in the scan numbering
            elif kind == "other":
                parse = self._parse_odom if name == "ODOM" else self._parse_param
                split = _split_first(parse)
                if self._read_or_skip(split, line, line_number, scan=False) is not None:
                    self.counts[name] += 1
            else:
                self.skipped[_skip_kind(name)] += 1

    def _record_kind(self, name: str, line: str, line_number: int) -> str:
        """``"scan"`` (a record of the laser message read), ``"other"`` (ODOM, PARAM),
        ``"ignored"``, or ``"damaged scan"``: a line under an unknown name whose fields make
        a record of the laser message is a scan record with a damaged name, so it keeps
        its place in the scan numbering and is reported (raised or counted here), not
        ignored."""
        if name == self.message:
            return "scan"
        if name in ("ODOM", "PARAM"):
            return "other"
        if name in KNOWN_MESSAGES or not _MESSAGE_NAME.fullmatch(name):
            return "ignored"
        try:
            self._check_line(line, line_number)
            self._parse_laser([self.message, *line.split()[1:]], line_number)
        except LogFormatError:
            return "ignored"
        self._bad_record(
            LogFormatError(
                f"unknown record name {quote(name)}; its fields make a {self.message} record, "
                "so it is taken as a damaged scan record",
                path=self.path,
                record=line_number,
                field="message name",
            )
        )
        return "damaged scan"

    def _read_or_skip(self, parse: Any, line: str, line_number: int, *, scan: bool = True) -> Any:
        try:
            self._check_line(line, line_number)
            return parse(line, line_number)
        except LogFormatError as error:
            self._bad_record(error, scan=scan)
            return None

    # -- record parsers -------------------------------------------------------------------

    def _parse_laser_line(self, line: str, line_number: int) -> Scan:
        fields = number_fields(line)
        scan = None
        if fields is not None:
            fast = self._fast_flaser if self.message in _SIDE else self._fast_new_laser
            scan = fast(fields, line_number)
        return scan if scan is not None else self._parse_laser(line.split(), line_number)

    def _fast_flaser(self, fields: NumberFields, line_number: int) -> Scan | None:
        """The ``FLASER`` / ``RLASER`` record of ``fields`` (read in one compiled pass), or
        ``None`` when a field needs the slow path (:mod:`scanlines.io.numbers`)."""
        n = _count_field(fields, 1)
        if n is None or len(fields) != n + 11 or fields.texts != [0, n + 9]:  # name, hostname
            return None
        numbers = np.concatenate((fields.values[2 : n + 9], fields.values[n + 10 :]))
        return self._flaser_scan(self.message, n, numbers, line_number)

    def _fast_new_laser(self, fields: NumberFields, line_number: int) -> Scan | None:
        """:meth:`_fast_flaser` for ``ROBOTLASER`` and ``RAWLASER`` records."""
        n = _count_field(fields, 8)
        m = None if n is None else _count_field(fields, 9 + n)
        if m is None:
            return None
        robot = self.message.startswith("ROBOT")
        stamps_at = 10 + n + m + (len(_ROBOTLASER_TAIL) if robot else 0)
        if len(fields) != stamps_at + 3 or fields.texts != [0, stamps_at + 1]:
            return None
        values = fields.values
        parts = (values[1:8], values[9 : 9 + n], values[10 + n : stamps_at + 1], values[-1:])
        return self._new_laser_scan(n, m, np.concatenate(parts), line_number, robot=robot)

    def _parse_laser(self, tokens: list[str], line_number: int) -> Scan:
        name = tokens[0]
        if name in _SIDE:
            return self._parse_flaser(tokens, line_number)
        return self._parse_new_laser(tokens, line_number, robot=name.startswith("ROBOT"))

    def _parse_flaser(self, tokens: list[str], line_number: int) -> Scan:
        n = _count(tokens, 1, "num_readings", self.path, line_number)
        _expect_length(tokens, n + 11, self.path, line_number, tokens[0], "num_readings", n)
        layout = FieldLayout([("range", n), *((f, None) for f in _FLASER_TAIL), *_STAMPS])
        numbers = parse_floats(
            [*tokens[2 : n + 8], tokens[n + 8], tokens[n + 10]],
            layout.name,
            path=self.path,
            record=line_number,
        )
        return self._flaser_scan(tokens[0], n, numbers, line_number)

    def _flaser_scan(self, name: str, n: int, numbers: np.ndarray, line_number: int) -> Scan:
        """The scan of a ``FLASER`` / ``RLASER`` record from its ``n`` ranges, two poses
        and two timestamps (``numbers``)."""
        side = _SIDE[name]
        laser_pose, robot_pose = numbers[n : n + 3], numbers[n + 3 : n + 6]
        self._pose_pair = (laser_pose, robot_pose)
        fov = math.radians(self._flaser_fov(side))
        steps = n if self.angle_convention == "step" else n - 1
        return self._make_scan(
            line_number,
            ranges=numbers[:n],
            angle_min=-fov / 2.0,
            angle_increment=fov / max(steps, 1),
            range_min=self.range_min,
            range_max=self._flaser_max_range(side),
            timestamp=self._stamp(numbers[n + 6], numbers[n + 7]),
            pose=laser_pose if self.pose_source == "laser" else robot_pose,
        )

    def _parse_new_laser(self, tokens: list[str], line_number: int, *, robot: bool) -> Scan:
        name = tokens[0]
        n = _count(tokens, 8, "num_readings", self.path, line_number)
        if len(tokens) <= 9 + n:
            raise LogFormatError(
                f"{name} says num_readings = {n}, but the record ends after "
                f"{max(len(tokens) - 9, 0)} values",
                path=self.path,
                record=line_number,
                field="num_readings",
            )
        m = _count(tokens, 9 + n, "num_remissions", self.path, line_number)
        tail = _ROBOTLASER_TAIL if robot else ()
        _expect_length(
            tokens, n + m + 13 + len(tail), self.path, line_number, name, "num_readings", n
        )
        stamps_at = 10 + n + m + len(tail)
        layout = FieldLayout(
            [
                *((f, None) for f in _LASER_HEADER),
                ("range", n),
                ("remission", m),
                *((f, None) for f in tail),
                *_STAMPS,
            ]
        )
        numbers = parse_floats(
            [
                *tokens[1:8],
                *tokens[9 : 9 + n],
                *tokens[10 + n : stamps_at],
                tokens[stamps_at],
                tokens[stamps_at + 2],
            ],
            layout.name,
            path=self.path,
            record=line_number,
        )
        return self._new_laser_scan(n, m, numbers, line_number, robot=robot)

    def _new_laser_scan(
        self, n: int, m: int, numbers: np.ndarray, line_number: int, *, robot: bool
    ) -> Scan:
        """The scan of a ``ROBOTLASER`` / ``RAWLASER`` record from its numbers: the seven
        header fields, ``n`` ranges, ``m`` remissions, the tail and two timestamps."""
        start_angle, resolution, record_max = numbers[1], numbers[3], numbers[4]
        ranges, remissions = numbers[7 : 7 + n], numbers[7 + n : 7 + n + m]
        after = 7 + n + m
        if robot:
            pose_at = after if self.pose_source == "laser" else after + 3
            pose: Any = numbers[pose_at : pose_at + 3]
            self._pose_pair = (numbers[after : after + 3], numbers[after + 3 : after + 6])
        else:
            pose = self._odom_pose
            self._pose_pair = None
            if pose is not None and self.mounting is not None:
                pose = compose(pose, self.mounting)
        if not math.isfinite(resolution) or resolution == 0.0:
            raise LogFormatError(
                f"must be a non-zero number of radians, got {resolution!r}",
                path=self.path,
                record=line_number,
                field="angular_resolution",
            )
        return self._make_scan(
            line_number,
            ranges=ranges,
            angle_min=start_angle,
            angle_increment=resolution,
            range_min=self.range_min,
            range_max=self._record_max_range(record_max),
            timestamp=self._stamp(numbers[-2], numbers[-1]),
            intensities=remissions if m == n and m > 0 else None,
            pose=pose,
        )

    def _parse_odom(self, tokens: list[str], line_number: int) -> bool:
        expected = len(_ODOM_ALL_FIELDS) + 1
        if len(tokens) != expected:
            missing = _ODOM_ALL_FIELDS[len(tokens) - 1] if len(tokens) < expected else None
            raise LogFormatError(
                f"ODOM has {len(tokens)} fields, expected {expected} "
                f"(ODOM {' '.join(_ODOM_ALL_FIELDS)})",
                path=self.path,
                record=line_number,
                field=missing or "logger_timestamp",
            )
        layout = FieldLayout([*((f, None) for f in _ODOM_FIELDS), *_STAMPS])
        numbers = parse_floats(
            [*tokens[1:7], tokens[7], tokens[9]], layout.name, path=self.path, record=line_number
        )
        x, y, theta = (float(v) for v in numbers[:3])
        self._odom_pose = (x, y, theta) if np.isfinite(numbers[:3]).all() else None
        return True

    def _parse_param(self, tokens: list[str], line_number: int) -> bool:
        if len(tokens) < 3:
            raise LogFormatError(
                "PARAM needs a name and a value",
                path=self.path,
                record=line_number,
                field="param_value" if len(tokens) == 2 else "param_name",
            )
        name, value = tokens[1], tokens[2]
        if name in _NUMERIC_PARAMS:
            try:
                self._numeric_params[name] = float(value)
            except ValueError:
                raise LogFormatError(
                    f"{name} is not a number: {value!r}",
                    path=self.path,
                    record=line_number,
                    field="param_value",
                ) from None
        self.params[name] = value
        return True

    # -- rules ----------------------------------------------------------------------------

    def _flaser_fov(self, side: str) -> float:
        if self.fov is not None:
            return self.fov
        return self._numeric_params.get(f"laser_{side}_laser_fov", DEFAULT_FOV_DEG)

    def _flaser_max_range(self, side: str) -> float:
        if self.max_range is not None:
            return self.max_range
        return self._numeric_params.get(f"robot_{side}_laser_max", DEFAULT_SICK_MAX_RANGE)

    def _record_max_range(self, record_max: float) -> float:
        if self.max_range is not None:
            return self.max_range
        return float(record_max) if record_max > 0.0 else math.inf

    def _stamp(self, ipc: float, logger: float) -> float | None:
        value = float(logger if self.timestamp_source == "logger" else ipc)
        return None if math.isnan(value) else value
