"""CoreSLAM / BreezySLAM ``.dat`` logs (Hokuyo URG-04LX), plain or gzip-compressed.

One scan per line, space-separated integers (lines end with a space). The
layout, from the Paris Mines Tech logs shipped with BreezySLAM (``exp1.dat``,
``exp2.dat``; see the ``PROVENANCE.md`` of the URG data):

* field 0: timestamp in microseconds -> ``Scan.timestamp`` in seconds;
* fields 2 and 3: left and right wheel encoder counts (raw ticks);
* fields 1 and 4-23: other robot words, not documented (parsed, not used);
* fields 24 onwards: ``beams`` ranges in millimetres (683 by default, the
  URG-04LX's 683 steps), converted to metres.

Geometry (URG-04LX datasheet; not stated in the file): step 360/1024 deg,
counter-clockwise, centred on the x axis, so ``angle_min = -(beams - 1)/2 *
step`` (-119.88 deg for 683 beams) and the beams span 239.77 deg. ``fov``
(degrees, first to last beam) overrides the step: ``angle_increment = fov /
(beams - 1)``.

No return: 0 mm means no return and 1..19 mm are URG error codes, so
``range_min`` defaults to 0.02 m and those readings are invalid.

Pose: ``None``. The log holds raw encoder ticks, not poses; the reader does
not integrate them.
"""

from __future__ import annotations

import math
from collections.abc import Iterator
from pathlib import Path
from typing import Any

import numpy as np

from scanlines.errors import LogFormatError, ParameterError
from scanlines.io.base import (
    DEFAULT_MAX_BEAMS,
    DEFAULT_MAX_RECORD_BYTES,
    ErrorPolicy,
    LogReader,
)
from scanlines.io.fields import FieldLayout
from scanlines.io.numbers import number_fields
from scanlines.io.text import iter_lines, parse_floats
from scanlines.scan import Scan

__all__ = [
    "URG04LX_BEAMS",
    "URG04LX_STEP_RAD",
    "CoreSlamReader",
    "looks_like_coreslam",
]

#: Beams per scan of the URG-04LX.
URG04LX_BEAMS = 683
#: Angular step of the URG-04LX: 360/1024 degrees.
URG04LX_STEP_RAD = 2.0 * math.pi / 1024.0
#: Readings below this (mm) are error codes or no return.
URG04LX_RANGE_MIN = 0.02
_FIRST_RANGE_FIELD = 24
_HEADER_FIELDS = [
    ("timestamp_us", None),
    ("field[1]", None),
    ("left_encoder", None),
    ("right_encoder", None),
    *((f"field[{k}]", None) for k in range(4, _FIRST_RANGE_FIELD)),
]


def looks_like_coreslam(head: bytes) -> bool:
    """True when the first line of ``head`` looks like a ``.dat`` record.

    That is: more than 24 space-separated fields, an integer timestamp in
    field 0 and integer millimetre ranges from field 24 on (fields 1-23 may
    hold decimals, e.g. field 7 of ``exp1.dat``).
    """
    lines = head.decode("utf-8", errors="replace").splitlines()
    if not lines:
        return False
    tokens = lines[0].split()
    if len(tokens) <= _FIRST_RANGE_FIELD or "," in lines[0]:
        return False
    integers = [tokens[0], *tokens[_FIRST_RANGE_FIELD:]]
    return all(t.isdigit() for t in integers) and all(_is_number(t) for t in tokens)


def _is_number(token: str) -> bool:
    try:
        float(token)
    except ValueError:
        return False
    return True


