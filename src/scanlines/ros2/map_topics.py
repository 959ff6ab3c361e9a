"""A line map as ROS 2 publishes maps: a ``nav_msgs/OccupancyGrid`` and a ``MarkerArray``."""

from __future__ import annotations

import math

import numpy as np

from scanlines.errors import ParameterError
from scanlines.map.align import LineSet
from scanlines.map.frame import LocalFrame
from scanlines.ros2 import messages as msg

__all__ = ["CELL", "map_markers", "occupancy_grid", "rasterise"]

#: The grid's cell (metres).
CELL = 0.05
#: Cells beyond the lines on each side.
MARGIN_CELLS = 10
#: The most cells a grid may have (a ROS 2 message of int8 cells: 256 MB).
MAX_CELLS = 256_000_000
OCCUPIED, FREE = 100, 0
MAP_MARKER_NS = "map_lines"
MAP_MARKER_WIDTH = 0.05
MAP_MARKER_COLOR = (0.2, 0.2, 0.2, 1.0)


def rasterise(lines: LineSet, frame: LocalFrame, cell: float = CELL):
    """The lines as a grid of ``cell`` metres: the cells (rows along y, int8, occupied
    where a line passes, free elsewhere: a line map holds no free space of its own, so
    none is unknown) and the world position of cell (0, 0)'s corner."""
    start = frame.world(np.asarray(lines.start, dtype=np.float64).reshape(-1, 2))
    end = frame.world(np.asarray(lines.end, dtype=np.float64).reshape(-1, 2))
    if not len(start):
        return np.full((1, 1), FREE, dtype=np.int8), (float(frame.x0), float(frame.y0))
    low = np.floor(np.minimum(start, end).min(axis=0) / cell) * cell - MARGIN_CELLS * cell
    high = np.maximum(start, end).max(axis=0) + MARGIN_CELLS * cell
    width, height = (int(v) for v in np.ceil((high - low) / cell))
    if width * height > MAX_CELLS:
        raise ParameterError(
            f"the map's grid would have {width:,} x {height:,} cells of {cell} m "
            f"(at most {MAX_CELLS:,})"
        )
    grid = np.full((height, width), FREE, dtype=np.int8)
    for a, b in zip(start, end, strict=True):
        steps = max(2, math.ceil(np.hypot(*(b - a)) / (0.5 * cell)) + 1)
        points = a + np.linspace(0.0, 1.0, steps)[:, None] * (b - a)
        cells = np.floor((points - low) / cell).astype(np.int64)
        grid[np.clip(cells[:, 1], 0, height - 1), np.clip(cells[:, 0], 0, width - 1)] = OCCUPIED
    return grid, (float(low[0]), float(low[1]))


def occupancy_grid(
    lines: LineSet, frame: LocalFrame, frame_id: str, stamp: msg.Time, cell: float = CELL
) -> msg.OccupancyGrid:
    """The map's lines rasterised (:func:`rasterise`) as a ``nav_msgs/OccupancyGrid`` in
    ``frame_id``."""
    grid, (x0, y0) = rasterise(lines, frame, cell)
    height, width = grid.shape
    return msg.OccupancyGrid(
        header=msg.Header(stamp=stamp, frame_id=frame_id),
        info=msg.MapMetaData(
            map_load_time=stamp,
            resolution=cell,
            width=width,
            height=height,
            origin=msg.Pose(position=msg.Point(x0, y0, 0.0)),
        ),
        data=grid.ravel().tolist(),
    )


def map_markers(lines: LineSet, frame: LocalFrame, frame_id: str, stamp: msg.Time):
    """The map's lines as a ``MarkerArray``: one line list in ``frame_id``."""
    start = frame.world(np.asarray(lines.start, dtype=np.float64).reshape(-1, 2))
    end = frame.world(np.asarray(lines.end, dtype=np.float64).reshape(-1, 2))
    points = []
    for a, b in zip(start, end, strict=True):
        points += [
            msg.Point(float(a[0]), float(a[1]), 0.0),
            msg.Point(float(b[0]), float(b[1]), 0.0),
        ]
    marker = msg.Marker(
        header=msg.Header(stamp=stamp, frame_id=frame_id),
        ns=MAP_MARKER_NS,
        id=0,
        type=msg.Marker.LINE_LIST,
        action=msg.Marker.ADD,
        scale=msg.Vector3(MAP_MARKER_WIDTH, 0.0, 0.0),
        color=msg.ColorRGBA(*MAP_MARKER_COLOR),
        points=points,
    )
    return msg.MarkerArray(markers=[marker])
