"""The filter of ``scanlines localize``: a scan's returns matched to a line map, odometry as
the prior, the odometry's own errors learnt on the way.

::

    from scanlines.map.filter import LineMapFilter

    tracker = LineMapFilter(lines)                 # a LineSet in the map's local frame
    tracker.start(pose)                            # where the robot stands (local frame)
    step = tracker.step(points, increment)         # each scan: sensor-frame returns, the
    step.pose, step.covariance, step.status        # odometry's move since the last scan

The state is the sensor's pose and what is systematically wrong with the odometry: a
heading drift per metre driven (a wheel a little larger than the other turns the robot as it
drives), a distance scale, and where the sensor sits on the odometry's frame (a lever: a
sensor ahead of the wheels' axle moves sideways when the robot turns in place). An extended
Kalman filter predicts each scan's state from the odometry increment, corrected by these,
with the increment's noise (:class:`FilterSettings`); the scan's returns then correct it (a
few Gauss-Newton steps on their distances to their map lines, the prediction's covariance as
the prior). What a scene does not pin (a corridor's axis, a room the map lacks) stays with
the odometry, whose errors the filter has been learning wherever the map pinned the pose: on
the raw Intel log it learns that the odometry turns 3.3 degrees too little per metre,
over-counts distance by 3.8 % and sits 9 cm behind the laser (docs/MEASUREMENTS.md).

Matching, made to refuse rather than pull wrongly:

* each return needs a local line (its neighbours in beam order, ``normal_window`` each side
  within ``neighbour_gap``, spread across at most ``flatness`` times along), and its map line
  must run the same way (within ``normal_tolerance``);
* the map line is the nearest such line within the return's gate: ``gate_base`` plus
  ``gate_sigmas`` standard deviations of the return's predicted position (position and
  heading times range), within ``gate_min`` and ``gate_max``; the candidates come from a
  uniform grid of the map's lines (:func:`line_grid`), so a query looks at the few lines of
  one cell, whatever the map's size;
* a map line is a wall's face seen from one side or both (:mod:`scanlines.map.fusion`);
  with ``sides`` a return matches it only from a side it was seen from, so the far face of
  a thin wall, or a wall the map holds only from behind, does not pull the pose. Off by
  default: on the raw Intel scans it halves the largest error (0.41 to 0.23 m), on raw
  Freiburg it raises the RMSE from 53 mm to 0.35 m, where the robot sees walls the map holds
  only from their other side (docs/MEASUREMENTS.md);
* a map line met by fewer than ``line_returns`` returns is ignored (a door that moved, a
  corner's few returns);
* each residual's variance is the return's noise plus ``line_sigma`` squared times the
  returns on its line: a map line's own error is shared by its returns, so one long wall
  cannot count as hundreds of independent measurements;
* Huber weights (``huber`` standard deviations); the correction is refused if its squared
  Mahalanobis distance from the prediction exceeds ``max_chi_square``.

A scan refused ("did not fit": too few returns on map lines, counting only those whose
weight did not vanish, as it does for a residual too large to weigh, or a correction
inconsistent with the prediction) keeps the predicted state and its grown covariance, so the
gate widens until the map is caught again.
"""

from __future__ import annotations

import math
from typing import ClassVar, NamedTuple

import numpy as np

from scanlines.geometry.poses import Pose
from scanlines.map.align import LineSet
from scanlines.map.fusion import BOTH
from scanlines.params import MAX_COUNT, MAX_METRES, KernelField, Param, choice, integer, number
from scanlines.params.tables import Groups, SettingsTable

__all__ = ["FilterSettings", "FilterStep", "LineGrid", "LineMapFilter", "line_grid"]

#: The prior (standard deviations: metres, radians) about an initial pose.
INITIAL_SIGMA = (0.1, math.radians(3.0))
#: The grid's cell (metres) and the most cells a grid takes (larger maps get larger cells).
CELL = 0.5
MAX_CELLS = 4_000_000
#: The cell (metres) of a second, finer grid, for the returns whose gate is at most twice
#: ``gate_min`` (nine in ten while the filter tracks): a query there looks at a third as many
#: lines, and finds the same one.
NEAR_CELL = 0.1
#: Statuses of a step, by the kernel's code.
STATUSES = ("aligned", "too few returns on map lines", "inconsistent with the prediction")