class CoreSlamReader(LogReader):
    """Stream the scans of a CoreSLAM ``.dat`` log (see the module docstring).

    Parameters
    ----------
    path:
        ``.dat`` file, plain or gzip.
    beams:
        Range fields per line after the 24 header fields; a line with another
        field count is malformed.
    fov:
        Degrees from the first to the last beam; ``None``: ``(beams - 1)`` URG steps.
    range_min, range_max:
        Valid range interval in metres.
    on_error:
        ``"fail"`` or ``"skip"`` malformed lines.
    max_beams, max_record_bytes:
        Limits of one record (:mod:`scanlines.io.base`).
    """

    format_name = "coreslam"

    def __init__(
        self,
        path: str | Path,
        *,
        beams: int = URG04LX_BEAMS,
        fov: float | None = None,
        range_min: float = URG04LX_RANGE_MIN,
        range_max: float = math.inf,
        on_error: ErrorPolicy = "fail",
        max_beams: int = DEFAULT_MAX_BEAMS,
        max_record_bytes: int = DEFAULT_MAX_RECORD_BYTES,
    ) -> None:
        super().__init__(
            path, on_error=on_error, max_beams=max_beams, max_record_bytes=max_record_bytes
        )
        if isinstance(beams, bool) or not isinstance(beams, int) or beams < 2:
            raise ParameterError(f"beams must be an integer >= 2, got {beams!r}")
        if fov is not None and not 0.0 < fov <= 360.0:
            raise ParameterError(f"fov must be in (0, 360] degrees, got {fov!r}")
        self.beams = beams
        self.fov = fov
        self.range_min = float(range_min)
        self.range_max = float(range_max)
        step = URG04LX_STEP_RAD if fov is None else math.radians(fov) / (beams - 1)
        self.angle_increment = step
        self.angle_min = -(beams - 1) / 2.0 * step
        self._layout = FieldLayout([*_HEADER_FIELDS, ("range_mm", beams)])

    def options(self) -> dict[str, Any]:
        """Resolved options, with the derived angles in radians."""
        return {
            **super().options(),
            "beams": self.beams,
            "fov": self.fov,
            "angle_min": self.angle_min,
            "angle_increment": self.angle_increment,
            "range_min": self.range_min,
            "range_max": self.range_max,
        }

    def _scans(self) -> Iterator[tuple[int, Scan]]:
        index = 0
        for line_number, line in iter_lines(self.path, self.max_record_bytes):
            start = line.lstrip()[:1]
            if not start:
                self.skipped["blank"] += 1
                continue
            if start == "#":
                self.skipped["comment"] += 1
                continue
            record_index = index
            index += 1
            try:
                self._check_line(line, line_number)
                scan = self._parse_line(line, line_number)
            except LogFormatError as error:
                self._bad_record(error)
                continue
            self.counts["scan"] += 1
            yield record_index, scan

    def _parse_line(self, line: str, line_number: int) -> Scan:
        """The scan of a record: its numbers read in one compiled pass when every field is
        one :func:`~scanlines.io.numbers.number_fields` reads, else token by token."""
        fields = number_fields(line)
        expected = _FIRST_RANGE_FIELD + self.beams
        if fields is not None and len(fields) == expected and not fields.texts:
            return self._scan_of(fields.values, line_number)
        return self._parse(line.split(), line_number)

    def _parse(self, tokens: list[str], line_number: int) -> Scan:
        expected = _FIRST_RANGE_FIELD + self.beams
        if len(tokens) != expected:
            raise LogFormatError(
                f"expected {expected} fields (24 header fields and {self.beams} ranges), "
                f"got {len(tokens)}",
                path=self.path,
                record=line_number,
                field=self._layout.name(min(len(tokens), expected)),
            )
        numbers = parse_floats(tokens, self._layout.name, path=self.path, record=line_number)
        return self._scan_of(numbers, line_number)

    def _scan_of(self, numbers: np.ndarray, line_number: int) -> Scan:
        return self._make_scan(
            line_number,
            ranges=numbers[_FIRST_RANGE_FIELD:] / 1000.0,
            angle_min=self.angle_min,
            angle_increment=self.angle_increment,
            range_min=self.range_min,
            range_max=self.range_max,
            timestamp=float(numbers[0]) / 1e6,
        )
