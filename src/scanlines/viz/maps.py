"""A line map drawn with matplotlib (``scanlines map --plot``)."""

from __future__ import annotations

from typing import TYPE_CHECKING

import numpy as np

from scanlines.viz.figures import pyplot

if TYPE_CHECKING:
    from matplotlib.axes import Axes

    from scanlines.map.fusion import MapLines

__all__ = ["plot_map"]


def plot_map(
    lines: MapLines,
    ax: Axes | None = None,
    *,
    title: str | None = None,
    trajectory: np.ndarray | None = None,
) -> Axes:
    """Draw the map's lines in the world frame (metres), coloured by how many scans saw
    each (log scale); ``trajectory`` (``N x 2``), where given, under them."""
    from matplotlib.collections import LineCollection
    from matplotlib.colors import LogNorm

    if ax is None:
        _, ax = pyplot().subplots(figsize=(8, 8))
    if trajectory is not None and len(trajectory):
        ax.plot(trajectory[:, 0], trajectory[:, 1], lw=0.6, c="tab:orange", alpha=0.6,
                label="poses", zorder=1)  # fmt: skip
    if len(lines):
        segments = np.stack((lines.world_start, lines.world_end), axis=1)
        scans = np.maximum(lines.scans, 1)
        shade = LineCollection(
            segments, cmap="viridis", norm=LogNorm(1, max(int(scans.max()), 2)), linewidths=1.2,
            zorder=2,
        )  # fmt: skip
        shade.set_array(scans.astype(float))
        ax.add_collection(shade)
        ax.figure.colorbar(shade, ax=ax, shrink=0.6, label="scans that saw the line")
        ax.autoscale()
    ax.set_aspect("equal")
    ax.set_xlabel("x (m)")
    ax.set_ylabel("y (m)")
    length = float(lines.lengths.sum()) if len(lines) else 0.0
    caption = f"{len(lines)} lines, {length:.0f} m"
    ax.set_title(f"{title}\n{caption}" if title else caption)
    if trajectory is not None and len(trajectory):
        ax.legend(loc="upper right")
    return ax
