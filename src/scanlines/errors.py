"""Exceptions raised by scanlines.

Every error a user can cause derives from :class:`ScanlinesError` and from
:class:`ValueError`, and its message names the field (and, for logs, the file and
record) that is wrong.
"""

from __future__ import annotations


class ScanlinesError(Exception):
    """Base class of every error scanlines raises on bad input."""


class ScanError(ScanlinesError, ValueError):
    """A :class:`~scanlines.Scan` was constructed from invalid data."""


class ParameterError(ScanlinesError, ValueError):
    """An unknown method, preset or parameter, or a parameter value out of range."""


class LogFormatError(ScanlinesError, ValueError):
    """A log file or one of its records cannot be read.

    Parameters
    ----------
    message:
        What is wrong.
    path:
        The file, when known.
    record:
        The line number (text logs) or message index (bags), when known.
    field:
        The field of the record, when known.
    """

    def __init__(
        self,
        message: str,
        *,
        path: object | None = None,
        record: int | None = None,
        field: str | None = None,
    ) -> None:
        self.path = None if path is None else str(path)
        self.record = record
        self.field = field
        self.reason = message
        where = []
        if self.path is not None:
            where.append(self.path)
        if record is not None:
            where.append(f"line {record}")
        if field is not None:
            where.append(f"field {field}")
        prefix = ": ".join([", ".join(where)]) + ": " if where else ""
        super().__init__(prefix + message)
