"""Pictures of scans and the features extracted from them."""

from __future__ import annotations

from collections.abc import Sequence
from typing import TYPE_CHECKING

import numpy as np

from scanlines import Extraction, Scan
from scanlines.viz.figures import pyplot

if TYPE_CHECKING:
    from matplotlib.axes import Axes
    from matplotlib.figure import Figure

__all__ = ["SEGMENT_COLOURS", "plot_extraction", "plot_grid"]

SEGMENT_COLOURS = ("#1f77b4", "#ff7f0e", "#2ca02c", "#9467bd", "#8c564b", "#e377c2", "#17becf")
"""Colours of consecutive segments (matplotlib's tab10 without red, grey and olive)."""

EVENT_MARKERS = {
    "breakpoints": ("^", "#d62728"),
    "corners": ("s", "#000000"),
    "outliers": ("x", "#bcbd22"),
}
"""The marker and colour of each kind of point feature, in a panel and in the legend."""

SENSOR_MARKER = (3, 0, -90)
"""The sensor at the origin: a triangle pointing along x."""

LEGEND_LABELS = ("returns", "segments", "breakpoints", "corners", "outliers", "sensor")
"""The entries of a grid's legend, in order."""


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
        _, ax = pyplot().subplots(figsize=(7, 7))
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
    for name, beams in (
        ("breakpoints", extraction.breakpoints),
        ("corners", extraction.corners),
        ("outliers", extraction.outliers),
    ):
        _events(ax, points, beams, *EVENT_MARKERS[name], name)
    ax.plot([0], [0], marker=SENSOR_MARKER, ms=12, c="k", ls="none", label="sensor")
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
    plt = pyplot()
    rows = max(1, -(-len(items) // columns))
    fig, axes = plt.subplots(rows, columns, figsize=(size * columns, size * rows), squeeze=False)
    for ax, (scan, extraction, title) in zip(axes.flat, items, strict=False):
        plot_extraction(scan, extraction, ax, title=title, legend=False)
    for ax in list(axes.flat)[len(items) :]:
        ax.axis("off")
    fig.legend(
        handles=legend_handles(), loc="upper center", ncols=len(LEGEND_LABELS), fontsize=9,
        frameon=False, bbox_to_anchor=(0.5, 1.0),
    )  # fmt: skip
    legend_height = 0.35 / (size * rows)  # inches of the legend row, as a figure fraction
    fig.tight_layout(rect=(0, 0, 1, 1 - legend_height))
    return fig


def legend_handles() -> list:
    """One legend entry per kind drawn in a panel, styled as the panels draw it: a grid
    has one legend for all its panels (a panel may have no corners, the legend still does)."""
    from matplotlib.lines import Line2D

    handles = [
        Line2D([], [], marker="o", ms=4, c="0.6", ls="none", label="returns"),
        Line2D([], [], lw=2.2, c=SEGMENT_COLOURS[0], label="segments"),
    ]
    for name in ("breakpoints", "corners", "outliers"):
        marker, colour = EVENT_MARKERS[name]
        handles.append(
            Line2D(
                [], [], marker=marker, ms=7, mfc="none", mec=colour, mew=1.6, ls="none", label=name
            )
        )
    handles.append(Line2D([], [], marker=SENSOR_MARKER, ms=12, c="k", ls="none", label="sensor"))
    return handles
