"""Scans as rows of a text table (``.csv``, plain or gzip-compressed).

One scan per row; every value of the row is a range in metres. Values are
separated by commas (when the row has any) or by whitespace. An empty value,
``nan`` or ``inf`` is a beam with no return. Every row must have the same
number of values as the first one.

Lines starting with ``#`` are comments. Comments before the first row may
carry the geometry as ``key=value`` or ``key: value`` pairs, e.g.
``# angle_min=-1.5708 angle_increment=0.0087266 range_max=30``; keyword
options override them. ``angle_min`` and ``angle_increment`` (radians) must
come from one or the other. Without ``range_max`` from either, the largest
range, when at least 1 % of all beams hold exactly it, is a no-return code
(the SICK LMS writes 81.83 m), read as no return as the NPZ reader does
(:class:`~scanlines.io.npz.LargestRange`; one pass over the file before the
scans), and :attr:`CsvReader.notes` says so.

An optional header row (the first non-comment row, if it is not numeric) names
the columns. When its first name is ``timestamp``, ``time``, ``stamp`` or
``t``, the first column of every row is the timestamp in seconds and the other
columns are the ranges. ``timestamp_column=True/False`` forces this either way
(also for headerless files).

Poses: ``None`` (a table of ranges has none).
"""

from __future__ import annotations

import math
import re
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
from scanlines.io.npz import LargestRange, no_return_limit, no_return_note
from scanlines.io.text import OverlongLine, iter_lines, parse_floats
from scanlines.scan import Scan

__all__ = ["CsvReader", "looks_like_table", "parse_preamble"]

_GEOMETRY_KEYS = ("angle_min", "angle_increment", "range_min", "range_max")
_TIMESTAMP_NAMES = {"timestamp", "time", "stamp", "t"}
_PAIR = re.compile(r"([A-Za-z_]+)\s*[=:]\s*([^\s,;]+)")


def parse_preamble(comment: str) -> dict[str, float]:
    """Geometry values found in one comment line (``key=value`` or ``key: value``)."""
    found: dict[str, float] = {}
    for key, value in _PAIR.findall(comment):
        if key in _GEOMETRY_KEYS:
            try:
                found[key] = float(value)
            except ValueError:
                continue
    return found


def looks_like_table(head: bytes, *, named: bool = False) -> bool:
    """True when ``head`` looks like a table of ranges.

    Without ``named`` (sniffing a file whose name says nothing), one of the
    first two non-comment rows must be at least two numbers separated by
    commas or whitespace. With ``named`` (the name says ``.csv``), any
    non-comment row will do: the reader reports bad rows by line and field.
    """
    rows = 0
    for raw in head.decode("utf-8", errors="replace").splitlines():
        line = raw.strip()
        if not line or line.startswith("#"):
            continue
        values = _split(line)
        if named or (_is_numeric_row(values) and len(values) >= 2):
            return True
        rows += 1
        if rows == 2:
            break
    return False


def _split(line: str) -> list[str]:
    if "," in line:
        return [v.strip() for v in line.split(",")]
    return line.split()


