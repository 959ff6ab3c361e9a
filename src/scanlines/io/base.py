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
``LaserScan``) raise in both modes.
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

__all__ = ["MAX_KEPT_ERRORS", "ErrorPolicy", "LogReader"]

ErrorPolicy = Literal["fail", "skip"]

#: How many error messages a reader keeps in ``errors`` in skip mode (all are counted).
MAX_KEPT_ERRORS = 1000


class LogReader(ABC):
    """Base class of the log readers: a re-iterable stream of scans.

    Parameters
    ----------
    path:
        The log file (or ROS 2 bag directory).
    on_error:
        ``"fail"`` raises at the first malformed record, ``"skip"`` drops and
        counts it.

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
    error_count : int
        Number of malformed records dropped in skip mode.
    scan_count : int or None
        Scans yielded by the last complete iteration, ``None`` before one.
    """

    format_name: ClassVar[str] = "log"

    def __init__(self, path: str | Path, *, on_error: ErrorPolicy = "fail") -> None:
        if on_error not in ("fail", "skip"):
            raise ParameterError(f"on_error must be 'fail' or 'skip', got {on_error!r}")
        self.path = Path(path)
        self.on_error: ErrorPolicy = on_error
        self.counts: Counter[str] = Counter()
        self.skipped: Counter[str] = Counter()
        self.errors: list[str] = []
        self.error_count = 0
        self.scan_count: int | None = None

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

    def _reset_bookkeeping(self) -> None:
        self.counts = Counter()
        self.skipped = Counter()
        self.errors = []
        self.error_count = 0

    def _bad_record(self, error: LogFormatError) -> None:
        """Raise ``error`` (fail mode) or count it (skip mode)."""
        if self.on_error == "fail":
            raise error
        self.error_count += 1
        if len(self.errors) < MAX_KEPT_ERRORS:
            self.errors.append(str(error))

    def _make_scan(self, record: int | None, **fields: Any) -> Scan:
        """Build a :class:`Scan`, turning a :class:`ScanError` into a :class:`LogFormatError`."""
        try:
            return Scan(**fields)
        except ScanError as exc:
            field = str(exc).split(" ", 1)[0]
            raise LogFormatError(str(exc), path=self.path, record=record, field=field) from None

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
        }

    def options(self) -> dict[str, Any]:
        """The resolved reader options (for ``.meta.json`` and ``info``)."""
        return {"on_error": self.on_error}

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
