"""Where in a configuration file a mistake is: tomllib's position, the line setting a key."""

from __future__ import annotations

import re

_TOML_POSITION = re.compile(r"\s*\(at line (\d+), column (\d+)\)$")
_TOML_END = re.compile(r"\s*\(at end of document\)$")


def _toml_error(text: str) -> tuple[str, int | None]:
    """tomllib's message without its position, and the line it names."""
    match = _TOML_POSITION.search(text)
    if match:
        return f"{text[: match.start()]} (column {match.group(2)})", int(match.group(1))
    return _TOML_END.sub(" (at the end of the file)", text), None


def _line_of(text: str | None, key: str | None) -> int | None:
    """The line of the file ``text`` that sets ``key`` (``"method"``, ``"params.k"``),
    found by a plain scan of the lines (good for the files :mod:`scanlines.config` writes and what
    people write by hand), or ``None``."""
    if text is None or key is None:
        return None
    table, _, name = key.rpartition(".")
    quoted = rf"(?:{re.escape(name)}|\"{re.escape(name)}\"|'{re.escape(name)}')"
    assignment = re.compile(rf"\s*{quoted}\s*=")
    dotted = re.compile(rf"\s*{re.escape(table)}\s*\.\s*{quoted}\s*=") if table else None
    header = re.compile(r"\s*\[\s*([^\[\]]*?)\s*\]\s*(?:#.*)?$")
    current, table_line = "", None
    for number, line in enumerate(text.splitlines(), start=1):
        found = header.match(line)
        if found:
            current = found.group(1).strip("\"'")
            if current == key:
                return number
            if current == table:
                table_line = number
            continue
        if current == table and assignment.match(line):
            return number
        if current == "" and dotted is not None and dotted.match(line):
            return number
    return table_line