class CsvReader(LogReader):
    """Stream one scan per row of a CSV or whitespace-separated table.

    Parameters
    ----------
    path:
        The table (plain or gzip).
    angle_min, angle_increment:
        Beam geometry in radians; ``None`` takes it from the comment preamble.
    range_min, range_max:
        Valid range interval in metres; ``None`` takes it from the preamble,
        else 0 and infinity.
    timestamp_column:
        Whether the first column is a timestamp; ``None`` decides from the header.
    on_error:
        ``"fail"`` or ``"skip"`` malformed rows.
    max_beams, max_record_bytes:
        Limits of one record (:mod:`scanlines.io.base`).

    Raises
    ------
    ParameterError
        When the angles are given neither as options nor in the preamble.
    """

    format_name = "csv"

    def __init__(
        self,
        path: str | Path,
        *,
        angle_min: float | None = None,
        angle_increment: float | None = None,
        range_min: float | None = None,
        range_max: float | None = None,
        timestamp_column: bool | None = None,
        on_error: ErrorPolicy = "fail",
        max_beams: int = DEFAULT_MAX_BEAMS,
        max_record_bytes: int = DEFAULT_MAX_RECORD_BYTES,
    ) -> None:
        super().__init__(
            path, on_error=on_error, max_beams=max_beams, max_record_bytes=max_record_bytes
        )
        preamble, header = self._read_preamble()
        given = {
            "angle_min": angle_min,
            "angle_increment": angle_increment,
            "range_min": range_min,
            "range_max": range_max,
        }
        geometry = dict(preamble) | {k: float(v) for k, v in given.items() if v is not None}
        missing = [k for k in ("angle_min", "angle_increment") if k not in geometry]
        if missing:
            raise ParameterError(
                f"{self.path}: a CSV log needs {' and '.join(missing)}: comment lines "
                f"'# angle_min=... angle_increment=...' in radians, or the options (radians "
                f"in the library; --angle-min and --angle-increment in degrees on the command "
                f"line)"
            )
        self.angle_min = geometry["angle_min"]
        self.angle_increment = geometry["angle_increment"]
        self.range_min = geometry.get("range_min", 0.0)
        self.range_max = geometry.get("range_max", math.inf)
        self.header = header
        if timestamp_column is None:
            timestamp_column = bool(header) and header[0].lower() in _TIMESTAMP_NAMES
        self.timestamp_column = timestamp_column
        #: Without ``range_max``: the no-return code found in the ranges (else None).
        self.no_return_code: float | None = None
        self._code_beams, self._beams = 0, 0
        if "range_max" not in geometry:
            self._find_no_return_code()

    def _find_no_return_code(self) -> None:
        """As the NPZ reader: the largest range, when at least 1 % of all beams hold
        exactly it, is a no-return code (the SICK 81.83 m), read as no return (the scans'
        ``range_max`` just below it). Rows that do not parse are left to the reading."""
        largest = LargestRange()
        header_pending = self.header is not None
        for _, line in iter_lines(self.path, self.max_record_bytes):
            if isinstance(line, OverlongLine):
                continue
            text = line.strip()
            if not text or text.startswith("#"):
                continue
            if header_pending:
                header_pending = False
                continue
            values = _split(text)[1 if self.timestamp_column else 0 :]
            try:
                largest.add([float(v) if v else math.nan for v in values])
            except ValueError:
                continue
        self._beams = largest.beams
        self.no_return_code, self._code_beams = largest.no_return_code()
        if self.no_return_code is not None:
            self.range_max = no_return_limit(self.no_return_code)

    @property
    def notes(self) -> list[str]:
        """The no-return code read as no return, if one was found."""
        if self.no_return_code is None:
            return []
        decides = "--range-max (or a '# range_max=' comment)"
        missing = "no range_max given"
        return [
            no_return_note(self.no_return_code, self._code_beams, self._beams, missing, decides)
        ]

    def options(self) -> dict[str, Any]:
        """Resolved geometry and column layout."""
        return {
            **super().options(),
            "angle_min": self.angle_min,
            "angle_increment": self.angle_increment,
            "range_min": self.range_min,
            "range_max": self.range_max,
            "timestamp_column": self.timestamp_column,
            **({"no_return_code": self.no_return_code} if self.no_return_code else {}),
        }

    def _read_preamble(self) -> tuple[dict[str, float], list[str] | None]:
        """Geometry from the leading comments and the header row, if any."""
        found: dict[str, float] = {}
        for line_number, line in iter_lines(self.path, self.max_record_bytes):
            if isinstance(line, OverlongLine):  # a data row (reported when it is read)
                return found, None
            text = line.strip()
            if not text:
                continue
            if text.startswith("#"):
                found |= parse_preamble(text)
                continue
            self._check_line(line, line_number)
            values = _split(text)
            return found, None if _is_numeric_row(values) else values
        return found, None

    def _scans(self) -> Iterator[tuple[int, Scan]]:
        width: int | None = None
        index = 0
        header_pending = self.header is not None
        for line_number, line in iter_lines(self.path, self.max_record_bytes):
            start = line.lstrip()[:1]
            if not start or start == "#":
                self.skipped["comment" if start else "blank"] += 1
                continue
            if header_pending:
                header_pending = False
                self.skipped["header"] += 1
                continue
            record_index = index
            index += 1
            try:
                self._check_line(line, line_number)
                values = _split(line.strip())
                width = width or len(values)
                scan = self._parse(values, width, line_number)
            except LogFormatError as error:
                self._bad_record(error)
                continue
            self.counts["row"] += 1
            yield record_index, scan

    def _parse(self, values: list[str], width: int, line_number: int) -> Scan:
        if len(values) != width:
            raise LogFormatError(
                f"row has {len(values)} values, the first row has {width}",
                path=self.path,
                record=line_number,
                field="ranges",
            )
        has_stamp = self.timestamp_column
        layout = FieldLayout([("timestamp", None)] * has_stamp + [("range", width - has_stamp)])
        numbers = parse_floats(
            [v or "nan" for v in values], layout.name, path=self.path, record=line_number
        )
        stamp = float(numbers[0]) if has_stamp and not np.isnan(numbers[0]) else None
        return self._make_scan(
            line_number,
            ranges=numbers[1:] if has_stamp else numbers,
            angle_min=self.angle_min,
            angle_increment=self.angle_increment,
            range_min=self.range_min,
            range_max=self.range_max,
            timestamp=stamp,
        )


def _is_numeric_row(values: list[str]) -> bool:
    try:
        [float(v) for v in values if v]
    except ValueError:
        return False
    return True
