"""Localisation on a saved line map: a log tracked from a given pose, odometry as the prior.

::

    from scanlines.io import open_log
    from scanlines.map.localize import localize, read_line_map

    lines, frame = read_line_map("intel.json")           # a map `scanlines map` wrote
    with open_log("intel.clf.gz") as reader:
        run = localize(reader.enumerate(), lines, frame, (t0, (x0, y0, yaw0)))
    run.tracked                                            # poses, covariances, status

The run starts at the scan of time ``t0``: the first (in the log's order) within
:data:`START_TOLERANCE` of it, else the first after it; the scans before it are skipped.
From there every scan is tracked in the log's order, whatever its clock says: a raw log's
clock may step back (the raw Intel scans' by up to 0.9 s, 265 times) while its odometry
runs on, and the log's order is the order of the odometry. So the start is chosen among
the scans up to :data:`START_WINDOW` past ``t0``: on the raw Intel scans the scan stamped
33.108 s comes before the one stamped 32.907 s, and the robot turned 6.7 degrees between
them. Each scan goes through :class:`~scanlines.map.filter.LineMapFilter`:
the pose predicted from the last one by the odometry increment (corrected by the odometry's
heading drift, scale and the sensor's lever, which the filter learns), then its returns
matched to the map's lines. A scan that does not fit is reported (``status`` ``"did not
fit"``), not forced: its predicted pose stands with the covariance grown by the increment's
noise, which widens the gate of the next scans until one fits again.

Earlier versions (docs/MEASUREMENTS.md) took only the increment's noise as each fit's prior
and searched every map line for every return: 0.21 m RMSE over the raw Intel keyframes at
252 scans/s; the filter, its matching (local lines, a grid of the map's lines) and the
odometry's learnt errors give the figures measured there now.
"""

from __future__ import annotations

import json
import math
from collections.abc import Callable, Iterable
from dataclasses import dataclass, field
from pathlib import Path

import numpy as np

from scanlines.errors import ScanlinesError
from scanlines.geometry.poses import Pose, relative_pose
from scanlines.map.align import LineSet
from scanlines.map.build import TrackedPose
from scanlines.map.filter import INITIAL_SIGMA, FilterSettings, LineMapFilter
from scanlines.map.frame import LocalFrame
from scanlines.scan import Scan

__all__ = ["Localisation", "MapFileError", "localize", "read_line_map"]

#: A scan this close (seconds) to the initial time is the scan of the initial pose.
START_TOLERANCE = 0.01
#: The scans read past the initial time (seconds of the log's clock) to find its scan.
START_WINDOW = 1.0


class MapFileError(ScanlinesError, ValueError):
    """A line map file that cannot be read."""


def read_line_map(path: str | Path) -> tuple[LineSet, LocalFrame]:
    """The lines of a ``.json`` map ``scanlines map`` wrote, in its local frame."""
    path = Path(path)
    try:
        document = json.loads(path.read_text(encoding="utf-8"))
    except UnicodeDecodeError as error:
        raise MapFileError(f"{path}: not a text file ({error.reason})") from None
    except json.JSONDecodeError as error:
        raise MapFileError(f"{path}: not JSON ({error.msg}, line {error.lineno})") from None
    if not isinstance(document, dict) or document.get("format") != "scanlines line map":
        raise MapFileError(f"{path}: not a line map (`scanlines map --out MAP.json` writes one)")
    try:
        origin = [float(v) for v in document["frame"]["origin"]]
        frame = LocalFrame(origin[0], origin[1])
    except (KeyError, TypeError, ValueError, IndexError):
        raise MapFileError(f"{path}: field frame.origin: not a pair of numbers") from None
    records = document.get("lines")
    if not isinstance(records, list):
        raise MapFileError(f"{path}: field lines: not a list")
    values = np.zeros((len(records), 6))
    for k, record in enumerate(records):
        for j, name in enumerate(("start", "end", "rho", "alpha")):
            try:
                value = record[name]
                numbers = [float(v) for v in value] if name in ("start", "end") else [float(value)]
                if len(numbers) != (2 if name in ("start", "end") else 1):
                    raise ValueError
            except (KeyError, TypeError, ValueError):
                raise MapFileError(
                    f"{path}: line {k}: field {name}: missing or not a number"
                ) from None
            if not all(math.isfinite(v) for v in numbers):
                raise MapFileError(f"{path}: line {k}: field {name}: not finite")
            values[k, [0, 1] if j == 0 else [2, 3] if j == 1 else [j + 2]] = numbers
    offset = np.array(frame.origin)
    lines = LineSet(values[:, 4], values[:, 5], values[:, 0:2] - offset, values[:, 2:4] - offset)
    return lines, frame


