"""Getting matplotlib, and writing a figure to a file.

Every figure of :mod:`scanlines.viz` is drawn with the pyplot :func:`pyplot` returns;
matplotlib is imported then, not when scanlines is.
"""

from __future__ import annotations

from pathlib import Path
from typing import Any

__all__ = ["pyplot", "save"]

FILE_BACKENDS = ("agg", "pdf", "svg", "cairo")
"""Backends that draw to files; any other (an interactive one) is replaced by Agg."""


def pyplot() -> Any:
    """``matplotlib.pyplot``, on a backend that writes files (Agg unless one already does)."""
    import matplotlib

    if matplotlib.get_backend().lower() not in FILE_BACKENDS:
        matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    return plt


def save(figure_or_axes: Any, path: str | Path, *, dpi: int = 130) -> Path:
    """Save a figure (or the figure of an axes) to ``path`` and close it."""
    figure = getattr(figure_or_axes, "figure", figure_or_axes)
    path = Path(path)
    path.parent.mkdir(parents=True, exist_ok=True)
    figure.savefig(path, dpi=dpi, bbox_inches="tight")
    pyplot().close(figure)
    return path
