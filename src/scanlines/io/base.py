"""The reader interface shared by every log format.

A reader is an iterable of :class:`~scanlines.Scan`. Iteration streams the file
(one record in memory at a time) and re-opens it each time, so a reader can be
iterated any number of times. Bookkeeping about the last iteration (records of
each kind, skipped lines, bad records) is kept on the reader for ``scanlines
info``.

Error policy
------------
``on_error="fail"`` (the default) raises :class:`~scanlines.LogFormatError` at
the first malformed record; the message names the file, the 1-based line (or
message) number and the field. ``on_error="skip"`` drops such records instead,
counts them in :attr:`LogReader.error_count` and keeps the first
:data:`MAX_KEPT_ERRORS` messages in :attr:`LogReader.errors`. Problems with the
file as a whole (unknown format, empty file, truncated gzip, a bag without
``LaserScan``) raise in both modes. A reader that cannot account for every
record its file declares (a bag's index counting more messages than could be
read) says so: an error, or those records counted as skipped.

Counts
------
:attr:`LogReader.bad_scans` counts the scan records dropped in skip mode (by
reason in :attr:`LogReader.skip_reasons`), :attr:`LogReader.bad_other` the
other records dropped (odometry, parameters), and :attr:`LogReader.skipped`
the records ignored by design (comments, other topics, unknown message names).
The index ``enumerate`` yields is the scan's position among the log's scan
records, dropped ones included.

Limits
------
``max_beams`` (beams in one scan) and ``max_record_bytes`` (bytes of one text
line) bound what one record may cost; a record beyond them is a malformed
record. The defaults are far above any 2D laser scanner and can be raised.
"""

from __future__ import annotations

from abc import ABC, abstractmethod
from collections import Counter
from collections.abc import Iterator
from pathlib import Path
from types import TracebackType
from typing import Any, ClassVar, Literal, Self

from scanlines.errors import LogFormatError, ParameterError, ScanError
from scanlines.scan import Scan

__all__ = [
    "DEFAULT_MAX_BEAMS",
    "DEFAULT_MAX_RECORD_BYTES",
    "MAX_KEPT_ERRORS",
    "ErrorPolicy",
    "LogReader",
]

ErrorPolicy = Literal["fail", "skip"]

#: How many error messages a reader keeps in ``errors`` in skip mode (all are counted).
MAX_KEPT_ERRORS = 1000
#: Most beams in one scan a reader accepts by default (a 0.01 degree, 360 degree scanner
#: has 36,000).
DEFAULT_MAX_BEAMS = 1_000_000
#: Longest text record (one line) a reader accepts by default, in bytes.
DEFAULT_MAX_RECORD_BYTES = 64 * 1024 * 1024


