"""Pictures of scans and extracted features (matplotlib, imported on use)."""

from __future__ import annotations

from collections.abc import Sequence
from pathlib import Path
from typing import TYPE_CHECKING, Any

import numpy as np

from scanlines.extraction import Extraction
from scanlines.scan import Scan

if TYPE_CHECKING:
    from matplotlib.axes import Axes
    from matplotlib.figure import Figure

__all__ = ["plot_extraction", "plot_grid", "save"]

SEGMENT_COLOURS = ("#1f77b4", "#ff7f0e", "#2ca02c", "#9467bd", "#8c564b", "#e377c2", "#17becf")


def _pyplot():
    import matplotlib

    if matplotlib.get_backend().lower() not in ("agg", "pdf", "svg", "cairo"):
        matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    return plt


def plot_extraction(
    scan: Scan,
    extraction: Extraction,
    ax: Axes | None = None,
    *,
    title: str | None = None,
    legend: bool = True,
) -> Axes:
    """Draw the scan's points, the segments, breakpoints, corners and outliers.

    Coordinates are the sensor frame (x forward, y left), in metres.
    """
    if ax is None:
        _, ax = _pyplot().subplots(figsize=(7, 7))
    points = scan.points
    ax.scatter(points[:, 0], points[:, 1], s=4, c="0.6", label="returns", zorder=1)
    for k, row in enumerate(extraction.lines):
        colour = SEGMENT_COLOURS[k % len(SEGMENT_COLOURS)]
        ax.plot(
            row[[2, 4]],
            row[[3, 5]],
            "-",
            lw=2.2,
            c=colour,
            zorder=2,
            label="segments" if k == 0 else None,
        )
    _events(ax, points, extraction.breakpoints, "^", "#d62728", "breakpoints")
    _events(ax, points, extraction.corners, "s", "#000000", "corners")
    _events(ax, points, extraction.outliers, "x", "#bcbd22", "outliers")
    ax.plot([0], [0], marker=(3, 0, -90), ms=12, c="k", ls="none", label="sensor")
    ax.set_aspect("equal", adjustable="datalim")
    ax.set_xlabel("x (m)")
    ax.set_ylabel("y (m)")
    ax.grid(True, lw=0.3)
    counts = ", ".join(
        _counted(n, noun)
        for n, noun in (
            (len(extraction), "segment"),
            (len(extraction.breakpoints), "breakpoint"),
            (len(extraction.corners), "corner"),
        )
    )
    ax.set_title(f"{title}\n{counts}" if title else f"{extraction.method}: {counts}", fontsize=10)
    if legend:
        ax.legend(loc="best", fontsize=8, markerscale=1.5)
    return ax


def _counted(n: int, noun: str) -> str:
    return f"{n} {noun}" + ("" if n == 1 else "s")


def _events(ax: Axes, points: np.ndarray, beams: np.ndarray, marker: str, colour: str, label: str):
    if beams.size:
        ax.plot(
            points[beams, 0],
            points[beams, 1],
            marker,
            ms=7,
            mfc="none",
            mec=colour,
            mew=1.6,
            ls="none",
            label=label,
            zorder=3,
        )


def plot_grid(
    items: Sequence[tuple[Scan, Extraction, str]], *, columns: int = 3, size: float = 4.0
) -> Figure:
    """A grid of :func:`plot_extraction` panels, one per ``(scan, extraction, title)``."""
    plt = _pyplot()
    rows = max(1, -(-len(items) // columns))
    fig, axes = plt.subplots(rows, columns, figsize=(size * columns, size * rows), squeeze=False)
    for ax, (scan, extraction, title) in zip(axes.flat, items, strict=False):
        plot_extraction(scan, extraction, ax, title=title, legend=False)
    for ax in list(axes.flat)[len(items) :]:
        ax.axis("off")
    fig.tight_layout()
    return fig


def save(figure_or_axes: Any, path: str | Path, *, dpi: int = 130) -> Path:
    """Save a figure (or the figure of an axes) to ``path`` and close it."""
    figure = getattr(figure_or_axes, "figure", figure_or_axes)
    path = Path(path)
    path.parent.mkdir(parents=True, exist_ok=True)
    figure.savefig(path, dpi=dpi, bbox_inches="tight")
    _pyplot().close(figure)
    return path