@dataclass
class Localisation:
    """A localisation run: every tracked scan (local frame; ``frame.world_pose`` for the
    world), the scans skipped before the initial time or without a pose."""

    frame: LocalFrame
    tracked: list[TrackedPose] = field(default_factory=list)
    skipped: int = 0
    without_pose: int = 0
    #: The odometry's errors as learnt at the end (:class:`~scanlines.map.filter.
    #: LineMapFilter`): heading drift (radians per metre), scale error, the sensor's lever.
    drift: float = 0.0
    scale: float = 0.0
    lever: tuple[float, float] = (0.0, 0.0)

    @property
    def not_fit(self) -> int:
        return sum(1 for t in self.tracked if t.status == "did not fit")


def _reporting(indexed: Iterable[tuple[int, Scan]], on_scan: Callable[[int], None] | None):
    """``indexed``, calling ``on_scan(index)`` as each pair is read."""
    for index, scan in indexed:
        if on_scan is not None:
            on_scan(index)
        yield index, scan


def _from_start(indexed: Iterable[tuple[int, Scan]], t0: float, run: Localisation):
    """``indexed`` from the scan of time ``t0`` on (module docstring), counting the scans
    skipped before it in ``run``."""
    scans = iter(indexed)
    pending: list[tuple[int, Scan]] = []
    for index, scan in scans:
        t = scan.timestamp
        if not pending and (t is None or t < t0 - START_TOLERANCE):
            run.skipped += 1
            continue
        pending.append((index, scan))
        if t is not None and t > t0 + START_WINDOW:
            break
    times = [scan.timestamp for _, scan in pending]
    near = [k for k, t in enumerate(times) if t is not None and abs(t - t0) <= START_TOLERANCE]
    after = [k for k, t in enumerate(times) if t is not None and t >= t0]
    first = near[0] if near else after[0] if after else len(pending)
    run.skipped += first
    yield from pending[first:]
    yield from scans


def localize(
    indexed: Iterable[tuple[int, Scan]],
    lines: LineSet,
    frame: LocalFrame,
    initial: tuple[float, Pose],
    *,
    poses: Callable[[int, Scan], Pose | None] | None = None,
    settings: FilterSettings | None = None,
    initial_sigma: tuple[float, float] = INITIAL_SIGMA,
    on_scan: Callable[[int], None] | None = None,
) -> Localisation:
    """Track ``indexed`` scans on ``lines`` (local ``frame``) from ``initial``: a time
    and a world pose (standard deviations ``initial_sigma``: metres, radians). ``poses``:
    each scan's odometry (default: the pose it carries); ``on_scan(index)``: called for
    each scan read, skipped ones too."""
    t0, start = initial
    run = Localisation(frame)
    tracker = LineMapFilter(lines, settings)
    odometry_of = poses or (lambda index, scan: scan.pose)
    last_odometry: Pose | None = None
    for index, scan in _from_start(_reporting(indexed, on_scan), t0, run):
        odometry = odometry_of(index, scan)
        if odometry is None:
            run.without_pose += 1
            continue
        if last_odometry is None:
            tracker.start(frame.pose(start), initial_sigma)
            increment = None
        else:
            increment = relative_pose(last_odometry, odometry)
        step = tracker.step(scan.points[scan.valid], increment)
        last_odometry = odometry
        status = "aligned" if step.aligned else "did not fit"
        run.tracked.append(
            TrackedPose(index, scan.timestamp, frame.pose(odometry), step.predicted, step.pose,
                        step.covariance, status)
        )  # fmt: skip
    if tracker.state is not None:
        run.drift, run.scale = float(tracker.state[3]), float(tracker.state[4])
        run.lever = (float(tracker.state[5]), float(tracker.state[6]))
    return run
