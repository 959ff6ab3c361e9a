"""Logs moved in the world: the shipped CARMEN excerpts with every pose shifted by a
constant (``FLASER``/``RLASER`` laser and robot poses, ``ODOM``), the same trajectory with
its world origin elsewhere."""

from __future__ import annotations

import gzip
from pathlib import Path

from scanlines.data import sample


def shift_carmen(text: str, dx: float, dy: float) -> str:
    """A CARMEN log's text with every pose moved by ``(dx, dy)`` metres."""
    out = []
    for line in text.splitlines():
        fields = line.split(" ")
        keyword = fields[0]
        if keyword in ("FLASER", "RLASER"):
            at = 2 + int(fields[1])
            for k, d in ((at, dx), (at + 1, dy), (at + 3, dx), (at + 4, dy)):
                fields[k] = repr(float(fields[k]) + d)
        elif keyword == "ODOM":
            fields[1] = repr(float(fields[1]) + dx)
            fields[2] = repr(float(fields[2]) + dy)
        out.append(" ".join(fields))
    return "\n".join(out) + "\n"


def shifted_sample(name: str, offset: float, folder: Path) -> Path:
    """The shipped excerpt ``name`` (``"intel"``, ``"freiburg"``) with every pose moved by
    ``offset`` metres in x and in y, written into ``folder``."""
    with gzip.open(sample(name), "rt", encoding="utf-8") as fh:
        text = fh.read()
    path = Path(folder) / f"{name}_{offset:g}.log"
    path.write_text(shift_carmen(text, offset, offset), encoding="utf-8")
    return path
