"""Localisation on a saved line map: a log tracked from a given pose, odometry as the prior.

::

    from scanlines.io import open_log
    from scanlines.map.localize import localize, read_line_map

    lines, frame = read_line_map("intel.json")           # a map `scanlines map` wrote
    with open_log("intel.clf.gz") as reader:
        run = localize(reader.enumerate(), lines, frame, (t0, (x0, y0, yaw0)))
    run.tracked                                            # poses, covariances, status

Each scan from time ``t0`` on (earlier scans are skipped) is predicted from the last pose
and its odometry increment; its returns are aligned to the map's lines
(:func:`~scanlines.map.tracking.track_points`) with the increment's noise (``Q`` of
:class:`~scanlines.map.tracking.TrackSettings`) as the prior (the first scan: the initial
pose's, :data:`INITIAL_SIGMA`), and the fit's covariance is the pose's. A scan that does not
fit is reported (``status`` ``"did not fit"``), not forced: its predicted pose stands with
its covariance propagated from the last fit (``F P F' + G Q G'``); each further miss widens
the gate and the prior (``Q (1 + misses)``) until a scan fits again.

The prior is the increment's noise, not the propagated covariance: with the latter (the
first version) a corridor's weak and partly wrong pull along its axis won over the odometry,
and on the raw Intel scans the track slid off the map at 683 s for good (RMSE 5.5 m over 345
keyframes, against 0.21 m now: docs/MEASUREMENTS.md).
"""

from __future__ import annotations

import json
import math
from collections.abc import Callable, Iterable
from dataclasses import dataclass, field, replace
from pathlib import Path

import numpy as np

from scanlines.errors import ScanlinesError
from scanlines.map.align import LineSet
from scanlines.map.build import TrackedPose
from scanlines.map.frame import LocalFrame
from scanlines.map.tracking import TrackSettings, track_points
from scanlines.poses import Pose, compose, relative_pose
from scanlines.scan import Scan

__all__ = ["Localisation", "MapFileError", "localize", "read_line_map"]

#: The prior (standard deviations: metres, radians) about the initial pose given.
INITIAL_SIGMA = (0.1, math.radians(3.0))
#: The share of a scan's returns that must meet a map line: lower than a map's own
#: (a saved map may miss what has changed since, and covers only where it was made).
MIN_SHARE = 0.1
#: Gauss-Newton stops at steps below this (0.1 mm, 0.006 deg): 30 % less time than
#: the mapping default (1e-6) for the same poses on the raw Intel scans.
TOLERANCE = 1e-4
#: A scan this much (seconds) before the initial time still starts the run.
START_TOLERANCE = 0.01


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

    @property
    def not_fit(self) -> int:
        return sum(1 for t in self.tracked if t.status == "did not fit")


def _widened(settings: TrackSettings, misses: int) -> TrackSettings:
    """``settings`` with the gate and the largest correction widened after ``misses``
    scans in a row that did not fit (their poses predicted only), so that tracking can
    catch the map again: by half the gate per miss, to at most 1 m and 30 degrees."""
    if not misses:
        return settings
    grow = 1.0 + 0.5 * misses
    return replace(
        settings,
        gate=min(settings.gate * grow, 1.0),
        max_shift=min(max(settings.max_shift, settings.gate * grow), 1.0),
        max_turn=min(settings.max_turn * grow, math.radians(30.0)),
    )


def _propagate(covariance: np.ndarray, pose: Pose, increment: Pose, noise: np.ndarray):
    """The covariance of ``compose(pose, increment)`` from that of ``pose`` and ``noise``."""
    c, s = math.cos(pose[2]), math.sin(pose[2])
    dx, dy = increment[0], increment[1]
    f = np.array([[1.0, 0.0, -s * dx - c * dy], [0.0, 1.0, c * dx - s * dy], [0.0, 0.0, 1.0]])
    g = np.array([[c, -s, 0.0], [s, c, 0.0], [0.0, 0.0, 1.0]])
    return f @ covariance @ f.T + g @ noise @ g.T


def localize(
    indexed: Iterable[tuple[int, Scan]],
    lines: LineSet,
    frame: LocalFrame,
    initial: tuple[float, Pose],
    *,
    poses: Callable[[int, Scan], Pose | None] | None = None,
    settings: TrackSettings | None = None,
) -> Localisation:
    """Track ``indexed`` scans on ``lines`` (local ``frame``) from ``initial``: a time
    and a world pose. ``poses``: each scan's odometry (default: the pose it carries)."""
    settings = settings or TrackSettings(min_share=MIN_SHARE, tolerance=TOLERANCE)
    t0, start = initial
    run = Localisation(frame)
    odometry_of = poses or (lambda index, scan: scan.pose)
    pose: Pose | None = None
    last_odometry: Pose | None = None
    covariance = np.diag([INITIAL_SIGMA[0] ** 2] * 2 + [INITIAL_SIGMA[1] ** 2])
    misses = 0
    for index, scan in indexed:
        if scan.timestamp is None or scan.timestamp < t0 - START_TOLERANCE:
            run.skipped += 1
            continue
        odometry = odometry_of(index, scan)
        if odometry is None:
            run.without_pose += 1
            continue
        first = pose is None or last_odometry is None
        if first:
            predicted: Pose = frame.pose(start)
        else:
            increment = relative_pose(last_odometry, odometry)
            predicted = compose(pose, increment)
            noise = settings.increment_covariance(increment)
            covariance = _propagate(covariance, pose, increment, noise)
        prior = covariance if first else noise * (1.0 + misses)
        fit = track_points(scan.points[scan.valid], predicted, prior, lines,
                           _widened(settings, misses))  # fmt: skip
        pose, last_odometry = fit.pose, odometry
        if fit.used:
            covariance = fit.covariance  # else the propagated covariance stands
        misses = 0 if fit.used else misses + 1
        status = "aligned" if fit.used else "did not fit"
        run.tracked.append(TrackedPose(index, scan.timestamp, frame.pose(odometry), predicted,
                                       fit.pose, covariance, status))  # fmt: skip
    return run
