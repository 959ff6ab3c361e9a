"""Getting matplotlib, and writing a figure to a file.

Every figure of :mod:`scanlines.viz` is drawn with the pyplot :func:`pyplot` returns;
matplotlib is imported then, not when scanlines is.
"""

from __future__ import annotations

from pathlib import Path
from typing import Any

from scanlines.errors import ParameterError

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
    """Save a figure (or the figure of an axes) to ``path`` and close it; the file
    appears complete or not at all. The format is the suffix's (``.png``, ``.pdf``,
    ``.svg``...); another suffix is a :class:`~scanlines.ParameterError`, and a file that
    cannot be written (a read-only folder, a full disk) an
    :class:`~scanlines.outputs.OutputError` naming ``path``."""
    from scanlines.outputs import OutputError, commit, discard, temp_path, write_error

    figure = getattr(figure_or_axes, "figure", figure_or_axes)
    path = Path(path)
    kind = path.suffix.lower().lstrip(".")
    if kind not in figure.canvas.get_supported_filetypes():
        pyplot().close(figure)
        known = ", ".join(sorted(figure.canvas.get_supported_filetypes()))
        raise ParameterError(f"{path}: figures are written as one of {known}, not {kind!r}")
    temporary = temp_path(path)
    try:
        path.parent.mkdir(parents=True, exist_ok=True)
        figure.savefig(temporary, dpi=dpi, bbox_inches="tight", format=kind)
        commit([(temporary, path)], overwrite=True)
    except OutputError:
        raise
    except OSError as error:
        raise write_error(path, error, "the figure") from None
    finally:
        discard(temporary)
        pyplot().close(figure)
    return path