_METRES = number(low=0.0, high=MAX_METRES)
_POSITIVE_METRES = number(low=0.0, low_open=True, high=MAX_METRES)
_SHARE = number(low=0.0)
_RADIANS = number(low=0.0, high=math.pi)
_COUNT = integer(1, MAX_COUNT)
_NOT_READ = ()  # a setting of the Python side only: no field of the kernel's record


class FilterSettings(SettingsTable):
    """The constants of the filter (metres, radians; module docstring): the odometry
    increment's noise and the priors and random walks of its errors, the association of
    returns to map lines, the residuals' noise, the Gauss-Newton steps and the gate on the
    correction, the returns used and whether walls have a side."""

    groups: ClassVar[Groups] = {
        "odometry": {
            "odometry_floor": Param(0.005, _METRES, "an increment's x, y sigma at rest (m)"),
            "odometry_per_metre": Param(0.05, _SHARE, "x, y sigma per metre driven (m/m)"),
            "turn_floor": Param(math.radians(0.2), _RADIANS, "heading sigma at rest (rad)"),
            "turn_per_radian": Param(0.05, _SHARE, "heading sigma per radian turned"),
            "turn_per_metre": Param(0.02, _SHARE, "heading sigma per metre driven (rad/m)"),
            "drift_sigma": Param(0.1, _SHARE, "prior of the heading drift (rad/m)", _NOT_READ),
            "scale_sigma": Param(0.05, _SHARE, "prior of the odometry's scale error", _NOT_READ),
            "lever_sigma": Param(0.2, _METRES, "prior of the laser's lever (m)", _NOT_READ),
            "drift_walk": Param(0.0005, _SHARE, "the drift's random walk per metre driven"),
            "scale_walk": Param(0.0005, _SHARE, "the scale's random walk per metre driven"),
        },
        "association": {
            "normal_window": Param(2, _COUNT, "neighbours each side of a return's local line"),
            "neighbour_gap": Param(0.3, _METRES, "farthest neighbour of that line (m)"),
            "flatness": Param(0.3, _SHARE, "largest spread across that line over along it"),
            "normal_tolerance": Param(
                math.radians(30.0),
                number(low=0.0, high=math.pi / 2),
                "largest angle between a return's line and its map line (rad)",
                (KernelField("normal_cosine", math.cos),),
            ),
            "gate_base": Param(0.05, _METRES, "a return's gate at a certain pose (m)"),
            "gate_sigmas": Param(2.0, _SHARE, "the gate's growth in position sigmas"),
            "gate_min": Param(0.1, _POSITIVE_METRES, "smallest gate (m)"),
            "gate_max": Param(0.5, _POSITIVE_METRES, "largest gate (m)"),
            "line_returns": Param(8, _COUNT, "returns a map line needs to count"),
        },
        "noise": {
            "return_sigma": Param(0.01, _POSITIVE_METRES, "a return's residual sigma (m)"),
            "line_sigma": Param(0.02, _METRES, "a map line's sigma, shared by its returns (m)"),
            "huber": Param(2.0, _SHARE, "Huber's width (standard deviations)"),
        },
        "solver": {
            "iterations": Param(10, _COUNT, "most Gauss-Newton steps a scan"),
            "tolerance": Param(1e-5, _METRES, "a step this small ends them (m, rad)"),
            "min_pairs": Param(10, _COUNT, "returns on map lines a correction needs"),
            "max_chi_square": Param(
                16.27, _SHARE, "largest squared distance of the correction from the prediction"
            ),
        },
        "scan": {
            "max_points": Param(
                400, integer(0, MAX_COUNT), "returns used, evenly subsampled (0: all)", _NOT_READ
            ),
            "sides": Param(
                False,
                choice(True, False),
                "a return matches only a face seen from its side",
                _NOT_READ,
            ),
        },
    }

    def check(self) -> None:
        self.require_at_most("gate_min", "gate_max")


class LineGrid(NamedTuple):
    """A uniform grid over map lines: ``shape`` (x0, y0, cell, nx, ny), and for cell
    ``c = i * ny + j`` (``i`` along x) the ids ``cell_lines[cell_start[c]:cell_start[c + 1]]``
    of every line within ``reach`` of the cell."""

    shape: np.ndarray
    cell_start: np.ndarray
    cell_lines: np.ndarray
    reach: float

    def candidates(self, point) -> np.ndarray:
        """The line ids of the cell holding ``point`` (none outside the grid)."""
        x0, y0, cell, nx, ny = self.shape
        i, j = math.floor((point[0] - x0) / cell), math.floor((point[1] - y0) / cell)
        if not (0 <= i < nx and 0 <= j < ny):
            return self.cell_lines[:0]
        c = int(i * int(ny) + j)
        return self.cell_lines[self.cell_start[c] : self.cell_start[c + 1]]


