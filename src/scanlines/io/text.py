"""Helpers for line-based text logs, plain or gzip-compressed.

Compression is recognised by the gzip magic bytes, not by the file name. A
truncated or corrupt gzip stream becomes a :class:`~scanlines.LogFormatError`
naming the file and the line at which the data ended.
"""

from __future__ import annotations

import gzip
import zlib
from collections.abc import Callable, Iterator, Sequence
from pathlib import Path
from typing import IO

import numpy as np

from scanlines.errors import NO_SUCH_FILE, LogFormatError

__all__ = [
    "GZIP_MAGIC",
    "OverlongLine",
    "check_record_size",
    "is_gzip",
    "iter_lines",
    "open_text",
    "parse_floats",
    "parse_int",
    "read_head",
]

GZIP_MAGIC = b"\x1f\x8b"
_GZIP_ERRORS = (EOFError, gzip.BadGzipFile, zlib.error)


def is_gzip(path: Path) -> bool:
    """True when the file starts with the gzip magic bytes."""
    with path.open("rb") as fh:
        return fh.read(2) == GZIP_MAGIC


def open_text(path: Path) -> IO[str]:
    """Open a text log for reading, decompressing gzip transparently.

    Undecodable bytes are replaced (U+FFFD) rather than raised, so they surface
    as a "not a number" error naming the field.
    """
    if is_gzip(path):
        return gzip.open(path, "rt", encoding="utf-8", errors="replace")
    return path.open("r", encoding="utf-8", errors="replace")


class OverlongLine(str):
    """The start of a line longer than the limit :func:`iter_lines` was given (the rest of
    the line was read past, never held); ``length`` is the whole line's length."""

    length: int = 0


#: How much of an overlong line :func:`iter_lines` keeps (enough for its record name).
_OVERLONG_HEAD = 256


def iter_lines(path: Path, max_line: int | None = None) -> Iterator[tuple[int, str]]:
    """Yield ``(line number, line)`` pairs, numbered from 1, streaming.

    A line longer than ``max_line`` characters is never held whole: it comes as an
    :class:`OverlongLine` (its start), which the reader reports with
    :func:`check_record_size`.

    Raises
    ------
    LogFormatError
        When the file is missing or its gzip stream is truncated or corrupt.
    """
    line_number = 0
    try:
        with open_text(path) as fh:
            lines = iter(fh) if max_line is None else _bounded_lines(fh, max_line)
            for line_number, line in enumerate(lines, start=1):
                yield line_number, line
    except _GZIP_ERRORS as exc:
        raise LogFormatError(
            f"the gzip data is truncated or corrupt ({exc})", path=path, record=line_number + 1
        ) from None
    except FileNotFoundError:
        raise LogFormatError(NO_SUCH_FILE, path=path) from None


def _bounded_lines(fh: IO[str], max_line: int) -> Iterator[str]:
    while line := fh.readline(max_line + 1):
        if len(line) <= max_line or line.endswith("\n"):
            yield line
            continue
        length = len(line)
        while rest := fh.readline(1 << 20):
            length += len(rest)
            if rest.endswith("\n"):
                break
        head = OverlongLine(line[:_OVERLONG_HEAD])
        head.length = length
        yield head


def check_record_size(
    line: str, *, path: Path, record: int, max_line: int, max_fields: int
) -> None:
    """Raise a :class:`LogFormatError` for a line over the limits, before it is split:
    longer than ``max_line`` (an :class:`OverlongLine`) or with more than ``max_fields``
    separators (counted without allocating)."""
    if isinstance(line, OverlongLine):
        raise LogFormatError(
            f"the line is {line.length} characters long, over the limit of {max_line} "
            "(option max_record_bytes)",
            path=path,
            record=record,
        )
    separators = line.count(" ") + line.count("\t") + line.count(",")
    if separators > max_fields:
        raise LogFormatError(
            f"about {separators} fields, over the limit of {max_fields} for scans of at most "
            "--max-beams beams",
            path=path,
            record=record,
        )


def read_head(path: Path, max_bytes: int = 65536) -> bytes:
    """The first ``max_bytes`` bytes of the (decompressed) content.

    Raises
    ------
    LogFormatError
        When a gzip file is corrupt before ``max_bytes`` of data.
    """
    try:
        if is_gzip(path):
            with gzip.open(path, "rb") as fh:
                return _read_upto(fh, max_bytes)
        with path.open("rb") as fh:
            return fh.read(max_bytes)
    except _GZIP_ERRORS as exc:
        raise LogFormatError(f"the gzip data is truncated or corrupt ({exc})", path=path) from None


def _read_upto(fh: IO[bytes], max_bytes: int) -> bytes:
    """Read up to ``max_bytes``, returning what was decompressed before a truncation."""
    chunks: list[bytes] = []
    size = 0
    try:
        while size < max_bytes:
            chunk = fh.read(min(8192, max_bytes - size))
            if not chunk:
                break
            chunks.append(chunk)
            size += len(chunk)
    except EOFError:
        if not chunks:
            raise
    return b"".join(chunks)


def parse_floats(
    tokens: Sequence[str],
    field_name: Callable[[int], str],
    *,
    path: Path,
    record: int,
) -> np.ndarray:
    """Parse tokens as float64 in one numpy call; on failure name the bad field.

    Parameters
    ----------
    tokens:
        The text values.
    field_name:
        Maps a position in ``tokens`` to the field name used in the error.
    path, record:
        File and line number for the error.

    Raises
    ------
    LogFormatError
        When a token is not a number.
    """
    try:
        return np.array(tokens, dtype=np.float64)
    except ValueError:
        pass
    for position, token in enumerate(tokens):
        try:
            float(token)
        except ValueError:
            raise LogFormatError(
                f"not a number: {token!r}", path=path, record=record, field=field_name(position)
            ) from None
    raise LogFormatError("cannot parse the numbers", path=path, record=record)  # pragma: no cover


def parse_int(token: str, field: str, *, path: Path, record: int, minimum: int = 0) -> int:
    """Parse a count field as a non-negative integer naming ``field`` on failure."""
    try:
        value = int(token)
    except ValueError:
        raise LogFormatError(
            f"not an integer: {token!r}", path=path, record=record, field=field
        ) from None
    if value < minimum:
        raise LogFormatError(
            f"must be at least {minimum}, got {value}", path=path, record=record, field=field
        )
    return value