class LogReader(ABC):
    """Base class of the log readers: a re-iterable stream of scans.

    Parameters
    ----------
    path:
        The log file (or ROS 2 bag directory).
    on_error:
        ``"fail"`` raises at the first malformed record, ``"skip"`` drops and
        counts it.
    max_beams, max_record_bytes:
        Limits of one record (see the module docstring).

    Attributes
    ----------
    path : pathlib.Path
        The file being read.
    format_name : str
        Short name of the format (``"carmen"``, ``"rosbag"``, ...).
    counts : collections.Counter
        Records read in the last iteration, by kind (e.g. ``FLASER``, ``ODOM``).
    skipped : collections.Counter
        Lines or messages ignored in the last iteration, by kind (message name,
        ``"comment"``, ``"blank"``, ...).
    errors : list of str
        Messages of the malformed records dropped in skip mode (the first
        :data:`MAX_KEPT_ERRORS`).
    bad_scans, bad_other : int
        Malformed scan records and malformed other records dropped in skip mode.
    skip_reasons : collections.Counter
        The dropped scan records by reason (the field at fault, or the damage).
    scan_count : int or None
        Scans yielded by the last complete iteration, ``None`` before one.
    recorded_mounting : tuple of float or None
        The laser's ``(x, y, theta)`` on the robot as recorded with the scan just
        yielded, where the record holds both the laser's and the robot's pose (CARMEN
        ``FLASER``, ``ROBOTLASER``); ``None`` elsewhere.
    """

    format_name: ClassVar[str] = "log"
    #: What a record number counts in error messages.
    record_unit: ClassVar[str] = "line"

    def __init__(
        self,
        path: str | Path,
        *,
        on_error: ErrorPolicy = "fail",
        max_beams: int = DEFAULT_MAX_BEAMS,
        max_record_bytes: int = DEFAULT_MAX_RECORD_BYTES,
    ) -> None:
        if on_error not in ("fail", "skip"):
            raise ParameterError(f"on_error must be 'fail' or 'skip', got {on_error!r}")
        self.path = Path(path)
        self.on_error: ErrorPolicy = on_error
        self.max_beams = _positive_limit("max_beams", max_beams)
        self.max_record_bytes = _positive_limit("max_record_bytes", max_record_bytes)
        self.counts: Counter[str] = Counter()
        self.skipped: Counter[str] = Counter()
        self.errors: list[str] = []
        self.bad_scans = 0
        self.bad_other = 0
        self.skip_reasons: Counter[str] = Counter()
        self.scan_count: int | None = None

    @property
    def notes(self) -> list[str]:
        """What the reader had to decide about the file (a damaged index read past, a
        no-return code found): one sentence each, for ``info`` and ``run``'s summary."""
        return []

    @property
    def scans_in_file(self) -> int | None:
        """Scan records the file holds, counted or declared without reading it (``None``
        where the format does not say), else those of the last complete iteration."""
        return None if self.scan_count is None else self.scan_count + self.bad_scans

    @property
    def recorded_mounting(self) -> tuple[float, float, float] | None:
        """See the class docstring; ``None`` for formats that record no robot pose."""
        return None

    # -- iteration -------------------------------------------------------------------------

    def __iter__(self) -> Iterator[Scan]:
        for _, scan in self.enumerate():
            yield scan

    def enumerate(self) -> Iterator[tuple[int, Scan]]:
        """Yield ``(index, scan)`` pairs.

        ``index`` counts the scan records of the log from 0, including records
        dropped in skip mode, so it names the same record whatever the error
        policy. Writers use it as the ``scan`` column.
        """
        self._reset_bookkeeping()
        yielded = 0
        for index, scan in self._scans():
            yielded += 1
            yield index, scan
        self.scan_count = yielded

    @abstractmethod
    def _scans(self) -> Iterator[tuple[int, Scan]]:
        """Stream ``(record index, scan)`` pairs from a freshly opened file."""

    # -- bookkeeping -----------------------------------------------------------------------

    @property
    def error_count(self) -> int:
        """Malformed records dropped in skip mode (scans and others)."""
        return self.bad_scans + self.bad_other

    def _reset_bookkeeping(self) -> None:
        self.counts = Counter()
        self.skipped = Counter()
        self.errors = []
        self.bad_scans = 0
        self.bad_other = 0
        self.skip_reasons = Counter()

    def _bad_record(self, error: LogFormatError, *, scan: bool = True, count: int = 1) -> None:
        """Raise ``error`` (fail mode) or count it (skip mode): ``count`` records, scan
        records unless ``scan`` is false."""
        if self.on_error == "fail":
            raise error
        if scan:
            self.bad_scans += count
            self.skip_reasons[_reason(error)] += count
        else:
            self.bad_other += count
        if len(self.errors) < MAX_KEPT_ERRORS:
            self.errors.append(str(error))

    def _check_beams(self, beams: int, record: int | None, field: str = "ranges") -> None:
        """A record of more than ``max_beams`` beams is malformed (raised before parsing it)."""
        if beams > self.max_beams:
            raise LogFormatError(
                f"{beams} beams exceed the limit of {self.max_beams} (--max-beams)",
                path=self.path,
                record=record,
                field=field,
                unit=self.record_unit,
            )

    def _check_line(self, line: str, record: int) -> None:
        """A text line over ``max_record_bytes`` or with fields for more than ``max_beams``
        beams is malformed (checked before it is split)."""
        from scanlines.io.text import check_record_size

        check_record_size(
            line,
            path=self.path,
            record=record,
            max_line=self.max_record_bytes,
            max_fields=2 * self.max_beams + 64,
        )

    def _make_scan(self, record: int | None, **fields: Any) -> Scan:
        """Build a :class:`Scan`, turning a :class:`ScanError` into a :class:`LogFormatError`."""
        self._check_beams(len(fields["ranges"]), record)
        try:
            return Scan(**fields)
        except ScanError as exc:
            field = str(exc).split(" ", 1)[0]
            raise LogFormatError(
                str(exc), path=self.path, record=record, field=field, unit=self.record_unit
            ) from None

    # -- metadata --------------------------------------------------------------------------

    def info(self) -> dict[str, Any]:
        """What is known about the log without reading it all.

        After a complete iteration this also holds the counts of that
        iteration (``scans``, ``records``, ``skipped``, ``errors``).
        """
        return {
            "format": self.format_name,
            "path": str(self.path),
            "options": self.options(),
            "scans": self.scan_count,
            "records": dict(self.counts),
            "skipped": dict(self.skipped),
            "errors": self.error_count,
            "bad_scan_records": self.bad_scans,
            "bad_other_records": self.bad_other,
            "skip_reasons": dict(self.skip_reasons),
            **({"notes": self.notes} if self.notes else {}),
        }

    def options(self) -> dict[str, Any]:
        """The resolved reader options (for ``.meta.json`` and ``info``)."""
        options: dict[str, Any] = {"on_error": self.on_error}
        if self.max_beams != DEFAULT_MAX_BEAMS:
            options["max_beams"] = self.max_beams
        if self.max_record_bytes != DEFAULT_MAX_RECORD_BYTES:
            options["max_record_bytes"] = self.max_record_bytes
        return options

    # -- context manager (readers hold no open handle between iterations) -------------------

    def __enter__(self) -> Self:
        return self

    def __exit__(
        self,
        exc_type: type[BaseException] | None,
        exc: BaseException | None,
        traceback: TracebackType | None,
    ) -> None:
        self.close()

    def close(self) -> None:  # noqa: B027 - a hook, deliberately empty by default
        """Release resources; iteration re-opens the file, so this is a no-op for most readers."""

    def __repr__(self) -> str:
        return f"{type(self).__name__}({str(self.path)!r})"


def _positive_limit(name: str, value: Any) -> int:
    if isinstance(value, bool) or not isinstance(value, int) or value < 1:
        raise ParameterError(f"{name} must be a positive integer, got {value!r}")
    return value


def _reason(error: LogFormatError) -> str:
    """The reason a scan record was dropped, for counting: the field at fault (without
    its beam index), or the start of the message."""
    if error.field:
        return error.field.split("[", 1)[0].rstrip("0123456789 ")
    return error.reason.split(" (", 1)[0][:60]