def line_grid(lines: LineSet, reach: float, cell: float = CELL) -> LineGrid:
    """The :class:`LineGrid` of ``lines``: each cell lists the lines that come within
    ``reach`` (metres) of some point of the cell, so that every line within ``reach`` of a
    point is among its cell's."""
    start = np.asarray(lines.start, dtype=np.float64).reshape(-1, 2)
    end = np.asarray(lines.end, dtype=np.float64).reshape(-1, 2)
    if not len(start):
        shape = np.array([0.0, 0.0, cell, 1.0, 1.0])
        return LineGrid(shape, np.zeros(2, np.int64), np.zeros(0, np.int64), reach)
    # Half a cell beyond the reach on each side: a point at exactly ``reach`` stays inside.
    lo = np.minimum(start, end).min(axis=0) - reach - 0.5 * cell
    hi = np.maximum(start, end).max(axis=0) + reach + 0.5 * cell
    while np.prod(np.floor((hi - lo) / cell) + 1) > MAX_CELLS:
        cell *= 2.0
    nx, ny = (int(v) for v in np.floor((hi - lo) / cell) + 1)
    # The centre's distance to the cell's corners, and a hair more: the test below must
    # not lose a line at exactly ``reach`` to rounding.
    slack = (reach + cell * math.sqrt(0.5)) * (1.0 + 1e-9) + 1e-12
    first = np.floor((np.minimum(start, end) - reach - lo) / cell).astype(np.int64)
    last = np.floor((np.maximum(start, end) + reach - lo) / cell).astype(np.int64)
    first, last = np.maximum(first, 0), np.minimum(last, [nx - 1, ny - 1])
    boxes = np.maximum(last - first + 1, 0)
    ids, cells = [], []
    for lines_of in _batches(boxes[:, 0] * boxes[:, 1], GRID_BATCH):
        near, line_cell = _cells_near(start, end, first, boxes, lines_of, lo, cell, slack)
        cells.append(line_cell[0][near] * ny + line_cell[1][near])
        ids.append(lines_of[near])
    cell_of = np.concatenate(cells).astype(np.int64)
    line_of = np.concatenate(ids)
    order = np.argsort(cell_of, kind="stable")
    cell_start = np.zeros(nx * ny + 1, dtype=np.int64)
    np.cumsum(np.bincount(cell_of, minlength=nx * ny), out=cell_start[1:])
    shape = np.array([lo[0], lo[1], cell, nx, ny], dtype=np.float64)
    return LineGrid(shape, cell_start, np.ascontiguousarray(line_of[order]), reach)


#: The most (line, cell) pairs :func:`line_grid` tests at once (memory, not results).
GRID_BATCH = 1 << 15


def _batches(sizes: np.ndarray, most: int):
    """For consecutive runs of items (``sizes`` each) adding up to about ``most`` (one item
    at least), each item's id repeated its size."""
    ends = np.cumsum(sizes)
    begin = 0
    while begin < len(sizes):
        done = ends[begin - 1] if begin else 0
        stop = max(int(np.searchsorted(ends, done + most, side="right")), begin + 1)
        yield np.repeat(np.arange(begin, stop), sizes[begin:stop])
        begin = stop


def _cells_near(start, end, first, boxes, lines_of, lo, cell: float, slack: float):
    """Of each line's box of cells (``lines_of``: a line id per cell of its box, in order),
    which cells' centres lie within ``slack`` of the line, and the cells (ix, iy)."""
    offset = np.flatnonzero(np.r_[True, lines_of[1:] != lines_of[:-1]])
    runs = np.diff(np.r_[offset, len(lines_of)])
    k = np.arange(len(lines_of)) - np.repeat(offset, runs)  # the cell's place in its box
    depth = boxes[lines_of, 1]
    ix, iy = first[lines_of, 0] + k // depth, first[lines_of, 1] + k % depth
    cx, cy = lo[0] + (ix + 0.5) * cell, lo[1] + (iy + 0.5) * cell
    a, ab = start[lines_of], end[lines_of] - start[lines_of]
    length2 = np.maximum(ab[:, 0] * ab[:, 0] + ab[:, 1] * ab[:, 1], 1e-18)
    t = np.clip(((cx - a[:, 0]) * ab[:, 0] + (cy - a[:, 1]) * ab[:, 1]) / length2, 0.0, 1.0)
    near = np.hypot(cx - a[:, 0] - t * ab[:, 0], cy - a[:, 1] - t * ab[:, 1]) <= slack
    return near, (ix, iy)


