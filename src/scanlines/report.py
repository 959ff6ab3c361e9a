"""Writing results down: markdown tables, number formats, JSON values, CSV files.

Every report (the ``eval`` outputs, the ``bench`` tables, ``RESULTS.md``,
``PERFORMANCE.md``) and the command line tables write through this one module:

* :func:`number` formats a value, or gives ``-`` when there is none (``None``, NaN,
  infinite); :func:`percent` and :func:`microseconds` are its two special cases;
* :func:`markdown_table` writes a table, and :class:`TableData` holds one with its title
  and caption for the command (rich) and the pages (markdown) alike;
* :func:`jsonable` is the one conversion every JSON output of scanlines uses (NaN
  becomes ``null``, infinities ``"inf"``/``"-inf"``), :func:`write_csv` writes rows of
  dicts;
* :func:`command_line` is the command a page records as its origin.
"""

from __future__ import annotations

import csv
import math
import sys
from collections.abc import Mapping, Sequence
from dataclasses import dataclass
from pathlib import Path
from typing import Any

import numpy as np

__all__ = [
    "MISSING",
    "TableData",
    "command_line",
    "jsonable",
    "markdown_table",
    "microseconds",
    "number",
    "percent",
    "write_csv",
]

MISSING = "-"
"""What a table shows where there is no number."""


# --------------------------------------------------------------------------- numbers


def number(value: float | None, fmt: str = ".2f") -> str:
    """``value`` in format ``fmt``; :data:`MISSING` for ``None``, NaN and infinities."""
    if value is None or (isinstance(value, float) and not math.isfinite(value)):
        return MISSING
    return format(value, fmt)


def percent(share: float | None) -> str:
    """A share (0.25) as a percentage with one decimal (``25.0 %``)."""
    if share is None or not math.isfinite(share):
        return MISSING
    return f"{100 * share:.1f} %"


def microseconds(value: float | None) -> str:
    """A time in microseconds with three or four significant digits (``1,234``, ``56.7``)."""
    if value is None or not math.isfinite(value):
        return MISSING
    if value >= 100:
        return f"{value:,.0f}"
    if value >= 10:
        return f"{value:.1f}"
    if value >= 1:
        return f"{value:.2f}"
    return f"{value:.3f}"


# --------------------------------------------------------------------------- tables


def markdown_table(columns: Sequence[str], rows: Sequence[Sequence[str]], left: int = 1) -> str:
    """A markdown table; the first ``left`` columns are aligned left, the rest right."""

    def cell(text: object) -> str:
        return str(text).replace("|", "\\|")

    lines = ["| " + " | ".join(cell(c) for c in columns) + " |"]
    lines.append("|" + "|".join(":---" if i < left else "---:" for i in range(len(columns))) + "|")
    lines += ["| " + " | ".join(cell(c) for c in row) + " |" for row in rows]
    return "\n".join(lines) + "\n"


@dataclass(frozen=True)
class TableData:
    """A table as text cells, rendered by the commands (rich) and the pages (markdown).

    Attributes
    ----------
    title:
        One line above the table.
    columns, rows:
        Header and cells.
    caption:
        Text below the table (none when empty).
    left:
        Leading columns aligned left; the rest are numbers, aligned right.
    """

    title: str
    columns: tuple[str, ...]
    rows: tuple[tuple[str, ...], ...]
    caption: str = ""
    left: int = 1

    def to_markdown(self, heading: str = "###") -> str:
        """The title as a ``heading`` line, the table, then the caption."""
        text = f"{heading} {self.title}\n\n" + markdown_table(self.columns, self.rows, self.left)
        return text + (f"\n{self.caption}\n" if self.caption else "")


# --------------------------------------------------------------------------- files


def jsonable(value: Any) -> Any:
    """``value`` with mappings as dicts (keys as strings), arrays and tuples as lists, numpy
    scalars as Python ones, NaN as ``None`` and infinities as ``"inf"`` / ``"-inf"`` (JSON
    has no number for them); anything else JSON cannot hold becomes its ``str``."""
    if isinstance(value, Mapping):
        return {str(k): jsonable(v) for k, v in value.items()}
    if isinstance(value, np.ndarray):
        return jsonable(value.tolist())
    if isinstance(value, list | tuple):
        return [jsonable(v) for v in value]
    if isinstance(value, np.generic):
        return jsonable(value.item())
    if isinstance(value, float) and not math.isfinite(value):
        return None if math.isnan(value) else ("inf" if value > 0 else "-inf")
    if value is None or isinstance(value, bool | int | float | str):
        return value
    return str(value)


def write_csv(path: Path, rows: list[dict[str, Any]]) -> Path:
    """Write ``rows`` (dicts with the same keys) as CSV with a header line."""
    with path.open("w", newline="") as handle:
        writer = csv.DictWriter(handle, fieldnames=list(rows[0]) if rows else [])
        writer.writeheader()
        writer.writerows(rows)
    return path


def command_line(argv: Sequence[str] | None = None, program: str = "scanlines") -> str:
    """``program`` plus the arguments of this process, shell-quoted."""
    import shlex

    args = list(sys.argv[1:] if argv is None else argv)
    return " ".join([program, shlex.join(args)]) if args else program
