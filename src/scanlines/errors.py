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
    """An unknown method, preset or parameter, or a parameter value out of range;
    ``parameter`` names the parameter at fault, when there is one."""

    def __init__(self, message: str = "", *, parameter: str | None = None) -> None:
        super().__init__(message)
        self.parameter = parameter


class LogFormatError(ScanlinesError, ValueError):
    """A log file or one of its records cannot be read.

    Parameters
    ----------
    message:
        What is wrong.
    path:
        The file, when known.
    record:
        The line number (text logs) or message number (bags), when known.
    field:
        The field of the record, when known.
    unit:
        What ``record`` counts: ``"line"`` (the default) or ``"message"``.
    """

    def __init__(
        self,
        message: str,
        *,
        path: object | None = None,
        record: int | None = None,
        field: str | None = None,
        unit: str = "line",
    ) -> None:
        self.path = None if path is None else one_line(str(path))
        self.record = record
        self.field = None if field is None else one_line(field)
        self.reason = one_line(message)
        where = []
        if self.path is not None:
            where.append(self.path)
        if record is not None:
            where.append(f"{unit} {record}")
        if self.field is not None:
            where.append(f"field {self.field}")
        prefix = ": ".join([", ".join(where)]) + ": " if where else ""
        super().__init__(prefix + self.reason)


#: How every command and reader says that a file it was given is not there
#: (``PATH: no such file or directory``).
NO_SUCH_FILE = "no such file or directory"

#: Longest text of a foreign exception quoted in an error message.
QUOTED_CHARACTERS = 200


def one_line(text: str) -> str:
    """``text`` on one line: line breaks (and the indentation after them) become ``" / "``,
    other control characters (from a damaged file name, say) their escapes."""
    lines = [line.strip() for line in str(text).splitlines()]
    joined = " / ".join(line for line in lines if line)
    return "".join(c if c.isprintable() else repr(c)[1:-1] for c in joined)


def describe(exc: BaseException) -> str:
    """A foreign exception (from numpy, zipfile, rosbags...) as a short one-line quote for
    an error message: its type and the start of its text."""
    text = one_line(str(exc))
    if len(text) > QUOTED_CHARACTERS:
        text = text[: QUOTED_CHARACTERS - 3] + "..."
    return f"{type(exc).__name__}: {text}" if text else type(exc).__name__