class FilterStep(NamedTuple):
    """One scan through the filter: the pose (local frame) and its 3 x 3 covariance, the
    predicted pose, the returns and map lines matched, the squared Mahalanobis distance of
    the correction, the status (:data:`STATUSES`), and the full state (pose, heading drift
    per metre, scale error) with its 5 x 5 covariance."""

    pose: Pose
    covariance: np.ndarray
    predicted: Pose
    pairs: int
    lines: int
    chi_square: float
    status: str
    state: np.ndarray
    state_covariance: np.ndarray

    @property
    def aligned(self) -> bool:
        return self.status == "aligned"


class LineMapFilter:
    """The filter on one map (``lines``: a :class:`~scanlines.map.align.LineSet`, local
    frame); :meth:`start`, then :meth:`step` for each scan in the log's order."""

    def __init__(self, lines: LineSet, settings: FilterSettings | None = None) -> None:
        self.settings = settings or FilterSettings()
        self.use_lines(lines)
        self._record = self.settings.record()
        self.state: np.ndarray | None = None
        self.covariance: np.ndarray | None = None
        self._first = True

    def use_lines(self, lines: LineSet) -> None:
        """Match the next scans to ``lines`` (a map that grows: ``scanlines map --align``);
        lines without ``sides`` are taken as seen from both sides."""
        sides = lines.sides
        if sides is None or not self.settings.sides:
            sides = np.full(len(lines.rho), BOTH)
        from scanlines import _core

        self.lines = LineSet(
            *(np.ascontiguousarray(a, dtype=np.float64).reshape(-1, *np.shape(a)[1:])
              for a in lines[:4]),
            np.ascontiguousarray(sides, dtype=np.int64),
        )  # fmt: skip
        self.grid = line_grid(self.lines, self.settings.gate_max)
        near = min(2.0 * self.settings.gate_min, self.settings.gate_max)
        self.near_grid = line_grid(self.lines, near, NEAR_CELL)
        self.normals = _core.line_normals(self.lines.alpha)

    def start(self, pose: Pose, sigma: tuple[float, float] = INITIAL_SIGMA) -> None:
        """Start (or restart) at the local ``pose`` with standard deviations ``sigma``
        (metres, radians); the odometry's errors start at zero with the settings' priors."""
        s = self.settings
        self.state = np.array([*map(float, pose), 0.0, 0.0, 0.0, 0.0])
        self.covariance = np.diag(
            [sigma[0] ** 2, sigma[0] ** 2, sigma[1] ** 2, s.drift_sigma**2, s.scale_sigma**2,
             s.lever_sigma**2, s.lever_sigma**2]
        )  # fmt: skip
        self._first = True

    def step(self, points: np.ndarray, increment: Pose | None) -> FilterStep:
        """The scan whose valid returns (sensor frame, beam order, K x 2) are ``points``,
        ``increment`` the odometry's move since the last scan (its frame; ignored for the
        first scan after :meth:`start`)."""
        if self.state is None or self.covariance is None:
            raise RuntimeError("LineMapFilter.step before start")
        from scanlines import _core

        points = np.asarray(points, dtype=np.float64).reshape(-1, 2)
        grid, near, lines = self.grid, self.near_grid, self.lines
        move = np.zeros(3) if increment is None else np.asarray(increment, dtype=np.float64)
        state, covariance, predicted, pairs, matched, chi2, status = _core.filter_scan(
            self.state, self.covariance, move, self._first or increment is None,
            np.ascontiguousarray(points[:, 0]), np.ascontiguousarray(points[:, 1]),
            lines.rho, self.normals, lines.start, lines.end, lines.sides,
            grid.shape, grid.cell_start, grid.cell_lines, near.shape, near.cell_start,
            near.cell_lines, near.reach, self._record,
            self.settings.max_points,
        )  # fmt: skip
        self._first = False
        self.state, self.covariance = state, covariance
        pose = (float(state[0]), float(state[1]), float(state[2]))
        return FilterStep(pose, covariance[:3, :3].copy(), predicted, int(pairs), int(matched),
                          float(chi2), STATUSES[status], state, covariance)  # fmt: skip
